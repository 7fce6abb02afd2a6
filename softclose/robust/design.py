"""Robust design: the soft-close design that meets every constraint over the tolerance box.

``optimise_robust(cfg)`` (``softclose optimise --robust``, ``softclose.optimise(cfg,
robust=True)``):

1. **Scenarios**: the nominal lid and the 2^d corners of the ``[tolerance]`` box (d
   toleranced keys; spring and damper spreads are relative to the design, so they move
   with it). With more than :data:`MAX_CORNERS` corners (d > 4) the NLP would grow with
   2^d: it starts instead from the nominal lid and the corners worst for each constraint
   (and the objective) at the start design, found by simulating every corner in the C
   kernel (:func:`_initial_scenarios`); see 4 for how the others are guaranteed.
2. **Start**: a coarse sweep of the design box in the C kernel, each design judged over all
   scenarios; the design with the best worst-case objective that meets every constraint in
   every scenario (else the least violating one).
3. **Scenario NLP** (:mod:`softclose.robust.nlp`): one multiple-shooting NLP with the
   design shared and one set of shooting states per scenario; every constraint in every
   scenario; the worst (or mean) scenario objective through an epigraph variable. As in the
   nominal optimiser, the RK4 sub-steps are doubled while the worst scenario's objective
   differs from an accurate simulation by more than 1e-4 (or any scenario's own objective,
   impact speed or peak tip speed by more than half the verification tolerance), and each
   scenario's closing-time bounds are corrected for the NLP's own discretisation error.
   A scenario's own peak tip speed (and so its J) is read from its sub-step speeds and
   their Hermite maxima, never from its epigraph variable (:mod:`softclose.robust.nlp`).
4. **Interior worst cases**: the worst case need not be a corner. After each solve a Monte
   Carlo pass (uniform in the box, C kernel) looks for samples that break a constraint or
   exceed the worst-case objective; the worst two, each improved by a local ascent in the
   box, join the scenarios and the NLP is re-solved from the previous answer's primal point,
   until none is found ("local reduction", Zagorowska et al., arXiv 2204.14145). In the
   same pass all 2^d corners are simulated in the kernel (:func:`_check_corners`) and every
   violating corner not yet a scenario joins too, so that, whatever subset the NLP started
   from, every corner of the box closes within the window and holds shut at the answer
   (``corner_check`` in the result; a corner still violating fails the result).
5. **Verification**: every scenario is re-simulated by the adaptive reference (CVODES on the
   exact equations) with every constraint checked, and the NLP's own numbers of it (closing
   time, impact speed, peak tip speed, holding moment, J) compared with the reference's
   (``scenarios[i].agreement``; a scenario is ``verified`` when both hold); the yield of
   the robust design and of the nominal optimum are estimated on the same Monte Carlo
   samples of the configured distribution (:mod:`softclose.robust.analysis`). When the yield falls short of
   ``required_yield`` (a normal distribution has tails beyond the 3-sigma box), the box is
   widened by 15 % and the design re-solved, at most three times.

When no design meets the constraints over the box, the result says which constraint fails in
which scenario and by how much, and how far the spreads would have to shrink (the largest
fraction of them for which the scenario NLP still has a solution, by bisection).
"""

from __future__ import annotations

import itertools
import math
import time
from dataclasses import dataclass, field

import numpy as np

from ..config import Config, check_batch
from ..errors import ConfigError, NumericalError
from ..problem import (DESIGN_KEYS, METRIC_KEYS, PARAM_KEYS, VERIFY_RTOL, describe, design_of,
                       objective, params_of, with_designs)
from .analysis import YieldResult, analyse_samples
from .box import Box, box_of
from .evaluate import evaluate, simulator, slow_keys
from .nlp import (T_FLOOR, ScenarioNLP, discretise, get_scenario_nlp, model_config, t_limit,
                  time_grid)
from .stats import CI_METHOD, margins
from .verify import reference_check

#: most corners of the box that enter the scenario NLP all together (d <= 4 keys). Each
#: scenario adds 2N + 2 variables and a copy of every constraint to the NLP, and one
#: reference re-simulation: with five keys tolerance (33 scenarios) one solve took 2.4 s
#: and a warm re-solve up to 10 s, against 0.5 s for the default nine. Beyond it the NLP
#: starts from the corners that matter (:func:`_initial_scenarios`) and every one of the
#: 2^d corners is simulated in the kernel after each solve instead (:func:`_check_corners`:
#: 2^d strokes, milliseconds), the violating ones joining the scenarios.
MAX_CORNERS = 16
#: most toleranced keys that need a model per value (geometry, crank masses, stroke
#: angles): each corner check builds 2^s models (~0.04 s each; 2^8: ~10 s). With the five
#: kernel-column keys (design, rotary damper, lid mass) that bounds d by 13 (8192 corners,
#: ~0.1 s a check)
MAX_SLOW_KEYS = 8
#: Monte Carlo samples of each interior worst-case search (uniform in the box)
CHECK_SAMPLES = 4096
#: the same when a toleranced key needs a model per sample (geometry, crank masses ...)
SLOW_CHECK_SAMPLES = 256
#: most yield samples of the robust optimiser when a key needs a model per sample
SLOW_YIELD_SAMPLES = 2000
#: scenarios added per search round, and the most rounds
ADD_PER_ROUND = 2
MAX_ROUNDS = 6
#: a sample counts as violating when its relative margin is below -MC_TOL (the kernel's
#: closing-time error at the default step is ~1e-7 s) or its objective exceeds the worst
#: scenario's by more than OBJ_RTOL
MC_TOL = 1e-6
OBJ_RTOL = 1e-3
#: the NLP's worst-scenario objective must agree with an accurate simulation to this
REFINE_RTOL = 1e-4
#: and every scenario's own objective, impact speed and peak tip speed to this (half the
#: reference's VERIFY_RTOL, the rest left for the verification's margin)
AGREE_RTOL = VERIFY_RTOL / 2
MAX_REFINE = 3
#: box widening when the yield falls short (normal distribution), and how often
WIDEN = 1.15
MAX_WIDEN = 3
#: samples near the boundary re-simulated by the reference in each yield estimate
YIELD_REFERENCE = 1


@dataclass(frozen=True)
class Scenario:
    """One point of the tolerance box, in unit coordinates (z = ±1 at the faces)."""

    z: tuple
    origin: str           # "nominal", "corner", "Monte Carlo, round r"


