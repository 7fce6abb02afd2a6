"""The scenario NLP: one multiple-shooting problem over several scenarios of the lid.

A *scenario* is one point of the tolerance box: a model (geometry and masses: a scenario
with another lid mass has its own model and its own Chebyshev fit of the equation of
motion) and a map from the drawn design to the parameters the lid really has,

    p_s = a_s * p + b_s       (p the parameter vector (k, l0, c, c_rot, ...), elementwise;
                               a_s = 1 + relative deviation, b_s = absolute deviation)

The design d (scaled as in the nominal NLP) is shared; every scenario has its own closing
time T_s, shooting states X_s at the N nodes and peak-speed bound s_s, and its own copy of
every constraint of the problem: continuity, theta(T_s) = theta_closed, the closing-time
window on T_s, theta' <= 0 and theta >= theta_closed at every RK4 sub-step, the peak tip
speed caught by the cubic Hermite bound inside every sub-step, the lid moving down at
release, and the holding moment. The objective is

    worst:  minimise t  subject to  t >= J_s / J_ref  for every scenario (epigraph), or
    mean:   minimise the mean of J_s / J_ref,

with J_s = weight_impact theta'_s(T_s)^2 + weight_peak_tip s_s^2 in the NLP. s_s is only an
epigraph variable: with ``weight_peak_tip = 0`` nothing pins it, and in worst-case mode
nothing pins it in a scenario that is not the worst either. So a scenario's own peak tip
speed is never read from s_s but from its sub-step speeds and their Hermite maxima at the
solution (:meth:`ScenarioNLP.peaks`, as :meth:`ShootingNLP.peak` in the nominal optimiser),
and every J_s reported or compared (:meth:`ScenarioNLP.objectives`) uses that peak. Each
scenario's shooting
interval is the nominal optimiser's (``ShootingNLP.interval``: M RK4 sub-steps on the
Chebyshev series of its model, with the Hermite peak bound), so the robust and the nominal
problem share their discretisation (N, M); only the node grid differs (:func:`time_grid`:
the first two intervals are half as long, for the release transient of the stiffly damped
scenarios). The NLP is built for a given list of scenario models
(:func:`get_scenario_nlp` caches it); the a_s, b_s are parameters.
"""

from __future__ import annotations

import math
import time

import casadi as ca
import numpy as np

from ..config import Config
from ..optimiser.nlp import opening_bound
from ..problem import DESIGN_KEYS, PARAM_KEYS, SCALES, params_of

#: the parameters of p that are not design variables: NLP parameters
FIXED = PARAM_KEYS[len(DESIGN_KEYS):]
NP = len(PARAM_KEYS)

#: NLP parameters before the time grid and the scenario maps
PARAMS = ("theta0", "theta_closed", "weight_impact", "weight_peak_tip", *FIXED, "J_ref")
#: smallest closing time a scenario may take (s)
T_FLOOR = 1e-3
#: per-scenario constraint groups, in order
GROUPS = ("continuity", "theta_above_closed", "theta_dot_nonpositive", "peak_tip_speed",
          "holding_moment", "release_downwards", "epigraph", "opening_force",
          "spring_long", "spring_short", "spring_length", "keep_out")
CONVERGED = ("Solve_Succeeded", "Solved_To_Acceptable_Level")
WARM_OPTIONS = {"ipopt.warm_start_init_point": "yes", "ipopt.mu_init": 1e-6,
                "ipopt.warm_start_bound_push": 1e-9, "ipopt.warm_start_mult_bound_push": 1e-9,
                "ipopt.warm_start_slack_bound_push": 1e-9}


#: the node grid is graded (:func:`time_grid`) from this many nodes on
GRADED_MIN_NODES = 6


def time_grid(N: int) -> np.ndarray:
    """Fractions of T_s of the N shooting intervals: the first two half as long as the
    others (uniform for N < :data:`GRADED_MIN_NODES`).

    Why: robust designs sit at stiff springs and strong dampers, and the scenarios add
    +20 % to them. The lid then accelerates from rest with a time constant of ~20 ms and
    reaches its peak tip speed at ~0.07 s, inside the first interval, while a uniform
    sub-step is T/(N M) = 25 ms at T = 1 s (h |lambda| ~ 1.5). RK4's error on that
    transient decays by the rim (closing time 4e-5 relative) but not at the peak: the
    scenario's own peak tip speed was 2.9e-3 below the adaptive reference's, beyond
    VERIFY_RTOL. Halving the first two intervals (the first 10 % of the stroke at N = 10)
    cuts that to 1.2e-4 at no cost; the other intervals grow by (N-1)/(N-2) (12.5 % at
    N = 10), which moved no metric of the default problem by more than 1.2e-4 (the
    accuracy loop of :mod:`softclose.robust.design` refines M if a scenario still
    disagrees). Doubling M instead costs ~3 s more per robust optimisation.
    """
    if N < GRADED_MIN_NODES:
        return np.full(N, 1.0 / N)
    rest = (1.0 - 1.0 / N) / (N - 2)
    return np.r_[0.5 / N, 0.5 / N, np.full(N - 2, rest)]


