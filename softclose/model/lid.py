"""The lid model: one geometry and mass set, its branch, and its CasADi functions.

``LidModel(case)`` (a config resolved by :func:`softclose.problem.resolve`; from a config:
``softclose.LidModel.from_config(cfg)``) picks the branch on the side named by
``geometry.assembly`` (the sign of ``sin(gamma - phi)``, which only a toggle changes; see
:mod:`softclose.model.kinematics`), checks
that the loop closes without a toggle from the assembly angle over every angle the stroke
visits, and builds the CasADi functions the rest of softclose calls:

- ``ode(x, p) -> x'`` with x = (theta, theta') and p the parameter vector of
  :data:`softclose.model.elements.PARAMS` (k, l0, c, c_rot, then the elements added since) (SX,
  cheap): the exact equation, an end damper acting where theta lies below its engagement
  angle (discontinuous there); ``ode_moving(x, p, moving, engaged)`` the smooth flow between
  two events, with dry friction's direction and each end damper's engagement given;
- ``coeffs(theta) -> (M, dM, Vg, dVg, l, dl, dd, tau)`` and their theta-derivatives, which the
  fast kernels tabulate, and ``xcoeffs`` the same for the columns of the coordinate table
  (:data:`softclose.model.dynamics.COORDINATE_COEFFS`);
- ``dV(theta, p)``, ``opening(theta, p) -> (F, dF/dtheta)`` and ``hand(theta, p) -> (dV, F,
  dF, tau)`` (what the hand force evaluates on its grid, in one function);
- kinematics, energy and (built only on first use) the Newton-Euler reactions.
"""

from __future__ import annotations

import math
from functools import cached_property

import casadi as ca
import numpy as np

from . import dynamics as dyn, elements
from .elements import as_params
from ..errors import ConfigError
from .kinematics import branch_of, closure, points, velocity_loop
from .resolved import LidCase
from ..buildcache import text

#: |u| above which the linkage counts as "at a toggle": acos|u| < 0.81 deg, i.e. the crank
#: angles phi of the two assemblies (phi = arg w +- acos u) less than 1.6 deg apart
TOGGLE_U = 0.9999
#: assembly angles with the cranks closer to in line than this (deg) name no branch
INLINE_DEG = 0.01
#: angle below the closed position tabulated for the stages of the last step (deg)
MARGIN_DEG = 5.0
#: angle above the release position tabulated for a lid that a spring first pushes open (deg);
#: the table stops earlier at a toggle position
MARGIN_OPEN_DEG = 30.0


def _wrap(a):
    return (a + math.pi) % (2 * math.pi) - math.pi


def model_key(case: LidCase) -> tuple:
    """What a model depends on: geometry, masses, the stroke's angles and the element choices
    that change its structure (:func:`softclose.model.elements.structure`). Equal keys, equal
    models: every cache of models, tables and NLPs is keyed by it."""
    lid, st = case.lid, case.stroke
    return (lid.geometry, lid.mass, st.theta0_deg, st.theta_closed_deg,
            elements.structure(lid.mounting))


#: the CasADi functions a model carries (attribute names), kept serialised in the disk cache
FUNCTIONS = ("ode", "ode_moving", "coeffs", "xcoeffs", "energy_fn", "power_fn", "kin", "dV",
             "opening", "friction_moment", "hand", "_u")


_SHARED: dict = {}


def shared_model(case: LidCase) -> "LidModel":
    """The LidModel of the case's geometry, mass and stroke, kept for the process (and on
    disk: :meth:`LidModel.cached`): every model a process needs is built or loaded once (its
    own design, :meth:`LidModel.params`, is that of the first case it was built for)."""
    key = model_key(case)
    if key not in _SHARED:
        _SHARED[key] = LidModel.cached(case)
    return _SHARED[key]


def _checked(case) -> LidCase:
    """``case`` if it is a resolved config, else a TypeError saying how to make one."""
    if not isinstance(case, LidCase):
        raise TypeError(f"LidModel takes a resolved config (softclose.problem.resolve(cfg), "
                        f"or LidModel.from_config(cfg)), got {type(case).__name__}")
    return case