@dataclass(frozen=True)
class RobustResult:
    """The robust design, its scenarios, its verification and its yield beside the nominal
    optimum's. A failure is reported in it (``success`` False, ``message``), never raised."""

    success: bool
    message: str
    status: str
    design: dict | None
    objective: float | None
    robust_objective: str
    metrics: dict | None
    scenarios: list
    verification: dict | None
    yield_result: YieldResult | None
    nominal: dict
    nominal_yield: YieldResult | None
    box: dict
    box_scale: float
    rounds: list
    problem: dict
    solver: dict
    infeasibility: dict | None = None
    notes: tuple = ()
    times: dict = field(default_factory=dict)
    #: every corner of the box simulated in the kernel at the design: corners, violating,
    #: worst_margin, breaking (labels of corners outside the NLP that break a constraint),
    #: in_nlp (corners among the scenarios), scenarios (how many the NLP had)
    corner_check: dict | None = None

    @property
    def yield_(self) -> float | None:
        return None if self.yield_result is None else self.yield_result.yield_

    @property
    def yield_ci(self) -> tuple | None:
        return None if self.yield_result is None else self.yield_result.yield_ci

    def to_json(self) -> dict:
        from ..jsonio import jsonable
        out = {"success": self.success, "status": self.status, "message": self.message,
               "design": self.design, "objective": self.objective,
               "robust_objective": self.robust_objective}
        for k in METRIC_KEYS:
            out[k] = None if self.metrics is None else self.metrics.get(k)
        y = self.yield_result
        out.update({
            "verification": self.verification,
            "yield": None if y is None else y.yield_,
            "yield_ci": None if y is None else list(y.yield_ci),
            "ci_method": CI_METHOD,
            "required_yield": None if y is None else y.required_yield,
            "samples": None if y is None else y.samples,
            "distribution": None if y is None else y.distribution,
            "percentiles": None if y is None else y.percentiles,
            "failures": None if y is None else y.failures,
            "scenarios": self.scenarios,
            "nominal": self.nominal,
            "box": self.box, "box_scale": self.box_scale,
            "rounds": self.rounds, "problem": self.problem, "solver": self.solver,
            "times": self.times})
        if self.corner_check is not None:
            out["corner_check"] = self.corner_check
        if self.infeasibility is not None:
            out["infeasibility"] = self.infeasibility
        if self.notes:
            out["notes"] = list(self.notes)
        return jsonable(out)

    def to_frame(self):
        """One row per scenario: the toleranced values, the NLP's metrics, the reference's
        verdict."""
        import pandas as pd
        rows = []
        for s in self.scenarios:
            row = {"scenario": s["label"], "origin": s["origin"], **s["values"]}
            row.update({k: s.get("metrics", {}).get(k) for k in METRIC_KEYS})
            row["objective"] = s.get("objective")
            row["verified"] = s.get("verified")
            rows.append(row)
        return pd.DataFrame(rows)

    def plot(self):
        """Histograms of closing time and impact speed, nominal against robust design, over
        the same samples (a Figure)."""
        from ..figures.robust import plot_yield
        if self.yield_result is None:
            raise ValueError("no robust design: nothing to plot")
        ys = [y for y in (self.nominal_yield, self.yield_result) if y is not None]
        labels = (["nominal optimum"] if self.nominal_yield is not None else []) + \
            ["robust design"]
        return plot_yield(ys, labels)


# -- scenarios ------------------------------------------------------------------------------------
def _maps(box: Box, z) -> tuple[np.ndarray, np.ndarray, dict]:
    """(a, b, model values) of the point z: p = a * p_design + b (the parameter vector,
    PARAM_KEYS), model keys."""
    a, b, values = np.ones(len(PARAM_KEYS)), np.zeros(len(PARAM_KEYS)), {}
    for j, key in enumerate(box.keys):
        name = key.removeprefix("design.")
        if name in PARAM_KEYS:
            col = PARAM_KEYS.index(name)
            zj = max(z[j], box.z_min[j])
            if box.relative[j]:
                a[col] = 1.0 + box.spreads[j] * zj
            else:
                b[col] = box.spreads[j] * zj
        else:
            values[key] = float(box.nominal[j] + box.half[j] * max(z[j], box.z_min[j]))
    return a, b, values


def _scenario_rows(box: Box, designs: np.ndarray, Z: np.ndarray, cfg: Config):
    """Evaluation rows of every design (G, 3) in every scenario (S, d): (keys, X (G S, .))."""
    keys = [f"design.{k}" for k in PARAM_KEYS] + [k for k in box.keys
                                                   if not k.startswith("design.")]
    rows = []
    for q in with_designs(cfg, np.atleast_2d(designs)):
        for z in Z:
            a, b, vals = _maps(box, z)
            rows.append(np.r_[a * q + b, [vals[k] for k in keys[len(PARAM_KEYS):]]])
    return keys, np.array(rows)


def _start_design(cfg: Config, box: Box, Z: np.ndarray,
                  shape=(8, 6, 8)) -> tuple[np.ndarray, dict]:
    """The design of a coarse sweep with the best worst-case objective over the scenarios."""
    o = cfg.optimise
    axes = [np.linspace(*getattr(o, k), n) for k, n in zip(DESIGN_KEYS, shape)]
    G = np.array(np.meshgrid(*axes, indexing="ij")).reshape(3, -1).T
    keys, X = _scenario_rows(box, G, Z, cfg)
    cols = evaluate(cfg, keys, X, t_end=_t_end(cfg))
    S = len(Z)
    m = margins(cols, o).reshape(len(G), S)
    J = np.asarray(cols["objective"], float).reshape(len(G), S)
    viol = np.where(np.isfinite(m), np.maximum(-m, 0.0), 10.0).sum(axis=1)
    Jf = np.where(np.isfinite(J), J, np.inf)      # a stroke without an objective: inf
    Jw = Jf.max(axis=1) if cfg.tolerance.robust_objective == "worst" else Jf.mean(axis=1)
    feasible = viol == 0
    if feasible.any():
        i = int(np.argmin(np.where(feasible, Jw, np.inf)))
    else:
        i = int(np.argmin(viol))
    return G[i], {"evaluated": int(len(G)), "scenarios": S, "robust_feasible": int(feasible.sum()),
                  "start": dict(zip(DESIGN_KEYS, map(float, G[i]))),
                  "start_worst_objective": float(Jw[i]) if feasible.any() else None}


