"""Robust design with free attachment points or a free end damper (``optimise --robust
--free geometry.* --free design.end_damper_c=... --free design.end_damper_angle_deg=...``).

The points are shared by every lid of the tolerance box (they are where the parts are
mounted, not a spread); so is the end damper's engagement angle, and its coefficient is the
nominal value of a part made to a tolerance (its relative spread, like the dashpot's, moves
with it). Two stages:

1. **Where**: the nominal optimum with the points free (:func:`softclose.optimise`'s NLP)
   gives the start points; a coarse kernel sweep of (k, l0, c) at them, judged over the
   box's starting scenarios (:func:`softclose.robust.solve.start_design`), the start design;
   then the scenario NLP with the points (the end damper's c_e and angle) as shared design
   variables (:class:`softclose.robust.nlp.ScenarioNLP`: every scenario's spring length and
   holding moment at the points, each scenario's spring kind valid over the stroke with its
   own free length; every scenario two-phase at the shared angle, with its own c_e) chooses
   them and the design for the worst case over the scenarios. The spring kinds are solved
   one after the other: a later kind whose nominal optimum already exceeds an earlier
   kind's worst case stops there (:func:`choose_points`).
2. **What, verified**: at those points (a config with them set, the points no longer free)
   the robust optimiser runs as without free points (:func:`optimise_robust_kind`: start,
   scenario NLP, the interior worst cases and every corner in the kernel, the accuracy
   loop, every scenario re-simulated by the adaptive reference, the yield). Its design is
   the answer; the points are reported with it (``design``: ``spring_anchor[0]`` ...).

Stage 2 only adds scenarios the NLP of stage 1 did not have; the points are not moved for
them (a design that stays feasible over them is still verified over every corner).
"""

from __future__ import annotations

import time

import numpy as np

from ..config import Config
from ..optimiser.interval import END_ANGLE, END_C, free_layout, free_of
from ..optimiser.free_points import SLOTS, placed_config, placement_layout
from ..problem import DESIGN_KEYS
from ..config.free import config_value
from .solve import Problem, start_design
from .scenarios import initial_scenarios
from ..optimiser.discretisation import discretisation
from .box import box_of
from ..optimiser.optimiser import optimise_kind

#: the free keys the first stage chooses: the points and the end damper
CHOSEN = SLOTS + (END_C, END_ANGLE)


def fixed_points(cfg: Config, points: dict) -> Config:
    """``cfg`` with the attachment points (the end damper's keys) set and no longer free."""
    rest = {k: [lo, hi] for k, lo, hi in (cfg.optimise.free or ()) if k not in CHOSEN}
    ends = {k: float(v) for k, v in points.items() if k in (END_C, END_ANGLE)}
    out = placed_config(cfg, {k: v for k, v in points.items() if k not in ends})
    return (out.update(ends) if ends else out).set("optimise.free", rest or None)


def _layout(cfg: Config) -> list:
    """The first stage's variables, in the scenario NLP's order: the end damper's, then the
    points."""
    return [k for k, _, _ in free_layout(cfg)] + [k for k, _, _ in placement_layout(cfg)]


def choose_points(cfg: Config, notes: list, bound: float | None = None) -> tuple[dict, dict]:
    """Stage 1 (module docstring): (points {key: m}, what it found). With no solution the
    points of the nominal optimum (or the config's) are returned, and ``info`` says so.

    ``bound``: the best worst-case J another spring kind reached. The nominal lid is one of
    the box's scenarios, so a kind whose nominal co-design optimum already exceeds it cannot
    do better: then (None, info) at once, without the scenario NLP."""
    t0 = time.perf_counter()
    layout = _layout(cfg)
    nominal = _solve_nominal(cfg)
    c = _at(cfg, nominal.design or {})
    points = {k: _value(c, k) for k in layout}
    info = {"nominal_objective": nominal.objective, "nominal_points": dict(points)}
    if bound is not None and nominal.objective is not None and nominal.objective > bound:
        return None, info
    own = {k: float(np.clip(_value(cfg, k), lo, hi)) for k, lo, hi in free_of(cfg)
           if k in CHOSEN}
    run = None
    for origin, pts in (("the nominal co-design's points", points),
                        ("the config's own points", own)):
        run, c_s, scen = _joint(_at(cfg, pts), nominal)
        info.setdefault("attempts", []).append({"from": origin, "status": run.r.status,
                                                "iterations": run.r.iterations})
        if run.success:
            break
    info.update(scenarios=len(scen), status=run.r.status, time=time.perf_counter() - t0)
    if run.success:
        points = {k: float(v) for k, v in zip(layout, run.design[3:])}
        info.update(worst_objective=float(np.max(run.J)), points=dict(points))
        notes.append(f"{_what(layout)} chosen by the scenario NLP over {len(scen)} "
                     f"scenarios from {origin} (worst J {np.max(run.J):.6g} in the NLP): "
                     + ", ".join(_quoted(k, v) for k, v in points.items()))
    else:
        points = own
        notes.append(f"the scenario NLP with free {_what(layout)} stopped "
                     f"({run.r.status}) from the nominal co-design's and from the "
                     "config's own: the config's (clipped into their bounds) are used")
    return points, info


def _solve_nominal(cfg: Config):
    """The nominal co-design optimum of ``cfg``'s spring kind (the points free), unverified:
    stage 1's start."""
    return optimise_kind(cfg, verify=False)


#: Ipopt iterations of one joint solve (one iteration of 9 scenarios takes ~0.15-0.3 s)
JOINT_MAX_ITER = 200


def _joint(c: Config, nominal):
    """The scenario NLP with the points free, from the points of ``c``: (run, c, scenarios)."""
    c = c.set("optimise.max_iter", min(c.optimise.max_iter, JOINT_MAX_ITER))
    disc = discretisation(c)
    N, M = disc.nodes, disc.substeps
    box = box_of(c)
    ref = ([nominal.design[k] for k in DESIGN_KEYS] if nominal.design else
           [getattr(c.design, k) for k in DESIGN_KEYS])
    first = initial_scenarios(box, c, [ref], 1.0)
    start, _ = start_design(c, box, first)
    scen = initial_scenarios(box, c, [start], 1.0)
    problem = Problem(c, 1.0, scen, N, M)
    x0, J_ref = problem.initial(start)
    return problem.solve(x0, J_ref), c, scen


def _value(cfg: Config, key: str) -> float:
    return float(config_value(cfg, key))


def _at(cfg: Config, values: dict) -> Config:
    """``cfg`` with the first stage's variables at ``values`` (by full key, or -- as the
    optimiser's design names them -- without the section), still free."""
    full = {}
    for k, v in values.items():
        for key in (k, f"geometry.{k}", f"design.{k}"):
            if key in CHOSEN:
                full[key] = float(v)
    pts = {k: v for k, v in full.items() if k in SLOTS}
    ends = {k: v for k, v in full.items() if k not in SLOTS}
    out = placed_config(cfg, pts)
    return out.update(ends) if ends else out


def _what(layout) -> str:
    """What the first stage chooses, in words."""
    parts = (["the end damper"] if any(k in (END_C, END_ANGLE) for k in layout) else []) + \
        (["attachment points"] if any(k in SLOTS for k in layout) else [])
    return " and ".join(parts)


def _quoted(key: str, v: float) -> str:
    """One chosen value with its unit (a point in mm)."""
    if key in SLOTS:
        return f"{key} = {v * 1e3:.2f} mm"
    return f"{key} = {v:.6g} " + ("deg" if key == END_ANGLE else "N m s/rad")


__all__ = ["choose_points", "fixed_points"]