def t_limit(cfg: Config) -> float:
    """The largest closing time the NLP allows: a stroke must close within stroke.t_max."""
    return min(cfg.optimise.closing_time_max, cfg.stroke.t_max)


def discretise(cfg: Config) -> tuple[int, int, float, list[str]]:
    """(N, M, closing-time limit, notes) of the nominal optimiser's discretisation."""
    from ..optimiser.nlp import discretisation
    d = discretisation(cfg)
    if isinstance(d, tuple):                    # the optimiser module before its split
        N, M, note = d
        return N, M, cfg.optimise.closing_time_max, [note] if note else []
    return d.nodes, d.substeps, d.t_limit, list(d.notes)


def model_config(cfg: Config, values: dict) -> Config:
    """The config of a scenario's model: ``cfg`` with its keys set that are not in the
    parameter vector (those the scenario maps as a q + b)."""
    from ..problem import PARAM_COLUMNS
    from .evaluate import with_values
    return with_values(cfg, {k: v for k, v in values.items() if k not in PARAM_COLUMNS})


def _model_key(cfg: Config) -> tuple:
    """A scenario model's key: the model's, and the elements the NLP carries."""
    from ..model import model_key
    from ..optimiser.interval import nlp_elements
    return model_key(cfg) + (tuple(e.name for e in nlp_elements(cfg)),)


def interval_of(cfg_model: Config, nodes: int, substeps: int, placement: bool = False):
    """(model, shooting-interval Function) of a scenario's model: the nominal optimiser's;
    with ``placement`` also its fit and ODE (the attachment points an input: the fit is of
    the closure, which the points do not change)."""
    from ..optimiser.cache import get_model
    from ..optimiser.interval import ChebyshevFit, interval_function, nlp_elements
    model = get_model(cfg_model)
    fit = ChebyshevFit(model, els=nlp_elements(cfg_model), pose=placement)
    if not placement:
        return model, interval_function(model, substeps, fit)
    f, ode = interval_function(model, substeps, fit, with_ode=True, placement=True)
    return model, (f, fit, ode)