def _guess(cfg_m: Config, p: np.ndarray, N: int, t_lo: float, t_hi: float):
    """(T, X (2, N), peak, J) of a scenario from its simulated stroke at parameters p."""
    st, o = cfg_m.stroke, cfg_m.optimise
    sim = simulator(cfg_m)
    frac = np.minimum(np.cumsum(time_grid(N)), 1.0)     # node times / T
    r = sim.run(p, trajectory=True, estimate_error=False)
    if r.ok and r.trajectory is not None:
        tr = r.trajectory
        T = r.closing_time if r.closed else tr["t"][-1]
        T = float(np.clip(T, t_lo, t_hi))
        tn = T * frac
        X = np.vstack([np.interp(tn, tr["t"], tr["theta"]),
                       np.minimum(np.interp(tn, tr["t"], tr["theta_dot"]), 0.0)])
        peak = float(np.max(tr["tip_speed"][tr["t"] <= T + 1e-12]))
    else:
        T = t_hi
        X = np.vstack([st.theta0 + frac * (st.theta_closed - st.theta0),
                       np.full(N, (st.theta_closed - st.theta0) / T)])
        peak = 1.0
    X[0, -1] = st.theta_closed
    J = objective(o, float(X[1, -1]), peak)
    return T, X, peak, (J if J is not None and math.isfinite(J) else 1.0)


class _Problem:
    """The scenario set of one box and the solves over it (state carried between rounds)."""

    def __init__(self, cfg: Config, scale: float, scenarios: list[Scenario], N: int, M: int):
        self.cfg, self.scale, self.scenarios, self.N, self.M = cfg, scale, scenarios, N, M
        self.box = box = box_of(cfg, scale=scale)
        self.maps = [_maps(box, np.asarray(s.z)) for s in scenarios]
        self.model_cfgs = [model_config(cfg, v) for _, _, v in self.maps]
        self.nlp, cached = get_scenario_nlp(cfg, self.model_cfgs, N, M,
                                            cfg.tolerance.robust_objective)
        self.build_time = 0.0 if cached else self.nlp.build_time
        o = cfg.optimise
        self.t_hi = [t_limit(cfg)] * len(scenarios)
        self.t_lo = [max(o.closing_time_min, T_FLOOR)] * len(scenarios)
        # absolute spreads of design keys must not take a scenario below zero
        self.design_lb = np.zeros(3)
        for j, key in enumerate(box.keys):
            name = key.removeprefix("design.")
            if name in DESIGN_KEYS and not box.relative[j]:
                self.design_lb[DESIGN_KEYS.index(name)] = box.spreads[j]

    def param(self, design) -> np.ndarray:
        return with_designs(self.cfg, np.asarray(design, float)[:3])

    def scenario_params(self, design, s: int) -> np.ndarray:
        a, b, _ = self.maps[s]
        return a * self.param(design) + b

    def initial(self, design, prev: "_Run | None" = None):
        """Primal start: a previous answer's states where it has them, simulated strokes
        for the new scenarios."""
        o = self.cfg.optimise
        states, Js = [], []
        for s in range(len(self.scenarios)):
            if prev is not None and s < prev.problem.nlp.S:
                # s_s from the scenario's own peak (the epigraph variable may be anywhere
                # above it when nothing pins it)
                T, X, _ = prev.states[s]
                pk = float(prev.peaks[s])
                states.append((T, X, pk))
                Js.append(objective(o, float(X[1, -1]), pk))
                continue
            T, X, pk, J = _guess(self.model_cfgs[s], self.scenario_params(design, s), self.N,
                                 self.t_lo[s], self.t_hi[s])
            states.append((T, X, pk))
            Js.append(J)
        J_ref = prev.J_ref if prev is not None else max(max(Js), 1e-8)
        t = max(Js) / J_ref
        return self.nlp.pack(design, t, states), J_ref

    def solve(self, x0, J_ref, lam=None) -> "_Run":
        nlp = self.nlp
        p = nlp.params(self.cfg, [(a, b) for a, b, _ in self.maps], J_ref)
        lbx, ubx, lbg, ubg = nlp.bounds(self.cfg, self.t_hi, self.t_lo, self.design_lb)
        if lam is not None:
            r = nlp.solve(x0, p, lbx, ubx, lbg, ubg, lam[0], lam[1], warm=True)
        else:
            r = nlp.solve(x0, p, lbx, ubx, lbg, ubg)
        return _Run(self, r, p, J_ref, (lbx, ubx, lbg, ubg))


class _Run:
    """One solve of a _Problem."""

    def __init__(self, problem: _Problem, r: dict, p, J_ref, bounds):
        self.problem, self.r, self.p, self.J_ref, self.bounds = problem, r, p, J_ref, bounds
        self.success = r["success"]
        self.design, self.t, self.states = problem.nlp.unpack(r["x"])
        # each scenario's own peak tip speed and objective (sub-step speeds and Hermite
        # maxima, not the epigraph variables: see softclose.robust.nlp)
        self.peaks = problem.nlp.peaks(r["x"], p)
        self.J = problem.nlp.objectives(r["x"], p)
        self.violations = problem.nlp.violations(r["g"], bounds[2], bounds[3]) \
            if np.all(np.isfinite(r["g"])) else None

    def extended_lam(self, nlp: ScenarioNLP):
        """The multipliers, with zeros for the scenarios a bigger NLP adds."""
        if self.r["lam_x"] is None:
            return None
        old = self.problem.nlp
        extra = nlp.S - old.S
        lam_x = np.r_[self.r["lam_x"], np.zeros(extra * nlp.per)]
        lam_g = np.r_[self.r["lam_g"], np.zeros(extra * nlp.block)]
        return lam_x, lam_g


# -- the accuracy loop: sub-steps and closing-time bounds -----------------------------------------
def _accurate(problem: _Problem, design) -> list:
    """Each scenario's stroke by the C kernel at a small step: (closed, T, J, impact
    theta', peak tip speed) per scenario."""
    out = []
    for s, c in enumerate(problem.model_cfgs):
        sim = simulator(c.replace(simulate={"step": min(c.simulate.step, 1e-3)}))
        r = sim.run(problem.scenario_params(design, s), estimate_error=False)
        out.append((r.closed, r.closing_time,
                    objective(c.optimise, r.impact_theta_dot, r.peak_tip_speed),
                    r.impact_theta_dot, r.peak_tip_speed))
    return out


def _inaccurate(run: _Run, sims: list) -> str | None:
    """Why the NLP's discretisation is too coarse at ``run`` (None if it is not): the worst
    scenario's objective differs from the accurate simulation by more than REFINE_RTOL, or
    some scenario's own impact speed, peak tip speed or objective by more than AGREE_RTOL
    (they are reported per scenario and must agree with the reference to VERIFY_RTOL)."""
    w = int(np.argmax(run.J))
    closed, _, Js, _, _ = sims[w]
    if closed and Js is not None and abs(run.J[w] - Js) > REFINE_RTOL * abs(Js):
        return f"worst-scenario objective {run.J[w]:.6g} differed from the simulated {Js:.6g}"
    for s, (closed, _, Js, thd, pk) in enumerate(sims):
        if not closed:
            continue
        own = {"objective": (run.J[s], Js), "impact_theta_dot": (run.states[s][1][1, -1], thd),
               "peak_tip_speed": (run.peaks[s], pk)}
        for k, (a, b) in own.items():
            if b is not None and math.isfinite(b) and abs(a - b) > AGREE_RTOL * abs(b):
                return (f"scenario {s}: its {k} {a:.6g} differed from the simulated {b:.6g} by "
                        f"more than {AGREE_RTOL:g} (relative)")
    return None


