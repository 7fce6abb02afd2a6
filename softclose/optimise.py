"""The soft-close design problem (SPEC §5) by direct multiple shooting and Ipopt.

Decision variables (all of order one): the design (k/1000 N/m, l0/0.1 m, c/1000 N s/m), the
closing time T (s; time is scaled to [0, 1], so each of the N shooting intervals lasts T/N and
holds M RK4 sub-steps of T/(N·M)), the states (theta, theta') at the nodes 1..N (node 0 is
the release from rest), and an epigraph variable s for the peak tip speed.

    minimise   (weight_impact · theta'(T)² + weight_peak_tip · s²) / J_ref
    subject to continuity at every node, theta(T) = theta_closed,
               closing_time_min <= T <= closing_time_max,
               theta' <= 0 and theta >= theta_closed at every sub-step, theta''(release) <= 0,
               s >= |v_T| = tau(theta)·|theta'| at every sub-step, and s >= the maximum of
               the cubic Hermite interpolant of |v_T| inside every sub-step (so the peak
               between sub-steps is caught: error O(h^4), not O(h^2)),
               dV/dtheta(theta_closed) >= holding_moment_min.

The equation of motion depends on theta only through seven geometric functions
(-dVg/M, -l dl/M, dl/M, -dd/M, -dM/(2M), -1/M and tau = |dT/dtheta|); in the NLP they are
Chebyshev series fitted on the stroke's angles ±3° to machine precision (degree 14 for the
default geometry, max relative error ~4e-15, ``ShootingNLP.fit.max_rel_error``). One RK4
sub-step is then ~730 operations instead of ~4200, and the exact Hessian is cheap.
Everything reported is re-checked on the exact equations by the adaptive CVODES reference
(:func:`verify_design`).

The NLP is built once per geometry and (N, M) and cached (:func:`get_nlp`); every number that
can change between solves (theta0, theta_closed, weights, rotary damper, time grid) is an NLP
parameter, and closing-time bounds, design bounds and holding_moment_min are bounds, so
multistart, warm re-solves and Pareto fronts reuse the same functions. See docs/optimise.md.

Entry points: :func:`optimise` (multistart, refinement, verification -> OptimiseResult),
:func:`solve` (one solve, cold or warm, for benchmarks), :func:`front` (continuation in
closing_time_max), :func:`command` (``softclose optimise``).
"""

from __future__ import annotations

import json
import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import casadi as ca
import numpy as np

from .config import Config
from .dynamics import coefficients
from .errors import NumericalError
from .model import LidModel
from .simulate import Simulator

DESIGN_KEYS = ("spring_k", "spring_rest_length", "damper_c")
#: scale of each design variable in the NLP (so the scaled values are of order one)
SCALES = np.array([1000.0, 0.1, 1000.0])
#: Ipopt return statuses that count as converged
CONVERGED = ("Solve_Succeeded", "Solved_To_Acceptable_Level")
#: relative agreement of the objective with its verification that counts as success
VERIFY_RTOL = 1e-3
#: tolerance of the constraint checks in verification (absolute, SI)
CONSTRAINT_TOL = 1e-7
METRIC_KEYS = ("closed", "closing_time", "impact_theta_dot", "impact_tip_speed",
               "peak_tip_speed", "min_spring_length", "max_spring_length", "holding_moment")


#: margin (deg) beyond the stroke over which the Chebyshev series are fitted
FIT_MARGIN_DEG = 3.0


# -- the geometric functions as Chebyshev series -----------------------------------------
class ChebyshevFit:
    """g(theta) (7 functions) as Chebyshev series on [lo, hi], to machine precision."""

    NAMES = ("g_grav", "g_kl", "g_kl0", "g_c", "g_dM", "g_rot", "tau", "dtau")

    def __init__(self, model: LidModel, tol: float = 1e-13, max_degree: int = 64):
        th = ca.SX.sym("theta")
        cf = coefficients(th, model.geo, model.mass, model.sigma)
        M = cf["M"]
        g = ca.vertcat(-cf["dVg"] / M, -cf["l"] * cf["dl"] / M, cf["dl"] / M, -cf["dd"] / M,
                       -0.5 * cf["dM"] / M, -1.0 / M, cf["tau"])
        self.exact = ca.Function("g_exact", [th], [ca.cse(g)])
        # the stroke's angles with a margin for overshooting stages and iterates (the
        # series extrapolate smoothly beyond it), within the range where the loop closes
        st = model.cfg.stroke
        lo = max(model.theta_range[0], st.theta_closed - math.radians(FIT_MARGIN_DEG))
        hi = min(model.theta_range[1], st.theta0 + math.radians(FIT_MARGIN_DEG))
        self.lo, self.hi = lo, hi
        dense = np.linspace(lo, hi, 2001)
        G = np.asarray(self.exact.map(len(dense))(dense))
        scale = np.maximum(np.abs(G).max(axis=1), 1e-300)
        ud = self._u(dense)
        for n in range(8, max_degree + 1, 2):
            k = np.arange(n + 1)
            u = np.cos(np.pi * (k + 0.5) / (n + 1))
            Gn = np.asarray(self.exact.map(n + 1)(lo + (u + 1) * (hi - lo) / 2))
            C = np.array([np.polynomial.chebyshev.chebfit(u, Gn[i], n) for i in range(len(G))])
            err = np.max(np.abs(np.polynomial.chebyshev.chebval(ud, C.T) - G).max(axis=1)
                         / scale)
            if err < tol:
                break
        dtau = np.polynomial.chebyshev.chebder(C[6]) * 2 / (hi - lo)
        C = np.vstack([C, np.r_[dtau, 0.0]])
        self.coef, self.degree, self.max_rel_error = C, n, float(err)

    def _u(self, theta):
        return (2 * theta - (self.lo + self.hi)) / (self.hi - self.lo)

    def basis(self, theta):
        """Chebyshev polynomials T_0..T_n at theta (an SX column)."""
        u = self._u(theta)
        T = [1, u]
        for _ in range(2, self.degree + 1):
            T.append(2 * u * T[-1] - T[-2])
        return ca.vertcat(*T)

    def __call__(self, theta):
        """The eight functions (``NAMES``) at an SX scalar ``theta``."""
        return ca.mtimes(ca.DM(self.coef), self.basis(theta))


def _hermite_max(va, ma, vb, mb):
    """Maximum over one sub-step of the cubic Hermite interpolant of the tip speed.

    ``va, vb`` are the speeds at the ends, ``ma, mb`` their time derivatives times the step.
    The interior maximum (p' = 0, p'' < 0) is clipped into [0, 1]; by the envelope theorem
    the value is C1 in the data where it matters (the sub-step holding the peak).
    """
    a3 = 2 * va + ma - 2 * vb + mb
    a2 = -3 * va - 2 * ma + 3 * vb - mb
    a1 = ma
    D = a2 * a2 - 3 * a3 * a1
    # every operation is kept finite (with finite derivatives) in the branch not taken:
    # reverse-mode AD multiplies a zero seed by the untaken branch's partials
    pos = D > 0
    r = ca.sqrt(ca.if_else(pos, D, 1.0))
    den1 = r - a2                                # > 0 when a2 <= 0 (and D > 0)
    use1 = a2 <= 0
    ok1 = den1 > 0
    s1 = a1 / ca.if_else(ok1, den1, 1.0)
    ok2 = a3 != 0
    s2 = (-a2 - r) / ca.if_else(ok2, 3 * a3, 1.0)
    sig = ca.if_else(use1, ca.if_else(ok1, s1, 0.0), ca.if_else(ok2, s2, 0.0))
    sig = ca.if_else(pos, ca.fmin(ca.fmax(sig, 0), 1), 0)
    return ((a3 * sig + a2) * sig + a1) * sig + va


# -- the NLP -------------------------------------------------------------------------------
#: NLP parameters, in order
NLP_PARAMS = ("theta0", "theta_closed", "weight_impact", "weight_peak_tip", "weight_time",
              "rotary_damper_c", "J_ref")
#: Ipopt options of the cold solver and of the warm re-solve (same NLP functions)
COLD_OPTIONS = {"ipopt.mu_strategy": "adaptive"}
WARM_OPTIONS = {"ipopt.warm_start_init_point": "yes", "ipopt.mu_init": 1e-8,
                "ipopt.warm_start_bound_push": 1e-9, "ipopt.warm_start_mult_bound_push": 1e-9,
                "ipopt.warm_start_slack_bound_push": 1e-9}


