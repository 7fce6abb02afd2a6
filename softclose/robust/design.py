"""Robust design: the soft-close design that meets every constraint over the tolerance box.

``optimise_robust(cfg)`` (``softclose optimise --robust``, ``softclose.optimise(cfg,
robust=True)``):

1. **Scenarios**: the nominal lid and the 2^d corners of the ``[tolerance]`` box (d
   toleranced keys; spring and damper spreads are relative to the design, so they move
   with it). With more than :data:`MAX_CORNERS` corners (d > 4) the NLP would grow with
   2^d: it starts instead from the nominal lid and the corners worst for each constraint
   (and the objective) at the start design, found by simulating every corner in the C
   kernel (:func:`softclose.robust.scenarios.initial_scenarios`); see 4 for how the others
   are guaranteed.
2. **Start** (:func:`softclose.robust.solve.start_design`): a coarse sweep of the design box
   in the C kernel, each design judged over all scenarios; the design with the best
   worst-case objective that meets every constraint in every scenario (else the least
   violating one).
3. **Scenario NLP** (:mod:`softclose.robust.nlp`, solved in :mod:`softclose.robust.solve`):
   one multiple-shooting NLP with the design shared and one set of shooting states per
   scenario; every constraint in every scenario; the worst (or mean) scenario objective
   through an epigraph variable. As in the nominal optimiser, the RK4 sub-steps are doubled
   while the worst scenario's objective differs from an accurate simulation by more than 1e-4
   (or any scenario's own objective, impact speed or peak tip speed by more than half the
   verification tolerance), and each scenario's closing-time bounds are corrected for the
   NLP's own discretisation error. A scenario's own peak tip speed (and so its J) is read
   from its sub-step speeds and their Hermite maxima, never from its epigraph variable
   (:mod:`softclose.robust.nlp`).
4. **Interior worst cases**: the worst case need not be a corner. After each solve a Monte
   Carlo pass (uniform in the box, C kernel) looks for samples that break a constraint or
   exceed the worst-case objective; the worst two, each improved by a local ascent in the
   box, join the scenarios and the NLP is re-solved from the previous answer's primal point,
   until none is found ("local reduction", Zagorowska et al., arXiv 2204.14145). In the
   same pass all 2^d corners are simulated in the kernel (:mod:`softclose.robust.worst_cases`)
   and every violating corner not yet a scenario joins too, so that, whatever subset the NLP started
   from, every corner of the box closes within the window and holds shut at the answer
   (``corner_check`` in the result; a corner still violating fails the result).
5. **Verification**: every scenario is re-simulated by the adaptive reference (CVODES on the
   exact equations) with every constraint checked, and the NLP's own numbers of it (closing
   time, impact speed, peak tip speed, holding moment, J) compared with the reference's
   (``scenarios[i].agreement``; a scenario is ``verified`` when both hold); the yield of
   the robust design and of the nominal optimum are estimated on the same Monte Carlo
   samples of the configured distribution (:mod:`softclose.robust.analysis`). When the
   yield falls short of ``required_yield`` (a normal distribution has tails beyond the
   3-sigma box), the box is widened by 15 % and the design re-solved, at most three times.

When no design meets the constraints over the box, the result says which constraint fails in
which scenario and by how much, and how far the spreads would have to shrink (the largest
fraction of them for which the scenario NLP still has a solution, by bisection:
:mod:`softclose.robust.infeasible`).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from ..config import Config, check_batch
from ..errors import ConfigError
from ..problem import (DESIGN_KEYS, ENGAGE_KEYS, METRIC_KEYS, VERIFY_RTOL, describe, design_of,
                       params_of)
from .active import active_set
from .analysis import YieldResult, analyse_samples
from .box import box_of
from .evaluate import slow_keys
from .infeasible import diagnose
from ..optimiser.discretisation import discretisation, t_limit
from ..optimiser.nlp import T_FLOOR
from .policy import (MAX_WIDEN, SLOW_YIELD_SAMPLES, WIDEN, YIELD_REFERENCE, check_keys,
                     max_corners)
from .result import RobustResult, box_summary
from .spring_box import made_to_order, spring_rounds
from .scenarios import (all_corners, at_reference, corner_count, design_dict, initial_scenarios,
                        temperatures)
from .solve import Problem, Run, solve_box, start_design
from .verify import scenario_report
from .worst_cases import check_corners
from ..optimiser.optimiser import optimise_kind
from ..present.progress import Progress
from ..optimiser.keep_out import clearance
from .codesign import best_verified, choose_points, fixed_points
from ..optimiser.free_points import SLOTS
from ..optimiser.interval import END_ANGLE, END_C
from ..optimiser.spring_part import spring_part
from ..optimiser.kinds import kind_config
from ..problem import (at_temperature, condition_parts, condition_text, sign_off_states,
                       sign_off_temperatures)


def optimise_robust(cfg: Config, *, progress: bool = False, samples: int | None = None,
                    seed: int = 0, verify: bool = True, report: bool = True,
                    own_box: bool = True) -> RobustResult:
    """The robust soft-close design over cfg's ``[tolerance]`` box, for each spring kind the
    optimiser may choose (``optimise.spring_kinds``; the free length bounded so that the
    spring stays valid over the stroke and its own tolerance:
    :func:`softclose.optimiser.kinds.kind_config`); the best successful one is kept, with the
    part to buy (``part``) and every kind tried (``kinds``).

    ``samples`` (default ``[tolerance] samples``) and ``seed`` fix the yield estimate;
    ``verify`` re-simulates every scenario with the adaptive reference. ``report=False``
    (``softclose select``'s re-solves, which read the design, its worst-case objective and
    the verdict): the same design, objective, success and message, without what only the
    report shows (:func:`optimise_robust_kind`). With a compression spring made to order
    (``spring.material`` given) and ``own_box``, the answer holds for its spring's own EN 15800
    box (:func:`softclose.robust.spring_box.spring_rounds`).
    """
    if own_box and report and made_to_order(cfg):
        return spring_rounds(cfg, lambda c: optimise_robust(
            c, progress=progress, samples=samples, seed=seed, verify=verify, own_box=False))
    from dataclasses import replace

    t_start = time.perf_counter()
    given, cfg = cfg, at_reference(cfg)      # (every scenario at its sign-off temperature)
    check_batch(cfg, int(samples or cfg.tolerance.samples),
                "--samples" if samples else "tolerance.samples")
    check_keys(cfg)
    # the attachment points and the end damper are chosen first (robust/codesign.py); every
    # other free design value (a rotary damper, a preload, a strut's F1) is a design
    # variable of the scenario NLP beside k, l0 and c
    placed = any(k in SLOTS + (END_C, END_ANGLE) for k, _, _ in cfg.optimise.free or ())
    if placed:
        toleranced = [k for k in cfg.tolerance.keys if any(
            s.startswith(k.split("[")[0]) for s in (k2 for k2, _, _ in cfg.optimise.free
                                                    if k2 in SLOTS))]
        if toleranced:
            raise ConfigError(f"[tolerance]: {toleranced[0]} is a free attachment point; a "
                              "point the optimiser chooses carries no tolerance here")
    rows, results, deferred = [], [], {}
    configs = [(kind, *kind_config(cfg, kind, robust=True))
               for kind in cfg.optimise.spring_kinds]
    for kind, c, why in configs:
        if why is None and placed:      # stage 1: where (robust/placement.py)
            stage_notes: list = []
            bound = min((x[1].objective for x in results if x[1].success
                         and x[1].objective is not None), default=None)
            points, info = choose_points(c, stage_notes, bound)
            if points is None:
                rows.append({"kind": kind, "success": False, "objective": None,
                             "message": (
                                 f"not solved: its nominal co-design optimum J = "
                                 f"{info['nominal_objective']:.6g} already exceeds the "
                                 f"worst case {bound:.6g} of a kind solved before (the "
                                 "nominal lid is a scenario)")})
                continue
            c, why = kind_config(fixed_points(cfg, points), kind, robust=True)
            screening = info.get("screening")
        if why is not None:
            rows.append({"kind": kind, "success": False, "objective": None,
                         "message": why})
            continue
        if report and not placed:       # the report of the kind kept only (below)
            r, finish = optimise_robust_kind(c, progress=progress, samples=samples,
                                             seed=seed, verify=verify, defer=True)
            deferred[kind] = finish
        else:
            r = optimise_robust_kind(c, progress=progress, samples=samples, seed=seed,
                                     verify=verify, report=report)
        if placed:      # the best verified: another candidate when this one is worse
            r, c, points = best_verified(cfg, kind, r, c, points, info, stage_notes,
                                         lambda c2: optimise_robust_kind(
                                             c2, progress=progress, samples=samples,
                                             seed=seed, verify=verify, report=report))
            if screening is not None:
                r = replace(r, screening=screening.to_json())
        if placed:              # stage 2 ran at the points (end damper): report them
            r = replace(r, design={**(r.design or {}), **{k.split(".", 1)[1]: v
                                                          for k, v in points.items()}},
                        notes=tuple(stage_notes) + r.notes)
            r = _keep_out_check(c, r)
        rows.append({"kind": kind, "success": r.success, "objective": r.objective,
                     "message": r.message})
        results.append((kind, r, c))
    if not results:
        raise ConfigError("no spring kind of optimise.spring_kinds can be valid: "
                          + "; ".join(f"{r['kind']}: {r['message']}" for r in rows))
    results = _finish_kinds(results, rows, deferred)
    pool = [x for x in results if x[1].success] or [x for x in results if x[1].design] \
        or results
    kind, best, c = min(pool, key=lambda x: x[1].objective if x[1].objective is not None
                        else np.inf)
    part = spring_part(c, best.design, best.metrics) if best.design is not None else None
    notes = best.notes + ("spring kinds: " + "; ".join(
        f"{r['kind']}: " + (f"worst J = {r['objective']:.8g}" if r["objective"] is not None
                            else "no design") + ("" if r["success"] else
                                                 f" ({r['message'] or 'failed'})")
        for r in rows),)
    times = dict(best.times, total=time.perf_counter() - t_start)
    out_cfg = given.set("design.spring_kind", kind)       # (not the kind's bounds)
    if placed:                          # with the points (end damper) set, no longer free
        chosen = {k for k, _, _ in cfg.optimise.free}
        out_cfg = fixed_points(out_cfg, {full: v for k, v in (best.design or {}).items()
                                         for full in (f"geometry.{k}", f"design.{k}")
                                         if full in chosen})
    conditions = temperatures(cfg)      # (each sign-off temperature, in each state)
    limiting = (best.corner_check or {}).get("limiting_temperature_c")
    if limiting is None and len(conditions) == 1 and best.design is not None:
        limiting = conditions[0]
    states = sign_off_states(cfg)
    lim_T, lim_state = (None, None) if limiting is None else condition_parts(limiting)
    return replace(best, kind=kind, kinds=tuple(rows), part=part, notes=notes, times=times,
                   config=out_cfg, temperatures=sign_off_temperatures(cfg),
                   limiting_temperature_c=lim_T, states=states,
                   limiting_state=None if lim_T is None else (lim_state or "new"))


def _objective(x) -> float:
    return x[1].objective if x[1].objective is not None else np.inf


def _finish_kinds(results: list, rows: list, deferred: dict) -> list:
    """The whole report of the kind :func:`optimise_robust` keeps, and of no other: the
    kinds whose lean results succeeded are finished (their scenarios verified) in the order
    of their worst-case objectives until one succeeds -- verification can only fail a design,
    so that one is the best successful kind, as if every kind had been finished; without
    one, the kind the rule keeps then (the best with a design) is finished. A kind left
    unfinished says so in its row."""
    if not deferred:
        return results
    results = list(results)

    def finish(i):
        kind, lean, c = results[i]
        full = deferred.pop(kind)()
        results[i] = (kind, full, c)
        rows[:] = [dict(r, success=full.success, message=full.message)
                   if r["kind"] == kind else r for r in rows]
        return full

    order = sorted(range(len(results)), key=lambda i: _objective(results[i]))
    if not any(results[i][1].success and finish(i).success for i in order
               if results[i][0] in deferred):
        pool = [i for i in order if results[i][1].design] or order
        if results[pool[0]][0] in deferred:
            finish(pool[0])
    for r in rows:
        if r["kind"] in deferred and r["success"]:
            r["message"] = ("not verified by the reference: a kind with a lower worst-case J "
                            "was kept")
    return results


def _keep_out_check(cfg: Config, r: RobustResult) -> RobustResult:
    """The exact keep-out check at the result's points (``optimise.keep_out``)."""
    from dataclasses import replace

    if not cfg.optimise.keep_out:
        return r
    notes, msgs = list(r.notes), []
    for line, c in clearance(cfg).items():
        notes.append(f"keep-out: the {line}'s line clears the regions by "
                     f"{c['clearance'] * 1e3:.3f} mm at the least (theta = {c['theta_deg']:.1f} "
                     "deg; exact closure, 2001 angles)")
        if not c["ok"]:
            msgs.append(f"the {line}'s line crosses a keep-out region by "
                        f"{-c['clearance'] * 1e3:.3f} mm")
    if msgs:
        return replace(r, success=False, message="; ".join(filter(None, [r.message, *msgs])),
                       notes=tuple(notes))
    return replace(r, notes=tuple(notes))