def _polish(problem: _Problem, run: _Run, notes: list) -> tuple[_Problem, _Run]:
    """Refine the sub-steps and correct the closing-time bounds (see the module docstring)."""
    o = problem.cfg.optimise
    for _ in range(MAX_REFINE):
        why = _inaccurate(run, _accurate(problem, run.design))
        if why is None:
            break
        finer = _Problem(problem.cfg, problem.scale, problem.scenarios, problem.N,
                         2 * problem.M)
        finer.t_hi, finer.t_lo = list(problem.t_hi), list(problem.t_lo)
        r2 = finer.solve(run.r["x"], run.J_ref)
        if not r2.success:
            break
        notes.append(f"{why}: sub-steps doubled to {finer.M}")
        problem, run = finer, r2
    for _ in range(3):
        sims = _accurate(problem, run.design)
        changed = False
        for s, (closed, T, *_) in enumerate(sims):
            if not closed:
                continue
            T_nlp = run.states[s][0]
            if T > o.closing_time_max * (1 + 1e-9):
                problem.t_hi[s] = min(problem.t_hi[s], T_nlp - (T - o.closing_time_max)
                                      - 1e-9 * o.closing_time_max)
                changed = True
            elif o.closing_time_min > 0 and T < o.closing_time_min * (1 - 1e-9):
                problem.t_lo[s] = max(problem.t_lo[s], T_nlp + (o.closing_time_min - T)
                                      + 1e-9 * o.closing_time_min)
                changed = True
        if not changed:
            break
        # from the previous primal point (Ipopt's warm-start mode with the multipliers took
        # 54 iterations and 10.7 s against 11 and 1.8 s with five keys tolerance; 6 against
        # 10 iterations, the same time, on the default problem)
        r2 = problem.solve(run.r["x"], run.J_ref)
        if not r2.success:
            r2 = problem.solve(run.r["x"], run.J_ref, (run.r["lam_x"], run.r["lam_g"]))
            if not r2.success:
                break
        run = r2
        notes.append("closing-time bounds of some scenarios corrected for the NLP's "
                     "discretisation error")
    return problem, run


# -- interior worst cases -------------------------------------------------------------------------
def _scores(cfg: Config, c: Config, box_d: Box, z: np.ndarray, Jmax: float,
            cut: bool = True, cols: dict | None = None):
    """(score, margin) of unit points z at the design of ``c``: the score is the worst
    relative constraint violation (-margin; for a lid that does not close, 10 + the lowest
    angle it reached, so that lids stopping higher score higher) or, in worst-case mode,
    the objective's excess over the worst scenario's, scaled so that an excess of OBJ_RTOL
    scores like a violation of MC_TOL. ``cut``: strokes end shortly after the closing-time
    limit (fast; later closings count as not closed); ``cols``: their kernel columns, if
    already simulated."""
    t_end = _t_end(cfg) if cut else None
    if cols is None:
        cols = evaluate(c, box_d.keys, box_d.values(z), t_end=t_end)
    m = margins(cols, cfg.optimise)
    th = np.nan_to_num(np.asarray(cols["theta_min"], float), nan=10.0)
    score = np.where(np.isfinite(m), -m, 10.0 + th)
    if cfg.tolerance.robust_objective == "worst":
        J = np.asarray(cols["objective"], float)
        score = np.maximum(score, np.where(np.isfinite(J), (J - Jmax) / Jmax * MC_TOL / OBJ_RTOL,
                                           0.0))
    return score, m


def _climb(cfg, c, box_d, z, f, Jmax, step: float = 0.5, min_step: float = 1e-3):
    """Local ascent of the score from a violating sample (compass search in the box):
    sampling finds the region of a worst case, this finds its point (often a face or
    corner of the box)."""
    d = box_d.dim
    E = np.vstack([np.eye(d), -np.eye(d)])
    f = float(_scores(cfg, c, box_d, z[None, :], Jmax, cut=False)[0][0])  # whole stroke
    while step >= min_step:
        cand = np.clip(z + step * E, -1.0, 1.0)
        fs, _ = _scores(cfg, c, box_d, cand, Jmax, cut=False)
        i = int(np.argmax(fs))
        if fs[i] > f * (1 + 1e-9) + 1e-15:
            z, f = cand[i], float(fs[i])
        else:
            step /= 2
    return z, f


def _search(cfg: Config, scale: float, run: _Run, seed: int, n: int) -> tuple[list, dict]:
    """Points inside the box that break a constraint or exceed the worst objective: the
    highest-scoring of ``n`` uniform samples (:func:`_scores`), each improved by a local
    ascent (:func:`_climb`); those scoring above MC_TOL become scenarios."""
    box_d = box_of(cfg, dict(zip(DESIGN_KEYS, run.design)), scale=scale)
    z = box_d.draw(n, seed, "uniform")
    c = cfg.with_design(**dict(zip(DESIGN_KEYS, map(float, run.design))))
    Jmax = float(np.max(run.J))
    score, m = _scores(cfg, c, box_d, z, Jmax)
    bad = score > MC_TOL
    picks = []
    for i in np.argsort(-score)[:ADD_PER_ROUND]:
        if not bad[i]:
            break
        zi, fi = _climb(cfg, c, box_d, z[i], float(score[i]), Jmax)
        if all(np.max(np.abs(zi - zj)) > 1e-6 for zj, _ in picks):
            picks.append((zi, fi))
    info = {"samples": int(n), "violating": int(bad.sum()),
            "worst_margin": float(np.min(m)) if len(m) else None,
            "added": [box_d.label(zi) for zi, _ in picks],
            "added_scores": [fi for _, fi in picks]}
    return [tuple(map(float, zi)) for zi, _ in picks], info


# -- the whole procedure --------------------------------------------------------------------------
def _nominal(cfg: Config) -> dict:
    """The nominal optimum (no tolerances), for the start and the comparison."""
    from ..optimiser import optimise
    res = optimise(cfg, verify=False)
    return {"success": bool(res.success), "design": res.design, "objective": res.objective,
            "message": res.message}


