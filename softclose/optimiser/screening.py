"""The global first stage of a co-design: the C kernel screens the box of the shared design
variables (the free attachment points; in a robust co-design also a free end damper) before
any NLP is solved.

A placement is one value of every shared variable. The box is sampled by a grid of
:data:`LEVELS` levels per variable (its corners and its centre among them) while that grid
has at most :data:`MAX_PLACEMENTS` points, else by its corners (while there are at most
half as many) and the centre, filled up with a scrambled Halton sequence to
:data:`MAX_PLACEMENTS`. Each placement's start design is chosen from a coarse grid of
(k, l0, c) (:data:`SCREEN_SHAPE`) and judged over the scenarios' corners (the nominal
co-design: its one lid; the robust one: the nominal lid and the tolerance box's corners at
every sign-off temperature): its worst-case objective over those that meet every
constraint in every scenario. Each stroke stops as soon as its energy proves it cannot
close any more (the kernel's early exit).

A scenario's objective is a lower bound of the worst case over the scenarios, so the pairs
(placement, design) are judged in the first scenario (the nominal lid) first and in the
others only in order of that objective, while it is below the best worst case their
placement has reached and below the :data:`KEEP`-th best placement's (:func:`screen`):
the same ranking of the best placements as judging every pair everywhere.

The best :data:`KEEP` placements start the NLPs (:mod:`softclose.robust.codesign`, and the
nominal optimiser's starts: :func:`softclose.optimiser.optimiser.plan_kind`).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from ..problem import DESIGN_KEYS, PARAM_COLUMNS, objective, with_designs
from .free_points import SLOTS
from .interval import END_ANGLE, END_C, free_of
from .starts import batch_violation

#: levels per shared variable of the grid of placements
LEVELS = 3
#: most placements screened (3^4: a grid over four free coordinates)
MAX_PLACEMENTS = 81
#: each placement's coarse grid of (spring_k, spring_rest_length, damper_c)
SCREEN_SHAPE = (6, 9, 6)
#: placements the NLPs start from
KEEP = 3
#: pairs (placement, design) judged in the other scenarios per kernel call
CHUNK = 4096


def shared_box(cfg, end_damper: bool = False) -> tuple:
    """The shared variables a co-design screens, with their bounds ((key, lo, hi), ...):
    the free attachment points and, with ``end_damper``, a free end damper's keys."""
    keys = SLOTS + ((END_C, END_ANGLE) if end_damper else ())
    return tuple((k, float(lo), float(hi)) for k, lo, hi in free_of(cfg) if k in keys)


def placements(box: tuple) -> np.ndarray:
    """The placements screened (rows of the box's keys' values; module docstring)."""
    d = len(box)
    lo = np.array([b[1] for b in box])
    hi = np.array([b[2] for b in box])
    if d == 0:
        return np.zeros((1, 0))
    if LEVELS ** d <= MAX_PLACEMENTS:
        U = np.array(np.meshgrid(*[np.linspace(0, 1, LEVELS)] * d, indexing="ij")
                     ).reshape(d, -1).T
    else:
        U = np.full((1, d), 0.5)
        if 2 ** d <= MAX_PLACEMENTS // 2:
            corners = np.array(np.meshgrid(*[[0.0, 1.0]] * d, indexing="ij")).reshape(d, -1).T
            U = np.vstack([corners, U])
        from scipy.stats import qmc
        rest = MAX_PLACEMENTS - len(U)
        U = np.vstack([U, qmc.Halton(d, scramble=True, seed=0).random(rest)])
    return lo + U * (hi - lo)


def design_grid(cfg, shape=SCREEN_SHAPE, l0=None) -> np.ndarray:
    """The coarse grid of (k, l0, c) every placement is screened with: cfg's design box,
    (g, 3); with ``l0`` = (lo, hi), arrays of the placements' free-length bounds, each
    placement's own, (placements, g, 3), its levels dense near the side the spring kind's
    validity bounds (a compression spring's shortest free length, an extension spring's
    longest: a stiff spring's force moves fast with l0 there)."""
    o = cfg.optimise
    axes = [np.linspace(*getattr(o, k), n) for k, n in zip(DESIGN_KEYS, shape)]
    G = np.array(np.meshgrid(*axes, indexing="ij")).reshape(3, -1).T
    if l0 is None:
        return G
    lo, hi = (np.atleast_1d(np.asarray(x, float)) for x in l0)
    t = np.linspace(0, 1, shape[1]) ** 2       # dense at the valid side's edge
    t = {"compression": t, "extension": 1 - t[::-1]}.get(cfg.design.spring_kind,
                                                        np.linspace(0, 1, shape[1]))
    u = np.array(np.meshgrid(axes[0], t, axes[2], indexing="ij")).reshape(3, -1).T
    out = np.repeat(u[None], len(lo), axis=0)
    hi = np.maximum(hi, lo)         # (no valid free length: the kernel says so)
    out[:, :, 1] = lo[:, None] + u[None, :, 1] * (hi - lo)[:, None]
    return out


