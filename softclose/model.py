"""The lid model: one geometry and mass set, its branch, and its CasADi functions.

``LidModel(cfg)`` picks the assembly branch named by ``geometry.assembly``, checks that
the loop closes without a toggle over every angle the stroke can visit, and builds the
CasADi functions the rest of softclose calls:

- ``ode(x, p) -> x'`` with x = (theta, theta'), p = (k, l0, c, c_rot) (SX, cheap);
- ``coeffs(theta) -> (M, dM, Vg, dVg, l, dl, dd, tau)`` and their theta-derivatives, which the
  fast kernels tabulate;
- kinematics, energy and (built only on first use) the Newton-Euler reactions.
"""

from __future__ import annotations

import math
from functools import cached_property

import casadi as ca
import numpy as np

from . import dynamics as dyn
from .config import Config
from .errors import ConfigError
from .kinematics import closure, points, velocity_loop

#: |u| above which the linkage counts as "at a toggle" (transmission angle < 0.8 deg)
TOGGLE_U = 0.9999
#: angle below the closed position tabulated for the stages of the last step (deg)
MARGIN_DEG = 5.0
#: angle above the release position tabulated for a lid that a spring first pushes open (deg);
#: the table stops earlier at a toggle position
MARGIN_OPEN_DEG = 30.0


def _wrap(a):
    return (a + math.pi) % (2 * math.pi) - math.pi


