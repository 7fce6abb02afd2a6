"""The multiple-shooting NLP of the soft-close problem, and its discretisation.

Decision variables (all of order one): the design scaled by :data:`softclose.problem.SCALES`,
the closing time T (s; time is scaled to [0, 1], so each of the N shooting intervals lasts
T/N and holds M RK4 sub-steps of T/(N·M)), the states (theta, theta') at the nodes 1..N
(node 0 is the release from rest), and an epigraph variable s for the peak tip speed.

    minimise   J(theta'(T), s) / J_ref           (J: :func:`softclose.problem.objective`)
    subject to continuity at every node, theta(T) = theta_closed,
               closing_time_min <= T <= closing_time_max,
               theta' <= 0 and theta >= theta_closed at every sub-step, theta''(release) <= 0,
               s >= |v_T| = tau(theta)·|theta'| at every sub-step, and s >= the maximum of
               the cubic Hermite interpolant of |v_T| inside every sub-step (so the peak
               between sub-steps is caught: error O(h^4), not O(h^2)),
               dV/dtheta(theta_closed) >= holding_moment_min.

s is only an epigraph variable: with ``weight_peak_tip = 0`` nothing pins it, so the
optimiser's own peak tip speed is never read from s but from the sub-step speeds and their
Hermite maxima at the solution (:meth:`ShootingNLP.peak`).

The equation of motion is theta'' = a0(theta) + a1(theta) theta' + a2(theta) theta'^2 with
every element's law affine in its parameters (:mod:`softclose.elements.base`):
a0 = sum over the conservative elements of a_e (-q_e'/M) + b_e (-q_e q_e'/M) (T_e = a_e + b_e q),
a1 = sum over the dampers of B_e (-q_e'^2/M), a2 = -M'/(2M). So it depends on theta only
through a few geometric functions (for the seed's elements -dVg/M, -dl/M, -l dl/M, -dd/M,
-1/M, -dM/(2M), and tau = |dT/dtheta|); in the NLP they are Chebyshev series fitted on the
stroke's angles ±3° to machine precision (:class:`ChebyshevFit`). One RK4 sub-step is then ~730 operations instead of ~4200, and the
exact Hessian is cheap. Everything reported is re-checked on the exact equations by the
adaptive reference (:mod:`softclose.optimiser.verify`).

Every number that can change between solves (theta0, theta_closed, weights, the parameters
that are not design variables -- the rotary damper, those of the elements added since --, the
time grid) is an NLP parameter, and closing-time bounds, design bounds and
holding_moment_min are bounds: one NLP per geometry and (N, M) serves multistart, warm
re-solves and Pareto fronts (:func:`softclose.optimiser.cache.get_nlp`).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from .. import elements
from ..config import NLP_BUDGET
from ..dynamics import coefficients
from ..errors import ConfigError
from ..problem import DESIGN_KEYS, PARAM_KEYS, SCALES

#: margin (deg) beyond the stroke over which the Chebyshev series are fitted
FIT_MARGIN_DEG = 3.0
#: Ipopt return statuses that count as converged
CONVERGED = ("Solve_Succeeded", "Solved_To_Acceptable_Level")
#: the parameters of p that are not design variables: NLP parameters
FIXED_PARAMS = PARAM_KEYS[len(DESIGN_KEYS):]
#: NLP parameters, in order (then the time grid: the fractions of T of the N intervals)
NLP_PARAMS = ("theta0", "theta_closed", "weight_impact", "weight_peak_tip", "weight_time",
              *FIXED_PARAMS, "J_ref")
J_INDEX = NLP_PARAMS.index("J_ref")
#: Ipopt options of the cold solver and of the warm re-solve (same NLP functions)
COLD_OPTIONS = {"ipopt.mu_strategy": "adaptive"}
WARM_OPTIONS = {"ipopt.warm_start_init_point": "yes", "ipopt.mu_init": 1e-8,
                "ipopt.warm_start_bound_push": 1e-9, "ipopt.warm_start_mult_bound_push": 1e-9,
                "ipopt.warm_start_slack_bound_push": 1e-9}
#: smallest closing time the NLP may take (s): T = 0 would make every step vanish
T_FLOOR = 1e-3
#: up to this many sub-steps an interval is unrolled in SX; beyond, one SX sub-step is
#: accumulated (mapaccum), so that building the NLP does not grow with the sub-steps
UNROLL_MAX = 8
#: largest RK4 step of the NLP (s) when the sub-steps are chosen automatically: the default
#: discretisation's step (1 s / (10 x 4)); it keeps long strokes accurate and RK4 stable
#: on the damper (h |lambda| <= 0.025 * 70 < 2.79 for damper_c up to 5000 N s/m)
H_MAX = 0.025
#: most RK4 steps (nodes x substeps) of one NLP, the config's budget: ~0.2 ms per step and
#: Ipopt iteration, so one solve at the limit takes ~10 s; larger grids are refused
MAX_STEPS = NLP_BUDGET


# -- the geometric functions as Chebyshev series -----------------------------------------
def nlp_elements(cfg) -> tuple:
    """The elements the NLP carries: the seed's always, the others when they act in ``cfg``
    (an element that exerts no force adds nothing but series to fit)."""
    acting = elements.acting(cfg)
    return tuple(e for e in elements.ELEMENTS if e.table == "base" or e in acting)


def series_terms(els) -> list[tuple[str, str, str]]:
    """(name, element, what) of the geometric functions of the equation of motion carried by
    the elements ``els``: per conservative element "b" (-q q'/M; not for gravity, whose T
    is constant) and "a" (-q'/M), per damper "B" (-q'^2/M); summed in this order."""
    out = []
    for e in els:
        if e in elements.SPRINGS:
            if e.name != "gravity":
                out.append((f"{e.name}:b", e.name, "b"))
            out.append((f"{e.name}:a", e.name, "a"))
        if e in elements.DAMPERS:
            out.append((f"{e.name}:B", e.name, "B"))
    return out


class ChebyshevFit:
    """The geometric functions of theta (and tau') as Chebyshev series on [lo, hi].

    :attr:`names` lists them: the elements' series (:func:`series_terms`), then "inertia"
    (-M'/(2M)), "tau" and "dtau". The degree is raised until the series match the exact
    CasADi expressions to ``tol`` (relative to each function's largest value) on a 2001-point
    grid: degree 14 and a maximal relative error ~4e-15 for the default geometry
    (``max_rel_error``).
    """

    def __init__(self, model, tol: float = 1e-13, max_degree: int = 64, els=None):
        th = ca.SX.sym("theta")
        cf = coefficients(th, model.cfg, model.sigma)
        M, co = cf["M"], cf["coords"]
        self.elements = tuple(els if els is not None else nlp_elements(model.cfg))
        terms = series_terms(self.elements)
        what = {"a": lambda c: -c.dq / M, "b": lambda c: -c.q * c.dq / M,
                "B": lambda c: -c.dq2 / M}
        funcs = [what[w](co[e]) for _, e, w in terms] + [-0.5 * cf["dM"] / M, cf["tau"]]
        self.names = tuple(n for n, _, _ in terms) + ("inertia", "tau", "dtau")
        g = ca.vertcat(*funcs)
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
        dtau = np.polynomial.chebyshev.chebder(C[-1]) * 2 / (hi - lo)
        C = np.vstack([C, np.r_[dtau, 0.0]])
        self.coef, self.degree, self.max_rel_error = C, n, float(err)

    def state(self) -> dict:
        """The fitted numbers (the disk cache keeps them beside a compiled NLP)."""
        import numpy as np
        return {"fit_coef": self.coef, "fit_numbers": np.array([self.lo, self.hi, self.degree,
                                                                self.max_rel_error]),
                "fit_names": np.array(self.names)}

    @classmethod
    def restore(cls, state: dict, els) -> "ChebyshevFit":
        """The fit from :meth:`state`'s numbers (the elements ``els`` as when it was made)."""
        f = cls.__new__(cls)
        f.elements = tuple(els)
        f.names = tuple(str(n) for n in state["fit_names"])
        lo, hi, degree, err = (float(v) for v in state["fit_numbers"])
        f.lo, f.hi, f.degree, f.max_rel_error = lo, hi, int(degree), err
        f.coef = np.array(state["fit_coef"], float)
        if f.names != tuple(n for n, _, _ in series_terms(f.elements)) + ("inertia", "tau",
                                                                           "dtau"):
            raise ValueError("the fit's series are not those of its elements")
        return f

    def series(self, name: str) -> ca.DM:
        """The Chebyshev coefficients of one function (by its name in :attr:`names`)."""
        return ca.DM(self.coef[self.names.index(name)])

    def _u(self, theta):
        return (2 * theta - (self.lo + self.hi)) / (self.hi - self.lo)

    def basis(self, theta):
        """Chebyshev polynomials T_0..T_n at theta (an SX column)."""
        u = self._u(theta)
        T = [1, u]
        for _ in range(2, self.degree + 1):
            T.append(2 * u * T[-1] - T[-2])
        return ca.vertcat(*T)


def hermite_max(va, ma, vb, mb):
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


def interval_function(model, substeps: int, fit: ChebyshevFit | None = None,
                      with_ode: bool = False):
    """One shooting interval of ``substeps`` RK4 sub-steps on ``model``'s equation of motion
    (its Chebyshev series): ``interval(x0, q, h) -> (x1, theta, theta_dot, speed)``.

    ``q`` the parameter vector (:data:`softclose.problem.PARAM_KEYS`), ``h`` the sub-step;
    ``theta``/``theta_dot`` are the states
    after sub-steps 1..M-1, ``speed`` the tip speeds after each sub-step followed by the
    Hermite maxima inside each. With ``with_ode`` also returns the ODE ``f(x, q)``.
    """
    fit = fit or ChebyshevFit(model)
    M = substeps
    nb = fit.degree + 1
    # theta'' = a0(theta) + a1(theta) theta' + a2(theta) theta'^2; the series of a0 and a1
    # are combined from the parameters once per interval, not at every evaluation: each
    # element's law gives the coefficients of its series (a_e, b_e of T = a + b q; B_e)
    x0, q, h = ca.SX.sym("x0", 2), ca.SX.sym("q", len(PARAM_KEYS)), ca.SX.sym("h")
    P = elements.params(q)
    a0, a1 = [], []
    for name, e, what in series_terms(fit.elements):
        el = elements.BY_NAME[e]
        coef = el.viscous(P) if what == "B" else el.affine(P)["ab".index(what)]
        (a1 if what == "B" else a0).append(coef * fit.series(name))
    cq = ca.vertcat(sum(a0[1:], a0[0]), sum(a1[1:], a1[0]))
    xs, cs = ca.SX.sym("x", 2), ca.SX.sym("cq", 2 * nb)
    B = fit.basis(xs[0])
    acc = (ca.dot(cs[:nb], B) + ca.dot(cs[nb:], B) * xs[1]
           + ca.dot(fit.series("inertia"), B) * xs[1] ** 2)
    f_c = ca.Function("f_c", [xs, cs], [ca.vertcat(xs[1], acc)])
    f = ca.Function("f", [xs, q], [f_c(xs, cq)])     # the ODE, for reporting
    th = ca.SX.sym("th")
    Bt = fit.basis(th)
    tau = ca.Function("tau", [th], [ca.dot(fit.series("tau"), Bt),
                                    ca.dot(fit.series("dtau"), Bt)])

    def speed(x, xdot):  # |v_T| = -tau theta' (theta' <= 0), and h d|v_T|/dt
        t, dt = tau(x[0])
        return -t * x[1], -h * (dt * x[1] * x[1] + t * xdot[1])

    def rk4(x, fx, cq_):  # one RK4 sub-step of length h; fx = f(x) (first stage reused)
        k2 = f_c(x + 0.5 * h * fx, cq_)
        k3 = f_c(x + 0.5 * h * k2, cq_)
        k4 = f_c(x + h * k3, cq_)
        return x + h / 6 * (fx + 2 * k2 + 2 * k3 + k4)

    names = (["x0", "q", "h"], ["x1", "theta", "theta_dot", "speed"])
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
            peak.append(hermite_max(va, ma, vb, mb))
            va, ma = vb, mb
        empty = ca.SX(0, 1)
        outs = [x, ca.vertcat(*ths) if ths else empty,
                ca.vertcat(*thds) if thds else empty, ca.vertcat(*spd, *peak)]
        interval = ca.Function("interval", [x0, q, h], ca.cse(outs), *names)
    else:  # one SX sub-step, accumulated M times (build time independent of M)
        a, cqs = ca.SX.sym("a", 6), ca.SX.sym("cq", 2 * nb)   # a = (x, x', v, h v')
        x, fx, va, ma = a[0:2], a[2:4], a[4], a[5]
        x1 = rk4(x, fx, cqs)
        fx1 = f_c(x1, cqs)
        vb, mb = speed(x1, fx1)
        step = ca.Function("substep", [a, cqs, h],
                           ca.cse([ca.vertcat(x1, fx1, vb, mb),
                                   ca.vertcat(x1, vb, hermite_max(va, ma, vb, mb))]))
        fx0 = f_c(x0, cq)
        start = ca.Function("start", [x0, q, h], [ca.vertcat(x0, fx0, *speed(x0, fx0)), cq])
        accum = step.mapaccum("substeps", M)
        x0m, qm, hm = ca.MX.sym("x0", 2), ca.MX.sym("q", len(PARAM_KEYS)), ca.MX.sym("h")
        a0, cqm = start(x0m, qm, hm)
        _, Y = accum(a0, ca.repmat(cqm, 1, M), ca.repmat(hm, 1, M))
        outs = [Y[0:2, M - 1], Y[0, :M - 1].T, Y[1, :M - 1].T,
                ca.vertcat(Y[2, :].T, Y[3, :].T)]
        interval = ca.Function("interval", [x0m, qm, hm], outs, *names)
    return (interval, f) if with_ode else interval


# -- the discretisation ----------------------------------------------------------------------
@dataclass(frozen=True)
class Discretisation:
    """N shooting intervals of M RK4 sub-steps, and the closing-time limit the NLP uses.

    ``t_limit`` is ``min(closing_time_max, stroke.t_max)``: a stroke must close within
    t_max, so a larger limit cannot bind (and must not make the grid huge).
    """

    nodes: int
    substeps: int
    t_limit: float
    notes: tuple[str, ...] = ()

    @property
    def steps(self) -> int:
        return self.nodes * self.substeps


def discretisation(cfg, nodes: int | None = None, substeps: int | None = None) -> Discretisation:
    """optimise.nodes, and optimise.substeps doubled if needed so that the RK4 step
    t_limit/(N M) stays <= :data:`H_MAX`; explicit arguments are kept as given.

    Raises ConfigError when the grid would exceed :data:`MAX_STEPS` RK4 steps.
    """
    o, st = cfg.optimise, cfg.stroke
    N = int(nodes or o.nodes)
    notes = []
    t_limit = o.closing_time_max
    if o.closing_time_max > st.t_max:     # (closing_time_min < t_max: checked by the config)
        t_limit = st.t_max
        notes.append(f"closing_time_max = {o.closing_time_max:g} s lies beyond stroke.t_max = "
                     f"{st.t_max:g} s (a stroke must close within t_max): the NLP uses "
                     f"closing_time <= {st.t_max:g} s")
    if substeps:
        M = int(substeps)
    else:
        M = o.substeps
        need = t_limit / (N * H_MAX * (1 + 1e-9))
        if M < need:   # doublings: few distinct NLPs to build (refinement doubles too)
            M *= 2 ** math.ceil(math.log2(need / M))
            if N * M <= MAX_STEPS:
                notes.append(f"substeps raised from {o.substeps} to {M} so that the RK4 step "
                             f"stays <= {H_MAX:g} s for closing times up to {t_limit:g} s")
    if N * M > MAX_STEPS:
        if substeps or M == o.substeps:
            raise ConfigError(
                f"optimise.nodes x optimise.substeps = {N} x {M} = {N * M} RK4 steps exceeds "
                f"the limit of {MAX_STEPS}; lower optimise.nodes or optimise.substeps")
        raise ConfigError(
            f"optimise.closing_time_max: closing times up to {t_limit:g} s need "
            f"{N} x {M} = {N * M} RK4 steps of at most {H_MAX:g} s, more than the limit of "
            f"{MAX_STEPS}; lower optimise.closing_time_max (or stroke.t_max) or "
            "optimise.nodes")
    return Discretisation(N, M, t_limit, tuple(notes))


def check_linear_solver(name: str) -> None:
    """ConfigError unless Ipopt can load the linear solver ``name``.

    MUMPS ships with CasADi's Ipopt. The HSL solvers (ma27, ma57, ma86, ma97) live in a
    separate library (``libhsl``/``libcoinhsl``) that Ipopt loads at run time; asking for one
    that is not installed must be refused here, before Ipopt is called: a failed load of
    ma86/ma97 leaves Ipopt in a state that crashes the process at exit.
    """
    if name == "mumps":
        return
    import ctypes
    import ctypes.util
    for lib in ("hsl", "coinhsl"):
        for candidate in filter(None, (ctypes.util.find_library(lib), f"lib{lib}.so")):
            try:
                ctypes.CDLL(candidate)
                return
            except OSError:
                continue
    raise ConfigError(f"optimise.linear_solver: \"{name}\" needs the HSL library (libhsl or "
                      "libcoinhsl), which is not installed here; use \"mumps\"")


def check_options(run: "Run", cfg) -> None:
    """ConfigError when Ipopt refused an option of cfg (e.g. a linear solver that this Ipopt
    build does not have)."""
    if run.status == "Invalid_Option":
        o = cfg.optimise
        raise ConfigError(f"optimise.linear_solver: Ipopt refused its options (status "
                          f"Invalid_Option); \"{o.linear_solver}\" is probably not in this Ipopt "
                          "build: use \"mumps\"")


# -- one Ipopt run ---------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class Run:
    """One Ipopt solve: the primal-dual point, its status and cost, and the problem data
    (parameters ``p`` and ``bounds`` = (lbx, ubx, lbg, ubg)) it was solved with."""

    x: np.ndarray
    f: float
    g: np.ndarray
    lam_x: np.ndarray | None
    lam_g: np.ndarray | None
    status: str
    success: bool
    iterations: int
    time: float
    p: np.ndarray
    bounds: tuple
    origin: str = ""
    violations: dict = field(default_factory=dict)

    @property
    def J_ref(self) -> float:
        return float(self.p[J_INDEX])


class ShootingNLP:
    """The multiple-shooting NLP of one geometry with N intervals of M RK4 sub-steps each.

    Built once (:func:`softclose.optimiser.cache.get_nlp` caches it per geometry and
    discretisation); :meth:`solve` takes the bounds and parameters of one problem, so
    changing closing_time_max, weights, design bounds or holding_moment_min never rebuilds
    anything.
    """

    def __init__(self, model, nodes: int, substeps: int, hessian: str = "exact",
                 linear_solver: str = "mumps", max_iter: int = 500, tol: float = 1e-10,
                 els=None, library=None, meta: dict | None = None):
        """Built symbolically (CasADi's virtual machine evaluates it), or -- ``library`` a
        compiled library of this NLP (:mod:`softclose.buildcache`) and ``meta`` what
        :meth:`meta` stored when it was built -- loaded: nothing symbolic is built, the
        solves call the compiled functions."""
        t0 = time.perf_counter()
        check_linear_solver(linear_solver)
        self.model, self.N, self.M = model, nodes, substeps
        N, M = nodes, substeps
        self.ipopt_options = {"print_time": False, "show_eval_warnings": False,
                              "calc_lam_p": False,
                              "ipopt.print_level": 0, "ipopt.sb": "yes",
                              "ipopt.tol": tol, "ipopt.max_iter": max_iter,
                              "ipopt.hessian_approximation": hessian,
                              "ipopt.linear_solver": linear_solver,
                              # constraints hold exactly at the answer, not to 1e-8
                              "ipopt.bound_relax_factor": 0.0}
        self.key = None
        self.library = library
        if library is not None:
            els = tuple(els if els is not None else nlp_elements(model.cfg))
            self.fit = ChebyshevFit.restore(meta, els)
            self.g_names = [str(n) for n in meta["g_names"]]
            self.g_sizes = [int(n) for n in meta["g_sizes"]]
            self.nw = int(meta["nw"][0])
            from ..buildcache import text
            self._peak = ca.Function.deserialize(text(meta["peak"]))
            lib = str(library)
            self.solver = ca.nlpsol("softclose_ms", "ipopt", lib,
                                    {**self.ipopt_options, **COLD_OPTIONS})
            self.warm_solver = ca.nlpsol("softclose_ms_warm", "ipopt", lib,
                                         {**self.ipopt_options, **WARM_OPTIONS})
            if (self.solver.size1_in(0), self.solver.size1_in(1),
                    self.solver.size1_in(5)) != (self.nw, len(NLP_PARAMS) + N,
                                                 sum(self.g_sizes)):
                raise ValueError("the compiled NLP has other dimensions")
            self.build_time = time.perf_counter() - t0
            return
        self.fit = ChebyshevFit(model, els=els)
        self.interval, self.f = interval_function(model, substeps, self.fit, with_ode=True)
        # the NLP: MX graph over the SX interval, mapped over the N intervals
        d, T, X, s = ca.MX.sym("d", 3), ca.MX.sym("T"), ca.MX.sym("X", 2, N), ca.MX.sym("s")
        npar = len(NLP_PARAMS)
        P = ca.MX.sym("P", npar + N)
        theta0, thc, wi, wp, wt = (P[i] for i in range(5))
        fixed, Jref = P[5:5 + len(FIXED_PARAMS)], P[J_INDEX]
        grid = P[npar:]
        design = ca.vertcat(d * ca.DM(SCALES), fixed)
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
        # softclose.problem.objective with the weights as NLP parameters (+ a time term that
        # only the infeasibility diagnosis uses: fastest / slowest stroke)
        J = wi * X[1, N - 1] ** 2 + wp * s ** 2 + wt * T
        w = ca.vertcat(d, T, ca.vec(X), s)
        self.nw = int(w.numel())
        # the largest sub-step speed or Hermite maximum: the NLP's own peak tip speed
        self._peak = ca.Function("peak", [w, P], [ca.mmax(sp)])
        nlp = {"x": w, "f": J / Jref, "g": ca.vertcat(*g_all.values()), "p": P}
        self.solver = ca.nlpsol("softclose_ms", "ipopt", nlp,
                                {**self.ipopt_options, **COLD_OPTIONS})
        # the warm solver shares the oracle (and its cached derivatives): ~0.05 s more
        oracle = self.solver.oracle()
        wx, wpar = ca.MX.sym("x", self.nw), ca.MX.sym("p", npar + N)
        fo, go = oracle(wx, wpar)
        self.warm_solver = ca.nlpsol("softclose_ms_warm", "ipopt",
                                     {"x": wx, "p": wpar, "f": fo, "g": go},
                                     {**self.ipopt_options, **WARM_OPTIONS})
        self.build_time = time.perf_counter() - t0

    def __getattr__(self, name):
        """``interval`` and ``f`` of an NLP loaded from its compiled library: built on first
        use (tests and reports ask for them; the solves do not)."""
        if name in ("interval", "f") and self.__dict__.get("library") is not None:
            self.interval, self.f = interval_function(self.model, self.M, self.fit,
                                                      with_ode=True)
            return getattr(self, name)
        raise AttributeError(name)

    def meta(self) -> dict:
        """What a compiled library of this NLP needs beside it (:mod:`softclose.buildcache`):
        the fit, the constraint groups, the size of w, the peak function."""
        return {**self.fit.state(), "g_names": np.array(self.g_names),
                "g_sizes": np.array(self.g_sizes), "nw": np.array([self.nw]),
                "peak": self._peak.serialize().encode()}

    # -- packing -------------------------------------------------------------------------
    def pack(self, design, T, X, s) -> np.ndarray:
        return np.r_[np.asarray(design[:3], float) / SCALES, T, np.asarray(X, float).T.ravel(), s]

    def unpack(self, w):
        """(design (3,), T, X (2, N), s) of a point ``w``."""
        w = np.asarray(w, float).ravel()
        N = self.N
        X = w[4:4 + 2 * N].reshape(N, 2).T
        return w[:3] * SCALES, float(w[3]), X, float(w[-1])

    def peak(self, run: Run) -> float:
        """The NLP's own peak tip speed at ``run``'s point: the largest sub-step speed or
        Hermite maximum (not the epigraph variable s, which is free when weight_peak_tip
        is zero)."""
        return float(self._peak(run.x, run.p))

    def bounds(self, cfg, t_max: float | None = None, t_min: float | None = None):
        """(lbx, ubx, lbg, ubg) of ``cfg``'s problem; the closing-time bounds default to
        [closing_time_min, min(closing_time_max, stroke.t_max)]."""
        o, st = cfg.optimise, cfg.stroke
        N = self.N
        lbx, ubx = np.full(self.nw, -np.inf), np.full(self.nw, np.inf)
        for i, key in enumerate(DESIGN_KEYS):
            lo, hi = getattr(o, key)
            lbx[i], ubx[i] = lo / SCALES[i], hi / SCALES[i]
        lbx[3] = max(o.closing_time_min if t_min is None else t_min, T_FLOOR)
        ubx[3] = min(o.closing_time_max, st.t_max) if t_max is None else t_max
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

    def params(self, cfg, J_ref: float = 1.0, weight_time: float = 0.0,
               weights: tuple | None = None) -> np.ndarray:
        """NLP parameters of ``cfg``'s problem (``weights`` overrides the objective's)."""
        o, st = cfg.optimise, cfg.stroke
        wi, wp = (o.weight_impact, o.weight_peak_tip) if weights is None else weights
        fixed = [getattr(cfg.design, k) for k in FIXED_PARAMS]
        return np.r_[st.theta0, st.theta_closed, wi, wp, weight_time, fixed, J_ref,
                     self.time_grid()]

    def time_grid(self) -> np.ndarray:
        """Fractions of T of the N intervals: uniform.

        The grid is an NLP parameter, so graded grids need no rebuild; but a graded grid
        does not pay here: the tip speed peaks early (~0.1 s) while the creep to the rim is
        limited by RK4's stability on the damper (h |lambda| < 2.79, lambda = c dd / M up
        to ~70 1/s), so long strokes need more steps anyway (see :func:`discretisation`).
        """
        return np.full(self.N, 1.0 / self.N)

    @staticmethod
    def grid_of(p) -> np.ndarray:
        return np.asarray(p, float)[len(NLP_PARAMS):]

    def groups(self):
        """(name, slice of g) of each constraint group."""
        i = 0
        for name, n in zip(self.g_names, self.g_sizes):
            yield name, slice(i, i + n)
            i += n

    def violations(self, g, lbg, ubg) -> dict:
        """The largest violation of each constraint group at a point (0 if satisfied)."""
        out = {}
        for name, sl in self.groups():
            gi, lo, hi = g[sl], lbg[sl], ubg[sl]
            v = np.maximum(np.maximum(lo - gi, gi - hi), 0.0)
            out[name] = float(np.nan_to_num(v, nan=np.inf).max()) if len(gi) else 0.0
        return out

    def solve(self, x0, p, lbx, ubx, lbg, ubg, lam_x0=None, lam_g0=None, warm=False,
              origin: str = "") -> Run:
        """One Ipopt run; never raises (an evaluation error is a failed status)."""
        solver = self.warm_solver if warm else self.solver
        x0 = np.clip(np.asarray(x0, float), lbx, ubx)
        args = dict(x0=x0, p=p, lbx=lbx, ubx=ubx, lbg=lbg, ubg=ubg)
        if lam_x0 is not None:
            args.update(lam_x0=lam_x0, lam_g0=lam_g0)
        bounds = (lbx, ubx, lbg, ubg)
        t0 = time.perf_counter()
        try:
            sol = solver(**args)
            st = solver.stats()
            status, ok, its = st["return_status"], bool(st["success"]), int(st["iter_count"])
        except RuntimeError as exc:  # an evaluation error before Ipopt could report
            g = np.full(len(lbg), np.nan)
            return Run(x0, math.nan, g, None, None, f"Error: {str(exc).splitlines()[0]}",
                       False, 0, time.perf_counter() - t0, np.asarray(p, float), bounds,
                       origin, self.violations(g, lbg, ubg))
        if status.startswith("Invalid") or its < 0:
            its = 0                       # Ipopt stopped before its first iteration
        g = np.asarray(sol["g"]).ravel()
        return Run(np.asarray(sol["x"]).ravel(), float(sol["f"]), g,
                   np.asarray(sol["lam_x"]).ravel(), np.asarray(sol["lam_g"]).ravel(),
                   status, ok and status in CONVERGED, its, time.perf_counter() - t0,
                   np.asarray(p, float), bounds, origin, self.violations(g, lbg, ubg))
