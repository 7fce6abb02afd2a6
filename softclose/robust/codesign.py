"""Robust design with free attachment points or a free end damper (``optimise --robust
--free geometry.* --free design.end_damper_c=... --free design.end_damper_angle_deg=...``).

The points are shared by every lid of the tolerance box (they are where the parts are
mounted, not a spread); so is the end damper's engagement angle, and its coefficient is the
nominal value of a part made to a tolerance (its relative spread, like the dashpot's, moves
with it). Two stages:

1. **Where**: the C kernel screens the box of the shared variables
   (:mod:`softclose.optimiser.screening`: a grid of placements, its corners among them,
   each with its best design of a coarse (k, l0, c) grid judged over the nominal lid and
   the box's corners at every sign-off temperature). The best few placements each start the
   scenario NLP with the points fixed there (the robust optimiser's own NLP, its start design
   the robust sweep's at those points); the best of those answers starts the scenario NLP
   with the points (the end damper's c_e and angle) as shared design variables
   (:class:`softclose.robust.nlp.ScenarioNLP`: every scenario's spring length and holding
   moment at the points, each scenario's spring kind valid over the stroke with its own free
   length; every scenario two-phase at the shared angle, with its own c_e), which chooses
   them and the design for the worst case over the scenarios. A free end damper (or a gas
   strut) goes from the best screened placement to the joint NLP at once (its NLP at fixed
   values is no cheaper). The spring kinds are solved one after the other: a later kind
   whose nominal co-design optimum already exceeds an earlier kind's worst case stops there
   (:func:`choose_points`).
2. **What, verified**: at those points (a config with them set, the points no longer free)
   the robust optimiser runs as without free points (:func:`optimise_robust_kind`: start,
   scenario NLP, the interior worst cases and every corner in the kernel, the accuracy
   loop, every scenario re-simulated by the adaptive reference, the yield). Its design is
   the answer; the points are reported with it (``design``: ``spring_anchor[0]`` ...).

Stage 2 runs at the first stage's answer; should its verified worst case be above the best
the screening saw (or should it fail), it runs at the first stage's other candidates too
(the fixed placements' answers, best first) and the best verified one is kept
(:func:`softclose.robust.design.optimise_robust`).

Stage 2 only adds scenarios the NLP of stage 1 did not have; the points are not moved for
them (a design that stays feasible over them is still verified over every corner).
"""

from __future__ import annotations