def optimise_robust_kind(cfg: Config, *, progress: bool = False, samples: int | None = None,
                         seed: int = 0, verify: bool = True, report: bool = True,
                         defer: bool = False):
    """The robust soft-close design over cfg's ``[tolerance]`` box with cfg's spring kind (see
    the module docstring).

    ``report=False``: the design, its objective, ``success`` and ``message`` alone, the
    numbers those have with ``report`` (and ``verify=False``). Left out is what they do not
    depend on: the nominal optimum (solved only when it chooses the scenarios the NLP starts
    from, a box of more than :func:`~.policy.max_corners` corners; else ``nominal`` is
    :data:`NOT_SOLVED`), its yield, the scenarios' report and their verification, the
    active set (``metrics``, ``scenarios`` and ``active`` empty).

    ``defer=True``: ``(the report=False result, finish)``, where ``finish()`` returns the
    whole report's result (the same as ``report=True``) -- what :func:`optimise_robust` makes
    of the kind it keeps only. Its ``success`` can only be that result's or False (the
    verification of the scenarios can fail a design, nothing else changes)."""
    t_start = time.perf_counter()
    cfg = at_reference(cfg)
    tol = cfg.tolerance
    check_batch(cfg, int(samples or tol.samples), "--samples" if samples else "tolerance.samples")
    check_keys(cfg)
    log = _Log(Progress(10, "robust design", enabled=progress, unit=""), t_start)
    log.bar.update(0, "nominal optimum")
    t0 = time.perf_counter()
    if (report and not defer) or not all_corners(cfg, box_of(cfg)):
        nominal = _nominal(cfg)
        log.times["nominal_optimise"] = time.perf_counter() - t0
    else:           # every corner is a scenario: the nominal optimum chooses none of them
        nominal = dict(NOT_SOLVED)
    disc = discretisation(cfg)
    N, M, disc_notes = disc.nodes, disc.substeps, list(disc.notes)
    log.notes += disc_notes
    z_yield = _yield_samples(cfg, samples, seed, log.notes)
    problem, run, yres, scale = _solve_widening(cfg, nominal, N, M, z_yield, seed, log)
    problem_json = describe(cfg)
    problem_json["closing_time_solved"] = [max(cfg.optimise.closing_time_min, T_FLOOR),
                                           t_limit(cfg)]
    base = dict(robust_objective=tol.robust_objective, problem=problem_json,
                solver=_solver(problem, log.rounds, N, M), rounds=log.rounds, box_scale=scale,
                box=box_summary(box_of(cfg, scale=scale)))
    if not run.success:
        if report and nominal is not None and nominal.get("success") is None:
            nominal = _nominal(cfg)          # (deferred: the report of no design shows it)
        done = _no_design(cfg, problem, run, nominal, N, M, seed, log, base)
        return (done, lambda: done) if defer else done
    design = design_dict(problem, run.design)
    J_obj = float(np.max(run.J)) if tol.robust_objective == "worst" else float(np.mean(run.J))
    if not report or defer:
        corner_check = _corner_guarantee(cfg, scale, problem, run, log)
        msgs = _failures(None, [], corner_check, yres, tol.required_yield, scale)
        lean = RobustResult(not msgs, "; ".join(msgs), run.r.status, design, J_obj,
                            metrics=None, scenarios=[], verification=None, yield_result=yres,
                            nominal=_nominal_json(nominal, None), nominal_yield=None,
                            notes=tuple(log.notes), times=dict(log.times),
                            corner_check=corner_check, config=cfg, **base)
        if not report:
            log.finish()
            return replace(lean, times=log.times)

        def finish() -> RobustResult:
            return _report(cfg, nominal, problem, run, yres, scale, z_yield, seed, verify,
                           log, base, design, J_obj, corner_check)
        return lean, finish
    return _report(cfg, nominal, problem, run, yres, scale, z_yield, seed, verify, log, base,
                   design, J_obj, None)