class ShootingNLP:
    """The multiple-shooting NLP of one geometry with N intervals of M RK4 sub-steps each.

    Built once (``get_nlp`` caches it per geometry and discretisation); ``solve`` takes the
    bounds and parameters of one problem, so changing closing_time_max, weights, design
    bounds or holding_moment_min never rebuilds anything.
    """

    def __init__(self, model: LidModel, nodes: int, substeps: int, hessian: str = "exact",
                 linear_solver: str = "mumps", max_iter: int = 500, tol: float = 1e-10):
        t0 = time.perf_counter()
        self.model, self.N, self.M = model, nodes, substeps
        self.fit = ChebyshevFit(model)
        N, M = nodes, substeps
        nb = self.fit.degree + 1
        C = [ca.DM(row) for row in self.fit.coef]
        # theta'' = a0(theta) + a1(theta) theta' + a2(theta) theta'^2; the series of a0 and a1
        # are combined from the design once per interval, not at every evaluation
        x0, q, h = ca.SX.sym("x0", 2), ca.SX.sym("q", 4), ca.SX.sym("h")
        k, l0, c, crot = q[0], q[1], q[2], q[3]
        cq = ca.vertcat(C[0] + k * C[1] + k * l0 * C[2], c * C[3] + crot * C[5])
        xs, cs = ca.SX.sym("x", 2), ca.SX.sym("cq", 2 * nb)
        B = self.fit.basis(xs[0])
        acc = (ca.dot(cs[:nb], B) + ca.dot(cs[nb:], B) * xs[1]
               + ca.dot(C[4], B) * xs[1] ** 2)
        f_c = ca.Function("f_c", [xs, cs], [ca.vertcat(xs[1], acc)])
        self.f = ca.Function("f", [xs, q], [f_c(xs, cq)])     # the ODE, for reporting
        th = ca.SX.sym("th")
        Bt = self.fit.basis(th)
        tau = ca.Function("tau", [th], [ca.dot(C[6], Bt), ca.dot(C[7], Bt)])

        def speed(x, xdot):  # |v_T| = -tau theta' (theta' <= 0), and h d|v_T|/dt
            t, dt = tau(x[0])
            return -t * x[1], -h * (dt * x[1] * x[1] + t * xdot[1])

        def rk4(x, fx, cq_):  # one RK4 sub-step of length h; fx = f(x) (first stage reused)
            k2 = f_c(x + 0.5 * h * fx, cq_)
            k3 = f_c(x + 0.5 * h * k2, cq_)
            k4 = f_c(x + h * k3, cq_)
            return x + h / 6 * (fx + 2 * k2 + 2 * k3 + k4)

        if M <= UNROLL_MAX:  # unrolled in SX (cheapest to evaluate)
            x = x0
            fx = f_c(x, cq)
            va, ma = speed(x, fx)
            ths, thds, spd, peak = [], [], [], []
            for j in range(M):
                x = rk4(x, fx, cq)
                fx = f_c(x, cq)
                vb, mb = speed(x, fx)
                if j < M - 1:
                    ths.append(x[0])
                    thds.append(x[1])
                spd.append(vb)
                peak.append(_hermite_max(va, ma, vb, mb))
                va, ma = vb, mb
            empty = ca.SX(0, 1)
            outs = [x, ca.vertcat(*ths) if ths else empty,
                    ca.vertcat(*thds) if thds else empty, ca.vertcat(*spd, *peak)]
            self.interval = ca.Function("interval", [x0, q, h], ca.cse(outs),
                                        ["x0", "q", "h"], ["x1", "theta", "theta_dot", "speed"])
        else:  # one SX sub-step, accumulated M times (build time independent of M)
            a, cqs = ca.SX.sym("a", 6), ca.SX.sym("cq", 2 * nb)   # a = (x, x', v, h v')
            x, fx, va, ma = a[0:2], a[2:4], a[4], a[5]
            x1 = rk4(x, fx, cqs)
            fx1 = f_c(x1, cqs)
            vb, mb = speed(x1, fx1)
            step = ca.Function("substep", [a, cqs, h],
                               ca.cse([ca.vertcat(x1, fx1, vb, mb),
                                       ca.vertcat(x1, vb, _hermite_max(va, ma, vb, mb))]))
            fx0 = f_c(x0, cq)
            start = ca.Function("start", [x0, q, h], [ca.vertcat(x0, fx0, *speed(x0, fx0)), cq])
            acc = step.mapaccum("substeps", M)
            x0m, qm, hm = ca.MX.sym("x0", 2), ca.MX.sym("q", 4), ca.MX.sym("h")
            a0, cqm = start(x0m, qm, hm)
            _, Y = acc(a0, ca.repmat(cqm, 1, M), ca.repmat(hm, 1, M))
            outs = [Y[0:2, M - 1], Y[0, :M - 1].T, Y[1, :M - 1].T,
                    ca.vertcat(Y[2, :].T, Y[3, :].T)]
            self.interval = ca.Function("interval", [x0m, qm, hm], outs,
                                        ["x0", "q", "h"], ["x1", "theta", "theta_dot", "speed"])
        # the NLP: MX graph over the SX interval, mapped over the N intervals
        d, T, X, s = ca.MX.sym("d", 3), ca.MX.sym("T"), ca.MX.sym("X", 2, N), ca.MX.sym("s")
        npar = len(NLP_PARAMS)
        P = ca.MX.sym("P", npar + N)          # + the time grid: fractions of T per interval
        theta0, thc, wi, wp, wt, crot_p, Jref = (P[i] for i in range(npar))
        grid = P[npar:]
        design = ca.vertcat(d * ca.DM(SCALES), crot_p)
        Xs = ca.horzcat(ca.vertcat(theta0, 0), X[:, :N - 1])
        xe, a, b, sp = self.interval.map(N)(Xs, ca.repmat(design, 1, N), T * grid.T / M)
        g_all = {"continuity": ca.vec(xe - X),                  # = 0
                 "theta_above_closed": ca.vec(a) - thc,          # >= 0
                 "theta_dot_nonpositive": ca.vec(b),             # <= 0
                 "peak_tip_speed": s - ca.vec(sp),               # >= 0
                 "holding_moment": model.dV(thc, design),        # >= holding_moment_min
                 "release_downwards": self.f(ca.vertcat(theta0, 0), design)[1]}  # <= 0
        self.g_names = list(g_all)
        self.g_sizes = [int(v.numel()) for v in g_all.values()]
        J = wi * X[1, N - 1] ** 2 + wp * s ** 2 + wt * T
        w = ca.vertcat(d, T, ca.vec(X), s)
        self.nw = int(w.numel())
        nlp = {"x": w, "f": J / Jref, "g": ca.vertcat(*g_all.values()), "p": P}
        self.ipopt_options = {"print_time": False, "show_eval_warnings": False,
                              "ipopt.print_level": 0, "ipopt.sb": "yes",
                              "ipopt.tol": tol, "ipopt.max_iter": max_iter,
                              "ipopt.hessian_approximation": hessian,
                              "ipopt.linear_solver": linear_solver,
                              # constraints hold exactly at the answer, not to 1e-8
                              "ipopt.bound_relax_factor": 0.0}
        self.solver = ca.nlpsol("softclose_ms", "ipopt", nlp,
                                {**self.ipopt_options, **COLD_OPTIONS})
        # the warm solver shares the oracle (and its cached derivatives): ~0.05 s more
        oracle = self.solver.oracle()
        wx, wpar = ca.MX.sym("x", self.nw), ca.MX.sym("p", npar + N)
        fo, go = oracle(wx, wpar)
        self.warm_solver = ca.nlpsol("softclose_ms_warm", "ipopt",
                                     {"x": wx, "p": wpar, "f": fo, "g": go},
                                     {**self.ipopt_options, **WARM_OPTIONS})
        self.key = None
        self.build_time = time.perf_counter() - t0

    # -- packing -------------------------------------------------------------------------
    def pack(self, design, T, X, s) -> np.ndarray:
        return np.r_[np.asarray(design[:3], float) / SCALES, T, np.asarray(X, float).T.ravel(), s]

    def unpack(self, w):
        w = np.asarray(w, float).ravel()
        N = self.N
        X = w[4:4 + 2 * N].reshape(N, 2).T
        return w[:3] * SCALES, float(w[3]), X, float(w[-1])

    def bounds(self, cfg: Config, t_max: float | None = None, t_min: float | None = None):
        """(lbx, ubx, lbg, ubg) of ``cfg``'s problem (closing-time bounds overridable)."""
        o, st = cfg.optimise, cfg.stroke
        N = self.N
        lbx, ubx = np.full(self.nw, -np.inf), np.full(self.nw, np.inf)
        for i, key in enumerate(DESIGN_KEYS):
            lo, hi = getattr(o, key)
            lbx[i], ubx[i] = lo / SCALES[i], hi / SCALES[i]
        lbx[3] = max(o.closing_time_min if t_min is None else t_min, T_FLOOR)
        ubx[3] = o.closing_time_max if t_max is None else t_max
        lbx[4:4 + 2 * N:2], ubx[4:4 + 2 * N:2] = st.theta_closed, st.theta0
        ubx[5:5 + 2 * N:2] = 0.0
        lbx[4 + 2 * (N - 1)] = ubx[4 + 2 * (N - 1)] = st.theta_closed
        lbx[-1] = 0.0
        lo = {"continuity": 0.0, "theta_above_closed": 0.0, "theta_dot_nonpositive": -np.inf,
              "peak_tip_speed": 0.0, "holding_moment": o.holding_moment_min,
              "release_downwards": -np.inf}
        hi = {"continuity": 0.0, "theta_above_closed": np.inf, "theta_dot_nonpositive": 0.0,
              "peak_tip_speed": np.inf, "holding_moment": np.inf, "release_downwards": 0.0}
        lbg = np.concatenate([np.full(n, lo[k]) for k, n in zip(self.g_names, self.g_sizes)])
        ubg = np.concatenate([np.full(n, hi[k]) for k, n in zip(self.g_names, self.g_sizes)])
        return lbx, ubx, lbg, ubg

    def params(self, cfg: Config, J_ref: float = 1.0, weight_time: float = 0.0,
               weights: tuple | None = None, t_hint: float | None = None) -> np.ndarray:
        """NLP parameters; the time grid is graded for strokes of about ``t_hint`` seconds
        (default closing_time_max)."""
        o, st = cfg.optimise, cfg.stroke
        wi, wp = (o.weight_impact, o.weight_peak_tip) if weights is None else weights
        grid = self.time_grid(o.closing_time_max if t_hint is None else t_hint)
        return np.r_[st.theta0, st.theta_closed, wi, wp, weight_time,
                     cfg.design.rotary_damper_c, J_ref, grid]

    def time_grid(self, T: float) -> np.ndarray:
        """Fractions of T of the N intervals: uniform.

        The grid is an NLP parameter, so graded grids need no rebuild; but a graded grid
        does not pay here: the tip speed peaks early (~0.1 s) while the creep to the rim is
        limited by RK4's stability on the damper (h |lambda| < 2.79, lambda = c dd / M up
        to ~70 1/s), so long strokes need more steps anyway (see ``discretisation``).
        """
        return np.full(self.N, 1.0 / self.N)

    @staticmethod
    def grid_of(p) -> np.ndarray:
        return np.asarray(p, float)[len(NLP_PARAMS):]

    def violations(self, g, lbg, ubg) -> dict:
        """The largest violation of each constraint group at a point (0 if satisfied)."""
        out, i = {}, 0
        for name, n in zip(self.g_names, self.g_sizes):
            gi, lo, hi = g[i:i + n], lbg[i:i + n], ubg[i:i + n]
            v = np.maximum(np.maximum(lo - gi, gi - hi), 0.0)
            out[name] = float(v.max()) if n else 0.0
            i += n
        return out

    def solve(self, x0, p, lbx, ubx, lbg, ubg, lam_x0=None, lam_g0=None, warm=False) -> dict:
        """One Ipopt run; never raises (a failed evaluation is a failed status)."""
        solver = self.warm_solver if warm else self.solver
        x0 = np.clip(np.asarray(x0, float), lbx, ubx)
        args = dict(x0=x0, p=p, lbx=lbx, ubx=ubx, lbg=lbg, ubg=ubg)
        if lam_x0 is not None:
            args.update(lam_x0=lam_x0, lam_g0=lam_g0)
        t0 = time.perf_counter()
        try:
            sol = solver(**args)
            st = solver.stats()
            status, ok, its = st["return_status"], bool(st["success"]), int(st["iter_count"])
        except RuntimeError as exc:  # an evaluation error before Ipopt could report
            return {"x": x0, "f": math.nan, "g": np.full(len(lbg), np.nan), "lam_x": None,
                    "lam_g": None, "status": f"Error: {str(exc).splitlines()[0]}",
                    "success": False, "iterations": 0, "time": time.perf_counter() - t0}
        dt = time.perf_counter() - t0
        return {"x": np.asarray(sol["x"]).ravel(), "f": float(sol["f"]),
                "g": np.asarray(sol["g"]).ravel(),
                "lam_x": np.asarray(sol["lam_x"]).ravel(),
                "lam_g": np.asarray(sol["lam_g"]).ravel(),
                "status": status, "success": ok and status in CONVERGED, "iterations": its,
                "time": dt}


