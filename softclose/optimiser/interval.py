"""The equation of motion as the NLP sees it: Chebyshev series of the geometry, and one
shooting interval of RK4 sub-steps on them.

theta'' = a0(theta) + a1(theta) theta' + a2(theta) theta'^2, with every element's law affine
in its parameters (:mod:`softclose.model.elements.base`): a0 sums the conservative elements'
a_e (-q_e'/M) + b_e (-q_e q_e'/M) (T_e = a_e + b_e q) and dry friction's C_e |q_e'|/M (the
stroke is monotone, theta' <= 0), a1 the dampers' B_e (-q_e'^2/M), a2 = -M'/(2M). A gas
strut's law is not affine in its length: its NLP (a structure of its own, :func:`gas_nlp`)
carries the spring's length l(theta) and -l'/M as series and adds T(l) (-l'/M) per stage. The
geometric functions are fitted once per geometry as Chebyshev series to machine precision
(:class:`ChebyshevFit`); the elements' parameters -- design variables or NLP parameters --
combine them once per interval (:func:`interval_function`). Which elements the NLP carries
(:func:`nlp_elements`) and which further design variables it has (``optimise.free``:
:func:`free_layout`) are read from the config here, and whether an end damper makes the
stroke two phases (:func:`end_damper_mode`).
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np

from ..model import elements
from ..model.dynamics import coefficients
from ..errors import ConfigError
from ..problem import PARAM_COLUMNS, PARAM_KEYS, params_of
from .free_points import POSE_SERIES, SLOTS, lengths, pose_functions
from .hermite import hermite_max
from .parameters import SymbolicSeries, chebyshev_basis, padded_degree
from ..simulation.kernel.binding import cores

#: margin (deg) beyond the stroke over which the Chebyshev series are fitted
FIT_MARGIN_DEG = 3.0
#: up to this many sub-steps an interval is unrolled in SX; beyond, one SX sub-step is
#: accumulated (mapaccum), so that building the NLP does not grow with the sub-steps
UNROLL_MAX = 8

#: the end damper's keys (:class:`softclose.model.elements.dampers.EndDamper`)
END_C, END_ANGLE = "design.end_damper_c", "design.end_damper_angle_deg"
#: a free engagement angle is bounded this far (a fraction of the stroke) inside the stroke:
#: each phase keeps a length, and the answer's lid meets the plunger between release and rim
ANGLE_MARGIN = 0.01


#: at most this many threads per map (the intervals of 9 scenarios are ~90 calls)
MAX_MAP_THREADS = 4


def map_threads() -> int:
    """Threads that evaluate an NLP's shooting intervals: the cores this process may use,
    at most :data:`MAX_MAP_THREADS`."""
    return min(cores(), MAX_MAP_THREADS)


def mapped(f: ca.Function, n: int, threads: int | None = None) -> ca.Function:
    """``f`` mapped over n shooting intervals, evaluated in ``threads`` threads (default
    :func:`map_threads`; CasADi's "thread" map, whose derivatives are thread maps too; the
    threads end with each call).

    Why: an Ipopt iteration is mostly the Hessian of the Lagrangian and the constraints'
    Jacobian, forward-over-reverse sweeps through these maps. The intervals are
    independent, so on 2 cores CasADi's virtual machine solves the robust co-design's joint
    NLP (9 scenarios, the points free) in 11.9 s instead of 20.6 s and the nominal
    end-damper co-design in 3.4 s instead of 4.5 s, in the same iterations to the same bits
    (each interval's numbers are computed alone; the sums over them are the MX graph's, in
    the same order). A nominal NLP compiled to C maps serially (``threads=1``): its
    intervals are too cheap for a thread each call (0.9 s against 0.6 s for
    ``softclose optimise``)."""
    k = map_threads() if threads is None else threads
    return f.map(n, "thread", k) if k > 1 and n > 1 else f.map(n)


def free_of(cfg) -> tuple:
    """``optimise.free``: the further design variables (key, lo, hi), possibly none; a free
    engagement angle's bounds clipped into the stroke (:func:`angle_bounds`)."""
    out = []
    for k, lo, hi in cfg.optimise.free or ():
        if k == END_ANGLE:
            lo, hi = angle_bounds(cfg, lo, hi)
        out.append((k, lo, hi))
    return tuple(out)