class LidModel:
    """The lid linkage of one resolved config (geometry + mass, the mounting of its elements,
    the stroke); design values are parameters."""

    @classmethod
    def cached(cls, case: LidCase) -> "LidModel":
        """``LidModel(case)``, loaded from the disk cache (:mod:`softclose.buildcache`) when
        this software built it before, else built and stored. A loaded model deserialises
        each CasADi function when it is first used; its numbers are the built model's."""
        from .. import buildcache
        key = buildcache.key_of("model", model_key(_checked(case)))
        entry = buildcache.load("model", key)
        if entry is not None:
            try:
                m = cls._restore(case, entry)
                m.cache_key = key
                return m
            except Exception:   # noqa: BLE001  (a foreign or damaged entry: build anew)
                pass
        m = cls(case)
        m.cache_key = key
        buildcache.store("model", key, m._state())
        return m

    def _state(self) -> dict:
        """What :meth:`cached` stores: the branch, the range, the serialised functions."""
        out = {"numbers": np.array([self.sigma, *self.theta_range, self.max_abs_u])}
        for name in FUNCTIONS:
            out[f"fn{name}"] = getattr(self, name).serialize().encode()
        for name, f in self.coordinate_fns.items():
            out[f"q_{name}"] = f.serialize().encode()
        return out

    @classmethod
    def _restore(cls, case: LidCase, entry: dict) -> "LidModel":
        m = cls.__new__(cls)
        m._keep(case)
        sigma, lo, hi, u = (float(v) for v in entry["numbers"])
        m.sigma, m.theta_range, m.max_abs_u = int(sigma), (lo, hi), u
        m._serialised = {k: text(v) for k, v in entry.items() if k != "numbers"}
        if not {f"fn{n}" for n in FUNCTIONS} <= set(m._serialised):
            raise ValueError("incomplete model entry")
        return m

    def __getattr__(self, name):
        """A function of a model loaded from the disk cache, deserialised on first use."""
        ser = self.__dict__.get("_serialised")
        if ser is None:
            raise AttributeError(name)
        if name == "coordinate_fns":
            value = {k[2:]: ca.Function.deserialize(v) for k, v in ser.items()
                     if k.startswith("q_")}
        elif f"fn{name}" in ser:
            value = ca.Function.deserialize(ser[f"fn{name}"])
        else:
            raise AttributeError(name)
        setattr(self, name, value)
        return value

    def __init__(self, case: LidCase):
        """``case``: a config resolved (:func:`softclose.problem.resolve`); the model keeps
        its lid, its stroke and its design (the default of every ``p``)."""
        self._keep(_checked(case))
        th = ca.SX.sym("theta")
        self._u = ca.Function("u", [th], [closure(th, self.geo, 1)[2]])
        self.sigma = self._pick_branch()
        self.theta_range = self._check_range()
        self._build()

    def _keep(self, case: LidCase) -> None:
        #: the lid on its mechanism (:class:`softclose.model.resolved.Lid`), the stroke's ends
        self.lid, self.stroke = case.lid, case.stroke
        #: the design's parameter vector (a tuple): the default of every ``p``
        self.design = case.design
        self.geo, self.mass = case.lid.geometry, case.lid.mass

    @property
    def mounting(self):
        """Where the elements sit and the spring's limits
        (:class:`softclose.model.resolved.Mounting`)."""
        return self.lid.mounting

    # -- branch and range ------------------------------------------------------------
    def _pick_branch(self) -> int:
        """sigma of the configuration named by ``geometry.assembly`` (by its side, not distance).

        The loop must close at the assembly's theta. The branch is the side of the
        assembly's cranks: sigma = -sign sin(gamma - phi) (:func:`kinematics.branch_of`),
        a sign that is constant along a branch and changes only at a toggle. phi and gamma
        therefore only select the branch: they need not close the loop for these lengths, so
        a changed crank length keeps its branch without touching ``geometry.assembly``.
        Cranks given in line (within ``INLINE_DEG``) name no side and are refused.
        """
        th_a_deg, phi_a_deg, gamma_a_deg = self.geo.assembly
        th_a = math.radians(th_a_deg)
        if not abs(float(self._u(th_a))) < 1:
            raise ConfigError(self._no_closure_message(th_a_deg))
        phi_a, gamma_a = math.radians(phi_a_deg), math.radians(gamma_a_deg)
        if abs(math.sin(gamma_a - phi_a)) < math.sin(math.radians(INLINE_DEG)):
            both = "; ".join(f"({math.degrees(p) % 360:.4f}, {math.degrees(g) % 360:.4f})"
                             for p, g in (self._closure_at(th_a, s) for s in (-1, 1)))
            raise ConfigError(
                f"geometry.assembly: phi = {phi_a_deg} and gamma = {gamma_a_deg} deg put the "
                f"cranks in line, which names neither assembly; give phi, gamma (deg) of the "
                f"wanted one, at theta = {th_a_deg} deg: {both}")
        return branch_of(phi_a, gamma_a)

    def _closure_at(self, theta: float, sigma: int) -> tuple[float, float]:
        th = ca.SX.sym("theta")
        phi, gamma, _ = closure(th, self.geo, sigma)
        out = ca.Function("pg", [th], [phi, gamma])(theta)
        return float(out[0]), float(out[1])

    def _no_closure_message(self, th_a_deg: float) -> str:
        """Where the loop closes at all (0.1-deg scan over a turn): the one-line refusal."""
        deg = th_a_deg + np.linspace(-180.0, 180.0, 3601)
        ok = np.abs(np.asarray(self._u.map(len(deg))(np.radians(deg))).ravel()) < 1
        lengths = "geometry.crank_oa, crank_bc, pivot_b or lid_c"
        if not ok.any():
            return (f"geometry: the loop cannot close at any lid angle (crank_oa = "
                    f"{self.geo.crank_oa}, crank_bc = {self.geo.crank_bc} m); change {lengths}")
        edges = np.flatnonzero(np.diff(ok.astype(int)))
        runs, i0 = [], (0 if ok[0] else None)
        for i in edges:
            if ok[i + 1]:
                i0 = i + 1
            else:
                runs.append((deg[i0], deg[i]))
        if i0 is not None and ok[-1]:
            if runs and ok[0]:   # the first and the last run are one interval across the seam
                runs[0] = (deg[i0], runs[0][1] + 360.0)
            else:
                runs.append((deg[i0], deg[-1]))
        where = ", ".join(f"{a:.1f}..{b:.1f}" for a, b in runs[:3])
        return (f"geometry.assembly: the loop cannot close at theta = {th_a_deg} deg with "
                f"these lengths (it closes for theta in {where} deg); move geometry.assembly[0] "
                f"and the stroke there, or change {lengths}")

    def _check_range(self) -> tuple[float, float]:
        """Check closure from the assembly angle over the stroke; return the table range."""
        st = self.stroke
        th_a = math.radians(self.geo.assembly[0])
        lo, hi = min(th_a, st.theta_closed), max(th_a, st.theta0)
        th_bad, u = self._scan(lo, hi, th_a)
        if th_bad is not None:
            raise ConfigError(self._toggle_message(th_bad, th_a))
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

    def _toggle_message(self, th_bad: float, th_a: float) -> str:
        """One line: the toggle met first from the assembly, and the keys that move it."""
        st = self.stroke
        inside = st.theta_closed <= th_bad <= st.theta0
        reached = not abs(float(self._u(th_bad))) < 1
        # print the angle rounded away from the assembly: the loop does not close there
        q = 1000.0
        deg = math.degrees(th_bad)
        deg = (math.ceil(deg * q) if th_bad > th_a else math.floor(deg * q)) / q
        what = ("reaches a toggle position (cranks in line; beyond it the loop cannot close)"
                if reached else
                f"nearly reaches a toggle position (the two assemblies' phi within "
                f"{2 * math.degrees(math.acos(TOGGLE_U)):.1f} deg)")
        where = (f"inside the stroke ({st.theta_closed_deg}..{st.theta0_deg} deg)" if inside else
                 f"between the assembly (theta = {self.geo.assembly[0]} deg) and the stroke "
                 f"({st.theta_closed_deg}..{st.theta0_deg} deg)")
        keys = "geometry.crank_oa, crank_bc, pivot_b or lid_c, or stroke.theta0_deg / " \
            "theta_closed_deg"
        if not inside:
            keys += ", or geometry.assembly[0]"
        return f"geometry: the linkage {what} at theta = {deg:.3f} deg, {where}; change {keys}"

    def _scan(self, lo: float, hi: float, start: float):
        """Sample |u| on [lo, hi]: (the toggle angle nearest ``start`` or None, |u| samples).

        A sample with |u| >= ``TOGGLE_U`` is a toggle; when |u| reaches 1 there, the angle
        returned is where |u| = 1, found by bisection between it and its neighbour on the
        ``start`` side.
        """
        grid = np.linspace(lo, hi, max(400, int((hi - lo) / math.radians(0.05)) + 1))
        u = np.abs(np.asarray(self._u.map(len(grid))(grid)).ravel())
        bad = np.nonzero(~(u < TOGGLE_U))[0]
        if not len(bad):
            return None, u
        i = int(bad[np.argmin(np.abs(grid[bad] - start))])
        j = i - 1 if grid[i] > start else i + 1
        if u[i] < 1 or not 0 <= j < len(grid) or not u[j] < 1:
            return float(grid[i]), u
        a, b = float(grid[j]), float(grid[i])   # |u(a)| < 1 <= |u(b)|
        for _ in range(60):
            m = 0.5 * (a + b)
            if abs(float(self._u(m))) < 1:
                a = m
            else:
                b = m
        return b, u

    def toggle_between(self, a: float, b: float) -> float | None:
        """The toggle position (or angle where the loop cannot close) met first when the
        lid moves on this branch from ``a`` towards ``b`` (rad); None if there is none."""
        return self._scan(min(a, b), max(a, b), a)[0]

    # -- CasADi functions ------------------------------------------------------------
    def _build(self):
        s = self.sigma
        th, thd = ca.SX.sym("theta"), ca.SX.sym("theta_dot")
        x, p = ca.vertcat(th, thd), ca.SX.sym("p", len(elements.PARAMS))
        cf = dyn.coefficients(th, self.lid, s)
        tdd = dyn.theta_ddot(cf, thd, p)
        self.ode = ca.Function("ode", [x, p], [ca.vertcat(thd, tdd)], ["x", "p"], ["xdot"])
        # the same with dry friction for a given direction of motion (+1 up, -1 down) and
        # each damper with an engagement angle engaged or not (1/0, elements.ENGAGING): what
        # an integrator takes between two events of a stroke (a rest, a crossing of an
        # engagement angle)
        mv, eg = ca.SX.sym("moving"), ca.SX.sym("engaged", len(elements.ENGAGING))
        engaged = {e.name: eg[i] for i, e in enumerate(elements.ENGAGING)}
        self.ode_moving = ca.Function(
            "ode_moving", [x, p, mv, eg],
            [ca.vertcat(thd, dyn.theta_ddot(cf, thd, p, mv, engaged))])
        vec = ca.vertcat(*[cf[k] for k in dyn.COEFFS])
        self.coeffs = ca.Function("coeffs", [th], [vec, ca.jacobian(vec, th)],
                                  ["theta"], ["c", "dc"])
        xvec = ca.vertcat(*[cf[k] for k in dyn.COORDINATE_COEFFS])
        self.xcoeffs = ca.Function("xcoeffs", [th], [xvec, ca.jacobian(xvec, th)],
                                   ["theta"], ["c", "dc"])
        self.energy_fn = ca.Function("energy", [x, p], [dyn.energy(cf, thd, p)])
        self.power_fn = ca.Function("power", [x, p], [dyn.damper_power(cf, thd, p)])
        phi, gamma, u = closure(th, self.geo, s)
        pts = points(th, phi, gamma, self.geo)
        phi_d, gamma_d = velocity_loop(th, phi, gamma, thd, self.geo)
        v_T = ca.jacobian(pts["T"], th) * thd
        self.kin = ca.Function(
            "kin", [x], [phi, gamma, phi_d, gamma_d, v_T, pts["A"], pts["C"], pts["E"],
                         pts["T"], pts["G1"]],
            ["x"], ["phi", "gamma", "phi_dot", "gamma_dot", "v_T", "A", "C", "E", "T", "G1"])
        # the holding moment dV/dtheta (gravity + springs), as a function of theta and p
        slope = dyn.slope(cf["coords"], elements.params(p))
        self.dV = ca.Function("dV", [th, p], [slope])
        # the hand force at the tip that lifts the lid slowly through theta: (dV + friction,
        # which opposes the lifting) / tau
        fr = dyn.friction(cf["coords"], elements.params(p))
        # the friction moment T_fr(theta) = T_f + F_R |dl/dtheta| (what holds a lid at rest)
        self.friction_moment = ca.Function("friction_moment", [th, p],
                                           [0.0 if fr is None else fr])
        F = (slope if fr is None else slope + fr) / cf["tau"]
        dF = ca.jacobian(F, th)
        self.opening = ca.Function("opening", [th, p], [F, dF])
        # what the hand force reads on its grid, in one function: dV, the opening force and
        # its derivative (``opening``) and the tip's lever tau (a row of ``coeffs``)
        # (the derivative repeats much of F: common subexpressions once, ~1/3 the work)
        hand = ca.cse(ca.vertcat(slope, F, dF, cf["tau"]))
        self.hand = ca.Function("hand", [th, p], [hand[i] for i in range(4)],
                                ["theta", "p"], ["dV", "F", "dF", "tau"])
        # every element's coordinate and its theta-derivative: {name: Function theta -> (q, q')}
        self.coordinate_fns = {e: ca.Function(f"q_{e}", [th], [c.q, c.dq])
                               for e, c in cf["coords"].items()}

    @cached_property
    def newton_euler(self) -> ca.Function:
        """(theta, theta', p) -> z = (R_O, R_A, R_B, R_C, theta''): built on first use."""
        npar = len(elements.PARAMS)
        th, thd, p = ca.SX.sym("theta"), ca.SX.sym("theta_dot"), ca.SX.sym("p", npar)
        A, b = dyn.newton_euler_system(th, thd, p, self.lid, self.sigma)
        sys = ca.Function("ne_sys", [th, thd, p], [A, b])
        thm, thdm, pm = ca.MX.sym("theta"), ca.MX.sym("theta_dot"), ca.MX.sym("p", npar)
        Am, bm = sys(thm, thdm, pm)
        return ca.Function("newton_euler", [thm, thdm, pm], [ca.solve(Am, bm)])

    # -- conveniences (numbers in, numbers out) ----------------------------------------
    def params(self) -> np.ndarray:
        """The parameter vector p of the model's design (another design's:
        :func:`softclose.problem.params_of` of its config)."""
        return np.array(self.design, float)

    def closure(self, theta: float) -> tuple[float, float]:
        """(phi, gamma) in radians on this model's branch."""
        out = self.kin(ca.vertcat(theta, 0.0))
        return float(out[0]), float(out[1])

    def theta_ddot(self, theta: float, theta_dot: float, p=None) -> float:
        p = self.params() if p is None else as_params(p)
        return float(self.ode(ca.vertcat(theta, theta_dot), p)[1])

    def holding_moment(self, p=None) -> float:
        """dV/dtheta at theta_closed (N m); > 0 presses the lid onto the rim."""
        p = self.params() if p is None else as_params(p)
        return float(self.dV(self.stroke.theta_closed, p))

    def state(self, theta: float, theta_dot: float, p=None) -> dict:
        """Every quantity of SPEC §7 ``state`` at one state (SI units, radians). A hinge lid
        has no cranks: its crank angles and rates are None and its one reaction is the
        hinge's, ``H``. A zero is +0.0 (at rest the rates are zero, not -0)."""
        p = self.params() if p is None else as_params(p)
        x = ca.vertcat(theta, theta_dot)
        k = self.kin(x)
        z = np.asarray(self.newton_euler(theta, theta_dot, p)).ravel() + 0.0
        tip = [float(v) + 0.0 for v in np.asarray(k[4]).ravel()]
        out = {"theta": theta + 0.0, "theta_dot": theta_dot + 0.0,
               "theta_ddot": self.theta_ddot(theta, theta_dot, p) + 0.0}
        if self.lid.mechanism == "hinge":
            return {**out, "phi": None, "gamma": None, "phi_dot": None, "gamma_dot": None,
                    "tip_velocity": tip, "reactions": {"H": z[2:4].tolist()}}
        phi, gamma = float(k[0]), float(k[1])
        ref_phi, ref_gamma = math.radians(self.geo.assembly[1]), math.radians(self.geo.assembly[2])
        phi = ref_phi + _wrap(phi - ref_phi)
        gamma = ref_gamma + _wrap(gamma - ref_gamma)
        return {**out, "phi": phi + 0.0, "gamma": gamma + 0.0,
                "phi_dot": float(k[2]) + 0.0, "gamma_dot": float(k[3]) + 0.0,
                "tip_velocity": tip,
                "reactions": {"O": z[0:2].tolist(), "A": z[2:4].tolist(),
                              "B": z[4:6].tolist(), "C": z[6:8].tolist()}}