def _solve_box(cfg: Config, scale: float, scenarios: list, N: int, M: int, start,
               seed: int, notes: list, rounds: list, bar) -> tuple[_Problem, _Run | None]:
    """Solve over ``scenarios``, then add interior worst cases and violating corners until
    none is found (the corner check only adds corners that are not yet scenarios)."""
    problem = _Problem(cfg, scale, scenarios, N, M)
    x0, J_ref = problem.initial(start)
    run = problem.solve(x0, J_ref)
    rounds.append({"scenarios": len(scenarios), "status": run.r["status"],
                   "iterations": run.r["iterations"], "solve_time": run.r["time"],
                   "build_time": problem.build_time})
    if not run.success:
        return problem, run
    problem, run = _polish(problem, run, notes)
    for k in range(MAX_ROUNDS):
        bar.update(min(2 + k, 8), f"searching the box ({len(problem.scenarios)} scenarios)")
        n_check = SLOW_CHECK_SAMPLES if slow_keys(cfg.tolerance.keys) else CHECK_SAMPLES
        new, info = _search(cfg, scale, run, seed + 1 + k, n_check)
        corners, cinfo = _check_corners(cfg, scale, run,
                                        [s.z for s in problem.scenarios] + list(new))
        rounds[-1].update(search=info, corner_check=cinfo)
        if not new and not corners:
            break
        scen = problem.scenarios + [Scenario(z, f"Monte Carlo, round {k + 1}") for z in new] \
            + [Scenario(z, f"corner check, round {k + 1}") for z in corners]
        n_new = len(new) + len(corners)
        bigger = _Problem(cfg, scale, scen, problem.N, problem.M)
        bigger.t_hi = problem.t_hi + [t_limit(cfg)] * n_new
        bigger.t_lo = problem.t_lo + [max(cfg.optimise.closing_time_min, T_FLOOR)] * n_new
        x0, _ = bigger.initial(run.design, run)
        # from the previous answer's primal point: with the new scenarios' multipliers
        # unknown, Ipopt's warm-start mode took 3x the iterations in tests (54 against 17)
        r2 = bigger.solve(x0, run.J_ref)
        if not r2.success:
            r2 = bigger.solve(x0, run.J_ref, run.extended_lam(bigger.nlp))
        rounds.append({"scenarios": len(scen), "status": r2.r["status"],
                       "iterations": r2.r["iterations"], "solve_time": r2.r["time"],
                       "build_time": bigger.build_time})
        if not r2.success:
            return bigger, r2
        problem, run = _polish(bigger, r2, notes)
    else:
        notes.append(f"the interior search and corner check still found violating points "
                     f"after {MAX_ROUNDS} rounds")
    return problem, run


def fractional_factorial(d: int) -> np.ndarray:
    """A regular two-level fractional factorial of resolution >= III in d factors: (n, d)
    of ±1 with n = 2^m the smallest power of two above d.

    Columns are the m base factors of the full 2^m factorial, then their products, highest
    order first (4 factors: A, B, C, ABC, resolution IV). Distinct products are never equal
    or opposite, so no main effect is aliased with another: every key is at each level in
    half the runs and every pair of keys in all four combinations (X^T X = n I), and the
    mean over the runs of any function additive in the keys is the full factorial's.
    """
    if d <= 0:
        return np.zeros((1, 0))
    m = max(1, math.ceil(math.log2(d + 1)))
    base = np.array(list(itertools.product((-1.0, 1.0), repeat=m)))
    ones = [1 << i for i in range(m)]
    rest = sorted((u for u in range(1, 1 << m) if u not in ones),
                  key=lambda u: (-bin(u).count("1"), u))
    cols = [np.prod(base[:, [i for i in range(m) if u >> i & 1]], axis=1)
            for u in (ones + rest)[:d]]
    return np.column_stack(cols)


def _corner_columns(cfg: Config, scale: float, design):
    """(box at ``design``, its corners Z (2^d, d), cfg with ``design``, the kernel's columns
    of every corner); a box without a dimension has no corners (Z empty, columns None)."""
    design = dict(zip(DESIGN_KEYS, map(float, design)))
    box_d = box_of(cfg, design, scale=scale)
    c = cfg.with_design(**design)
    if not box_d.dim:
        return box_d, np.zeros((0, 0)), c, None
    Z = box_d.corners()
    return box_d, Z, c, evaluate(c, box_d.keys, box_d.values(Z), t_end=_t_end(cfg))


def _t_end(cfg: Config) -> float:
    """Where the kernel may cut a stroke in the robust searches: anything slower is
    infeasible anyway (the closing window ends before it), with a margin."""
    return 1.05 * t_limit(cfg) + 0.05


def _worst_corners(cfg: Config, scale: float, design) -> list[tuple[tuple, str]]:
    """The corners of the box worst for each constraint, and for the objective in
    worst-case mode, at ``design``: (z, why) for each distinct one.

    Every corner is simulated in the kernel (2^d strokes: what one NLP scenario costs
    buys thousands of them), so the worst corner is exact at the design, not a first-order
    guess: the slowest (a lid that does not close counts as slowest, the one stopping
    highest first), the fastest (when closing_time_min > 0), the weakest holding moment,
    the one closest to rebounding (only when one rebounds), the largest J.
    """
    _, Z, _, cols = _corner_columns(cfg, scale, design)
    out: dict = {}
    for why, v in _badness(cfg, cols).items():
        z = tuple(map(float, Z[int(np.argmax(v))]))
        out[z] = f"{out[z]}, {why}" if z in out else why
    return list(out.items())


def _badness(cfg: Config, cols: dict) -> dict:
    """How bad each stroke of ``cols`` is for each constraint (and the objective in
    worst-case mode): larger is worse (see :func:`_worst_corners`)."""
    o = cfg.optimise
    closed = np.asarray(cols["closed"], bool)
    ct = np.asarray(cols["closing_time"], float)
    th = np.nan_to_num(np.asarray(cols["theta_min"], float), nan=10.0)
    worst = {"slowest": np.where(closed, ct, 1e3 + th),
             "weakest holding moment": np.nan_to_num(-np.asarray(cols["holding_moment"], float),
                                                     nan=-np.inf)}
    if o.closing_time_min > 0:
        worst["fastest"] = np.where(closed, -ct, -np.inf)
    tdm = np.nan_to_num(np.asarray(cols["theta_dot_max"], float), nan=-np.inf)
    if np.any(tdm > 0):
        worst["rebound"] = tdm
    if cfg.tolerance.robust_objective == "worst":
        J = np.asarray(cols["objective"], float)
        if np.any(np.isfinite(J)):
            worst["largest J"] = np.where(np.isfinite(J), J, -np.inf)
    return worst