#: angles of the stroke at which a placement's spring length is bounded (the kernel's pose
#: pieces interpolated: a few ns each)
LENGTH_ANGLES = 401


def placement_designs(cfg, table, box: tuple, V: np.ndarray, robust: bool = False,
                      shape=SCREEN_SHAPE) -> np.ndarray:
    """Each placement's coarse grid of (k, l0, c) (placements, g, 3): l0 over the free
    lengths that keep cfg's spring kind valid at its points (its length over the stroke
    from the kernel's pose table, :func:`softclose.simulation.kernel.binding.point_grid`;
    :func:`softclose.optimiser.kinds.free_length_bounds`), k and c over cfg's box."""
    from ..simulation.kernel.binding import point_grid
    from .kinds import free_length_bounds
    st = cfg.stroke
    pts = np.tile(table.own_points, (len(V), 1))
    for j, (k, _, _) in enumerate(box):
        if k in SLOTS:
            pts[:, SLOTS.index(k)] = V[:, j]
    th = np.linspace(st.theta_closed, st.theta0, LENGTH_ANGLES)
    L = point_grid(table, th, pts, "l")
    lo, hi = free_length_bounds(cfg, cfg.design.spring_kind, L.min(axis=1), L.max(axis=1),
                                robust)
    lo = np.broadcast_to(np.asarray(lo, float), (len(V),)) * (1 + 1e-9)
    hi = np.broadcast_to(np.asarray(hi, float), (len(V),))
    return design_grid(cfg, shape, (lo, hi))


@dataclass(frozen=True)
class Screening:
    """What the first stage saw: every placement screened, its best start design and its
    worst-case objective over the scenarios (inf: no design of the grid meets every
    constraint in every scenario), and the best :data:`KEEP` kept."""

    keys: tuple
    values: np.ndarray = field(repr=False)       # (placements, len(keys))
    objective: np.ndarray = field(repr=False)    # worst-case J of each's best start design
    violation: np.ndarray = field(repr=False)    # the least violation at each (0: feasible)
    designs: np.ndarray = field(repr=False)      # each's best (k, l0, c)
    scenarios: int
    strokes: int
    seconds: float
    kept: tuple                                  # indices, best first

    @property
    def best_objective(self) -> float | None:
        """The best worst-case J the screening saw (None: no placement met every
        constraint)."""
        J = self.objective[np.isfinite(self.objective)]
        return float(J.min()) if len(J) else None

    def placement(self, i: int) -> dict:
        """Placement ``i`` as {key: value}."""
        return {k: float(v) for k, v in zip(self.keys, self.values[i])}

    def to_json(self) -> dict:
        return {"placements": int(len(self.values)), "scenarios": self.scenarios,
                "strokes": self.strokes, "seconds": self.seconds,
                "best_objective": self.best_objective,
                "feasible": int(np.isfinite(self.objective).sum()),
                "kept": [{"values": self.placement(i),
                          "design": dict(zip(DESIGN_KEYS, map(float, self.designs[i]))),
                          "objective": (float(self.objective[i])
                                        if np.isfinite(self.objective[i]) else None)}
                         for i in self.kept]}

    def line(self, started: int | None = None) -> str:
        """The screening in one line of text (``started``: how many of the kept placements
        started an NLP, default all)."""
        best = self.best_objective
        return (f"screening: {len(self.values)} placements x {self.scenarios} scenario"
                f"{'s' if self.scenarios != 1 else ''} in the kernel ({self.strokes} strokes, "
                f"{self.seconds:.2f} s), best screened J "
                + (f"{best:.6g}" if best is not None else "none (no placement met every "
                   "constraint)") + "; " + (
                    "the best started the NLP" if started == 1 else
                    f"the best {len(self.kept) if started is None else started} started "
                    "the NLPs"))


