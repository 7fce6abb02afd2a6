"""Where the solves start: designs from a coarse sweep of the design box, and a primal
initial guess from each start's simulated stroke."""

from __future__ import annotations

import numpy as np

from ..model import elements
from ..simulation import statics
from ..model.dynamics import COEFFS
from ..problem import DESIGN_KEYS, PARAM_COLUMNS, objective, with_designs
from .cache import stroke_simulator
from .interval import END_ANGLE, END_C, free_layout, free_of
from .nlp import PHASE_FLOOR, T_FLOOR, ShootingNLP
from .free_points import placement_layout
from ..config.free import config_value

#: the coarse sweep of the design box: points along (spring_k, spring_rest_length, damper_c)
SWEEP_SHAPE = (8, 6, 8)
#: most starts one optimisation may solve (each is a full Ipopt solve, ~0.1 s)
MAX_STARTS = 100
#: a free end damper's keys are swept too, at their bounds and midpoint each (its
#: landscape has several basins: the strongest damper engaging as late as allowed; one
#: engaged over most of the stroke; none), with the coarser (k, l0, c) grid of
#: :data:`SWEEP_SHAPE_ENGAGING`. A coefficient's lower bound 0 is left out: a damper of
#: no coefficient makes its angle a variable of no effect, from which Ipopt took 60-90
#: iterations (against 20-25) to today's optimum, which the other starts reach as well when
#: the end damper does not pay (c_e falls to 0 from 0.5 N m s/rad in 14 iterations)
END_LEVELS = 3
SWEEP_SHAPE_ENGAGING = (6, 5, 6)


def _levels(key: str, lo: float, hi: float, count: int = END_LEVELS) -> np.ndarray:
    """The sweep's values of a free end-damper key (``count`` over its bounds, a
    coefficient's 0 left out)."""
    v = np.linspace(lo, hi, count)
    return v[1:] if key == END_C and lo == 0 and hi > 0 else v


def swept_keys(cfg) -> tuple:
    """The free keys the sweep of starts varies beside (k, l0, c): the end damper's
    (``optimise.free``), with their bounds: ((key, lo, hi), ...)."""
    return tuple((k, lo, hi) for k, lo, hi in free_of(cfg) if k in (END_C, END_ANGLE))


def design_rows(cfg, G: np.ndarray, keys=()) -> np.ndarray:
    """Rows of the NLP's design variables (k, l0, c, the free element parameters, the free
    points: :func:`~softclose.optimiser.interval.free_layout`, ``placement_layout``) from
    rows of (k, l0, c, then the columns of ``keys``): every other free variable at cfg's
    value clipped into its bounds."""
    bounds = {k: (lo, hi) for k, lo, hi in free_of(cfg)}
    layout = [k for k, _, _ in free_layout(cfg)] + [k for k, _, _ in placement_layout(cfg)]
    swept = [k for k, _, _ in keys]
    G = np.atleast_2d(np.asarray(G, float))
    cols = [G[:, 3 + swept.index(k)] if k in swept else
            np.full(len(G), float(np.clip(config_value(cfg, k), *bounds[k])))
            for k in layout]
    return np.column_stack([G[:, :3]] + cols) if cols else G[:, :3].copy()


def sweep_time(cfg, t_limit: float) -> float:
    """How long the strokes of the start sweep are simulated: a little beyond the limit."""
    return 1.05 * t_limit + 0.05


def batch_violation(o, r: dict, T: np.ndarray, t_limit: float, release=0.0) -> np.ndarray:
    """How far each stroke of a kernel batch ``r`` (closing times ``T``, inf where open)
    lies outside the problem's limits ``o`` (optimise): the closing-time window and the
    holding moment relative to their limits, plus ``release`` (the start sweep's measure of
    a lid that does not move down at release; 0 where not judged) and theta' > 0 anywhere;
    0 when feasible, 1e3 where a term is not finite."""
    with np.errstate(invalid="ignore"):
        v = (np.maximum(T - t_limit, 0) / t_limit
             + np.maximum(o.closing_time_min - T, 0) / max(t_limit, 1e-9)
             + np.maximum(o.holding_moment_min - r["holding_moment"], 0)
             / max(abs(o.holding_moment_min), 1e-3)
             + release
             + np.maximum(r["theta_dot_max"], 0))
    return np.where(np.isfinite(v), v, 1e3)