def _initial_scenarios(box: Box, cfg: Config | None = None, designs=(),
                       scale: float = 1.0) -> list[Scenario]:
    """The scenarios the NLP starts from: the nominal lid and every corner of the box when
    there are at most :data:`MAX_CORNERS` of them (or no ``cfg`` is given).

    Beyond, the nominal lid and, at each of ``designs``, the corners worst for each
    constraint and for the objective (:func:`_worst_corners`); in mean mode also a
    resolution-III fraction of the corners (:func:`fractional_factorial`, 8 or 16 runs),
    so that the mean objective is not an average over worst cases only.

    Why these: each constraint that binds in a robust design is set by one extreme lid (the
    slowest closes last, the weakest spring holds least, one lid has the worst J), and the
    scenario NLP needs exactly those; the other corners only cost size. Which corner is
    worst can change as the NLP moves the design: the corner check after every solve
    (:func:`_check_corners`) adds any that then violates, so the result still holds at
    every corner. (A fraction or a first-order model would guess the worst corners; the
    kernel simulates them all for less than one NLP scenario costs.)
    """
    out = [Scenario(tuple([0.0] * box.dim), "nominal")]
    if not box.dim:
        return out
    if 2 ** box.dim <= MAX_CORNERS or cfg is None:
        return out + [Scenario(tuple(map(float, z)), "corner") for z in box.corners()]
    seen = {out[0].z}
    for design in designs:
        for z, why in _worst_corners(cfg, scale, design):
            if z not in seen:
                seen.add(z)
                out.append(Scenario(z, f"corner ({why})"))
    if cfg.tolerance.robust_objective == "mean":
        for z in fractional_factorial(box.dim):
            z = tuple(map(float, z))
            if z not in seen:
                seen.add(z)
                out.append(Scenario(z, "corner (fractional factorial)"))
    return out


def _check_corners(cfg: Config, scale: float, run: "_Run", have=()) -> tuple[list, dict]:
    """Every corner of the box at the design of ``run``, in the kernel. A corner violates
    when it breaks a constraint by more than MC_TOL or, in worst-case mode, its J exceeds
    the worst scenario's by more than OBJ_RTOL (as in :func:`_scores`). Returns the
    violating corners to add -- among those not in ``have`` (unit points), the most
    violating one and the worst for each constraint and the objective (:func:`_badness`):
    at most six a round, so that a poor design (say the nominal optimum, where most
    corners fail) does not bring all 2^d corners into the NLP at once -- and a summary
    (``breaking``: every corner outside ``have`` that breaks a constraint)."""
    box_d, Z, c, cols = _corner_columns(cfg, scale, run.design)
    if not len(Z):
        return [], {"corners": 0, "violating": 0, "breaking": [], "added": []}
    score, m = _scores(cfg, c, box_d, Z, float(np.max(run.J)), cols=cols)
    H = np.array([h for h in have if len(h) == box_d.dim]).reshape(-1, box_d.dim)
    outside = np.array([not len(H) or np.min(np.max(np.abs(H - z), axis=1)) > 1e-6
                        for z in Z])
    bad = (score > MC_TOL) & outside
    picks = []
    if bad.any():
        crit = {"most violating": score, **_badness(cfg, cols)}
        for v in crit.values():
            i = int(np.argmax(np.where(bad, v, -np.inf)))
            if bad[i] and i not in picks:
                picks.append(i)
    breaking = [box_d.label(Z[i]) for i in np.nonzero(outside & (m < -MC_TOL))[0]]
    return [tuple(map(float, Z[i])) for i in picks], {
        "corners": int(len(Z)), "violating": int(np.sum(score > MC_TOL)),
        "worst_margin": float(np.min(m)) if np.all(np.isfinite(m)) else -math.inf,
        "breaking": breaking, "added": [box_d.label(Z[i]) for i in picks]}


def _scenario_report(cfg, problem: _Problem, run: _Run, verify: bool) -> tuple[list, bool]:
    """Per scenario: its values, the NLP's metrics and the reference's verdict."""
    box_d = box_of(cfg, dict(zip(DESIGN_KEYS, run.design)), scale=problem.scale)
    out, ok_all = [], True
    worst = int(np.argmax(run.J))
    for s, sc in enumerate(problem.scenarios):
        z = np.asarray(sc.z)
        T, X, _ = run.states[s]
        p = problem.scenario_params(run.design, s)
        model = problem.nlp.scenario_models[s]
        metrics = {"closed": True, "closing_time": T, "impact_theta_dot": float(X[1, -1]),
                   "peak_tip_speed": float(run.peaks[s]),
                   "holding_moment": model.holding_moment(p)}
        entry = {"label": box_d.label(z), "origin": sc.origin,
                 "values": {k: float(v) for k, v in zip(box_d.keys, box_d.values(z)[0])},
                 "z": list(map(float, z)), "metrics": metrics, "objective": float(run.J[s]),
                 "worst": s == worst}
        if verify:
            # the NLP's own numbers of this scenario against the reference's
            c_d = cfg.with_design(**dict(zip(DESIGN_KEYS, map(float, run.design))))
            chk = reference_check(c_d, box_d.keys, box_d.values(z)[0], entry["label"], None,
                                  float(run.J[s]),
                                  claims={**metrics, "objective": entry["objective"]})
            entry["reference"] = chk.get("reference")
            entry["constraints"] = chk.get("constraints")
            entry["agreement"] = chk.get("agreement")
            entry["verified"] = bool(chk.get("ok")) and bool(chk.get("agreement_ok"))
            if "error" in chk:
                entry["error"] = chk["error"]
            ok_all &= entry["verified"]
        out.append(entry)
    return out, ok_all


def check_keys(cfg: Config) -> None:
    """ConfigError unless the robust optimiser can check every corner of cfg's box in
    reasonable time: at most :data:`MAX_SLOW_KEYS` toleranced keys needing a model per
    value."""
    slow = slow_keys([s.key for s in cfg.tolerance.spreads])
    if len(slow) > MAX_SLOW_KEYS:
        raise ConfigError(f"tolerance: {len(slow)} toleranced keys need a model per value "
                          f"({', '.join(slow[:3])}, ...); optimise --robust checks all 2^d "
                          f"corners of the box and takes at most {MAX_SLOW_KEYS} of them "
                          "(softclose yield and sensitivity take any number)")