def _report(cfg, nominal, problem, run, yres, scale, z_yield, seed, verify, log, base, design,
            J_obj, corner_check) -> RobustResult:
    """The whole robust result of a solved kind: the nominal optimum (if not solved yet) and
    its yield on the same samples, every scenario verified by the reference, the corner
    guarantee (``corner_check``, unless checked already), the active set."""
    tol = cfg.tolerance
    if nominal.get("success") is None:
        t0 = time.perf_counter()
        nominal = _nominal(cfg)
        log.times["nominal_optimise"] = time.perf_counter() - t0
    log.bar.update(9, "verification")
    nyield = _nominal_yield(cfg, nominal, z_yield, seed, log)
    t0 = time.perf_counter()
    scen, verified = scenario_report(cfg, problem, run, verify)
    log.times["verification"] = time.perf_counter() - t0
    if corner_check is None:
        corner_check = _corner_guarantee(cfg, scale, problem, run, log)
    verification = _verification(scen, verified) if verify else None
    msgs = _failures(verification, scen, corner_check, yres, tol.required_yield, scale)
    active = active_set(run, [s["label"] for s in scen])
    log.bar.update(10, "done")
    log.finish()
    return RobustResult(not msgs, "; ".join(msgs), run.r.status, design, J_obj,
                        metrics=_reported_metrics(scen[0]), scenarios=scen,
                        verification=verification, yield_result=yres,
                        nominal=_nominal_json(nominal, nyield), nominal_yield=nyield,
                        notes=tuple(log.notes), times=log.times, corner_check=corner_check,
                        active=active, config=cfg, **base)