#: smallest closing time the NLP may take (s): T = 0 would make every step vanish
T_FLOOR = 1e-3
J_INDEX = NLP_PARAMS.index("J_ref")
#: up to this many sub-steps an interval is unrolled in SX; beyond, one SX sub-step is
#: accumulated (mapaccum), so that building the NLP does not grow with the sub-steps
UNROLL_MAX = 8
#: largest RK4 step of the NLP (s) when the sub-steps are chosen automatically: the default
#: discretisation's step (1 s / (10 x 4)); it keeps long strokes accurate and RK4 stable
#: on the damper (h |lambda| <= 0.025 * 70 < 2.79 for damper_c up to 5000 N s/m)
H_MAX = 0.025


def discretisation(cfg: Config, nodes: int | None = None,
                   substeps: int | None = None) -> tuple[int, int, str]:
    """(N, M, note): optimise.nodes, and optimise.substeps raised if needed so that the RK4
    step T/(N M) stays <= H_MAX at T = closing_time_max. Explicit arguments are kept."""
    o = cfg.optimise
    N = nodes or o.nodes
    if substeps:
        return N, substeps, ""
    M = o.substeps
    while o.closing_time_max / (N * M) > H_MAX * (1 + 1e-9):
        M *= 2          # doublings: few distinct NLPs to build (and refinement doubles too)
    note = "" if M == o.substeps else (
        f"substeps raised from {o.substeps} to {M} so that the RK4 step stays <= {H_MAX:g} s "
        f"for closing_time_max = {o.closing_time_max:g} s")
    return N, M, note

_MODELS: dict = {}
_NLPS: dict = {}


def get_model(cfg: Config) -> LidModel:
    """The LidModel of cfg's geometry, mass and stroke (cached)."""
    key = (cfg.geometry, cfg.mass, cfg.stroke.theta0_deg, cfg.stroke.theta_closed_deg)
    if key not in _MODELS:
        _MODELS[key] = LidModel(cfg)
    return _MODELS[key]


def _nlp_key(cfg: Config, nodes: int | None, substeps: int | None) -> tuple:
    o = cfg.optimise
    return (cfg.geometry, cfg.mass, cfg.stroke.theta0_deg, cfg.stroke.theta_closed_deg,
            nodes or o.nodes, substeps or o.substeps, o.hessian, o.linear_solver, o.max_iter)


def get_nlp(cfg: Config, nodes: int | None = None, substeps: int | None = None) -> ShootingNLP:
    """The ShootingNLP of cfg's geometry and discretisation (built once, then cached)."""
    o = cfg.optimise
    key = _nlp_key(cfg, nodes, substeps)
    if key not in _NLPS:
        nlp = ShootingNLP(get_model(cfg), key[4], key[5], o.hessian, o.linear_solver, o.max_iter)
        nlp.key = key
        _NLPS[key] = nlp
    return _NLPS[key]


# -- objective, starts, guesses ------------------------------------------------------------
def objective_of(cfg: Config, impact_theta_dot, peak_tip_speed) -> float | None:
    o = cfg.optimise
    if impact_theta_dot is None or peak_tip_speed is None:
        return None
    return o.weight_impact * impact_theta_dot ** 2 + o.weight_peak_tip * peak_tip_speed ** 2


def _stroke_simulator(cfg: Config, t_end: float | None = None) -> Simulator:
    """An RK4 simulator of cfg's model (strokes cut at t_end: the sweep needs no more)."""
    c = cfg
    if t_end is not None and t_end < cfg.stroke.t_max:
        c = cfg.replace(stroke={"t_max": float(t_end)})
    step = min(cfg.simulate.step, 1e-3)
    return Simulator(c, model=get_model(cfg), integrator="rk4", step=step)