def optimise_robust(cfg: Config, *, progress: bool = False, samples: int | None = None,
                    seed: int = 0, verify: bool = True) -> RobustResult:
    """The robust soft-close design over cfg's ``[tolerance]`` box (see the module docstring).

    ``samples`` (default ``[tolerance] samples``) and ``seed`` fix the yield estimate;
    ``verify`` re-simulates every scenario with the adaptive reference.
    """
    from ..progress import Progress
    t_start = time.perf_counter()
    tol = cfg.tolerance
    check_batch(cfg, int(samples or tol.samples), "--samples" if samples else "tolerance.samples")
    check_keys(cfg)
    times: dict = {}
    notes: list = []
    rounds: list = []
    bar = Progress(10, "robust design", enabled=progress, unit="")
    bar.update(0, "nominal optimum")
    t0 = time.perf_counter()
    nominal = _nominal(cfg)
    times["nominal_optimise"] = time.perf_counter() - t0
    N, M, t_limit, disc_notes = discretise(cfg)
    notes += disc_notes
    box_cfg = box_of(cfg)
    scale = 1.0
    n_yield = int(samples or tol.samples)
    slow = slow_keys(tol.keys)
    if slow and samples is None and n_yield > SLOW_YIELD_SAMPLES:
        n_yield = SLOW_YIELD_SAMPLES
        notes.append(f"{', '.join(slow)} need a model per sample (~0.05 s each): the yield "
                     f"uses {n_yield} samples (softclose yield --samples N for more)")
    z_yield = box_cfg.draw(n_yield, seed)
    problem = run = yres = None
    for attempt in range(MAX_WIDEN + 1):
        box_s = box_of(cfg, scale=scale)
        bar.update(1, "start")
        t0 = time.perf_counter()
        if run is None:
            # the sweep judges designs on the corners worst at the nominal optimum (all
            # corners when they are few), the NLP starts from those worst at its start
            ref = nominal["design"] or design_of(params_of(cfg))
            first = _initial_scenarios(box_s, cfg, [[ref[k] for k in DESIGN_KEYS]], scale)
            start, start_info = _start_design(cfg, box_s, np.array([s.z for s in first]))
        else:
            start = run.design
        scenarios = _initial_scenarios(box_s, cfg, [start], scale)
        times["start"] = times.get("start", 0.0) + time.perf_counter() - t0
        t0 = time.perf_counter()
        problem, run = _solve_box(cfg, scale, scenarios, N, M, start, seed, notes, rounds, bar)
        times["scenario_nlp"] = times.get("scenario_nlp", 0.0) + time.perf_counter() - t0
        if not run.success:
            break
        bar.update(8, "yield")
        t0 = time.perf_counter()
        design = dict(zip(DESIGN_KEYS, map(float, run.design)))
        c_rob = cfg.with_design(**design)
        yres = analyse_samples(c_rob, box_of(c_rob), z_yield, seed=seed,
                               reference=YIELD_REFERENCE)
        times["yield"] = times.get("yield", 0.0) + time.perf_counter() - t0
        if yres.meets_required or attempt == MAX_WIDEN:
            break
        scale *= WIDEN
        notes.append(f"yield {yres.yield_:.4f} below the required {tol.required_yield:g} with "
                     f"the box at x{scale / WIDEN:.3g} of the spreads: widened to x{scale:.3g}")
    solver = {"method": "scenario multiple shooting (design shared, states per scenario), "
                        "RK4, Ipopt", "nodes": N, "substeps": problem.M if problem else M,
              "scenarios": problem.nlp.S if problem else 0,
              "iterations": sum(r["iterations"] for r in rounds)}
    base = dict(robust_objective=tol.robust_objective, problem=describe(cfg), solver=solver,
                rounds=rounds, box_scale=scale, box=_box_summary(box_of(cfg, scale=scale)))
    if not run.success:
        bar.update(9, "why no robust design")
        t0 = time.perf_counter()
        msg, info = _diagnose(cfg, run, problem, N, M, seed)
        times["diagnosis"] = time.perf_counter() - t0
        nominal_json = {**nominal, "yield": None, "yield_ci": None}
        bar.close()
        times["total"] = time.perf_counter() - t_start
        return RobustResult(False, msg, run.r["status"], None, None, metrics=None, scenarios=[],
                            verification=None, yield_result=None, nominal=nominal_json,
                            nominal_yield=None, infeasibility=info, notes=tuple(notes),
                            times=times, **base)
    # the nominal optimum on the same samples
    bar.update(9, "verification")
    nyield = None
    if nominal["design"] is not None:
        t0 = time.perf_counter()
        c_nom = cfg.with_design(**nominal["design"])
        nyield = analyse_samples(c_nom, box_of(c_nom, scale=1.0), z_yield, seed=seed,
                                 reference=YIELD_REFERENCE)
        times["nominal_yield"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    scen, verified = _scenario_report(cfg, problem, run, verify)
    times["verification"] = time.perf_counter() - t0
    design = dict(zip(DESIGN_KEYS, map(float, run.design)))
    nom = scen[0]
    # the reported metrics are the adaptive reference's at the nominal scenario when it was
    # verified (as the nominal optimiser reports them; the NLP's own sit in `scenarios`), else
    # the NLP's, with what it does not compute as None
    ref = nom.get("reference") or {}
    metrics = ({k: ref.get(k) for k in METRIC_KEYS} if ref else
               {k: nom["metrics"].get(k) for k in METRIC_KEYS})
    J_obj = float(np.max(run.J)) if tol.robust_objective == "worst" else float(np.mean(run.J))
    # every corner of the box at the answer, in the kernel (the scenarios' corners are the
    # reference's to judge): the guarantee when the NLP did not have them all
    t0 = time.perf_counter()
    _, corner_check = _check_corners(cfg, scale, run, [sc.z for sc in problem.scenarios])
    times["corner_check"] = time.perf_counter() - t0
    n_corners = 2 ** box_s.dim if box_s.dim else 0
    in_nlp = sum(1 for sc in problem.scenarios if sc.z and all(abs(v) == 1.0 for v in sc.z))
    corner_check.update(in_nlp=in_nlp, scenarios=len(problem.scenarios))
    if n_corners > MAX_CORNERS:
        notes.append(f"{len(problem.scenarios)} scenarios instead of {n_corners + 1}: the "
                     f"nominal lid, {in_nlp} of the {n_corners} corners and "
                     f"{len(problem.scenarios) - 1 - in_nlp} interior points; all {n_corners} "
                     f"corners simulated in the kernel at the design, "
                     f"{len(corner_check['breaking'])} outside the NLP break a constraint")
    verification = None
    if verify:
        worst = [s for s in scen if s["worst"]][0]
        rel = None
        if worst.get("reference") and worst["reference"].get("objective"):
            Jr = worst["reference"]["objective"]
            rel = (worst["objective"] - Jr) / abs(Jr)
        verification = {"ok": verified and rel is not None and abs(rel) <= VERIFY_RTOL,
                        "scenarios_verified": sum(bool(s.get("verified")) for s in scen),
                        "scenarios": len(scen),
                        "worst_objective_relative_difference": rel,
                        "nominal_scenario": nom.get("reference"),
                        "method": "CVODES (adaptive BDF) on the exact equations, every "
                                  "scenario, every constraint"}
    ok = True
    msgs = []
    if verify and not verification["ok"]:
        ok = False
        bad = [s["label"] for s in scen if not s.get("verified")]
        msgs.append("the adaptive reference does not confirm " +
                    (f"the scenarios {', '.join(bad)}" if bad else
                     "the worst-case objective (raise optimise.substeps)"))
    if corner_check["breaking"]:
        ok = False
        b = corner_check["breaking"]
        msgs.append(f"{len(b)} corners of the tolerance box break a constraint at the design "
                    f"in the kernel ({'; '.join(b[:3])}{' ...' if len(b) > 3 else ''})")
    if not yres.meets_required:
        ok = False
        msgs.append(f"the Monte Carlo yield {yres.yield_:.4f} stays below the required "
                    f"{tol.required_yield:g} even with the box widened x{scale:.3g}")
    nominal_json = {**nominal,
                    "yield": None if nyield is None else nyield.yield_,
                    "yield_ci": None if nyield is None else list(nyield.yield_ci),
                    "percentiles": None if nyield is None else nyield.percentiles,
                    "failures": None if nyield is None else nyield.failures}
    bar.update(10, "done")
    bar.close()
    times["total"] = time.perf_counter() - t_start
    return RobustResult(ok, "; ".join(msgs), run.r["status"], design, J_obj, metrics=metrics,
                        scenarios=scen, verification=verification, yield_result=yres,
                        nominal=nominal_json, nominal_yield=nyield, notes=tuple(notes),
                        times=times, corner_check=corner_check, **base)


def _box_summary(box: Box) -> dict:
    return {k: {"spread": s, "relative": r} for k, s, r in zip(box.keys, box.spreads, box.relative)}


# -- no robust design: which constraint, where, by how much, and what spreads would do ------------


def _violation(cols: dict, i: int, o) -> tuple[str, str]:
    """(constraint, 'by how much') of sample i."""
    reason = cols["reason"][i]
    ct, hm = cols["closing_time"][i], cols["holding_moment"][i]
    if reason == "too slow":
        return "closing_time_max", (f"closes in {ct:.4g} s > closing_time_max = "
                                    f"{o.closing_time_max:g} s "
                                    f"(by {ct - o.closing_time_max:.3g} s)")
    if reason == "too fast":
        return "closing_time_min", (f"closes in {ct:.4g} s < closing_time_min = "
                                    f"{o.closing_time_min:g} s "
                                    f"(by {o.closing_time_min - ct:.3g} s)")
    if reason == "not held shut":
        return "holding_moment_min", (f"holding moment {hm:.4g} N m < holding_moment_min = "
                                      f"{o.holding_moment_min:g} N m (by "
                                      f"{o.holding_moment_min - hm:.3g} N m)")
    if reason == "rebound":
        return "no_rebound", f"rebounds (theta' reaches {cols['theta_dot_max'][i]:.3g} rad/s)"
    return "closed", "does not close within stroke.t_max"


def _diagnose(cfg: Config, run: _Run, problem: _Problem, N: int, M: int, seed: int):
    """Why the scenario NLP has no solution: bisection on the spreads' scale, then the worst
    violation at the full spreads of the best design found."""
    o = cfg.optimise
    lo, hi, best = 0.0, 1.0, None
    subset = 2 ** problem.box.dim > MAX_CORNERS

    def holds(a, design) -> bool:
        """With a subset of the corners as scenarios, a design counts only if every corner
        holds in the kernel."""
        if not subset:
            return True
        _, _, _, cols = _corner_columns(cfg, a, design)
        return bool(np.all(margins(cols, o) >= -MC_TOL))

    for _ in range(6):
        a = 0.5 * (lo + hi)
        box_a = box_of(cfg, scale=a)
        try:
            scen = _initial_scenarios(box_a, cfg, [run.design], a)
            start, info_a = _start_design(cfg, box_a, np.array([s.z for s in scen]))
        except NumericalError:
            hi = a
            continue
        if info_a["robust_feasible"] and holds(a, start):   # a sweep design meets everything
            lo, best = a, start
            continue
        try:
            pa = _Problem(cfg, a, scen, N, M)
            x0, J_ref = pa.initial(start)
            ra = pa.solve(x0, J_ref)
        except NumericalError:
            ra = None
        if ra is not None and ra.success and holds(a, ra.design):
            lo, best = a, ra.design
        else:
            hi = a
    design = best if best is not None else run.design
    box1 = box_of(cfg, dict(zip(DESIGN_KEYS, design)))
    Z = box1.corners()
    c = cfg.with_design(**dict(zip(DESIGN_KEYS, map(float, design))))
    cols = evaluate(c, box1.keys, box1.values(Z))
    m = margins(cols, o)
    i = int(np.argmin(m))
    info = {"feasible_scale": lo if best is not None else 0.0,
            "design_tried": dict(zip(DESIGN_KEYS, map(float, design)))}
    parts = []
    if m[i] < 0:
        constraint, amount = _violation(cols, i, o)
        label = box1.label(Z[i])
        info.update(constraint=constraint, scenario=label, detail=amount)
        ds = ", ".join(f"{k} = {v:.5g}" for k, v in info["design_tried"].items())
        parts.append(f"at the best design found ({ds}) the scenario {label} {amount}")
    else:
        if run.violations:
            info["nlp_violations"] = max(run.violations,
                                         key=lambda v: max(v.values(), default=0.0))
        parts.append(f"Ipopt stopped with {run.r['status']}")
    if best is not None:
        spreads = ", ".join(f"{s.key} ±{s.value * lo * (100 if s.relative else 1):.3g}"
                            f"{' %' if s.relative else ''}" for s in cfg.tolerance.spreads)
        info["feasible_spreads"] = {s.key: s.value * lo for s in cfg.tolerance.spreads}
        parts.append(f"a robust design exists for spreads up to x{lo:.2f} of the configured "
                     f"ones ({spreads})")
    else:
        parts.append("no robust design was found even for spreads of x0.02 of the configured "
                     "ones: check that the nominal problem has a solution (softclose optimise)")
    return "no design meets every constraint over the tolerance box: " + "; ".join(parts), info