def angle_bounds(cfg, lo: float, hi: float) -> tuple[float, float]:
    """The bounds (deg) of a free engagement angle within the stroke: [lo, hi] clipped to
    [theta_closed + m, theta0 - m], m = :data:`ANGLE_MARGIN` of the stroke. Outside it the
    end damper would act always or never -- a one-phase problem in which the angle does
    nothing -- so bounds that lie wholly outside are refused."""
    st = cfg.stroke
    a, b = st.theta_closed_deg, st.theta0_deg
    m = ANGLE_MARGIN * (b - a)
    lo2, hi2 = max(lo, a + m), min(hi, b - m)
    if lo2 > hi2:
        raise ConfigError(
            f"optimise.free {END_ANGLE} = [{lo:g}, {hi:g}] deg lies outside the stroke "
            f"({a:g} .. {b:g} deg, less {m:.3g} deg at each end): the end damper would act "
            "over the whole stroke or never, and its angle would change nothing; bound it "
            "inside the stroke")
    return lo2, hi2


def end_damper_mode(cfg) -> str | None:
    """How the NLP carries the end damper (:class:`~softclose.model.elements.dampers.EndDamper`):

    - ``"two-phase"``: it acts (c_e > 0, or ``design.end_damper_c`` free) and its engagement
      angle lies inside the stroke (or is free: bounded inside it): phase 1 from the release
      to the angle without it, phase 2 from the angle to the rim with it, a node at the
      switch whose time is free (:class:`softclose.optimiser.nlp.ShootingNLP`);
    - ``"always"``: it acts and the angle is at or above the release angle: a damper on the
      lid over the whole stroke (one phase);
    - None: it does not act, or the angle is at or below the rim (it never engages: the
      NLP leaves it out, :func:`nlp_elements`).

    A free coefficient makes the stroke two phases even with bounds [0, 0] (the two-phase
    NLP of a lid without end damper: today's one-phase answer). A free angle without a
    damper, or a free coefficient of a damper that never engages, would be a variable that
    changes nothing: refused (ConfigError)."""
    free = {k: (lo, hi) for k, lo, hi in cfg.optimise.free or ()}
    c_free = END_C in free
    acts = free[END_C][1] > 0 if c_free else cfg.design.end_damper_c > 0
    if END_ANGLE in free:
        if not acts:
            raise ConfigError(f"optimise.free: {END_ANGLE} is free but the end damper does not "
                              f"act (design.end_damper_c = {cfg.design.end_damper_c:g}"
                              + (", its bounds [0, 0]" if END_C in free else "") +
                              "): give it a coefficient or free design.end_damper_c too")
        angle_bounds(cfg, *free[END_ANGLE])
        return "two-phase"
    if not acts and not c_free:
        return None
    st, a = cfg.stroke, cfg.design.end_damper_angle_deg
    if a >= st.theta0_deg:
        return "always"
    if a <= st.theta_closed_deg:
        if c_free:
            raise ConfigError(
                f"optimise.free: {END_C} is free but the end damper engages at "
                f"{END_ANGLE} = {a:g} deg, at or below the rim ({st.theta_closed_deg:g} deg): "
                "it never acts; set the angle inside the stroke or free it too")
        return None
    return "two-phase"


def free_layout(cfg) -> tuple:
    """The NLP's further design variables: (key, column of p, scale) each, the scale the
    larger magnitude of the bounds (so that the scaled variable lies within [-1, 1])."""
    return tuple((k, PARAM_COLUMNS[k], max(abs(lo), abs(hi)) or 1.0)
                 for k, lo, hi in free_of(cfg) if k in PARAM_COLUMNS)