def _measure(cfg, sim, G: np.ndarray, keys: tuple, t_limit: float):
    """(violation, J, closing time) by the kernel of the designs ``G`` (rows of k, l0, c,
    then the values of the swept ``keys``): the violation (relative, 0 when feasible) ranks
    the infeasible points too."""
    o, st = cfg.optimise, cfg.stroke
    P = with_designs(cfg, G)
    for j, (k, _, _) in enumerate(keys):
        P[:, PARAM_COLUMNS[k]] = G[:, 3 + j]
    r = sim.run_batch(P)
    release = -statics.slopes(sim.table, st.theta0, P)         # M theta'' at release
    dVg0 = sim.table.evaluate([st.theta0])[0][COEFFS.index("dVg")]  # gravity's alone
    T = np.where(r["closed"], r["closing_time"], np.inf)
    J = objective(o, r["impact_theta_dot"], r["peak_tip_speed"])
    viol = batch_violation(o, r, T, t_limit, np.maximum(release, 0) / max(abs(dVg0), 1e-6))
    return viol, J, T


def sweep_starts(cfg, count: int, t_limit: float, sim=None,
                 shape=SWEEP_SHAPE) -> tuple[np.ndarray, dict]:
    """Start designs from a coarse sweep of the design box (C kernel, ~0.05 s).

    The feasible points (closed within the closing-time bounds, holding moment, moving down
    at release, no rebound) are ranked by objective and picked greedily so that each start
    lies at least 0.2 (in box-normalised units) from the ones before; with too few feasible
    points the least infeasible ones fill up. A free end damper's coefficient and angle
    are swept as well (:func:`swept_keys`). Returns (designs (count, the NLP's design
    variables: :func:`design_rows`), info).
    """
    o = cfg.optimise
    sim = sim or stroke_simulator(cfg, sweep_time(cfg, t_limit))
    keys = swept_keys(cfg)
    if keys and shape == SWEEP_SHAPE:
        shape = SWEEP_SHAPE_ENGAGING
    axes = [np.linspace(*getattr(o, k), n) for k, n in zip(DESIGN_KEYS, shape)] + \
        [_levels(k, lo, hi) for k, lo, hi in keys]
    G = np.array(np.meshgrid(*axes, indexing="ij")).reshape(len(axes), -1).T
    viol, J, T = _measure(cfg, sim, G, keys, t_limit)
    feasible = viol == 0
    order = np.lexsort((np.where(np.isfinite(J), J, np.inf), viol))
    lo = np.array([getattr(o, k)[0] for k in DESIGN_KEYS] + [a for _, a, _ in keys])
    span = np.maximum(np.array([getattr(o, k)[1] for k in DESIGN_KEYS]
                               + [b for _, _, b in keys]) - lo, 1e-12)
    picked: list[int] = []
    for min_dist in (0.2, 0.1, 0.0):
        for i in order:
            if len(picked) >= count:
                break
            if i in picked:
                continue
            z = (G[i] - lo) / span
            if all(np.linalg.norm(z - (G[j] - lo) / span) >= min_dist for j in picked):
                picked.append(int(i))
    G_picked = G[picked]
    if keys:            # each start's end damper refined on a finer grid of its own
        G_picked = _refine_end_damper(cfg, sim, G_picked, keys, t_limit)
    info = {"grid": [len(a) for a in axes],
            "evaluated": int(len(G)),
            "feasible": int(feasible.sum()),
            "best_feasible_objective": float(J[feasible].min()) if feasible.any() else None,
            "fastest_closing_time": float(T.min()) if np.isfinite(T).any() else None}
    return design_rows(cfg, G_picked, keys), info


#: the finer grid of a start's end-damper keys (:func:`_refine_end_damper`): per key
END_REFINE = 9


def _refine_end_damper(cfg, sim, G: np.ndarray, keys: tuple, t_limit: float) -> np.ndarray:
    """The starts ``G`` (rows of k, l0, c, then the end damper's swept keys) with their end
    damper's keys moved to the best point of a finer grid (:data:`END_REFINE` levels of each
    over its bounds, :func:`_levels`; k, l0, c held), by the sweep's own measure (the least
    violation, then J: never worse than the start's own level, which the grid holds); starts
    whose strokes the kernel cannot tell apart (the same row, or a spring of no rate at any
    free length) are kept once. The sweep's three levels of the engagement angle leave most
    starts far from where the angle ends (Ipopt took 100-190 iterations from the middle
    level against 14-21 from the best one)."""
    levels = [_levels(k, lo, hi, END_REFINE) for k, lo, hi in keys]
    mesh = np.array(np.meshgrid(*levels, indexing="ij")).reshape(len(keys), -1).T
    rows = np.repeat(G, len(mesh), axis=0)
    rows[:, 3:3 + len(keys)] = np.tile(mesh, (len(G), 1))
    viol, J, _ = _measure(cfg, sim, rows, keys, t_limit)
    out, seen = [], set()
    for i in range(len(G)):
        sl = slice(i * len(mesh), (i + 1) * len(mesh))
        best = i * len(mesh) + np.lexsort((np.where(np.isfinite(J[sl]), J[sl], np.inf),
                                           viol[sl]))[0]
        stroke = (float(viol[best]), float(J[best])) if np.isfinite(J[best]) else \
            tuple(rows[best])
        if stroke not in seen:
            seen.add(stroke)
            out.append(rows[best])
    return np.array(out)