def sweep_starts(cfg: Config, count: int, sim: Simulator | None = None,
                 shape=(8, 6, 8)) -> tuple[np.ndarray, dict]:
    """Start designs from a coarse sweep of the design box (C kernel, ~0.05 s).

    The feasible points (closed within the closing-time bounds, holding moment, moving down
    at release) are ranked by objective and picked greedily so that each start lies at least
    0.2 (in box-normalised units) from the ones before; with too few feasible points the
    least infeasible ones fill up. Returns (designs (count, 3), info).
    """
    o = cfg.optimise
    sim = sim or _stroke_simulator(cfg, 1.05 * o.closing_time_max + 0.05)
    axes = [np.linspace(*getattr(o, k), n) for k, n in zip(DESIGN_KEYS, shape)]
    G = np.array(np.meshgrid(*axes, indexing="ij")).reshape(3, -1).T
    P = np.column_stack([G, np.full(len(G), cfg.design.rotary_damper_c)])
    r = sim.run_batch(P)
    st = cfg.stroke
    c0 = sim.table.evaluate([st.theta0])[0]
    release = -(c0[3] + G[:, 0] * (c0[4] - G[:, 1]) * c0[5])   # M theta'' at release
    T = np.where(r["closed"], r["closing_time"], np.inf)
    J = o.weight_impact * r["impact_theta_dot"] ** 2 + o.weight_peak_tip * r["peak_tip_speed"] ** 2
    # violation measure (relative), 0 when feasible
    viol = (np.maximum(T - o.closing_time_max, 0) / o.closing_time_max
            + np.maximum(o.closing_time_min - T, 0) / max(o.closing_time_max, 1e-9)
            + np.maximum(o.holding_moment_min - r["holding_moment"], 0)
            / max(abs(o.holding_moment_min), 1e-3)
            + np.maximum(release, 0) / max(abs(c0[3]), 1e-6)
            + (np.maximum(r["theta_dot_max"], 0) if "theta_dot_max" in r else 0.0))
    viol = np.where(np.isfinite(viol), viol, 1e3)
    feasible = viol == 0
    order = np.lexsort((np.where(np.isfinite(J), J, np.inf), viol))
    lo = np.array([getattr(o, k)[0] for k in DESIGN_KEYS])
    span = np.maximum(np.array([getattr(o, k)[1] for k in DESIGN_KEYS]) - lo, 1e-12)
    picked: list[int] = []
    for min_dist in (0.2, 0.1, 0.0):
        for i in order:
            if len(picked) >= count:
                break
            if i in picked:
                continue
            z = (G[i] - lo) / span
            if all(np.linalg.norm(z - (G[j] - lo) / span) >= min_dist for j in picked):
                picked.append(int(i))
    info = {"grid": [int(n) for n in shape], "evaluated": int(len(G)),
            "feasible": int(feasible.sum()),
            "best_feasible_objective": float(J[feasible].min()) if feasible.any() else None,
            "fastest_closing_time": float(T.min()) if np.isfinite(T).any() else None}
    return G[picked], info


def initial_guess(nlp: ShootingNLP, cfg: Config, design, sim: Simulator, p: np.ndarray,
                  t_max: float | None = None) -> tuple[np.ndarray, float]:
    """Primal start from the simulated stroke of ``design`` on the time grid of ``p``:
    (w0, the stroke's objective)."""
    o, st = cfg.optimise, cfg.stroke
    t_max = o.closing_time_max if t_max is None else t_max
    frac = np.minimum(np.cumsum(nlp.grid_of(p)), 1.0)   # node times / T
    q = np.r_[np.asarray(design, float)[:3], cfg.design.rotary_damper_c]
    r = sim.run(q, trajectory=True, estimate_error=False)
    N = nlp.N
    if r.ok and r.trajectory is not None:
        tr = r.trajectory
        T = r.closing_time if r.closed else tr["t"][-1]
        T = float(np.clip(T, max(o.closing_time_min, T_FLOOR), t_max))
        tn = T * frac
        X = np.vstack([np.interp(tn, tr["t"], tr["theta"]),
                       np.minimum(np.interp(tn, tr["t"], tr["theta_dot"]), 0.0)])
        peak = float(np.max(tr["tip_speed"][tr["t"] <= T + 1e-12]))
        J0 = objective_of(cfg, float(X[1, -1]), peak)
    else:  # not integrable at this step: a straight line in theta
        T = t_max
        X = np.vstack([st.theta0 + frac * (st.theta_closed - st.theta0),
                       np.full(N, (st.theta_closed - st.theta0) / T)])
        peak, J0 = 1.0, None
    X[0, -1] = st.theta_closed
    J0 = J0 if J0 is not None and np.isfinite(J0) else 1.0
    return nlp.pack(q, T, X, peak), float(J0)


# -- verification by the adaptive reference ------------------------------------------------
class _Checker:
    """Independent checks of one model: CVODES reference metrics and theta' on a fine grid."""

    def __init__(self, model: LidModel):
        from .reference import Reference
        self.model = model
        # output grid of 10 ms (events and peaks are located by Newton inside it, to the
        # tolerance; a 2 ms grid changes the metrics by < 1e-9 and takes 3x longer)
        self.reference = Reference(model, grid_step=VERIFY_GRID)
        x, p, tau = ca.SX.sym("x", 2), ca.SX.sym("p", 4), ca.SX.sym("tau")
        tol = min(1e-10, model.cfg.simulate.reference_tol * 100)
        grid = list(np.linspace(0.0, 1.0, 801)[1:])
        self.grid = np.array(grid)
        dae = {"x": x, "p": ca.vertcat(p, tau), "ode": tau * model.ode(x, p)}
        self._grid_flow = ca.integrator("check_grid", "cvodes", dae, 0.0, grid,
                                        {"abstol": tol, "reltol": tol, "max_num_steps": 200000})
        th = ca.SX.sym("theta")
        cf = coefficients(th, model.geo, model.mass, model.sigma)
        self._l = ca.Function("l", [th], [cf["l"]])

    def theta_dot_max(self, p, T) -> float:
        """max theta' over (0, T] of the exact equation (CVODES on an 800-point grid)."""
        st = self.model.cfg.stroke
        out = self._grid_flow(x0=[st.theta0, 0.0], p=np.r_[p, T])["xf"]
        return float(np.max(np.asarray(out)[1]))

    def spring_extremes(self, a: float, b: float) -> tuple[float, float]:
        """min and max of the spring length over theta in [a, b] (grid + parabola)."""
        g = np.linspace(a, b, 2001)
        lv = np.asarray(self._l.map(len(g))(g)).ravel()
        out = []
        for sgn in (1, -1):
            i = int(np.argmin(sgn * lv))
            v = lv[i]
            if 0 < i < len(g) - 1:
                y0, y1, y2 = lv[i - 1], lv[i], lv[i + 1]
                den = y0 - 2 * y1 + y2
                if den != 0:
                    v = y1 - (y2 - y0) ** 2 / (8 * den)
            out.append(float(v))
        return out[0], out[1]


_CHECKERS: dict = {}


def _checker(cfg: Config) -> _Checker:
    model = get_model(cfg)
    key = id(model)
    if key not in _CHECKERS:
        _CHECKERS[key] = _Checker(model)
    return _CHECKERS[key]


