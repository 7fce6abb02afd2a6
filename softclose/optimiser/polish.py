"""After the solve: make the NLP's answer agree with the continuous problem.

1. :func:`refine` -- the NLP's objective and metrics are compared with an accurate C-kernel
   simulation of its design; while they differ (objective by more than :data:`REFINE_RTOL`,
   a metric by more than :data:`REFINE_SHARE` of its agreement tolerance) the RK4 sub-steps
   are doubled (same nodes, so the solution carries over) and the problem re-solved.
2. :func:`tighten` -- the NLP's closing time differs from the exact one by its own
   discretisation error; when the simulated stroke of the answer breaks a closing-time
   bound, the bound is shifted by that difference and the problem re-solved warm.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..problem import ERROR_KEYS, agreement_tolerance, objective
from .cache import get_nlp, stroke_simulator
from .discretisation import MAX_STEPS
from .nlp import T_FLOOR, Run, ShootingNLP
from .keep_out import clearance, free_lines

#: the NLP's objective must agree with an accurate simulation of its design to this
#: (relative) before the answer goes to verification; else the sub-steps are doubled
REFINE_RTOL = 1e-4
#: ... and each of its metrics to this share of the agreement tolerance that verification
#: applies (so that a metric the objective does not weigh is accurate too)
REFINE_SHARE = 0.25
#: at most this many doublings of the sub-steps (and never beyond MAX_STEPS RK4 steps)
MAX_REFINE = 4
#: at most this many shifts of the closing-time bounds
MAX_TIGHTEN = 3


def nlp_objective(nlp: ShootingNLP, cfg, run: Run) -> float:
    """J at ``run``'s point with the NLP's own impact speed and peak tip speed."""
    _, _, X, _ = nlp.unpack(run.x)
    return objective(cfg.optimise, float(X[1, -1]), nlp.peak(run))


def _sim(cfg, nlp: ShootingNLP, d, sim):
    """The simulator of ``d``'s stroke: ``sim``, or one at d's attachment points."""
    if not nlp.placed:
        return sim
    return stroke_simulator(nlp.placed_config(cfg, d))


def _merge(new: Run, old: Run) -> Run:
    """``new`` with the cost of the runs that led to it added."""
    return replace(new, time=new.time + old.time, iterations=new.iterations + old.iterations,
                   origin=old.origin)


def _rewarm(nlp: ShootingNLP, run: Run, bounds, notes: list, note) -> Run | None:
    """``run`` re-solved warm (its multipliers) under ``bounds``, merged with it and
    ``note(new run)`` noted; None when the re-solve fails."""
    r = nlp.solve(run.x, run.p, *bounds, run.lam_x, run.lam_g, warm=True)
    if not r.success:
        return None
    notes.append(note(r))
    return _merge(r, run)


def _own(nlp: ShootingNLP, run: Run) -> dict:
    """The NLP's own values of the metrics with an accuracy target (not the impact tip
    speed: it follows from the impact theta')."""
    _, T, X, _ = nlp.unpack(run.x)
    return {"closing_time": T, "impact_theta_dot": float(X[1, -1]),
            "peak_tip_speed": nlp.peak(run)}


def off(cfg, nlp: ShootingNLP, run: Run, rs) -> str:
    """'' when the NLP's objective and metrics at ``run`` agree with the simulated stroke
    ``rs`` of its design (:data:`REFINE_RTOL`, :data:`REFINE_SHARE`), else what differs."""
    J = nlp_objective(nlp, cfg, run)
    Js = objective(cfg.optimise, rs.impact_theta_dot, rs.peak_tip_speed)
    if abs(J - Js) > REFINE_RTOL * abs(Js):
        return f"objective {J:.6g} differs from the simulated {Js:.6g} by " \
               f"{abs(J - Js) / abs(Js):.1e}"
    for k, v in _own(nlp, run).items():
        if k == "closing_time":
            continue          # the closing time is corrected by tighten()
        ref = getattr(rs, k)
        if k in ERROR_KEYS and abs(v - ref) > REFINE_SHARE * agreement_tolerance(k, ref):
            return f"{k} {v:.6g} differs from the simulated {ref:.6g} by {abs(v - ref):.1e}"
    eng = nlp.engagement(run.x)
    if eng is not None and getattr(rs, "engage_time", None) is not None:
        # two phases: the node between them against the simulated engagement
        for k, v in zip(("engage_time", "engage_theta_dot"), eng):
            ref = getattr(rs, k)
            if abs(v - ref) > REFINE_SHARE * agreement_tolerance(k, ref):
                return f"{k} {v:.6g} differs from the simulated {ref:.6g} by {abs(v - ref):.1e}"
    return ""