def stroke_states(r, stroke, th_e: float | None, t_lo: float, t_hi: float, node_times,
                  nodes: int):
    """(T, X (2, N), peak tip speed, T1, simulated) of a shooting NLP's primal start from
    the simulated stroke ``r`` (a :class:`~softclose.simulation.stroke.StrokeResult` with
    its trajectory): the closing time clipped into [t_lo, t_hi], the states at
    ``node_times(T, T1)``; with two phases (``th_e`` the engagement angle, else None) T1
    where the stroke first reaches th_e and the node ``nodes`` - 1 between the phases on
    it. A stroke that could not be integrated (``simulated`` False): a straight line in
    theta over t_hi. The nominal and the scenario NLP start from it."""
    st = stroke
    T1 = None
    if r.ok and r.trajectory is not None:
        tr = r.trajectory
        T = r.closing_time if r.closed else tr["t"][-1]
        T = float(np.clip(T, t_lo, t_hi))
        if th_e is not None:    # where the simulated stroke first crosses theta_e
            below = np.flatnonzero(tr["theta"] <= th_e)
            T1 = T * (st.theta0 - th_e) / (st.theta0 - st.theta_closed)
            if len(below) and below[0] > 0:
                i = below[0]
                t0, t1, a, b = tr["t"][i - 1], tr["t"][i], tr["theta"][i - 1], tr["theta"][i]
                T1 = float(t0 + (t1 - t0) * (a - th_e) / (a - b)) if a != b else float(t1)
            T1 = float(np.clip(T1, PHASE_FLOOR, T - PHASE_FLOOR))
        tn = node_times(T, T1)
        X = np.vstack([np.interp(tn, tr["t"], tr["theta"]),
                       np.minimum(np.interp(tn, tr["t"], tr["theta_dot"]), 0.0)])
        peak = float(np.max(tr["tip_speed"][tr["t"] <= T + 1e-12]))
        simulated = True
    else:  # not integrable at this step: a straight line in theta
        T = t_hi
        if th_e is not None:
            T1 = T * (st.theta0 - th_e) / (st.theta0 - st.theta_closed)
        tn = node_times(T, T1)
        X = np.vstack([st.theta0 + tn / T * (st.theta_closed - st.theta0),
                       np.full(len(tn), (st.theta_closed - st.theta0) / T)])
        peak = 1.0
        simulated = False
    if th_e is not None:        # the node between the phases exactly on theta_e
        X[0, nodes - 1] = th_e
    X[0, -1] = st.theta_closed
    return T, X, peak, T1, simulated


def initial_guess(nlp: ShootingNLP, cfg, design, sim, p: np.ndarray,
                  t_max: float) -> tuple[np.ndarray, float]:
    """Primal start from the simulated stroke of ``design`` on the time grid of ``p``
    (closing time clipped into [closing_time_min, t_max]): (w0, the stroke's objective)."""
    o, st = cfg.optimise, cfg.stroke
    q = nlp.param_vector(cfg, design)
    r = sim.run(q, trajectory=("tip_speed",), estimate_error=False)
    # a two-phase stroke: the node between the phases on the engagement angle
    th_e = float(elements.params(q)["end_damper_angle_deg"]) if nlp.two_phase else None
    T, X, peak, T1, simulated = stroke_states(
        r, st, th_e, max(o.closing_time_min, T_FLOOR), t_max,
        lambda T, T1: nlp.node_times(p, T, T1), nlp.nodes)
    J0 = objective(o, float(X[1, -1]), peak) if simulated else None
    J0 = J0 if J0 is not None and np.isfinite(J0) else 1.0
    return nlp.pack(q, T, X, peak, T1), float(J0)