def verify_design(cfg: Config, design: dict, metrics: dict | None = None,
                  objective: float | None = None) -> dict:
    """Re-simulate ``design`` with the adaptive reference; metrics, objective, differences
    from ``metrics``/``objective`` (the optimiser's claims) and every constraint of SPEC §5."""
    o, st = cfg.optimise, cfg.stroke
    chk = _checker(cfg)
    model = chk.model
    p = np.array([design[k] for k in DESIGN_KEYS] + [cfg.design.rotary_damper_c])
    t0 = time.perf_counter()
    try:
        ref = chk.reference.simulate(p)
    except NumericalError as exc:
        return {"ok": False, "error": str(exc), "method": "CVODES"}
    ver = {k: _py(getattr(ref, k)) for k in METRIC_KEYS}
    J = objective_of(cfg, ver["impact_theta_dot"], ver["peak_tip_speed"])
    ver["objective"] = J
    if metrics is not None:
        ver["differences"] = {k: (metrics[k] - ver[k]) for k in METRIC_KEYS
                              if k != "closed" and metrics.get(k) is not None
                              and ver.get(k) is not None}
    if objective is not None and J is not None:
        ver["objective_difference"] = objective - J
        ver["objective_relative_difference"] = (objective - J) / abs(J) if J else math.inf
    T = ver["closing_time"]
    release = float(model.ode(ca.vertcat(st.theta0, 0.0), p)[1])
    cons = {"closed": {"value": bool(ver["closed"]), "ok": bool(ver["closed"])}}
    if T is not None:
        cons["closing_time_max"] = {"value": T, "bound": o.closing_time_max,
                                    "ok": T <= o.closing_time_max * (1 + CLOSING_RTOL)}
        cons["closing_time_min"] = {"value": T, "bound": o.closing_time_min,
                                    "ok": T >= o.closing_time_min * (1 - CLOSING_RTOL)}
        thd_max = chk.theta_dot_max(p, T)
        cons["theta_dot_nonpositive"] = {"value": max(thd_max, min(release, 0.0)), "bound": 0.0,
                                         "ok": thd_max <= CONSTRAINT_TOL and release <= 0.0}
    hm = ver["holding_moment"]
    cons["holding_moment_min"] = {"value": hm, "bound": o.holding_moment_min,
                                  "ok": hm >= o.holding_moment_min - CONSTRAINT_TOL}
    th_min = float(ref.theta_min)
    cons["theta_above_closed"] = {"value": th_min, "bound": st.theta_closed,
                                  "ok": th_min >= st.theta_closed - 1e-12}
    ver["constraints"] = cons
    ver["constraints_ok"] = all(c["ok"] for c in cons.values())
    rel = ver.get("objective_relative_difference")
    ver["objective_ok"] = rel is not None and abs(rel) <= VERIFY_RTOL
    ver["ok"] = ver["constraints_ok"] and ver["objective_ok"]
    ver["method"] = f"CVODES (adaptive BDF) on the exact equation, tolerance {chk.reference.tol:g}"
    ver["time"] = time.perf_counter() - t0
    return ver


#: output grid of the verifying reference simulation (s)
VERIFY_GRID = 0.01
#: relative slack of the closing-time bounds in verification (the NLP's bound is corrected
#: for its own discretisation error, so the verified closing time meets it to ~1e-10)
CLOSING_RTOL = 1e-6


def _py(v):
    if isinstance(v, (np.floating, np.integer)):
        return v.item()
    if isinstance(v, np.bool_):
        return bool(v)
    return v


# -- results -------------------------------------------------------------------------------
@dataclass
class OptimiseResult:
    """The optimiser's answer; a failure is reported in it (``success`` False), never raised."""

    success: bool
    status: str
    message: str
    design: dict | None
    objective: float | None
    metrics: dict | None
    verification: dict | None = None
    starts: list = field(default_factory=list)
    iterations: int = 0
    solve_time: float = 0.0
    build_time: float = 0.0
    total_time: float = 0.0
    nodes: int = 0
    substeps: int = 0
    hessian: str = ""
    problem: dict = field(default_factory=dict)
    sweep: dict | None = None
    infeasibility: dict | None = None
    notes: list = field(default_factory=list)
    raw: dict | None = field(default=None, repr=False)

    def to_json(self) -> dict:
        """The SPEC §7 payload (plain JSON types, NaN as null)."""
        out = {"success": self.success, "status": self.status, "message": self.message,
               "design": self.design, "objective": self.objective}
        for k in METRIC_KEYS:
            out[k] = None if self.metrics is None else self.metrics.get(k)
        out["verification"] = self.verification
        out["problem"] = self.problem
        out["starts"] = self.starts
        out["sweep"] = self.sweep
        out["solver"] = {"method": "direct multiple shooting, RK4, Ipopt",
                         "nodes": self.nodes, "substeps": self.substeps,
                         "hessian": self.hessian, "iterations": self.iterations,
                         "solve_time": self.solve_time, "build_time": self.build_time,
                         "total_time": self.total_time}
        if self.infeasibility is not None:
            out["infeasibility"] = self.infeasibility
        if self.notes:
            out["notes"] = self.notes
        return _jsonable(out)


def _jsonable(x):
    if isinstance(x, dict):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    x = _py(x)
    if isinstance(x, float) and not math.isfinite(x):
        return None
    return x


def _problem(cfg: Config) -> dict:
    o = cfg.optimise
    return {"closing_time_min": o.closing_time_min, "closing_time_max": o.closing_time_max,
            "holding_moment_min": o.holding_moment_min, "weight_impact": o.weight_impact,
            "weight_peak_tip": o.weight_peak_tip,
            "bounds": {k: list(getattr(o, k)) for k in DESIGN_KEYS}}


def nlp_metrics(nlp: ShootingNLP, cfg: Config, run: dict) -> tuple[dict, dict, float]:
    """Design dict, SPEC §4 metrics as the NLP has them, and the objective of one run."""
    d, T, X, s = nlp.unpack(run["x"])
    st = cfg.stroke
    model = nlp.model
    design = {k: float(v) for k, v in zip(DESIGN_KEYS, d)}
    p = np.r_[d, cfg.design.rotary_damper_c]
    thd = float(X[1, -1])
    vT = np.asarray(model.kin(ca.vertcat(st.theta_closed, thd))[4]).ravel()
    lmin, lmax = _checker(cfg).spring_extremes(st.theta_closed, st.theta0)
    m = {"closed": True, "closing_time": T, "impact_theta_dot": thd,
         "impact_tip_speed": float(np.hypot(*vT)), "peak_tip_speed": s,
         "min_spring_length": lmin, "max_spring_length": lmax,
         "holding_moment": model.holding_moment(p)}
    J = objective_of(cfg, thd, s)
    return design, m, J


def _parts(nlp, run) -> tuple[float, float]:
    """(impact theta', peak tip speed) of a run."""
    _, _, X, s = nlp.unpack(run["x"])
    return float(X[1, -1]), s


def _start_row(nlp, cfg, start, run, J0) -> dict:
    d, T, X, s = nlp.unpack(run["x"])
    row = {"start": {k: float(v) for k, v in zip(DESIGN_KEYS, start)},
           "start_objective": J0,
           "design": {k: float(v) for k, v in zip(DESIGN_KEYS, d)},
           "objective": objective_of(cfg, float(X[1, -1]), s) if run["success"] else None,
           "closing_time": T, "status": run["status"], "success": run["success"],
           "iterations": run["iterations"], "solve_time": run["time"]}
    return row


# -- refinement and the closing-time correction -------------------------------------------
#: the NLP's objective must agree with an accurate simulation of its design to this
#: (relative) before the answer goes to verification; else the sub-steps are doubled
REFINE_RTOL = 1e-4
#: at most this many doublings of the sub-steps
MAX_REFINE = 4


def _refine(cfg: Config, nlp: ShootingNLP, run: dict, sim: Simulator,
            notes: list) -> tuple[ShootingNLP, dict]:
    """Double the RK4 sub-steps (same nodes, so the solution carries over) until the NLP's
    objective agrees with the C-kernel simulation of its design to REFINE_RTOL."""
    for _ in range(MAX_REFINE):
        d, T, X, s = nlp.unpack(run["x"])
        J = objective_of(cfg, float(X[1, -1]), s)
        rs = sim.run(np.r_[d, cfg.design.rotary_damper_c], estimate_error=False)
        if not rs.closed:
            return nlp, run
        Js = objective_of(cfg, rs.impact_theta_dot, rs.peak_tip_speed)
        if abs(J - Js) <= REFINE_RTOL * abs(Js):
            return nlp, run
        fine = get_nlp(cfg, nlp.N, 2 * nlp.M)
        lbx, ubx, lbg, ubg = fine.bounds(cfg)
        r = fine.solve(run["x"], run["p"], lbx, ubx, lbg, ubg)
        if not r["success"]:
            return nlp, run
        notes.append(f"objective {J:.6g} differed from the simulated {Js:.6g} by "
                     f"{abs(J - Js) / abs(Js):.1e}: sub-steps doubled to {fine.M} "
                     f"({r['iterations']} iterations)")
        r["p"], r["time"] = run["p"], r["time"] + run["time"]
        r["iterations"] += run["iterations"]
        nlp, run = fine, r
    return nlp, run