# -- the geometric functions as Chebyshev series -----------------------------------------
def nlp_elements(cfg) -> tuple:
    """The elements the NLP carries: the seed's always, the others when they act in ``cfg``
    or may act through a free design variable (``optimise.free``; an element that exerts no
    force adds nothing but series to fit)."""
    extra = {k.split(".", 1)[1]: max(abs(lo), abs(hi)) for k, lo, hi in free_of(cfg)
             if k.startswith("design.")}
    acting = elements.acting(params_of(cfg), extra)
    never = end_damper_mode(cfg) is None        # an end damper that never engages
    return tuple(e for e in elements.ELEMENTS if e.seed or e in acting and not (
        never and e in elements.ENGAGING))


def gas_nlp(cfg) -> bool:
    """Is ``cfg``'s spring a gas strut (an NLP structure of its own: :func:`series_terms`)?"""
    return cfg.design.spring_kind == "gas_strut"


def series_terms(els, gas: bool = False) -> list[tuple[str, str, str]]:
    """(name, element, what) of the geometric functions of the equation of motion carried by
    the elements ``els``: per conservative element "b" (-q q'/M; not for gravity, whose T
    is constant) and "a" (-q'/M), per damper "B" (-q'^2/M), per dry friction "C" (|q'|/M:
    the stroke is monotone, theta' <= 0, so friction is the constant force C against it);
    summed in this order. With ``gas`` the spring is a gas strut: "l" (its length) and "a"
    (-l'/M), which a stage combines through the gas law."""
    out = []
    for e in els:
        if e in elements.SPRINGS:
            if e.name == "spring" and gas:
                out.append(("spring:l", e.name, "l"))
            elif e.name != "gravity":
                out.append((f"{e.name}:b", e.name, "b"))
            out.append((f"{e.name}:a", e.name, "a"))
        if e in elements.DAMPERS:
            out.append((f"{e.name}:B", e.name, "B"))
        if e in elements.FRICTIONS:
            out.append((f"{e.name}:C", e.name, "C"))
    return out


class ChebyshevFit:
    """The geometric functions of theta (and tau') as Chebyshev series on [lo, hi].

    :attr:`names` lists them: the elements' series (:func:`series_terms`), then "inertia"
    (-M'/(2M)), "tau" and "dtau". The degree is raised until the series match the exact
    CasADi expressions to ``tol`` (relative to each function's largest value) on a 2001-point
    grid: degree 14 and a maximal relative error ~4e-15 for the default geometry
    (``max_rel_error``).
    """

    def __init__(self, model, tol: float = 1e-13, max_degree: int = 64, els=None,
                 pose: bool = False, gas: bool = False):
        if els is None:
            raise TypeError("ChebyshevFit: els, the elements the NLP carries "
                            "(nlp_elements(cfg)), must be given")
        th = ca.SX.sym("theta")
        cf = coefficients(th, model.lid, model.sigma)
        M, co = cf["M"], cf["coords"]
        self.elements = tuple(els)
        terms = series_terms(self.elements, gas)
        what = {"a": lambda c: -c.dq / M, "b": lambda c: -c.q * c.dq / M,
                "B": lambda c: -c.dq2 / M, "C": lambda c: ca.fabs(c.dq) / M,
                "l": lambda c: c.q}
        funcs = [what[w](co[e]) for _, e, w in terms]
        names = [n for n, _, _ in terms]
        if pose:        # the closure itself, for attachment points as design variables
            funcs += pose_functions(th, model.lid, model.sigma, M)
            names += list(POSE_SERIES)
        funcs += [-0.5 * cf["dM"] / M, cf["tau"]]
        self.names = tuple(names) + ("inertia", "tau", "dtau")
        g = ca.vertcat(*funcs)
        self.exact = ca.Function("g_exact", [th], [ca.cse(g)])
        # the stroke's angles with a margin for overshooting stages and iterates (the
        # series extrapolate smoothly beyond it), within the range where the loop closes
        st = model.stroke
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
        return {"fit_coef": self.coef, "fit_numbers": np.array([self.lo, self.hi, self.degree,
                                                                self.max_rel_error]),
                "fit_names": np.array(self.names)}

    @property
    def pose(self) -> bool:
        """Does the fit hold the closure's series (attachment points as variables)?"""
        return "pose:Ax" in self.names

    @property
    def gas(self) -> bool:
        """Is the spring a gas strut (its length a series of its own)?"""
        return "spring:l" in self.names

    @classmethod
    def restore(cls, state: dict, els) -> "ChebyshevFit":
        """The fit from :meth:`state`'s numbers (the elements ``els`` as when it was made)."""
        f = cls.__new__(cls)
        f.elements = tuple(els)
        f.names = tuple(str(n) for n in state["fit_names"])
        lo, hi, degree, err = (float(v) for v in state["fit_numbers"])
        f.lo, f.hi, f.degree, f.max_rel_error = lo, hi, int(degree), err
        f.coef = np.array(state["fit_coef"], float)
        pose = POSE_SERIES if "pose:Ax" in f.names else ()
        if f.names != tuple(n for n, _, _ in series_terms(f.elements, f.gas)) + pose + (
                "inertia", "tau", "dtau"):
            raise ValueError("the fit's series are not those of its elements")
        return f

    def series(self, name: str) -> ca.DM:
        """The Chebyshev coefficients of one function (by its name in :attr:`names`)."""
        return ca.DM(self.coef[self.names.index(name)])

    def _u(self, theta):
        return (2 * theta - (self.lo + self.hi)) / (self.hi - self.lo)

    def basis(self, theta):
        """Chebyshev polynomials T_0..T_n at theta (an SX column)."""
        return chebyshev_basis(self._u(theta), self.degree)