import itertools
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
from ..optimiser.kinds import kind_config
from ..optimiser.screening import Screening, placement_designs, screen, shared_box
from ..problem import PARAM_COLUMNS, with_designs
from .scenarios import Scenario, factors, maps, temperatures
from .stats import margins
from .policy import t_end
from .evaluate import evaluate, simulator

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
    best screened placement (or the config's points) is returned, and ``info`` says so.

    ``bound``: the best worst-case J another spring kind reached. The nominal lid is one of
    the box's scenarios, so a kind whose nominal co-design optimum already exceeds it cannot
    do better: then (None, info) at once, without the scenario NLP.

    The kernel screens the box of the shared variables first
    (:mod:`softclose.optimiser.screening`); each of its best placements starts the scenario
    NLP with the points fixed there (its start design from the robust optimiser's sweep at
    those points), and the best of those answers starts the joint scenario NLP (the points
    free). ``info["candidates"]``: every placement stage 2 may verify, best first (the
    joint NLP's, then the fixed ones'), so that the answer is the best verified one."""
    t0 = time.perf_counter()
    layout = _layout(cfg)
    info: dict = {}
    if bound is not None:
        nominal = _solve_nominal(cfg)
        info["nominal_objective"] = nominal.objective
        if nominal.objective is not None and nominal.objective > bound:
            return None, info
    scr = screen_robust(cfg)
    info["screening"] = scr
    own = {k: float(np.clip(_value(cfg, k), lo, hi)) for k, lo, hi in free_of(cfg)
           if k in CHOSEN}
    fixed = []
    # the scenario NLP at fixed points is the robust optimiser's own (prepared, compiled):
    # cheaper than the joint one. Not so with the end damper chosen (its NLP at a fixed end
    # damper is another structure) or a gas strut (whose free variables are set up for free
    # points): those go to the joint NLP at once
    cheaper = cfg.design.spring_kind != "gas_strut" and not any(
        k in (END_C, END_ANGLE) for k in layout)
    for i in scr.kept if cheaper else ():
        pts = {**own, **scr.placement(i)}
        t1 = time.perf_counter()
        run, scen = _fixed(cfg, pts)
        if run is None:
            continue
        J = float(np.max(run.J)) if run.success else None
        fixed.append((J, i, pts, run))
        info.setdefault("attempts", []).append({
            "from": "screened placement", "points": pts, "fixed": True,
            "screened_objective": _finite(scr.objective[i]), "status": run.r.status,
            "iterations": run.r.iterations, "objective": J,
            "seconds": time.perf_counter() - t1})
    ranked = sorted((f for f in fixed if f[0] is not None), key=lambda f: f[0])
    candidates = [f[2] for f in ranked]
    start_pts = candidates[0] if candidates else \
        ({**own, **scr.placement(scr.kept[0])} if scr.kept else own)
    start = ranked[0][3].design[:3] if ranked else (scr.designs[scr.kept[0]] if scr.kept
                                                     else None)
    t1 = time.perf_counter()
    run, c_s, scen = _joint(_at(cfg, start_pts), start)
    info.setdefault("attempts", []).append({"from": "the best fixed placement"
                                            if ranked else "the best screened placement",
                                            "fixed": False, "status": run.r.status,
                                            "iterations": run.r.iterations,
                                            "objective": (float(np.max(run.J))
                                                          if run.success else None),
                                            "seconds": time.perf_counter() - t1})
    info.update(scenarios=len(scen), status=run.r.status)
    if run.success and (not ranked or np.max(run.J) <= ranked[0][0] * (1 + 1e-9)):
        points = {k: float(v) for k, v in zip(layout, run.design[3:])}
        candidates.insert(0, points)
        info.update(worst_objective=float(np.max(run.J)))
        notes.append(f"{_what(layout)} chosen by the scenario NLP over {len(scen)} "
                     f"scenarios from the best of {len(scr.kept)} screened placements "
                     f"(worst J {np.max(run.J):.6g} in the NLP): "
                     + ", ".join(_quoted(k, v) for k, v in points.items()))
    elif ranked:
        points = candidates[0]
        info.update(worst_objective=ranked[0][0])
        notes.append(f"{_what(layout)} of the best of {len(scr.kept)} screened placements, "
                     f"solved at fixed points (worst J {ranked[0][0]:.6g} in the NLP; the "
                     f"joint scenario NLP ended {run.r.status}): "
                     + ", ".join(_quoted(k, v) for k, v in points.items()))
    else:
        points = start_pts
        notes.append(f"the scenario NLP with free {_what(layout)} stopped "
                     f"({run.r.status}) from the best screened placements: the best screened "
                     "one is used")
    if not candidates:
        candidates = [points]
    info.update(points=dict(points), candidates=candidates, time=time.perf_counter() - t0)
    notes.append(scr.line(len(fixed) or 1))
    return points, info


def _finite(v) -> float | None:
    return float(v) if np.isfinite(v) else None


#: most scenarios the screening judges every placement in: beyond, those
#: :func:`~.scenarios.initial_scenarios` picks at the config's design
MAX_SCREENED_SCENARIOS = 257


def screened_scenarios(cfg: Config, box) -> list:
    """The scenarios the screening judges a placement's designs in: the nominal lid and
    every corner of the box, at every sign-off temperature (the nominal lid nearest the
    reference temperature first)."""
    ref = cfg.operating.reference_temperature_c
    temps = sorted(temperatures(cfg), key=lambda T: abs(T - ref))
    if (2 ** box.dim + 1) * len(temps) > MAX_SCREENED_SCENARIOS:
        return initial_scenarios(box, cfg, [[getattr(cfg.design, k) for k in DESIGN_KEYS]],
                                 1.0)
    zero = tuple([0.0] * box.dim)
    out = [Scenario(zero, "nominal", T) for T in temps]
    out += [Scenario(tuple(map(float, z)), "corner", T) for T in temps
            for z in itertools.product((-1.0, 1.0), repeat=box.dim)]
    return out


def screen_robust(cfg: Config) -> Screening:
    """The first stage's screening (:func:`softclose.optimiser.screening.screen`) over
    :func:`screened_scenarios`."""
    box = box_of(cfg)
    scen = screened_scenarios(cfg, box)
    m = [maps(box, np.asarray(s.z), factors(cfg, s.temperature_c)) for s in scen]
    shared = shared_box(cfg, end_damper=True)
    keys = [k for k, _, _ in shared]
    mkeys = [k for k in box.keys if k not in PARAM_COLUMNS]
    o = cfg.optimise
    tend = t_end(cfg)

    def judge(V, D, s):
        a, b, vals = m[s]
        P = with_designs(cfg, D)
        for j, k in enumerate(keys):
            if k in PARAM_COLUMNS:
                P[:, PARAM_COLUMNS[k]] = V[:, j]
        P = a * P + b
        cols_keys = list(PARAM_COLUMNS) + mkeys + [k for k in keys if k in SLOTS]
        X = np.column_stack([P] + [np.full(len(P), vals[k]) for k in mkeys]
                            + [V[:, j] for j, k in enumerate(keys) if k in SLOTS])
        cols = evaluate(cfg, cols_keys, X, t_end=tend, explain=False, opening=False)
        mg = margins(cols, o)
        v = np.where(np.isfinite(mg), np.maximum(-mg, 0.0), 10.0)
        return np.asarray(cols["objective"], float), v

    table = simulator(cfg, tend).table
    return screen(shared, lambda V: placement_designs(cfg, table, shared, V, robust=True),
                  judge, len(scen),
                  worst=cfg.tolerance.robust_objective == "worst")


def _fixed(cfg: Config, pts: dict):
    """The scenario NLP at the points ``pts`` (not free; the spring kind's free length
    bounded there, :func:`~softclose.optimiser.kinds.kind_config`), from the robust
    optimiser's start design there: (run, scenarios), or (None, why) when the kind cannot be
    valid at them."""
    c, why = kind_config(fixed_points(cfg, pts), cfg.design.spring_kind, robust=True)
    if why is not None:
        return None, why
    c = c.set("optimise.max_iter", min(c.optimise.max_iter, JOINT_MAX_ITER))
    disc = discretisation(c)
    box = box_of(c)
    first = initial_scenarios(box, c, [[getattr(c.design, k) for k in DESIGN_KEYS]], 1.0)
    start, _ = start_design(c, box, first)
    scen = initial_scenarios(box, c, [start], 1.0)
    problem = Problem(c, 1.0, scen, disc.nodes, disc.substeps)
    x0, J_ref = problem.initial(start)
    return problem.solve(x0, J_ref), scen


def _solve_nominal(cfg: Config):
    """The nominal co-design optimum of ``cfg``'s spring kind (the points free), unverified:
    stage 1's start."""
    return optimise_kind(cfg, verify=False)


#: Ipopt iterations of one joint solve (one iteration of 9 scenarios takes ~0.15-0.3 s)
JOINT_MAX_ITER = 200


def _joint(c: Config, start=None):
    """The scenario NLP with the points free, from the points of ``c`` and the design
    ``start`` (k, l0, c; None: the robust optimiser's start design there): (run, c,
    scenarios)."""
    c = c.set("optimise.max_iter", min(c.optimise.max_iter, JOINT_MAX_ITER))
    disc = discretisation(c)
    N, M = disc.nodes, disc.substeps
    box = box_of(c)
    if start is None:
        first = initial_scenarios(box, c, [[getattr(c.design, k) for k in DESIGN_KEYS]], 1.0)
        start, _ = start_design(c, box, first)
    start = np.asarray(start, float)[:3]
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


def best_verified(cfg, kind, r, c, points, info, notes, solve):
    """Stage 2's answer at the first stage's points, or -- when it failed, or its worst-case
    J is above the best the screening saw -- the best of it and stage 2 at the first stage's
    other candidates (:func:`choose_points`), tried in order until one is no worse than
    the screening's best: (result, its config, its points). ``solve``: stage 2 of a
    config."""
    scr = info.get("screening")
    target = None if scr is None else scr.best_objective
    best = (r, c, points)

    def good(x):
        return x.success and x.objective is not None and (
            target is None or x.objective <= target * (1 + 1e-9))

    for pts in (info.get("candidates") or [])[1:]:
        if good(best[0]):
            break
        c2, why = kind_config(fixed_points(cfg, pts), kind, robust=True)
        if why is not None:
            continue
        r2 = solve(c2)
        notes.append("stage 2 at another candidate of the first stage: worst J "
                     + (f"{r2.objective:.6g}" if r2.objective is not None else "none")
                     + f" ({'verified' if r2.success else 'not verified'}) against "
                     + (f"{best[0].objective:.6g}" if best[0].objective is not None
                        else "none"))
        if (r2.success, -(r2.objective if r2.objective is not None else np.inf)) > \
                (best[0].success, -(best[0].objective if best[0].objective is not None
                                    else np.inf)):
            best = (r2, c2, pts)
    return best


__all__ = ["choose_points", "fixed_points", "best_verified"]