class LidModel:
    """The lid linkage of one config (geometry + mass); design values are parameters."""

    def __init__(self, cfg: Config):
        self.cfg = cfg
        self.geo, self.mass = cfg.geometry, cfg.mass
        th = ca.SX.sym("theta")
        self._u = ca.Function("u", [th], [closure(th, self.geo, 1)[2]])
        self.sigma = self._pick_branch()
        self.theta_range = self._check_range()
        self._build()

    # -- branch and range ------------------------------------------------------------
    def _pick_branch(self) -> int:
        th_a, phi_a, gamma_a = (math.radians(v) for v in self.geo.assembly)
        u = float(self._u(th_a))
        if not abs(u) < 1:
            raise ConfigError(
                f"geometry.assembly: the loop cannot close at theta = {self.geo.assembly[0]} deg "
                f"with these lengths (crank_oa, crank_bc, pivot_b, lid_c)")
        th = ca.SX.sym("theta")
        best = None
        for sigma in (1, -1):
            phi, gamma, _ = closure(th, self.geo, sigma)
            f = ca.Function("pg", [th], [phi, gamma])
            p, g = (float(v) for v in f(th_a))
            dist = max(abs(_wrap(p - phi_a)), abs(_wrap(g - gamma_a)))
            if best is None or dist < best[0]:
                best = (dist, sigma, p, g)
        dist, sigma, p, g = best
        if dist > math.radians(10.0):
            raise ConfigError(
                f"geometry.assembly: phi = {phi_a * 180 / math.pi:.4f}, gamma = "
                f"{gamma_a * 180 / math.pi:.4f} deg is {math.degrees(dist):.1f} deg from the nearest "
                f"assembly at theta = {self.geo.assembly[0]} deg (phi = {math.degrees(p):.4f}, "
                f"gamma = {math.degrees(g):.4f} deg)")
        return sigma

    def _check_range(self) -> tuple[float, float]:
        """Check closure from the assembly angle over the stroke; return the table range."""
        st = self.cfg.stroke
        th_a = math.radians(self.geo.assembly[0])
        lo, hi = min(th_a, st.theta_closed), max(th_a, st.theta0)
        th_bad, u = self._scan(lo, hi, th_a)
        if th_bad is not None:  # name the toggle met first when moving away from the assembly
            where = ("at stroke.theta0_deg" if abs(th_bad - st.theta0) < 1e-9 else
                     f"at theta = {math.degrees(th_bad):.3f} deg")
            raise ConfigError(
                f"geometry: the loop reaches a toggle position or cannot close {where}, which "
                f"lies between the assembly (theta = {self.geo.assembly[0]} deg) and the stroke "
                f"({st.theta_closed_deg}..{st.theta0_deg} deg); change crank_oa, crank_bc, "
                f"pivot_b or lid_c, or the stroke angles")
        # extend by a margin on each side as far as the loop still closes (stage overshoot)
        # the margins stop where the linkage comes closer to a toggle than the stroke does
        u_margin = max(0.99, float(u.max()) + 0.5 * (1.0 - float(u.max())))
        ext = []
        for end, sgn, margin_deg in ((st.theta_closed, -1, MARGIN_DEG),
                                     (st.theta0, +1, MARGIN_OPEN_DEG)):
            margin = math.radians(margin_deg)
            t = np.linspace(0, margin, 201)
            ue = np.abs(np.asarray(self._u.map(len(t))(end + sgn * t)).ravel())
            ok = np.nonzero(~(ue < u_margin))[0]
            m = (t[ok[0] - 1] if ok[0] > 0 else 0.0) if len(ok) else margin
            ext.append(end + sgn * m)
        self.max_abs_u = float(u.max())
        return ext[0], ext[1]

    def _scan(self, lo: float, hi: float, start: float):
        """Sample |u| on [lo, hi]: (the toggle angle nearest ``start`` or None, |u| samples)."""
        grid = np.linspace(lo, hi, max(400, int((hi - lo) / math.radians(0.05)) + 1))
        u = np.abs(np.asarray(self._u.map(len(grid))(grid)).ravel())
        bad = np.nonzero(~(u < TOGGLE_U))[0]
        if not len(bad):
            return None, u
        return float(grid[bad[np.argmin(np.abs(grid[bad] - start))]]), u

    def toggle_between(self, a: float, b: float) -> float | None:
        """The toggle position (or angle where the loop cannot close) met first when the
        lid moves on this branch from ``a`` towards ``b`` (rad); None if there is none."""
        return self._scan(min(a, b), max(a, b), a)[0]

    @property
    def near_toggle(self) -> bool:
        """True when the transmission angle over the stroke drops below about 8 deg."""
        return self.max_abs_u > 0.99

    # -- CasADi functions ------------------------------------------------------------
    def _build(self):
        geo, mass, s = self.geo, self.mass, self.sigma
        th, thd = ca.SX.sym("theta"), ca.SX.sym("theta_dot")
        x, p = ca.vertcat(th, thd), ca.SX.sym("p", 4)
        cf = dyn.coefficients(th, geo, mass, s)
        self._cf_expr = cf
        tdd = dyn.theta_ddot(cf, thd, p)
        self.ode = ca.Function("ode", [x, p], [ca.vertcat(thd, tdd)], ["x", "p"], ["xdot"])
        vec = ca.vertcat(*[cf[k] for k in dyn.COEFFS])
        self.coeffs = ca.Function("coeffs", [th], [vec, ca.jacobian(vec, th)],
                                  ["theta"], ["c", "dc"])
        self.energy_fn = ca.Function("energy", [x, p], [dyn.energy(cf, thd, p)])
        self.power_fn = ca.Function("power", [x, p], [dyn.damper_power(cf, thd, p)])
        phi, gamma, u = closure(th, geo, s)
        pts = points(th, phi, gamma, geo)
        phi_d, gamma_d = velocity_loop(th, phi, gamma, thd, geo)
        v_T = ca.jacobian(pts["T"], th) * thd
        self.kin = ca.Function(
            "kin", [x], [phi, gamma, phi_d, gamma_d, v_T, pts["A"], pts["C"], pts["E"],
                         pts["T"], pts["G1"]],
            ["x"], ["phi", "gamma", "phi_dot", "gamma_dot", "v_T", "A", "C", "E", "T", "G1"])
        # the holding moment dV/dtheta (gravity + spring), as a function of theta and p
        self.dV = ca.Function("dV", [th, p], [cf["dVg"] + p[0] * (cf["l"] - p[1]) * cf["dl"]])

    @cached_property
    def newton_euler(self) -> ca.Function:
        """(theta, theta', p) -> z = (R_O, R_A, R_B, R_C, theta''): built on first use."""
        th, thd, p = ca.SX.sym("theta"), ca.SX.sym("theta_dot"), ca.SX.sym("p", 4)
        A, b = dyn.newton_euler_system(th, thd, p, self.geo, self.mass, self.sigma)
        sys = ca.Function("ne_sys", [th, thd, p], [A, b])
        thm, thdm, pm = ca.MX.sym("theta"), ca.MX.sym("theta_dot"), ca.MX.sym("p", 4)
        Am, bm = sys(thm, thdm, pm)
        return ca.Function("newton_euler", [thm, thdm, pm], [ca.solve(Am, bm)])

    # -- conveniences (numbers in, numbers out) ----------------------------------------
    def params(self, design=None) -> np.ndarray:
        d = design if design is not None else self.cfg.design
        return np.array([d.spring_k, d.spring_rest_length, d.damper_c, d.rotary_damper_c])

    def closure(self, theta: float) -> tuple[float, float]:
        """(phi, gamma) in radians on this model's branch."""
        out = self.kin(ca.vertcat(theta, 0.0))
        return float(out[0]), float(out[1])

    def theta_ddot(self, theta: float, theta_dot: float, p=None) -> float:
        p = self.params() if p is None else p
        return float(self.ode(ca.vertcat(theta, theta_dot), p)[1])

    def holding_moment(self, p=None) -> float:
        """dV/dtheta at theta_closed (N m); > 0 presses the lid onto the rim."""
        p = self.params() if p is None else p
        return float(self.dV(self.cfg.stroke.theta_closed, p))

    def state(self, theta: float, theta_dot: float, p=None) -> dict:
        """Every quantity of SPEC §7 ``state`` at one state (SI units, radians)."""
        p = self.params() if p is None else p
        x = ca.vertcat(theta, theta_dot)
        k = self.kin(x)
        z = np.asarray(self.newton_euler(theta, theta_dot, p)).ravel()
        phi, gamma = float(k[0]), float(k[1])
        ref_phi, ref_gamma = math.radians(self.geo.assembly[1]), math.radians(self.geo.assembly[2])
        phi = ref_phi + _wrap(phi - ref_phi)
        gamma = ref_gamma + _wrap(gamma - ref_gamma)
        return {
            "theta": theta, "theta_dot": theta_dot,
            "theta_ddot": self.theta_ddot(theta, theta_dot, p),
            "phi": phi, "gamma": gamma,
            "phi_dot": float(k[2]), "gamma_dot": float(k[3]),
            "tip_velocity": [float(v) for v in np.asarray(k[4]).ravel()],
            "reactions": {"O": z[0:2].tolist(), "A": z[2:4].tolist(),
                          "B": z[4:6].tolist(), "C": z[6:8].tolist()},
        }