def combine_function(series, placement: bool = False):
    """The coefficients of one stroke's equation of motion, combined once per NLP (not per
    interval): ``combine(q[, g], L) -> c``, c = (the series of a0 and of a1 -- each element's
    law gives the coefficients of its series, a_e and b_e of T = a + b q, B_e, C_e --, with
    ``placement`` the spring's (a_s, b_s), the dashpot's c and the points g, then the series
    L themselves). ``q`` the parameter vector (:data:`softclose.problem.PARAM_KEYS`), ``L``
    the series' numbers (``series.sym``)."""
    q, L = ca.SX.sym("q", len(PARAM_KEYS)), series.sym
    gas = "spring:l" in series.names
    P = elements.params(q, "gas" if gas else "coil")
    a0, a1 = [], []
    # with placement the spring, the dashpot and the friction along the spring act through
    # the points g: their laws' numbers go into c, not into the fixed series
    placed = ("spring", "dashpot", "strut_friction") if placement else \
        ("spring",) if gas else ()
    for name, e, what in series_terms(series.elements, gas):
        if e in placed:
            continue
        el = elements.BY_NAME[e]
        coef = el.viscous(P) if what == "B" else el.coulomb(P) if what == "C" else \
            el.affine(P)["ab".index(what)]
        (a1 if what == "B" else a0).append(coef * series.series(name))
    cq = [sum(a0[1:], a0[0]), sum(a1[1:], a1[0])]
    ins = [q]
    if placement:
        g = ca.SX.sym("g", len(SLOTS))
        sa, sb = elements.BY_NAME["spring"].affine(P)
        cq += [sa, sb, elements.BY_NAME["dashpot"].viscous(P), g]
        ins.append(g)
    if gas:             # the gas law's G = -F1, beta and the extended length (then)
        G, beta = elements.BY_NAME["spring"].gas(P)
        cq += [G, beta, P["spring_rest_length"]]
    if placed_friction(series, placement):    # F_R along the spring at the points (then)
        cq.append(elements.BY_NAME["strut_friction"].coulomb(P))
    view = _step_series(series, placement)
    return ca.Function("combine", ins + [L],
                       [ca.vertcat(*cq, *[series.series(n) for n in view.names],
                                   series.lo, series.hi)],
                       ["q"] + (["g"] if placement else []) + ["L"], ["c"])


def placed_friction(series, placement: bool) -> bool:
    """Does the friction along the spring act through the points g (placement, and the NLP
    carries it)?"""
    return placement and any(e.name == "strut_friction" for e in series.elements)