# -- the closing-time correction -------------------------------------------------------------
def _tighten(nlp: ShootingNLP, cfg: Config, run: dict, p: np.ndarray, sim: Simulator,
             notes: list) -> dict:
    """Correct the closing-time bounds for the NLP's own discretisation error.

    The NLP's closing time T differs from the exact one by the RK4 error (a few µs at the
    defaults). When the accurately simulated stroke of the answer lies outside
    [closing_time_min, closing_time_max], the bound is shifted by that difference and the
    problem re-solved warm (2-5 iterations), so the verified design meets the bound.
    """
    o = cfg.optimise
    t_lo, t_hi = max(o.closing_time_min, T_FLOOR), o.closing_time_max
    lo, hi = t_lo, t_hi
    for _ in range(3):
        d, T, _, _ = nlp.unpack(run["x"])
        rs = sim.run(np.r_[d, cfg.design.rotary_damper_c], estimate_error=False)
        if not rs.closed:
            return run
        Ts = rs.closing_time
        shift = Ts - T
        if Ts > t_hi * (1 + 1e-9):
            hi -= Ts - t_hi + 1e-9 * t_hi
        elif o.closing_time_min > 0 and Ts < t_lo * (1 - 1e-9):
            lo += t_lo - Ts + 1e-9 * t_lo
        else:
            return run
        lbx, ubx, lbg, ubg = nlp.bounds(cfg, t_max=hi, t_min=lo)
        r = nlp.solve(run["x"], p, lbx, ubx, lbg, ubg, run["lam_x"], run["lam_g"], warm=True)
        if not r["success"]:
            return run
        notes.append(f"closing-time bounds corrected for the NLP's discretisation error "
                     f"({shift:+.2e} s): solved with [{lo:.9g}, {hi:.9g}] s, "
                     f"{r['iterations']} warm iterations")
        r["time"] += run["time"]
        r["iterations"] += run["iterations"]
        r["p"] = p
        run = r
    return run


#: Ipopt statuses that suggest that the constraints cannot be met
INFEASIBLE = ("Infeasible_Problem_Detected", "Restoration_Failed",
              "Search_Direction_Becomes_Too_Small", "Not_Enough_Degrees_Of_Freedom")


# -- why a problem has no solution -------------------------------------------------------------
def diagnose(cfg: Config, nlp: ShootingNLP, runs: list, sim: Simulator) -> tuple[str, dict]:
    """Which constraint cannot be met (a one-line message and the numbers behind it)."""
    o, st = cfg.optimise, cfg.stroke
    info: dict = {"statuses": sorted({r["status"] for r in runs})}
    if not any(r["status"] in INFEASIBLE for r in runs):
        r = runs[0]
        if all(r["status"] == "Maximum_Iterations_Exceeded" for r in runs):
            return (f"Ipopt stopped at optimise.max_iter = {o.max_iter} iterations from every "
                    "start (status Maximum_Iterations_Exceeded); raise optimise.max_iter", info)
        return (f"Ipopt did not converge from any start (statuses: "
                f"{', '.join(info['statuses'])}); try more starts (optimise.starts), more "
                "iterations (optimise.max_iter) or hessian = \"limited-memory\"", info)
    # 1. the holding moment is linear in k for fixed l0: its maximum over the box is at a corner
    model = nlp.model
    corners = [(k, l0) for k in o.spring_k for l0 in o.spring_rest_length]
    hm = [(model.holding_moment(np.array([k, l0, 0.0, 0.0])), k, l0) for k, l0 in corners]
    hmax, kb, lb = max(hm)
    info["largest_holding_moment"] = {"value": hmax, "spring_k": kb, "spring_rest_length": lb}
    if hmax < o.holding_moment_min:
        return (f"holding_moment_min = {o.holding_moment_min:g} N m cannot be met: the largest "
                f"holding moment within the design bounds is {hmax:.4g} N m (spring_k = {kb:g}, "
                f"spring_rest_length = {lb:g}); lower holding_moment_min or widen the spring "
                "bounds", info)
    # 2. the fastest and (with a lower bound) the slowest stroke that meets everything else
    relaxed = cfg.replace(optimise={"closing_time_min": 0.0, "closing_time_max": st.t_max})
    for sense, name in ((1.0, "fastest"), (-1.0, "slowest")):
        if sense < 0 and o.closing_time_min <= 0:
            continue
        starts = _extreme_sweep_designs(relaxed, 2, sense)
        best = None
        for d0 in starts:
            rs0 = sim.run(np.r_[d0, cfg.design.rotary_damper_c], estimate_error=False)
            hint = rs0.closing_time if rs0.closed else st.t_max
            pp = nlp.params(cfg, 1.0, weight_time=sense, weights=(0.0, 0.0), t_hint=hint)
            w0, _ = initial_guess(nlp, relaxed, d0, sim, pp, t_max=st.t_max)
            lbx, ubx, lbg, ubg = nlp.bounds(relaxed, t_max=st.t_max, t_min=T_FLOOR)
            r = nlp.solve(w0, pp, lbx, ubx, lbg, ubg)
            if r["success"] and (best is None or sense * r["x"][3] < sense * best["x"][3]):
                best = r
        if best is None:
            continue
        d, T, _, _ = nlp.unpack(best["x"])
        rs = sim.run(np.r_[d, cfg.design.rotary_damper_c], estimate_error=False) \
            if T <= sim.cfg.stroke.t_max else None
        T_sim = rs.closing_time if rs is not None and rs.closed else T
        dd = {k: float(v) for k, v in zip(DESIGN_KEYS, d)}
        info[f"{name}_stroke"] = {"closing_time": T_sim, "design": dd}
        ds = ", ".join(f"{k} = {v:.4g}" for k, v in dd.items())
        if sense > 0 and T_sim > o.closing_time_max * (1 + 1e-6):
            return (f"closing_time_max = {o.closing_time_max:g} s cannot be met: the fastest "
                    f"stroke that any design within the bounds can make (holding moment >= "
                    f"{o.holding_moment_min:g} N m, no rebound) closes in {T_sim:.4g} s ({ds}); "
                    f"raise closing_time_max to at least {T_sim:.4g} s or widen the spring bounds",
                    info)
        if sense < 0 and T_sim < o.closing_time_min * (1 - 1e-6):
            return (f"closing_time_min = {o.closing_time_min:g} s cannot be met: the slowest "
                    f"stroke within the bounds closes in {T_sim:.4g} s ({ds}); lower "
                    "closing_time_min or widen the damper bounds", info)
    # 3. nothing obvious: Ipopt's verdict and the worst violated constraint group
    r = min(runs, key=lambda r: sum(r.get("violations", {}).values()) or math.inf)
    viol = r.get("violations", {})
    worst = max(viol, key=viol.get) if viol else None
    info["violations"] = viol
    hint = (f"the largest violation is in {worst} ({viol[worst]:.3g})" if worst and viol[worst] > 0
            else "no constraint group is clearly violated")
    return (f"Ipopt did not converge from any start (best status {r['status']}); {hint}; "
            "try more starts (optimise.starts), more iterations (optimise.max_iter) or "
            "hessian = \"limited-memory\"", info)


def _extreme_sweep_designs(cfg: Config, count: int, sense: float) -> np.ndarray:
    """Sweep designs that close (and hold) the fastest (sense 1) or the slowest (sense -1)."""
    o = cfg.optimise
    sim = _stroke_simulator(cfg)
    axes = [np.linspace(*getattr(o, k), n) for k, n in zip(DESIGN_KEYS, (6, 5, 5))]
    G = np.array(np.meshgrid(*axes, indexing="ij")).reshape(3, -1).T
    r = sim.run_batch(np.column_stack([G, np.full(len(G), cfg.design.rotary_damper_c)]))
    T = np.where(r["closed"] & (r["holding_moment"] >= o.holding_moment_min),
                 sense * r["closing_time"], np.inf)
    return G[np.argsort(T)[:count]]