def refine(cfg, nlp: ShootingNLP, run: Run, sim, notes: list) -> tuple[ShootingNLP, Run]:
    """Double the RK4 sub-steps until the NLP's objective and metrics agree with the
    C-kernel simulation of its design (:func:`off`; at most :data:`MAX_REFINE` times, and
    never beyond :data:`MAX_STEPS` steps; verification judges the result either way)."""
    for _ in range(MAX_REFINE):
        d = nlp.unpack(run.x)[0]
        rs = _sim(cfg, nlp, d, sim).run(nlp.param_vector(cfg, d), estimate_error=False)
        if not rs.closed:
            return nlp, run
        why = off(cfg, nlp, run, rs)
        if not why:
            return nlp, run
        if 2 * nlp.nodes * (nlp.M + (nlp.M_engaged or 0)) > MAX_STEPS:
            notes.append(f"{why}, but doubling the sub-steps would exceed {MAX_STEPS} RK4 "
                         "steps: not refined")
            return nlp, run
        # (two phases: both phases' sub-steps doubled)
        fine = get_nlp(cfg, nlp.nodes, 2 * nlp.M, 2 * nlp.M_engaged if nlp.M_engaged else None)
        r = fine.solve(run.x, run.p, *fine.bounds(cfg, *_time_bounds(nlp, run)))
        if not r.success:
            return nlp, run
        notes.append(f"{why}: sub-steps doubled to {fine.M}"
                     + (f" (phase 2: {fine.M_engaged})" if fine.M_engaged else "")
                     + f" ({r.iterations} iterations)")
        nlp, run = fine, _merge(r, run)
    return nlp, run


def _time_bounds(nlp: ShootingNLP, run: Run) -> tuple[float, float]:
    lbx, ubx = run.bounds[0], run.bounds[1]
    return float(ubx[nlp.iT]), float(lbx[nlp.iT])


def tighten(cfg, nlp: ShootingNLP, run: Run, sim, t_limit: float, notes: list) -> Run:
    """Correct the closing-time bounds for the NLP's own discretisation error.

    The NLP's closing time T differs from the exact one by the RK4 error (a few µs at the
    defaults). When the accurately simulated stroke of the answer lies outside
    [closing_time_min, t_limit], the bound is shifted by that difference and the problem
    re-solved warm (2-5 iterations), so the verified design meets the bound.
    """
    o = cfg.optimise
    t_lo, t_hi = max(o.closing_time_min, T_FLOOR), t_limit
    lo, hi = t_lo, t_hi
    for _ in range(MAX_TIGHTEN):
        d, T, _, _ = nlp.unpack(run.x)
        rs = _sim(cfg, nlp, d, sim).run(nlp.param_vector(cfg, d), estimate_error=False)
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
        new = _rewarm(nlp, run, nlp.bounds(cfg, t_max=hi, t_min=lo), notes, lambda r: (
            f"closing-time bounds corrected for the NLP's discretisation error "
            f"({shift:+.2e} s): solved with [{lo:.9g}, {hi:.9g}] s, "
            f"{r.iterations} warm iterations"))
        if new is None:
            return run
        run = new
    return run


def keep_clear(cfg, nlp: ShootingNLP, run: Run, notes: list) -> Run:
    """The keep-out regions hold at the NLP's angle nodes; between them a line may still
    graze a region. Checked exactly (:func:`softclose.optimiser.keep_out.clearance`); while
    a free line crosses one, the nodes' bound is raised by 1.5 times the crossing and the
    problem re-solved warm (at most :data:`MAX_TIGHTEN` times)."""
    groups = dict(nlp.groups())
    if not cfg.optimise.keep_out or "keep_out" not in groups:
        return run
    names = {ln[0] for ln in free_lines(nlp.place)}
    margin = 0.0
    for _ in range(MAX_TIGHTEN):
        d = nlp.unpack(run.x)[0]
        worst = min((c["clearance"] for line, c in clearance(nlp.placed_config(cfg, d)).items()
                     if line in names), default=0.0)
        if worst >= 0.0:
            return run
        margin += 1.5 * -worst + 1e-7
        lbx, ubx, lbg, ubg = (np.array(b, float) for b in run.bounds)
        lbg[groups["keep_out"]] = margin
        new = _rewarm(nlp, run, (lbx, ubx, lbg, ubg), notes, lambda r: (
            f"keep-out: a line grazed a region between the NLP's angle nodes by "
            f"{-worst * 1e3:.3f} mm: re-solved with a clearance of {margin * 1e3:.3f} mm "
            f"at the nodes ({r.iterations} warm iterations)"))
        if new is None:
            return run
        run = new
    return run