@dataclass
class _Log:
    """What the procedure records as it goes: its progress line, the notes of the result,
    one entry per NLP solve (``rounds``) and the seconds of each stage (``times``)."""

    bar: Any
    t_start: float
    notes: list = field(default_factory=list)
    rounds: list = field(default_factory=list)
    times: dict = field(default_factory=dict)

    def add_time(self, stage: str, t0: float) -> None:
        """The seconds since ``t0`` added to ``stage`` (stages repeat as the box widens)."""
        self.times[stage] = self.times.get(stage, 0.0) + time.perf_counter() - t0

    def finish(self) -> None:
        self.bar.close()
        self.times["total"] = time.perf_counter() - self.t_start


# -- the steps ------------------------------------------------------------------------------------
#: the nominal optimum of a result that did not need it (``report=False``)
NOT_SOLVED = {"success": None, "design": None, "objective": None,
              "message": "not solved (it chooses none of the scenarios)"}


def _nominal(cfg: Config) -> dict:
    """The nominal optimum (no tolerances) with cfg's spring kind, for the start and the
    comparison."""
    res = optimise_kind(cfg, verify=False)
    return {"success": bool(res.success), "design": res.design, "objective": res.objective,
            "message": res.message}


def _yield_samples(cfg: Config, samples: int | None, seed: int, notes: list) -> np.ndarray:
    """The unit points of the yield estimate, drawn once from the configured distribution:
    ``samples`` (default ``[tolerance] samples``), at most :data:`SLOW_YIELD_SAMPLES` when a
    toleranced key needs a model per sample and no number was asked for."""
    tol = cfg.tolerance
    n_yield = int(samples or tol.samples)
    slow = slow_keys(tol.keys)
    if slow and samples is None and n_yield > SLOW_YIELD_SAMPLES:
        n_yield = SLOW_YIELD_SAMPLES
        notes.append(f"{', '.join(slow)} need a model per sample (~0.05 s each): the yield "
                     f"uses {n_yield} samples (softclose yield --samples N for more)")
    return box_of(cfg).draw(n_yield, seed)


