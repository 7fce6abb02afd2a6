"""Solving the scenario NLP over one tolerance box.

- :func:`start_design` -- the start: a coarse sweep of the design box in the C kernel, each
  design judged over all scenarios (the best worst-case objective that meets every
  constraint in every scenario, else the least violating design);
- :class:`Problem` -- the scenario set of one box and its NLP (:mod:`softclose.robust.nlp`),
  the primal start of each scenario from its simulated stroke or a previous answer;
  :class:`Run` -- one solve of it;
- the accuracy loop (:func:`_polish`): the RK4 sub-steps are doubled while the worst
  scenario's objective differs from an accurate simulation by more than REFINE_RTOL (or any
  scenario's own objective, impact speed or peak tip speed by more than AGREE_RTOL), and
  each scenario's closing-time bounds are corrected for the NLP's own discretisation error;
- :func:`solve_box` -- solve, then add the interior worst cases and violating corners
  (:mod:`softclose.robust.worst_cases`) and solve again, until none is found.
"""

from __future__ import annotations

import math

import numpy as np

from ..config import Config
from ..problem import DESIGN_KEYS, objective, PARAM_COLUMNS, with_designs
from .box import Box, box_of
from .evaluate import evaluate, simulator, slow_keys
from ..optimiser.discretisation import scenario_node_times, t_limit
from .nlp import ScenarioNLP, model_config
from ..optimiser.nlp import T_FLOOR
from .scenario_cache import get_scenario_nlp
from .policy import (AGREE_RTOL, CHECK_SAMPLES, MAX_REFINE, MAX_ROUNDS, REFINE_RTOL,
                     SLOW_CHECK_SAMPLES, t_end)
from .scenarios import Scenario, factors, maps, scenario_rows
from .stats import margins
from .worst_cases import check_corners, search
from ..optimiser.starts import stroke_states
from ..model import elements


def start_design(cfg: Config, box: Box, Z,
                 shape=(8, 6, 8)) -> tuple[np.ndarray, dict]:
    """The design of a coarse sweep with the best worst-case objective over the scenarios
    ``Z`` (:class:`~.scenarios.Scenario` objects, each at its temperature, or unit points at
    the reference temperature).

    A design the grid holds more than once (a bound with lo = hi, as ``select`` fixes the
    catalog spring's rate and free length) is simulated once, for every copy of it."""
    o = cfg.optimise
    axes = [np.linspace(*getattr(o, k), n) for k, n in zip(DESIGN_KEYS, shape)]
    G = np.array(np.meshgrid(*axes, indexing="ij")).reshape(3, -1).T
    _, first, of = np.unique(G, axis=0, return_index=True, return_inverse=True)
    keys, X = scenario_rows(box, G[first], Z, cfg)
    cols = evaluate(cfg, keys, X, t_end=t_end(cfg))
    S = len(Z)
    of = np.asarray(of).ravel()                 # each design of G -> its distinct design
    m = margins(cols, o).reshape(-1, S)[of]
    J = np.asarray(cols["objective"], float).reshape(-1, S)[of]
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


def _guess(cfg_m: Config, p: np.ndarray, N: int, t_lo: float, t_hi: float,
           two_phase: bool = False):
    """(T, X (2, N), peak, J, T1) of a scenario from its simulated stroke at parameters p
    (N intervals per phase; with ``two_phase`` T1 is where the stroke first reaches the
    end damper's angle, else None)."""
    o = cfg_m.optimise
    sim = simulator(cfg_m)
    r = sim.run(p, trajectory=True, estimate_error=False)
    th_e = float(elements.params(np.asarray(p, float))["end_damper_angle_deg"]) \
        if two_phase else None
    T, X, peak, T1, _ = stroke_states(
        r, cfg_m.stroke, th_e, t_lo, t_hi,
        lambda T, T1: scenario_node_times(N, two_phase, T, T1), N)
    J = objective(o, float(X[1, -1]), peak)
    return T, X, peak, (J if J is not None and math.isfinite(J) else 1.0), T1


