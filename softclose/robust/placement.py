"""Robust design with free attachment points (``optimise --robust --free geometry.*``).

The points are shared by every lid of the tolerance box (they are where the parts are
mounted, not a spread). Two stages:

1. **Where**: the nominal optimum with the points free (:func:`softclose.optimise`'s NLP)
   gives the start points; a coarse kernel sweep of (k, l0, c) at them, judged over the
   box's starting scenarios (:func:`softclose.robust.solve.start_design`), the start design;
   then the scenario NLP with the points as shared design variables
   (:class:`softclose.robust.nlp.ScenarioNLP`: every scenario's spring length and holding
   moment at the points, each scenario's spring kind valid over the stroke with its own
   free length) chooses the points and the design for the worst case over the scenarios.
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
from ..optimiser.placement import SLOTS, placed_config, placement_layout
from ..problem import DESIGN_KEYS


def fixed_points(cfg: Config, points: dict) -> Config:
    """``cfg`` with the attachment points set and no longer free."""
    rest = {k: [lo, hi] for k, lo, hi in (cfg.optimise.free or ()) if k not in SLOTS}
    return placed_config(cfg, points).set("optimise.free", rest or None)


def choose_points(cfg: Config, notes: list, bound: float | None = None) -> tuple[dict, dict]:
    """Stage 1 (module docstring): (points {key: m}, what it found). With no solution the
    points of the nominal optimum (or the config's) are returned, and ``info`` says so.

    ``bound``: the best worst-case J another spring kind reached. The nominal lid is one of
    the box's scenarios, so a kind whose nominal co-design optimum already exceeds it cannot
    do better: then (None, info) at once, without the scenario NLP."""
    from ..optimiser.optimiser import optimise_kind
    t0 = time.perf_counter()
    layout = placement_layout(cfg)
    nominal = optimise_kind(cfg, verify=False)
    c = placed_config(cfg, nominal.design) if nominal.design else cfg
    points = {k: float(v) for k, v in zip(
        (k for k, _, _ in layout),
        (_value(c, k) for k, _, _ in layout))}
    info = {"nominal_objective": nominal.objective, "nominal_points": dict(points)}
    if bound is not None and nominal.objective is not None and nominal.objective > bound:
        return None, info
    own = {k: float(np.clip(_value(cfg, k), lo, hi)) for k, lo, hi in cfg.optimise.free
           if k in SLOTS}
    run = None
    for origin, pts in (("the nominal co-design's points", points),
                        ("the config's own points", own)):
        run, c_s, scen = _joint(placed_config(cfg, pts), nominal)
        info.setdefault("attempts", []).append({"from": origin, "status": run.r["status"],
                                                "iterations": run.r["iterations"]})
        if run.success:
            break
    info.update(scenarios=len(scen), status=run.r["status"], time=time.perf_counter() - t0)
    if run.success:
        points = {k: float(v) for (k, _, _), v in zip(layout, run.design[3:])}
        info.update(worst_objective=float(np.max(run.J)), points=dict(points))
        notes.append(f"attachment points chosen by the scenario NLP over {len(scen)} "
                     f"scenarios from {origin} (worst J {np.max(run.J):.6g} in the NLP): "
                     + ", ".join(f"{k} = {v * 1e3:.2f} mm" for k, v in points.items()))
    else:
        points = own
        notes.append(f"the scenario NLP with free attachment points stopped "
                     f"({run.r['status']}) from the nominal co-design's points and from the "
                     "config's own: the config's points (clipped into their bounds) are used")
    return points, info


#: Ipopt iterations of one joint solve (one iteration of 9 scenarios takes ~0.15-0.3 s)
JOINT_MAX_ITER = 200


def _joint(c: Config, nominal):
    """The scenario NLP with the points free, from the points of ``c``: (run, c, scenarios)."""
    from .box import box_of
    from .nlp import discretise
    from .scenarios import initial_scenarios
    from .solve import Problem, start_design
    c = c.set("optimise.max_iter", min(c.optimise.max_iter, JOINT_MAX_ITER))
    N, M, _, _ = discretise(c)
    box = box_of(c)
    ref = ([nominal.design[k] for k in DESIGN_KEYS] if nominal.design else
           [getattr(c.design, k) for k in DESIGN_KEYS])
    first = initial_scenarios(box, c, [ref], 1.0)
    start, _ = start_design(c, box, np.array([s.z for s in first]))
    scen = initial_scenarios(box, c, [start], 1.0)
    problem = Problem(c, 1.0, scen, N, M)
    x0, J_ref = problem.initial(start)
    return problem.solve(x0, J_ref), c, scen


def _value(cfg: Config, key: str) -> float:
    from ..config.free import config_value
    return config_value(cfg, key)


__all__ = ["choose_points", "fixed_points"]