def _step_series(series, placement: bool, vector=None):
    """The series a sub-step reads beside the combined coefficients (the inertia's, the
    tip's lever tau and tau', with ``placement`` the closure's), as the tail of c."""
    names = (POSE_SERIES if placement else ()) + (
        ("spring:l", "spring:a") if "spring:l" in series.names else ()) + (
        "inertia", "tau", "dtau")
    if vector is None:
        vector = ca.SX.sym("s", len(names) * (series.degree + 1) + 2)
    return SymbolicSeries(names, series.elements, series.degree, vector)


def interval_function(series, substeps: int, with_ode: bool = False,
                      placement: bool = False):
    """One shooting interval of ``substeps`` RK4 sub-steps on the equation of motion whose
    geometric functions are the symbolic Chebyshev ``series``
    (:class:`softclose.optimiser.parameters.SymbolicSeries`): ``interval(x0, c, h) -> (x1, theta,
    theta_dot, speed)``, ``c`` the coefficients of :func:`combine_function` (the design and
    the lid's series), ``h`` the sub-step; ``theta``/``theta_dot`` are the states after
    sub-steps 1..M-1, ``speed`` the tip speeds after each sub-step followed by the Hermite
    maxima inside each. With ``with_ode`` also returns the ODE ``f(x, c)``.

    theta'' = a0(theta) + a1(theta) theta' + a2(theta) theta'^2 (a2 = -M'/(2M), a series of
    its own); with ``placement`` the spring and the dashpot act through the attachment
    points g in c (:mod:`.placement`).
    """
    M = substeps
    nb = series.degree + 1
    n_c = int(combine_function(series, placement).size1_out(0))
    x0, cs, h = ca.SX.sym("x0", 2), ca.SX.sym("c", n_c), ca.SX.sym("h")
    fit = _step_series(series, placement)
    fit = fit.over(cs[n_c - fit.size:])
    xs = ca.SX.sym("x", 2)
    B = fit.basis(xs[0])
    acc = (ca.dot(cs[:nb], B) + ca.dot(cs[nb:2 * nb], B) * xs[1]
           + ca.dot(fit.series("inertia"), B) * xs[1] ** 2)
    gas = "spring:l" in series.names
    i = 2 * nb + (11 if placement else 0)   # the gas law's numbers, after the placement's
    if gas:
        G, beta, L_ext = cs[i], cs[i + 1], cs[i + 2]
        i += 3
    if gas and not placement:           # the gas strut: T(l) (-l'/M)
        u = ca.dot(fit.series("spring:l"), B) - L_ext
        acc = acc + G / (1 + beta * u) * ca.dot(fit.series("spring:a"), B)
    if placement:
        l, ldl, dq2, invM = lengths(fit, xs[0], B, cs[2 * nb + 3:2 * nb + 11])
        a_s, b_s, c_d = cs[2 * nb], cs[2 * nb + 1], cs[2 * nb + 2]
        moment = G / (1 + beta * (l - L_ext)) * ldl / l if gas else a_s * ldl / l + b_s * ldl
        acc = acc - moment * invM - c_d * dq2 * invM * xs[1]
        if placed_friction(series, placement):      # F_R |l'| (the stroke is monotone)
            acc = acc + cs[i] * ca.fabs(ldl / l) * invM
    f = ca.Function("f", [xs, cs], [ca.vertcat(xs[1], acc)], ["x", "c"], ["xdot"])
    th = ca.SX.sym("th")
    Bt = fit.basis(th)
    tau = ca.Function("tau", [th, cs], [ca.dot(fit.series("tau"), Bt),
                                        ca.dot(fit.series("dtau"), Bt)])

    def speed(x, xdot, c):  # |v_T| = -tau theta' (theta' <= 0), and h d|v_T|/dt
        t, dt = tau(x[0], c)
        return -t * x[1], -h * (dt * x[1] * x[1] + t * xdot[1])

    def rk4(x, fx, c):  # one RK4 sub-step of length h; fx = f(x) (first stage reused)
        k2 = f(x + 0.5 * h * fx, c)
        k3 = f(x + 0.5 * h * k2, c)
        k4 = f(x + h * k3, c)
        return x + h / 6 * (fx + 2 * k2 + 2 * k3 + k4)

    names = (["x0", "c", "h"], ["x1", "theta", "theta_dot", "speed"])
    if M <= UNROLL_MAX:  # unrolled in SX (cheapest to evaluate)
        x = x0
        fx = f(x, cs)
        va, ma = speed(x, fx, cs)
        ths, thds, spd, peak = [], [], [], []
        for j in range(M):
            x = rk4(x, fx, cs)
            fx = f(x, cs)
            vb, mb = speed(x, fx, cs)
            if j < M - 1:
                ths.append(x[0])
                thds.append(x[1])
            spd.append(vb)
            peak.append(hermite_max(va, ma, vb, mb))
            va, ma = vb, mb
        empty = ca.SX(0, 1)
        outs = [x, ca.vertcat(*ths) if ths else empty,
                ca.vertcat(*thds) if thds else empty, ca.vertcat(*spd, *peak)]
        interval = ca.Function("interval", [x0, cs, h], ca.cse(outs), *names)
    else:  # one SX sub-step, accumulated M times (build time independent of M)
        a = ca.SX.sym("a", 6)    # a = (x, x', v, h v')
        x, fx, va, ma = a[0:2], a[2:4], a[4], a[5]
        x1 = rk4(x, fx, cs)
        fx1 = f(x1, cs)
        vb, mb = speed(x1, fx1, cs)
        step = ca.Function("substep", [a, cs, h],
                           ca.cse([ca.vertcat(x1, fx1, vb, mb),
                                   ca.vertcat(x1, vb, hermite_max(va, ma, vb, mb))]))
        fx0 = f(x0, cs)
        start = ca.Function("start", [x0, cs, h], [ca.vertcat(x0, fx0, *speed(x0, fx0, cs))])
        accum = step.mapaccum("substeps", M)
        x0m, cm, hm = ca.MX.sym("x0", 2), ca.MX.sym("c", n_c), ca.MX.sym("h")
        _, Y = accum(start(x0m, cm, hm), ca.repmat(cm, 1, M), ca.repmat(hm, 1, M))
        outs = [Y[0:2, M - 1], Y[0, :M - 1].T, Y[1, :M - 1].T,
                ca.vertcat(Y[2, :].T, Y[3, :].T)]
        interval = ca.Function("interval", [x0m, cm, hm], outs, *names)
    return (interval, f) if with_ode else interval