# -- the one-call optimiser --------------------------------------------------------------------
def optimise(cfg: Config, starts: int | None = None, verify: bool = True,
             nodes: int | None = None, substeps: int | None = None,
             log=None) -> OptimiseResult:
    """Solve cfg's soft-close problem from several starts; the best answer, verified.

    Starts come from a coarse sweep of the design box (:func:`sweep_starts`); each is solved
    by Ipopt; the best converged one has its closing-time bounds corrected for the NLP's
    discretisation error and is re-simulated by the adaptive reference. ``success`` means:
    Ipopt converged, the objective agrees with the reference to 1e-3 (relative) and every
    constraint holds in the reference simulation.
    """
    log = log or (lambda *a: None)
    t_start = time.perf_counter()
    o = cfg.optimise
    n_starts = starts or o.starts
    notes: list = []
    nodes, substeps, note = discretisation(cfg, nodes, substeps)
    if note:
        notes.append(note)
    cached = _nlp_key(cfg, nodes, substeps) in _NLPS
    nlp = get_nlp(cfg, nodes, substeps)
    build = 0.0 if cached else nlp.build_time
    sim_sweep = _stroke_simulator(cfg, 1.05 * o.closing_time_max + 0.05)
    designs, info = sweep_starts(cfg, n_starts, sim_sweep)
    log(f"sweep: {info['feasible']} of {info['evaluated']} designs feasible")
    lbx, ubx, lbg, ubg = nlp.bounds(cfg)
    runs, rows = [], []
    for d0 in designs:
        p = nlp.params(cfg)
        w0, J0 = initial_guess(nlp, cfg, d0, sim_sweep, p)
        p[J_INDEX] = max(J0, 1e-8)
        r = nlp.solve(w0, p, lbx, ubx, lbg, ubg)
        r["p"] = p
        r["violations"] = nlp.violations(r["g"], lbg, ubg)
        runs.append(r)
        rows.append(_start_row(nlp, cfg, d0, r, J0))
        log(f"start {len(rows)}: {r['status']} in {r['iterations']} iterations, "
            f"J = {rows[-1]['objective']}")
    base = dict(starts=rows, build_time=build, nodes=nlp.N, substeps=nlp.M,
                hessian=o.hessian, problem=_problem(cfg), sweep=info, notes=notes)
    ok = [i for i, r in enumerate(runs) if r["success"]]
    if not ok:
        msg, inf = diagnose(cfg, nlp, runs, _stroke_simulator(cfg))
        best = min(runs, key=lambda r: sum(r["violations"].values()))
        res = OptimiseResult(False, best["status"], msg, None, None, None,
                             iterations=sum(r["iterations"] for r in runs),
                             solve_time=sum(r["time"] for r in runs), infeasibility=inf, **base)
        res.total_time = time.perf_counter() - t_start
        return res
    i_best = min(ok, key=lambda i: rows[i]["objective"])
    best = runs[i_best]
    distinct = _distinct([rows[i] for i in ok])
    notes.append(f"{len(ok)} of {len(runs)} starts converged, to {distinct} distinct optima")
    sim = _stroke_simulator(cfg)
    nlp, best = _refine(cfg, nlp, best, sim, notes)
    best = _tighten(nlp, cfg, best, best["p"], sim, notes)
    base["substeps"] = nlp.M
    design, metrics, J = nlp_metrics(nlp, cfg, best)
    res = OptimiseResult(True, best["status"], "", design, J, metrics,
                         iterations=best["iterations"], solve_time=best["time"], **base)
    res.raw = {"x": best["x"], "lam_x": best["lam_x"], "lam_g": best["lam_g"], "p": best["p"],
               "key": nlp.key, "bounds": (lbx, ubx, lbg, ubg)}
    if verify:
        ver = verify_design(cfg, design, metrics, J)
        res.verification = ver
        if not ver.get("ok"):
            res.success = False
            res.message = _verification_message(ver)
    res.total_time = time.perf_counter() - t_start
    return res


def _distinct(rows: list, rtol: float = 1e-4) -> int:
    seen: list = []
    for r in rows:
        v = np.array([r["design"][k] for k in DESIGN_KEYS]) / SCALES
        if all(np.linalg.norm(v - s) > rtol * max(1.0, np.linalg.norm(s)) * 10 for s in seen):
            seen.append(v)
    return len(seen)


def _verification_message(ver: dict) -> str:
    if "error" in ver:
        return f"the adaptive reference could not simulate the answer ({ver['error']})"
    bad = [k for k, c in ver.get("constraints", {}).items() if not c["ok"]]
    parts = []
    if bad:
        parts.append("violates " + ", ".join(
            f"{k} ({ver['constraints'][k].get('value')} vs bound "
            f"{ver['constraints'][k].get('bound')})" for k in bad) + " in verification")
    if not ver.get("objective_ok"):
        parts.append(f"its objective differs from the reference by "
                     f"{ver.get('objective_relative_difference', math.nan):.2e} (relative; "
                     f"allowed {VERIFY_RTOL:g}); raise optimise.nodes or optimise.substeps")
    return "the answer is not confirmed by the adaptive reference: " + "; ".join(parts)


def solve(cfg: Config, nodes: int | None = None, substeps: int | None = None,
          warm: OptimiseResult | None = None, verify: bool = False) -> OptimiseResult:
    """One Ipopt solve (for benchmarks and continuation): no multistart, no bound correction.

    Cold: from the best point of the coarse sweep. Warm (``warm`` = an earlier result of the
    same NLP): from its primal-dual point -- with the warm-start solver when the problem is
    unchanged, else with the cold solver from its primal point.
    """
    t_start = time.perf_counter()
    o = cfg.optimise
    cached = _nlp_key(cfg, nodes, substeps) in _NLPS
    nlp = get_nlp(cfg, nodes, substeps)
    build = 0.0 if cached else nlp.build_time
    lbx, ubx, lbg, ubg = nlp.bounds(cfg)
    rows, info = [], None
    if warm is not None and warm.raw is not None and warm.raw.get("key") == nlp.key:
        raw = warm.raw
        p = nlp.params(cfg, J_ref=float(raw["p"][J_INDEX]))
        same = all(np.array_equal(a, b) for a, b in zip(raw["bounds"], (lbx, ubx, lbg, ubg))) \
            and np.array_equal(p, raw["p"])
        x0 = np.clip(raw["x"], lbx, ubx)
        if same:
            r = nlp.solve(x0, p, lbx, ubx, lbg, ubg, raw["lam_x"], raw["lam_g"], warm=True)
        else:
            r = nlp.solve(x0, p, lbx, ubx, lbg, ubg)
    else:
        sim = _stroke_simulator(cfg, 1.05 * o.closing_time_max + 0.05)
        designs, info = sweep_starts(cfg, 1, sim)
        p = nlp.params(cfg)
        w0, J0 = initial_guess(nlp, cfg, designs[0], sim, p)
        p[J_INDEX] = max(J0, 1e-8)
        r = nlp.solve(w0, p, lbx, ubx, lbg, ubg)
        rows.append(_start_row(nlp, cfg, designs[0], r, J0))
    r["p"] = p
    if r["success"]:
        design, metrics, J = nlp_metrics(nlp, cfg, r)
        msg = ""
    else:
        design = metrics = J = None
        msg = (f"Ipopt stopped with status {r['status']} after {r['iterations']} iterations; "
               "use optimise() (several starts) or raise optimise.max_iter")
    res = OptimiseResult(r["success"], r["status"], msg, design, J, metrics, starts=rows,
                         iterations=r["iterations"], solve_time=r["time"], build_time=build,
                         nodes=nlp.N, substeps=nlp.M, hessian=o.hessian, problem=_problem(cfg),
                         sweep=info)
    res.raw = {"x": r["x"], "lam_x": r["lam_x"], "lam_g": r["lam_g"], "p": p, "key": nlp.key,
               "bounds": (lbx, ubx, lbg, ubg)}
    if verify and r["success"]:
        res.verification = verify_design(cfg, design, metrics, J)
        if not res.verification.get("ok"):
            res.success = False
            res.message = _verification_message(res.verification)
    res.total_time = time.perf_counter() - t_start
    return res


# -- continuation in closing_time_max (the Pareto front) ----------------------------------------
def front(cfg: Config, closing_times, starts: int | None = 3, verify: bool = False,
          log=None) -> list[OptimiseResult]:
    """Optima for each closing_time_max in ``closing_times``, warm-started point to point.

    The first point is solved from ``starts`` sweep starts (default 3; None: cfg's); each next one
    starts from the previous optimum (its design, T moved to the new bound, the same
    normalised-time states) and, as a guard against changing basins, also from the best
    sweep start of its own problem; the better converged answer is kept. The closing-time
    bound is corrected for the discretisation error as in :func:`optimise`.
    """
    log = log or (lambda *a: None)
    out: list[OptimiseResult] = []
    prev = None
    for i, tm in enumerate(closing_times):
        c = cfg.replace(optimise={"closing_time_max": float(tm)})
        t0 = time.perf_counter()
        if prev is None or prev.raw is None:
            r = optimise(c, starts=starts, verify=verify)
        else:
            r = _continue(c, prev, verify)
        r.total_time = time.perf_counter() - t0
        log(f"closing_time_max = {tm:g} s: J = {r.objective}, {r.total_time:.2f} s")
        out.append(r)
        if r.raw is not None:
            prev = r
    return out