def screen(box: tuple, G: np.ndarray, judge, scenarios: int, worst: bool = True,
           keep: int = KEEP) -> Screening:
    """Screen the placements of ``box`` with the designs ``G`` (rows of k, l0, c, (g, 3),
    or each placement's own, (placements, g, 3); or a function of the placements giving
    those).

    ``judge(V, D, s)`` gives, for rows of placements V and designs D, in scenario s, the
    objective (NaN where the stroke has none) and the constraint violation (0: met) of each
    row. With ``worst`` (the worst case over the scenarios is ranked; else their mean) the
    other scenarios judge only the pairs whose objective in the first may still matter
    (module docstring)."""
    t0 = time.perf_counter()
    V = placements(box)
    G = G(V) if callable(G) else G
    m = len(V)
    G = np.broadcast_to(G, (m,) + G.shape[-2:])
    g = G.shape[1]
    pi, di = np.repeat(np.arange(m), g), np.tile(np.arange(g), m)
    G = G[pi, di]
    di = np.arange(len(pi))
    J0, v0 = judge(V[pi], G[di], 0)
    strokes = len(pi)
    Jw = np.where(np.isfinite(J0), J0, np.inf)
    viol = np.asarray(v0, float).copy()
    Jsum = np.where(np.isfinite(J0), J0, 0.0)
    done = np.ones(len(pi), bool)
    if scenarios > 1:
        if worst:
            done[:] = False
            cand = np.flatnonzero((viol == 0) & np.isfinite(Jw))
            cand = cand[np.argsort(Jw[cand], kind="stable")]
            best = np.full(m, np.inf)
            for start in range(0, len(cand), CHUNK):
                rows = cand[start:start + CHUNK]
                kth = np.sort(best)[min(keep, m) - 1]
                top = best <= kth
                limit = np.minimum(best[pi[rows]], np.where(top[pi[rows]], np.inf, kth))
                rows = rows[Jw[rows] < limit]
                if not len(rows):
                    if np.isfinite(kth) and Jw[cand[start]] >= kth:
                        break
                    continue
                Jr, vr = _others(judge, V[pi[rows]], G[di[rows]], scenarios)
                strokes += len(rows) * (scenarios - 1)
                Jw[rows] = np.maximum(Jw[rows], Jr)
                viol[rows] += vr
                done[rows] = True
                ok = rows[viol[rows] == 0]
                np.minimum.at(best, pi[ok], Jw[ok])
            if not (done & (viol == 0)).any():     # none met every scenario: rank them all
                rows = np.flatnonzero(~done)
                Jr, vr = _others(judge, V[pi[rows]], G[di[rows]], scenarios)
                strokes += len(rows) * (scenarios - 1)
                Jw[rows] = np.maximum(Jw[rows], Jr)
                viol[rows] += vr
                done[rows] = True
        else:
            Jr, vr, Js = _others(judge, V[pi], G[di], scenarios, total=True)
            strokes += len(pi) * (scenarios - 1)
            Jw = np.where(np.isfinite(Jw) & np.isfinite(Js), (Jsum + Js) / scenarios, np.inf)
            viol += vr
    viol = np.where(done, viol, np.inf)
    J = np.where(done & (viol == 0), Jw, np.inf).reshape(m, g)
    vv = viol.reshape(m, g)
    pick = np.where(np.isfinite(J).any(axis=1), np.argmin(J, axis=1), np.argmin(vv, axis=1))
    Jp = J[np.arange(m), pick]
    vp = vv[np.arange(m), pick]
    order = np.lexsort((Jp, vp))
    kept: list[int] = []
    span = np.array([max(b[2] - b[1], 1e-12) for b in box])
    for i in order:
        if len(kept) >= keep:
            break
        if all(np.linalg.norm((V[i] - V[j]) / span) > 1e-9 for j in kept):
            kept.append(int(i))
    return Screening(tuple(b[0] for b in box), V, Jp, vp, G.reshape(m, g, 3)[np.arange(m), pick],
                     scenarios, int(strokes),
                     time.perf_counter() - t0, tuple(kept))


def _others(judge, V, D, scenarios: int, total: bool = False):
    """The worst objective and the summed violation of rows over scenarios 1 .. S-1 (and
    the sum of their objectives with ``total``)."""
    Jw = np.full(len(V), -np.inf)
    Js = np.zeros(len(V))
    vs = np.zeros(len(V))
    for s in range(1, scenarios):
        J, v = judge(V, D, s)
        Jf = np.where(np.isfinite(J), J, np.inf)
        Jw = np.maximum(Jw, Jf)
        Js = Js + Jf
        vs = vs + np.asarray(v, float)
    return (Jw, vs, Js) if total else (Jw, vs)


def nominal_judge(cfg, sim, box: tuple, t_limit: float):
    """``judge`` of :func:`screen` for the nominal co-design: cfg's lid, the kernel's strokes
    (``sim``: :func:`softclose.optimiser.cache.stroke_simulator`) with each row's points."""
    o = cfg.optimise
    keys = [b[0] for b in box]

    def judge(V, D, s):
        P = with_designs(cfg, D)
        points = {k: V[:, j] for j, k in enumerate(keys) if k in SLOTS}
        for j, k in enumerate(keys):
            if k in PARAM_COLUMNS:
                P[:, PARAM_COLUMNS[k]] = V[:, j]
        r = sim.run_batch(P, points=points or None, explain=False)
        T = np.where(r["closed"], r["closing_time"], np.inf)
        J = objective(o, r["impact_theta_dot"], r["peak_tip_speed"])
        v = batch_violation(o, r, T, t_limit)
        return np.where(np.isfinite(T), J, np.nan), v
    return judge


__all__ = ["Screening", "screen", "placements", "shared_box", "design_grid", "nominal_judge",
           "placement_designs", "LEVELS", "MAX_PLACEMENTS", "SCREEN_SHAPE", "KEEP"]