def bound_interval(fit, substeps: int, with_ode: bool = False, placement: bool = False,
                   degree: int | None = None):
    """:func:`interval_function` on a lid's numeric ``fit``: ``interval(x0, q, h[, g])``
    (and ``f(x, q[, g])``), the design's parameters q, the series' numbers bound (reports
    and tests evaluate it); ``degree`` the padded degree (by default
    :func:`softclose.optimiser.parameters.padded_degree`)."""
    sym = SymbolicSeries(fit.names, fit.elements, degree or padded_degree(fit.degree))
    Lv = ca.DM(sym.values(fit))
    combine = combine_function(sym, placement)
    interval, f = interval_function(sym, substeps, with_ode=True, placement=placement)
    x, q, h = ca.MX.sym("x", 2), ca.MX.sym("q", len(PARAM_KEYS)), ca.MX.sym("h")
    g = [ca.MX.sym("g", 8)] if placement else []
    c = combine(q, *g, Lv)
    gn = ["g"] if placement else []
    bi = ca.Function("interval", [x, q, h] + g, interval.call([x, c, h]),
                     ["x0", "q", "h"] + gn, interval.name_out())
    bf = ca.Function("f", [x, q] + g, [f(x, c)], ["x", "q"] + gn, ["xdot"])
    return (bi, bf) if with_ode else bi


__all__ = ["FIT_MARGIN_DEG", "UNROLL_MAX", "END_C", "END_ANGLE", "ANGLE_MARGIN", "angle_bounds",
           "end_damper_mode", "free_of", "gas_nlp", "free_layout", "nlp_elements",
           "series_terms", "ChebyshevFit", "hermite_max", "interval_function",
           "combine_function", "bound_interval"]