def _solve_widening(cfg: Config, nominal: dict, N: int, M: int, z_yield: np.ndarray,
                    seed: int, log: _Log) -> tuple[Problem, Run, YieldResult | None, float]:
    """Solve over the box and estimate the yield of the answer on ``z_yield``; while the
    yield falls short of ``required_yield``, widen the box by :data:`WIDEN` and solve again
    from the answer, at most :data:`MAX_WIDEN` times. Returns the last (problem, run, yield,
    scale of the box); the yield is None when a solve failed."""
    tol = cfg.tolerance
    scale = 1.0
    problem = run = yres = None
    for attempt in range(MAX_WIDEN + 1):
        box_s = box_of(cfg, scale=scale)
        log.bar.update(1, "start")
        t0 = time.perf_counter()
        start = _start(cfg, box_s, scale, nominal) if run is None else run.design
        scenarios = initial_scenarios(box_s, cfg, [start], scale)
        log.add_time("start", t0)
        t0 = time.perf_counter()
        problem, run = solve_box(cfg, scale, scenarios, N, M, start, seed, log.notes,
                                 log.rounds, log.bar)
        log.add_time("scenario_nlp", t0)
        if not run.success:
            break
        log.bar.update(8, "yield")
        t0 = time.perf_counter()
        design = design_dict(problem, run.design)
        c_rob = cfg.with_design(**design)
        yres, at = _lowest_yield(c_rob, box_of(c_rob), z_yield, seed)
        log.add_time("yield", t0)
        if yres.meets_required or attempt == MAX_WIDEN:
            break
        scale *= WIDEN
        log.notes.append(f"yield {yres.yield_:.4f} below the required {tol.required_yield:g} "
                         f"with the box at x{scale / WIDEN:.3g} of the spreads: widened to "
                         f"x{scale:.3g}")
    return problem, run, yres, scale