class ScenarioNLP:
    """The multiple-shooting NLP of S scenarios (see the module docstring).

    ``models`` lists the scenarios' model configs (equal configs share a model and its
    interval Function). Variables: w = (d (3), t, then per scenario T_s, X_s (2N), s_s).
    """

    def __init__(self, cfg: Config, model_cfgs: list[Config], nodes: int, substeps: int,
                 robust_objective: str = "worst", tol: float = 1e-10):
        t0 = time.perf_counter()
        o = cfg.optimise
        self.N, self.M, self.S = nodes, substeps, len(model_cfgs)
        self.robust_objective = robust_objective
        N, M, S = nodes, substeps, self.S
        # free attachment points (optimise.free geometry.*), shared by every scenario
        from ..optimiser.placement import (length_bounds, placement_layout, slot_values,
                                           spring_moment)
        self.place = placement_layout(cfg)
        self.placed = bool(self.place)
        self.g0 = slot_values(cfg)
        self.nd = 3 + len(self.place)
        self.scales = np.r_[SCALES, [sc for _, _, sc in self.place]]
        # one interval Function per distinct model
        keys, self.model_index, funcs, models = [], [], [], []
        for c in model_cfgs:
            key = _model_key(c)
            if key not in keys:
                keys.append(key)
                model, f = interval_of(c, N, M, self.placed)
                models.append(model)
                funcs.append(f)
            self.model_index.append(keys.index(key))
        self.models = models
        self.scenario_models = [models[i] for i in self.model_index]
        npar = len(PARAMS)
        P = ca.MX.sym("P", npar + N + 2 * NP * S)
        theta0, thc, wi, wp = (P[i] for i in range(4))
        fixed, Jref = P[4:4 + len(FIXED)], P[npar - 1]
        grid = P[npar:npar + N]
        A = ca.reshape(P[npar + N:npar + N + NP * S], NP, S)
        B = ca.reshape(P[npar + N + NP * S:], NP, S)
        d, t = ca.MX.sym("d", self.nd), ca.MX.sym("t")
        T = [ca.MX.sym(f"T{s}") for s in range(S)]
        X = [ca.MX.sym(f"X{s}", 2, N) for s in range(S)]
        pk = [ca.MX.sym(f"s{s}") for s in range(S)]
        q = ca.vertcat(d[:3] * ca.DM(SCALES), fixed)
        if self.placed:
            gl = [ca.MX(float(v)) for v in self.g0]
            for j, (_, slot, sc) in enumerate(self.place):
                gl[slot] = d[3 + j] * sc
            gvec = ca.vertcat(*gl)
        ps = [A[:, s] * q + B[:, s] for s in range(S)]
        # the shooting intervals, one map per model over all of its scenarios' intervals
        outs: list = [None] * S
        for m, f in enumerate(funcs):
            ss = [s for s in range(S) if self.model_index[s] == m]
            if not ss:
                continue
            X0 = ca.horzcat(*[ca.horzcat(ca.vertcat(theta0, 0), X[s][:, :N - 1]) for s in ss])
            Q = ca.horzcat(*[ca.repmat(ps[s], 1, N) for s in ss])
            H = ca.horzcat(*[T[s] * grid.T / M for s in ss])
            gin = [ca.repmat(gvec, 1, N * len(ss))] if self.placed else []
            xe, a, b, sp = (f[0] if self.placed else f).map(N * len(ss))(X0, Q, H, *gin)
            for j, s in enumerate(ss):
                cols = slice(j * N, (j + 1) * N)
                outs[s] = (xe[:, cols], a[:, cols], b[:, cols], sp[:, cols])
        g, self.g_sizes, J, peaks = [], [], [], []
        for s in range(S):
            xe, a, b, sp = outs[s]
            model = self.scenario_models[s]
            Js = wi * X[s][1, N - 1] ** 2 + wp * pk[s] ** 2
            J.append(Js)
            peaks.append(ca.mmax(sp))     # the scenario's own peak: sub-steps, Hermite maxima
            none = ca.MX(0, 1)
            if self.placed:     # the spring at the shared points g (optimiser.placement)
                from .. import elements
                from ..problem import PARAM_COLUMNS
                _, fit, ode = funcs[self.model_index[s]]
                mask = np.ones(NP)
                mask[[PARAM_COLUMNS["design.spring_k"], PARAM_COLUMNS["design.spring_preload"]]] = 0
                sa, sb = elements.BY_NAME["spring"].affine(elements.params(ps[s]))
                hold = model.dV(thc, ps[s] * ca.DM(mask)) + spring_moment(fit, thc, gvec, sa, sb)
                release = ode(ca.vertcat(theta0, 0), ps[s], gvec)[1]
                L, Lmax, Lmin = length_bounds(fit, theta0, thc, gvec)
                l0 = ps[s][PARAM_COLUMNS["design.spring_rest_length"]]
                lengths = [l0 - ca.vertcat(ca.vec(L), ca.vec(Lmax)),
                           ca.vertcat(ca.vec(L), ca.vec(Lmin)) - l0,
                           ca.vertcat(ca.vec(L), ca.vec(Lmax), ca.vec(Lmin))]
            else:
                hold, release = model.dV(thc, ps[s]), model.ode(ca.vertcat(theta0, 0), ps[s])[1]
                lengths = [none, none, none]
            blocks = [ca.vec(xe - X[s]), ca.vec(a) - thc, ca.vec(b), pk[s] - ca.vec(sp),
                      hold, release, t - Js / Jref,
                      opening_bound(model, theta0, thc, ps[s]) if o.opening_force_max
                      is not None and not self.placed else none] + lengths + [
                          self._keep_out(cfg, fit, theta0, thc, gvec) if self.placed and s == 0
                          else none]
            g += blocks
            self.g_sizes.append([int(v.numel()) for v in blocks])
        self.block = sum(self.g_sizes[0])
        if robust_objective == "worst":
            f_obj = t
        else:
            f_obj = sum(J) / (S * Jref)
        w = ca.vertcat(d, t, *[ca.vertcat(T[s], ca.vec(X[s]), pk[s]) for s in range(S)])
        self.nw = int(w.numel())
        # each scenario's own peak tip speed (not s_s) and its objective with that peak
        pv = ca.vertcat(*peaks)
        thd = ca.vertcat(*[X[s][1, N - 1] for s in range(S)])
        self.peak_fn = ca.Function("peaks", [w, P], [pv])
        self.J_fn = ca.Function("J", [w, P], [wi * thd ** 2 + wp * pv ** 2])
        nlp = {"x": w, "f": f_obj, "g": ca.vertcat(*g), "p": P}
        from ..optimiser.nlp import check_linear_solver
        check_linear_solver(o.linear_solver)
        self.options = {"print_time": False, "show_eval_warnings": False, "calc_lam_p": False,
                        "ipopt.print_level": 0, "ipopt.sb": "yes", "ipopt.tol": tol,
                        "ipopt.max_iter": o.max_iter,
                        "ipopt.hessian_approximation": o.hessian,
                        "ipopt.linear_solver": o.linear_solver,
                        "ipopt.bound_relax_factor": 0.0}
        self.solver = ca.nlpsol("softclose_robust", "ipopt", nlp,
                                {**self.options, "ipopt.mu_strategy": "adaptive"})
        oracle = self.solver.oracle()
        wx, wp_ = ca.MX.sym("x", self.nw), ca.MX.sym("p", P.numel())
        fo, go = oracle(wx, wp_)
        self.warm_solver = ca.nlpsol("softclose_robust_warm", "ipopt",
                                     {"x": wx, "p": wp_, "f": fo, "g": go},
                                     {**self.options, **WARM_OPTIONS})
        self.build_time = time.perf_counter() - t0

    def _keep_out(self, cfg, fit, theta0, thc, g):
        """optimise.keep_out at the shared points (in the first scenario's block only)."""
        from ..optimiser.cache import keep_out_of
        from ..optimiser.keep_out import keep_out_constraints
        polys = keep_out_of(cfg)
        return keep_out_constraints(fit, theta0, thc, g, polys, self.place) if polys \
            else ca.MX(0, 1)

    # -- layout ------------------------------------------------------------------------
    @property
    def per(self) -> int:
        """Variables per scenario: T, X (2N), s."""
        return 2 * self.N + 2

    def offset(self, s: int) -> int:
        return self.nd + 1 + s * self.per

    def pack(self, design, t, states) -> np.ndarray:
        """w from the design (SI; k, l0, c alone: the free points from the config), t, and
        per scenario (T, X (2, N), s)."""
        d = np.asarray(design, float)
        if len(d) < self.nd:
            d = np.r_[d[:3], [self.g0[slot] for _, slot, _ in self.place]]
        parts = [d[:self.nd] / self.scales, [t]]
        for T, X, pk in states:
            parts += [[T], np.asarray(X, float).T.ravel(), [pk]]
        return np.concatenate([np.atleast_1d(np.asarray(p, float)) for p in parts])

    def unpack(self, w):
        """(design (SI), t, [(T, X (2, N), s) per scenario])."""
        w = np.asarray(w, float).ravel()
        N = self.N
        states = []
        for s in range(self.S):
            i = self.offset(s)
            states.append((float(w[i]), w[i + 1:i + 1 + 2 * N].reshape(N, 2).T,
                           float(w[i + 1 + 2 * N])))
        return w[:self.nd] * self.scales, float(w[self.nd]), states

    def params(self, cfg: Config, maps: list[tuple[np.ndarray, np.ndarray]],
               J_ref: float = 1.0) -> np.ndarray:
        o, st = cfg.optimise, cfg.stroke
        A = np.concatenate([np.asarray(a, float) for a, _ in maps])
        B = np.concatenate([np.asarray(b, float) for _, b in maps])
        return np.r_[st.theta0, st.theta_closed, o.weight_impact, o.weight_peak_tip,
                     params_of(cfg)[len(DESIGN_KEYS):], J_ref, time_grid(self.N), A, B]

    def bounds(self, cfg: Config, t_hi: list[float] | None = None,
               t_lo: list[float] | None = None, design_lb=None):
        """(lbx, ubx, lbg, ubg); ``t_hi``/``t_lo`` give per-scenario closing-time bounds
        (corrected for the discretisation error), ``design_lb`` raised lower design bounds."""
        o, st = cfg.optimise, cfg.stroke
        N = self.N
        lbx, ubx = np.full(self.nw, -np.inf), np.full(self.nw, np.inf)
        for i, key in enumerate(("spring_k", "spring_rest_length", "damper_c")):
            lo, hi = getattr(o, key)
            if design_lb is not None:
                lo = max(lo, design_lb[i])
            lbx[i], ubx[i] = lo / SCALES[i], hi / SCALES[i]
        free = {k: (lo, hi) for k, lo, hi in (o.free or ())}
        for j, (k, _, sc) in enumerate(self.place):
            lbx[3 + j], ubx[3 + j] = free[k][0] / sc, free[k][1] / sc
        if self.robust_objective != "worst":
            lbx[self.nd] = ubx[self.nd] = 0.0
        for s in range(self.S):
            i = self.offset(s)
            lbx[i] = max(o.closing_time_min if t_lo is None else t_lo[s], T_FLOOR)
            ubx[i] = t_limit(cfg) if t_hi is None else t_hi[s]
            th = slice(i + 1, i + 1 + 2 * N, 2)
            thd = slice(i + 2, i + 2 + 2 * N, 2)
            lbx[th], ubx[th] = st.theta_closed, st.theta0
            ubx[thd] = 0.0
            lbx[i + 1 + 2 * (N - 1)] = ubx[i + 1 + 2 * (N - 1)] = st.theta_closed
            lbx[i + 1 + 2 * N] = 0.0
        lo = {"continuity": 0.0, "theta_above_closed": 0.0, "theta_dot_nonpositive": -np.inf,
              "peak_tip_speed": 0.0, "holding_moment": o.holding_moment_min,
              "release_downwards": -np.inf,
              "epigraph": 0.0 if self.robust_objective == "worst" else -np.inf,
              "opening_force": -np.inf}
        hi = {"continuity": 0.0, "theta_above_closed": np.inf, "theta_dot_nonpositive": 0.0,
              "peak_tip_speed": np.inf, "holding_moment": np.inf, "release_downwards": 0.0,
              "epigraph": np.inf,
              "opening_force": np.inf if o.opening_force_max is None else o.opening_force_max}
        from ..optimiser.placement import placed_bounds
        placed_bounds(cfg, lo, hi)
        lbg = np.concatenate([np.full(n, lo[k]) for sizes in self.g_sizes
                              for k, n in zip(GROUPS, sizes)])
        ubg = np.concatenate([np.full(n, hi[k]) for sizes in self.g_sizes
                              for k, n in zip(GROUPS, sizes)])
        return lbx, ubx, lbg, ubg

    def violations(self, g, lbg, ubg) -> list[dict]:
        """Per scenario, the largest violation of each constraint group."""
        out, i = [], 0
        for sizes in self.g_sizes:
            row = {}
            for k, n in zip(GROUPS, sizes):
                gi, lo, hi = g[i:i + n], lbg[i:i + n], ubg[i:i + n]
                row[k] = float(np.max(np.maximum(np.maximum(lo - gi, gi - hi), 0.0))) if n else 0.0
                i += n
            out.append(row)
        return out

    def peaks(self, w, p) -> np.ndarray:
        """Each scenario's own peak tip speed at w: its largest sub-step speed or Hermite
        maximum (not the epigraph variable s_s, which nothing pins when weight_peak_tip is
        zero or the scenario is not the worst)."""
        return np.asarray(self.peak_fn(w, p)).ravel() * 1.0

    def objectives(self, w, p) -> np.ndarray:
        """J_s of every scenario at w (unscaled), with its own peak (:meth:`peaks`)."""
        return np.asarray(self.J_fn(w, p)).ravel() * 1.0

    def solve(self, x0, p, lbx, ubx, lbg, ubg, lam_x0=None, lam_g0=None,
              warm: bool = False) -> dict:
        """One Ipopt run; never raises (an evaluation error is a failed status)."""
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
        except RuntimeError as exc:
            return {"x": x0, "g": np.full(len(lbg), np.nan), "lam_x": None, "lam_g": None,
                    "status": f"Error: {str(exc).splitlines()[0]}", "success": False,
                    "iterations": 0, "time": time.perf_counter() - t0, "f": math.nan}
        return {"x": np.asarray(sol["x"]).ravel(), "f": float(sol["f"]),
                "g": np.asarray(sol["g"]).ravel(), "lam_x": np.asarray(sol["lam_x"]).ravel(),
                "lam_g": np.asarray(sol["lam_g"]).ravel(), "status": status,
                "success": ok and status in CONVERGED, "iterations": its,
                "time": time.perf_counter() - t0}


_NLPS: dict = {}


def get_scenario_nlp(cfg: Config, model_cfgs: list[Config], nodes: int, substeps: int,
                     robust_objective: str) -> tuple[ScenarioNLP, bool]:
    """The ScenarioNLP of these scenario models (cached); (nlp, was it cached)."""
    o = cfg.optimise
    from ..optimiser.placement import placement_layout
    key = (tuple(_model_key(c)
                 for c in model_cfgs), nodes, substeps, robust_objective, o.hessian,
           o.linear_solver, o.max_iter, o.opening_force_max is not None,
           placement_layout(cfg))
    if key in _NLPS:
        return _NLPS[key], True
    if len(_NLPS) > 16:
        _NLPS.clear()
    nlp = ScenarioNLP(cfg, model_cfgs, nodes, substeps, robust_objective)
    _NLPS[key] = nlp
    return nlp, False