class Problem:
    """The scenario set of one box and the solves over it (state carried between rounds)."""

    def __init__(self, cfg: Config, scale: float, scenarios: list[Scenario], N: int, M: int,
                 M_engaged: int | None = None):
        self.cfg, self.scale, self.scenarios, self.N, self.M = cfg, scale, scenarios, N, M
        self.box = box = box_of(cfg, scale=scale)
        # a scenario at temperature T: p = f (a p_design + b) (SPEC §12)
        self.maps = [maps(box, np.asarray(s.z), factors(cfg, s.temperature_c))
                     for s in scenarios]
        self.model_cfgs = [model_config(cfg, v) for _, _, v in self.maps]
        self.nlp, cached = get_scenario_nlp(cfg, self.model_cfgs, N, M,
                                            cfg.tolerance.robust_objective, M_engaged)
        #: phase 2's sub-steps (two phases), None for one phase
        self.M_engaged = self.nlp.M_engaged
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
        """The parameter vector of a design (k, l0, c, then the NLP's free end damper, when
        given)."""
        d = np.asarray(design, float)
        p = with_designs(self.cfg, d[:3])
        for j, (k, _, _) in enumerate(self.nlp.free):
            p[PARAM_COLUMNS[k]] = d[3 + j] if len(d) > 3 + j else self.nlp.free_values[j]
        return p

    def scenario_params(self, design, s: int) -> np.ndarray:
        a, b, _ = self.maps[s]
        return a * self.param(design) + b

    def initial(self, design, prev: "Run | None" = None):
        """Primal start: a previous answer's states where it has them, simulated strokes
        for the new scenarios."""
        o = self.cfg.optimise
        states, Js, T1s = [], [], []
        for s in range(len(self.scenarios)):
            if prev is not None and s < prev.problem.nlp.S:
                # s_s from the scenario's own peak (the epigraph variable may be anywhere
                # above it when nothing pins it)
                T, X, _ = prev.states[s]
                pk = float(prev.peaks[s])
                states.append((T, X, pk))
                T1s.append(prev.engage[s][0] if prev.engage else None)
                Js.append(objective(o, float(X[1, -1]), pk))
                continue
            T, X, pk, J, T1 = _guess(self.model_cfgs[s], self.scenario_params(design, s),
                                     self.N, self.t_lo[s], self.t_hi[s], self.nlp.two_phase)
            states.append((T, X, pk))
            T1s.append(T1)
            Js.append(J)
        J_ref = prev.J_ref if prev is not None else max(max(Js), 1e-8)
        t = max(Js) / J_ref
        return self.nlp.pack(design, t, states, T1s), J_ref

    def solve(self, x0, J_ref, lam=None) -> "Run":
        nlp = self.nlp
        p = nlp.params(self.cfg, [(a, b) for a, b, _ in self.maps], J_ref)
        lbx, ubx, lbg, ubg = nlp.bounds(self.cfg, self.t_hi, self.t_lo, self.design_lb)
        if lam is not None:
            r = nlp.solve(x0, p, lbx, ubx, lbg, ubg, lam[0], lam[1], warm=True)
        else:
            r = nlp.solve(x0, p, lbx, ubx, lbg, ubg)
        return Run(self, r, p, J_ref, (lbx, ubx, lbg, ubg))


class Run:
    """One solve of a Problem: the NLP's run ``r`` (:class:`softclose.optimiser.run.Run`)
    read as a design and each scenario's stroke."""

    def __init__(self, problem: Problem, r, p, J_ref, bounds):
        self.problem, self.r, self.p, self.J_ref, self.bounds = problem, r, p, J_ref, bounds
        self.success = r.success
        self.design, self.t, self.states = problem.nlp.unpack(r.x)
        #: per scenario (engagement time, theta' there) with two phases, else None
        self.engage = problem.nlp.engagements(r.x)
        # each scenario's own peak tip speed and objective (sub-step speeds and Hermite
        # maxima, not the epigraph variables: see softclose.robust.nlp)
        self.peaks = problem.nlp.peaks(r.x, p)
        self.J = problem.nlp.objectives(r.x, p)
        #: per scenario, the largest violation of each constraint group (None: no g)
        self.violations = r.violations if np.all(np.isfinite(r.g)) else None

    def summary(self) -> dict:
        """This solve as an entry of the result's ``rounds``."""
        return {"scenarios": len(self.problem.scenarios), "status": self.r.status,
                "iterations": self.r.iterations, "solve_time": self.r.time,
                "build_time": self.problem.build_time}

    def extended_lam(self, nlp: ScenarioNLP):
        """The multipliers, with zeros for the scenarios a bigger NLP adds."""
        if self.r.lam_x is None:
            return None
        old = self.problem.nlp
        extra = nlp.S - old.S
        lam_x = np.r_[self.r.lam_x, np.zeros(extra * nlp.per)]
        lam_g = np.r_[self.r.lam_g, np.zeros(extra * nlp.block)]
        return lam_x, lam_g