def _start(cfg: Config, box, scale: float, nominal: dict) -> np.ndarray:
    """The first start design: the sweep judges designs on the corners worst at the nominal
    optimum (all corners when they are few), the NLP starts from those worst at its start."""
    ref = nominal["design"] or design_of(params_of(cfg))
    first = initial_scenarios(box, cfg, [[ref[k] for k in DESIGN_KEYS]], scale)
    start, _ = start_design(cfg, box, np.array([s.z for s in first]))
    return start


def _solver(problem: Problem | None, rounds: list, N: int, M: int) -> dict:
    """How the scenario NLP was solved: its size and Ipopt's iterations over every round."""
    return {"method": "scenario multiple shooting (design shared, states per scenario), "
                      "RK4, Ipopt", "nodes": N, "substeps": problem.M if problem else M,
            "scenarios": problem.nlp.S if problem else 0,
            "iterations": sum(r["iterations"] for r in rounds)}


def _no_design(cfg: Config, problem: Problem, run: Run, nominal: dict, N: int, M: int,
               seed: int, log: _Log, base: dict) -> RobustResult:
    """The result when the scenario NLP has no solution: why (:func:`diagnose`)."""
    log.bar.update(9, "why no robust design")
    t0 = time.perf_counter()
    msg, info = diagnose(cfg, run, problem, N, M, seed)
    log.times["diagnosis"] = time.perf_counter() - t0
    nominal_json = {**nominal, "yield": None, "yield_ci": None}
    log.finish()
    return RobustResult(False, msg, run.r.status, None, None, metrics=None, scenarios=[],
                        verification=None, yield_result=None, nominal=nominal_json,
                        nominal_yield=None, infeasibility=info, notes=tuple(log.notes),
                        times=log.times, config=cfg, **base)


def _lowest_yield(c: Config, box, z: np.ndarray, seed: int) -> tuple[YieldResult, float]:
    """The yield of ``c``'s design on the unit samples ``z`` at each sign-off temperature
    (the same samples at each): the lowest of them and its temperature (the reference
    temperature's alone by default). ``softclose yield`` with ``operating.temperatures_c``
    reports each and the joint one."""
    out, at = None, None
    for T in temperatures(c):
        y = analyse_samples(at_temperature(c, T), box, z, seed=seed, reference=YIELD_REFERENCE)
        if out is None or y.yield_ < out.yield_:
            out, at = y, T
    return out, at


def _yield_note(cfg: Config, what: str, at: float) -> str | None:
    """Which temperature a reported yield is at, with several sign-off temperatures."""
    if len(temperatures(cfg)) <= 1:
        return None
    return (f"{what}'s yield and nominal lid: at {condition_text(at)}, the lowest yield of "
            "the sign-off conditions (the same samples at each; softclose yield gives the "
            "joint one)")


def _nominal_yield(cfg: Config, nominal: dict, z_yield: np.ndarray, seed: int,
                   log: _Log) -> YieldResult | None:
    """The yield of the nominal optimum on the robust design's samples (None without one)."""
    if nominal["design"] is None:
        return None
    t0 = time.perf_counter()
    c_nom = cfg.with_design(**nominal["design"])
    nyield, at = _lowest_yield(c_nom, box_of(c_nom, scale=1.0), z_yield, seed)
    log.notes += filter(None, [_yield_note(cfg, "the nominal optimum", at)])
    log.times["nominal_yield"] = time.perf_counter() - t0
    return nyield