def _continue(cfg: Config, prev: OptimiseResult, verify: bool) -> OptimiseResult:
    o = cfg.optimise
    N, M, note = discretisation(cfg, prev.nodes)
    nlp = get_nlp(cfg, N, M)
    lbx, ubx, lbg, ubg = nlp.bounds(cfg)
    p = nlp.params(cfg, J_ref=max(prev.objective or 1.0, 1e-8))
    # the previous optimum, its states moved to the new grid (same normalised time)
    x0 = np.array(prev.raw["x"], float)
    x0[3] = float(np.clip(x0[3], lbx[3], ubx[3]))
    N, st = nlp.N, cfg.stroke
    tau_old = np.r_[0.0, np.cumsum(ShootingNLP.grid_of(prev.raw["p"]))]
    tau_new = np.cumsum(nlp.grid_of(p))
    Xold = np.column_stack([[st.theta0, 0.0], x0[4:4 + 2 * N].reshape(N, 2).T])
    Xnew = np.vstack([np.interp(tau_new, tau_old, Xold[0]), np.interp(tau_new, tau_old, Xold[1])])
    Xnew[0, -1] = st.theta_closed
    x0[4:4 + 2 * N] = Xnew.T.ravel()
    runs = []
    r = nlp.solve(x0, p, lbx, ubx, lbg, ubg)
    r["p"], r["from"] = p, "previous optimum"
    runs.append(r)
    starts = [nlp.unpack(x0)[0]]
    # guard against following a local branch: the best point of a coarse sweep of this
    # problem is solved too when the warm answer failed or the sweep already beats it
    sim = _stroke_simulator(cfg, 1.05 * o.closing_time_max + 0.05)
    designs, info = sweep_starts(cfg, 1, sim, shape=(6, 5, 6))
    J_warm = objective_of(cfg, *_parts(nlp, r)) if r["success"] else math.inf
    J_sweep = info["best_feasible_objective"]
    if not r["success"] or (J_sweep is not None and J_sweep < J_warm * (1 - 1e-3)):
        p2 = nlp.params(cfg)
        w0, J0 = initial_guess(nlp, cfg, designs[0], sim, p2)
        p2[J_INDEX] = max(J0, 1e-8)
        r2 = nlp.solve(w0, p2, lbx, ubx, lbg, ubg)
        r2["p"], r2["from"] = p2, "best sweep point"
        runs.append(r2)
        starts.append(designs[0])
    rows = []
    for rr, start in zip(runs, starts):
        row = _start_row(nlp, cfg, start, rr, None)
        row["from"] = rr["from"]
        rows.append(row)
    ok = [i for i, rr in enumerate(runs) if rr["success"]]
    base = dict(starts=rows, nodes=nlp.N, substeps=nlp.M, hessian=o.hessian,
                problem=_problem(cfg), sweep=info, notes=[note] if note else [])
    if not ok:
        return OptimiseResult(False, runs[0]["status"],
                              f"Ipopt did not converge ({runs[0]['status']})", None, None, None,
                              **base)
    best = runs[min(ok, key=lambda i: rows[i]["objective"])]
    sim = _stroke_simulator(cfg)
    nlp, best = _refine(cfg, nlp, best, sim, base["notes"])
    best = _tighten(nlp, cfg, best, best["p"], sim, base["notes"])
    base["substeps"] = nlp.M
    design, metrics, J = nlp_metrics(nlp, cfg, best)
    res = OptimiseResult(True, best["status"], "", design, J, metrics,
                         iterations=sum(rr["iterations"] for rr in runs),
                         solve_time=sum(rr["time"] for rr in runs), **base)
    res.raw = {"x": best["x"], "lam_x": best["lam_x"], "lam_g": best["lam_g"], "p": best["p"],
               "key": nlp.key, "bounds": (lbx, ubx, lbg, ubg)}
    if verify:
        res.verification = verify_design(cfg, design, metrics, J)
        if not res.verification.get("ok"):
            res.success = False
            res.message = _verification_message(res.verification)
    return res


# -- command line ------------------------------------------------------------------------------
def format_result(res: OptimiseResult) -> str:
    """Human-readable report of an optimisation."""
    lines = []
    head = "optimum found and verified" if res.success else "NO verified optimum"
    lines.append(f"softclose optimise: {head} (Ipopt: {res.status})")
    if res.message:
        lines.append(f"  {res.message}")
    pr = res.problem
    if pr:
        lines.append(f"  problem: J = {pr['weight_impact']:g}·impact_theta_dot² + "
                     f"{pr['weight_peak_tip']:g}·peak_tip_speed², "
                     f"{pr['closing_time_min']:g} s <= closing_time <= "
                     f"{pr['closing_time_max']:g} s, holding moment >= "
                     f"{pr['holding_moment_min']:g} N m")
    if res.design:
        d = res.design
        lines.append(f"  design: spring_k = {d['spring_k']:.6g} N/m, spring_rest_length = "
                     f"{d['spring_rest_length']:.6g} m, damper_c = {d['damper_c']:.6g} N s/m")
        lines.append(f"  objective J = {res.objective:.8g}")
    if res.metrics:
        ver = res.verification or {}
        diff = ver.get("differences", {})
        lines.append(f"  {'metric':<19} {'optimiser':>14} {'reference':>14} {'difference':>11}")
        for k in METRIC_KEYS:
            a, b = res.metrics.get(k), ver.get(k)
            if k == "closed":
                lines.append(f"  {k:<19} {str(a):>14} {str(b):>14}")
                continue
            sa = f"{a:.9g}" if a is not None else "—"
            sb = f"{b:.9g}" if b is not None else "—"
            sd = f"{diff[k]:.2e}" if k in diff else ""
            lines.append(f"  {k:<19} {sa:>14} {sb:>14} {sd:>11}")
        if ver.get("objective") is not None:
            lines.append(f"  {'objective':<19} {res.objective:>14.9g} {ver['objective']:>14.9g} "
                         f"{ver['objective_difference']:>11.2e}  (relative "
                         f"{ver['objective_relative_difference']:.1e}, allowed {VERIFY_RTOL:g})")
        if ver.get("constraints"):
            bad = [k for k, c in ver["constraints"].items() if not c["ok"]]
            lines.append("  constraints in verification: " +
                         ("all hold" if not bad else "VIOLATED: " + ", ".join(bad)))
    if res.starts:
        lines.append(f"  starts ({len(res.starts)}, from a coarse sweep of the design box):")
        for i, s in enumerate(res.starts, 1):
            st = s["start"]
            J = f"{s['objective']:.8g}" if s.get("objective") is not None else "—"
            lines.append(f"    {i}. from k={st['spring_k']:.4g}, "
                         f"l0={st['spring_rest_length']:.4g}, c={st['damper_c']:.4g}: "
                         f"{s['status']}, {s['iterations']} it, {s['solve_time']:.3f} s, J = {J}")
    for n in res.notes:
        lines.append(f"  note: {n}")
    lines.append(f"  ({res.nodes} shooting intervals x {res.substeps} RK4 sub-steps, "
                 f"{res.hessian} Hessian; total {res.total_time:.2f} s)")
    return "\n".join(lines)


def command(cfg: Config, args):
    """``softclose optimise [--json] [--out DIR]``: exit code 0 verified optimum, 3 otherwise."""
    from .cli.common import Outcome
    from .errors import SoftcloseError
    try:
        res = optimise(cfg)
    except SoftcloseError:
        raise
    except (RuntimeError, ArithmeticError, ValueError) as exc:  # never a traceback
        msg = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise NumericalError(f"the optimiser failed: {msg}") from None
    payload = res.to_json()
    files: list = []
    if getattr(args, "out", None) and res.design is not None:
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        files = write_outputs(cfg, res, out)
        payload["files"] = [str(f) for f in files]
    text = format_result(res)
    if files:
        text += "\n  wrote " + ", ".join(str(f) for f in files)
    return Outcome(payload, text, 0 if res.success else 3, files)


def write_outputs(cfg: Config, res: OptimiseResult, out: Path) -> list[Path]:
    """The optimum's stroke (trajectory CSV, figures) and ``optimise.json`` in ``out``."""
    from .cli.files import write_stroke_outputs
    d = res.design
    cfg_opt = cfg.with_design(spring_k=d["spring_k"], spring_rest_length=d["spring_rest_length"],
                              damper_c=d["damper_c"])
    sim = Simulator(cfg_opt)          # its own model: carries the optimal design
    stroke = sim.run(trajectory=True)
    files = write_stroke_outputs(sim.model, stroke, out, stem="optimum")
    path = out / "optimise.json"
    path.write_text(json.dumps(res.to_json(), indent=1))
    return [path, *files]