# -- the accuracy loop: sub-steps and closing-time bounds -----------------------------------------
def _accurate(problem: Problem, design) -> list:
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


def _inaccurate(run: Run, sims: list) -> str | None:
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


def _polish(problem: Problem, run: Run, notes: list) -> tuple[Problem, Run]:
    """Refine the sub-steps and correct the closing-time bounds (see the module docstring)."""
    o = problem.cfg.optimise
    for _ in range(MAX_REFINE):
        why = _inaccurate(run, _accurate(problem, run.design))
        if why is None:
            break
        finer = Problem(problem.cfg, problem.scale, problem.scenarios, problem.N,
                        2 * problem.M, 2 * problem.M_engaged if problem.M_engaged else None)
        finer.t_hi, finer.t_lo = list(problem.t_hi), list(problem.t_lo)
        r2 = finer.solve(run.r.x, run.J_ref)
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
        r2 = problem.solve(run.r.x, run.J_ref)
        if not r2.success:
            r2 = problem.solve(run.r.x, run.J_ref, (run.r.lam_x, run.r.lam_g))
            if not r2.success:
                break
        run = r2
        notes.append("closing-time bounds of some scenarios corrected for the NLP's "
                     "discretisation error")
    return problem, run


def solve_box(cfg: Config, scale: float, scenarios: list, N: int, M: int, start,
              seed: int, notes: list, rounds: list, bar) -> tuple[Problem, Run | None]:
    """Solve over ``scenarios``, then add interior worst cases and violating corners until
    none is found (the corner check only adds corners that are not yet scenarios)."""
    problem = Problem(cfg, scale, scenarios, N, M)
    x0, J_ref = problem.initial(start)
    run = problem.solve(x0, J_ref)
    rounds.append(run.summary())
    if not run.success:
        return problem, run
    problem, run = _polish(problem, run, notes)
    for k in range(MAX_ROUNDS):
        bar.update(min(2 + k, 8), f"searching the box ({len(problem.scenarios)} scenarios)")
        n_check = SLOW_CHECK_SAMPLES if slow_keys(cfg.tolerance.keys) else CHECK_SAMPLES
        new, info = search(cfg, scale, run, seed + 1 + k, n_check)
        corners, cinfo = check_corners(
            cfg, scale, run, [(s.z, s.temperature_c) for s in problem.scenarios] + list(new))
        rounds[-1].update(search=info, corner_check=cinfo)
        if not new and not corners:
            break
        scen = problem.scenarios \
            + [Scenario(z, f"Monte Carlo, round {k + 1}", T) for z, T in new] \
            + [Scenario(z, f"corner check, round {k + 1}", T) for z, T in corners]
        n_new = len(new) + len(corners)
        bigger = Problem(cfg, scale, scen, problem.N, problem.M, problem.M_engaged)
        bigger.t_hi = problem.t_hi + [t_limit(cfg)] * n_new
        bigger.t_lo = problem.t_lo + [max(cfg.optimise.closing_time_min, T_FLOOR)] * n_new
        x0, _ = bigger.initial(run.design, run)
        # from the previous answer's primal point: with the new scenarios' multipliers
        # unknown, Ipopt's warm-start mode took 3x the iterations in tests (54 against 17)
        r2 = bigger.solve(x0, run.J_ref)
        if not r2.success:
            r2 = bigger.solve(x0, run.J_ref, run.extended_lam(bigger.nlp))
        rounds.append(r2.summary())
        if not r2.success:
            return bigger, r2
        problem, run = _polish(bigger, r2, notes)
    else:
        notes.append(f"the interior search and corner check still found violating points "
                     f"after {MAX_ROUNDS} rounds")
    return problem, run