def _reported_metrics(nom: dict) -> dict:
    """The reported metrics are the adaptive reference's at the nominal scenario when it was
    verified (as the nominal optimiser reports them; the NLP's own sit in `scenarios`), else
    the NLP's, with what it does not compute as None."""
    ref = nom.get("reference") or {}
    keys = METRIC_KEYS + tuple(k for k in ENGAGE_KEYS if (ref or nom["metrics"]).get(k)
                               is not None)
    return ({k: ref.get(k) for k in keys} if ref else {k: nom["metrics"].get(k) for k in keys})


def _corner_guarantee(cfg: Config, scale: float, problem: Problem, run: Run, log: _Log) -> dict:
    """Every corner of the box at the answer, in the kernel (the scenarios' corners are the
    reference's to judge): the guarantee when the NLP did not have them all."""
    t0 = time.perf_counter()
    _, corner_check = check_corners(cfg, scale, run, [(sc.z, sc.temperature_c)
                                                      for sc in problem.scenarios])
    log.times["corner_check"] = time.perf_counter() - t0
    n_corners = corner_count(cfg, problem.box)
    temps = temperatures(cfg)
    at = f" at {len(temps)} temperatures" if len(temps) > 1 else ""
    in_nlp = sum(1 for sc in problem.scenarios if sc.z and all(abs(v) == 1.0 for v in sc.z))
    n_nom = sum(1 for sc in problem.scenarios if sc.origin == "nominal")
    corner_check.update(in_nlp=in_nlp, scenarios=len(problem.scenarios))
    if n_corners > max_corners(cfg):
        lids = "the nominal lid" + (f" at each of the {n_nom} temperatures" if n_nom > 1
                                    else "")
        log.notes.append(f"{len(problem.scenarios)} scenarios instead of {n_corners + n_nom}: "
                         f"{lids}, {in_nlp} of the {n_corners} corners{at} and "
                         f"{len(problem.scenarios) - n_nom - in_nlp} interior points; all "
                         f"{n_corners} corners simulated in the kernel at the design, "
                         f"{len(corner_check['breaking'])} outside the NLP break a constraint")
    return corner_check


def _verification(scen: list, verified: bool) -> dict:
    """The reference's verdict over every scenario and on the worst-case objective."""
    nom = scen[0]
    worst = [s for s in scen if s["worst"]][0]
    rel = None
    if worst.get("reference") and worst["reference"].get("objective"):
        Jr = worst["reference"]["objective"]
        rel = (worst["objective"] - Jr) / abs(Jr)
    return {"ok": verified and rel is not None and abs(rel) <= VERIFY_RTOL,
            "scenarios_verified": sum(bool(s.get("verified")) for s in scen),
            "scenarios": len(scen),
            "worst_objective_relative_difference": rel,
            "nominal_scenario": nom.get("reference"),
            "method": "CVODES (adaptive BDF) on the exact equations, every "
                      "scenario, every constraint"}


def _failures(verification: dict | None, scen: list, corner_check: dict, yres: YieldResult,
              required_yield: float, scale: float) -> list[str]:
    """Why the robust design fails ([] when it succeeds): the reference does not confirm it,
    a corner of the box breaks a constraint, or the yield stays short."""
    msgs = []
    if verification is not None and not verification["ok"]:
        bad = [s["label"] for s in scen if not s.get("verified")]
        msgs.append("the adaptive reference does not confirm " +
                    (f"the scenarios {', '.join(bad)}" if bad else
                     "the worst-case objective (raise optimise.substeps)"))
    if corner_check["breaking"]:
        b = corner_check["breaking"]
        msgs.append(f"{len(b)} corners of the tolerance box break a constraint at the design "
                    f"in the kernel ({'; '.join(b[:3])}{' ...' if len(b) > 3 else ''})")
    if not yres.meets_required:
        msgs.append(f"the Monte Carlo yield {yres.yield_:.4f} stays below the required "
                    f"{required_yield:g} even with the box widened x{scale:.3g}")
    return msgs


def _nominal_json(nominal: dict, nyield: YieldResult | None) -> dict:
    """The nominal optimum as reported beside the robust design, with its yield."""
    return {**nominal,
            "yield": None if nyield is None else nyield.yield_,
            "yield_ci": None if nyield is None else list(nyield.yield_ci),
            "percentiles": None if nyield is None else nyield.percentiles,
            "failures": None if nyield is None else nyield.failures}


__all__ = ["optimise_robust", "RobustResult"]
