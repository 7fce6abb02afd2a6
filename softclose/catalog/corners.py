"""Corners first: the Monte Carlo samples run only for the pairs their corners leave open.

Every pair is first run at the corners of its tolerance box and at its nominal point
(:meth:`.screen.PairBox.head`). Each constraint of a row is a slack, >= 0 where it is met
(:func:`constraint_slacks`: closing time against its window, the holding moment, a
rebound, closed or not, the spring within its valid range and its part's length limits,
integrated, the opening force where it is bounded). Then, per pair:

- **met at every corner**: if every constraint is monotone over the box, its smallest value
  over the box is at a corner, so every sample inside the box meets it too: the pair's
  yield is 1 without a sample run;
- **failed at every corner by one constraint**: if that constraint is monotone over the
  box, its largest value is at a corner, so it fails at every sample inside the box too:
  yield 0 without a sample run (a pair whose corners fail different constraints -- too
  slow at one, too fast at another -- may pass between them: it is sampled);
- **anything else** (some corners met, or monotonicity not shown) is open: every sample
  runs, as when each pair is sampled. (With ``screen_rows(..., infer=True)``, not the
  default: where each constraint its corners do not settle keeps one sign
  along every axis (:func:`orientation`; the slacks of :data:`WHERE_CLOSED` read only
  where the lid closed), the samples run in rounds (:data:`ROUNDS`): a sample no better
  placed along a constraint's orientation than one that fails it fails it too, one no
  worse placed than one that meets it meets it too, so such samples are decided without
  a run; the rest run in the next round. On the shipped catalogs that ranks every pair
  as every sample does, with 47 % fewer sample strokes of the open pairs; on a catalog
  ten times larger it did not, so it is not ``select``'s.)

**Where monotonicity is checked** (:func:`wobble`): along each axis of the box, the corners
pair up into 2^(d-1) edges, and each edge's difference of a slack is the sign of that
slack's partial derivative along the axis. A slack monotone over the box has the same sign
on every edge of an axis. Where an axis's edges disagree, the smaller side's largest
difference is how far the slack wobbles along that axis; the sum over the axes bounds how
far it may dip between corners. A pair is decided by its corners only where each slack
the decision rests on keeps ``MARGIN`` times its wobble clear of 0 (met: its smallest
corner value above it; failed: its largest below minus it) and the nominal point agrees (a
monotone slack's value at the centre lies within its corners'; a nominal point below the
smallest corner by more than the wobble means it is not monotone). It is a check of
necessary conditions on the rows run anyway, not a proof: a slack could bend between
corners with the same sign on every edge. The shipped catalogs' rankings are checked
equal to the every-sample screening's (tests/test_select_corners.py).

With several sign-off temperatures each temperature's corners are their own box (the
samples run at every temperature). With ``distribution = "normal"`` the samples beyond
the box (a unit coordinate past ±1, about 1 % of them) are not bounded by its corners:
they are run for every pair, decided or not.

A decided pair's worst J is over its corners and nominal point (an open pair's: also over
the samples run) (J's largest value over
the box where J too is monotone in it; on the shipped catalogs the same as over the
samples); its reason is its corners' (as when every sample is run: corners decide it).
"""

from __future__ import annotations

import itertools
import warnings

import numpy as np

from ..simulation.stroke import NUMERICAL_FAILURES, StrokeStatus
from .screen import LIMIT_RTOL, PairBox, run_pairs

#: how many times its wobble a slack must keep clear of 0 for corners to decide a pair
MARGIN = 2.0
#: a decided pair's verdict (decisions of :func:`corner_verdicts`)
MET, FAILED, OPEN = 1, -1, 0


def constraint_slacks(cols: dict, opt) -> dict:
    """Each constraint's slack at every row of ``cols`` (:func:`.screen.run_pairs`'s
    columns): >= 0 where it is met. A lid that did not close is the slow extreme
    (closing time +inf); a limit not given is +inf; what is met or not (closed, in range,
    integrated) is ±1."""
    closed = np.asarray(cols["closed"], bool)
    status = np.asarray(cols["status"])
    with np.errstate(invalid="ignore"):
        ct = np.where(closed, np.asarray(cols["closing_time"], float), np.inf)
        lo, hi = np.asarray(cols["lo"], float), np.asarray(cols["hi"], float)
        s = {"closing_time_max": opt.closing_time_max - ct,
             "holding_moment_min": np.asarray(cols["holding_moment"], float)
             - opt.holding_moment_min,
             "rebound": np.where(closed, -np.asarray(cols["theta_dot_max"], float), np.inf),
             "closed": np.where(closed, 1.0, -1.0),
             "min_length": np.where(np.isnan(lo), np.inf, np.asarray(
                 cols["min_spring_length"], float) - lo * (1 - LIMIT_RTOL)),
             "max_length": np.where(np.isnan(hi), np.inf, hi * (1 + LIMIT_RTOL) - np.asarray(
                 cols["max_spring_length"], float)),
             "in_range": np.where(status == StrokeStatus.OUT_OF_RANGE, -1.0, 1.0),
             "integrated": np.where(np.isin(status, NUMERICAL_FAILURES), -1.0, 1.0)}
        if opt.closing_time_min > 0:
            s["closing_time_min"] = ct - opt.closing_time_min
        if opt.opening_force_max is not None:
            s["opening_force_max"] = opt.opening_force_max - np.asarray(
                cols["opening_force"], float)
    return s


def edges(d: int) -> list:
    """Per axis of a d-dimensional box, the corner indices (in
    ``itertools.product((-1, 1), repeat=d)`` order) at its low and at its high face,
    paired edge by edge."""
    C = np.array(list(itertools.product((-1.0, 1.0), repeat=d)))
    out = []
    for ax in range(d):
        low = np.flatnonzero(C[:, ax] < 0)
        out.append((low, low + 2 ** (d - 1 - ax)))
    return out


def wobble(S: np.ndarray, d: int) -> np.ndarray:
    """How far a slack departs from monotone over each pair's box: ``S`` (pairs, 2^d), its
    values at the corners; per axis, the edges' differences of the smaller sign (their
    largest magnitude, 0 where every edge agrees), summed over the axes. +inf where a
    difference is not a number (a slack infinite at one end of an edge only, or NaN)."""
    w = np.zeros(len(S))
    for low, high in edges(d):
        a, b = S[:, low], S[:, high]
        with np.errstate(invalid="ignore"):
            df = np.where(a == b, 0.0, b - a)        # (inf == inf: flat)
        bad = ~np.isfinite(df)
        up = np.where(df > 0, df, 0.0).max(axis=1)
        down = np.where(df < 0, -df, 0.0).max(axis=1)
        w += np.minimum(up, down)
        w[bad.any(axis=1) & (up > 0) & (down > 0)] = np.inf
        w[np.isnan(df).any(axis=1)] = np.inf
    return w


#: the constraints whose slack means something only where the lid closed (elsewhere it
#: is not evidence for :func:`orientation` and :func:`_infer`)
WHERE_CLOSED = ("rebound", "min_length", "max_length", "holding_moment_min")


def as_evidence(S: dict, closed) -> dict:
    """The slacks of :func:`constraint_slacks` as evidence of a monotone constraint: those
    of :data:`WHERE_CLOSED` NaN where the lid did not close."""
    closed = np.asarray(closed, bool)
    return {k: np.where(closed, v, np.nan) if k in WHERE_CLOSED else v for k, v in S.items()}


def orientation(S: np.ndarray, d: int) -> np.ndarray:
    """Per pair and axis, the sign of a slack's edge differences (``S`` (pairs, 2^d) at the
    corners; edges with a NaN end left out): +1 rising, -1 falling, 0 flat along the axis;
    NaN where the edges disagree or none is left."""
    out = np.full((len(S), d), np.nan)
    for ax, (low, high) in enumerate(edges(d)):
        a, b = S[:, low], S[:, high]
        with np.errstate(invalid="ignore"):
            df = np.where(a == b, 0.0, b - a)
        ok = ~np.isnan(df).all(axis=1)
        up, down = (df > 0).any(axis=1), (df < 0).any(axis=1)
        out[ok & up & ~down, ax] = 1.0
        out[ok & down & ~up, ax] = -1.0
        out[ok & ~up & ~down, ax] = 0.0
    return out


def _verdicts(box: PairBox, head: dict, npairs: int, opt):
    """:func:`corner_verdicts`, and per pair the slacks at its head rows, which constraints
    its corners do not settle (met at every corner with a margin) and their orientations
    per temperature (NaN: not monotone)."""
    nh, nc = box.corners + 1, box.corners
    nT = max(len(box.temperatures), 1)
    per_T = nc // nT
    d = box.dim
    F = np.asarray(head["feasible"], bool).reshape(npairs, nh)
    met = F[:, :nc].all(axis=1)
    none = ~F[:, :nc].any(axis=1)
    ok_met = met.copy()
    failed_by = np.zeros(npairs, bool)
    slacks, open_, sigma = {}, {}, {}
    closed = np.asarray(head["closed"], bool).reshape(npairs, nh)
    for k, S in constraint_slacks(head, opt).items():
        S = S.reshape(npairs, nh)
        corners = S[:, :nc]
        blocks = [corners[:, t * per_T:(t + 1) * per_T] for t in range(nT)]
        w = np.max([wobble(b, d) for b in blocks], axis=0)
        with np.errstate(invalid="ignore"):
            lowest, highest = corners.min(axis=1), corners.max(axis=1)
            settled = (lowest > MARGIN * w) & ~(S[:, nc] < lowest - w)
            ok_met &= settled
            failed_by |= (highest < -MARGIN * w) & ~(S[:, nc] > highest + w)
        slacks[k], open_[k] = S, ~settled
        if k in WHERE_CLOSED:
            corners = np.where(closed[:, :nc], corners, np.nan)
            blocks = [corners[:, t * per_T:(t + 1) * per_T] for t in range(nT)]
            # one value, met, at every corner where the lid closes (a spring length's
            # extreme: the stroke's geometry): met wherever the lid closes, which the
            # constraint "closed" judges
            with np.errstate(invalid="ignore"), warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)
                lo_c, hi_c = np.nanmin(corners, axis=1), np.nanmax(corners, axis=1)
            open_[k] &= ~((lo_c == hi_c) & (lo_c > 0))
        sigma[k] = np.stack([orientation(b, d) for b in blocks], axis=1)   # (P, nT, d)
    out = np.full(npairs, OPEN)
    out[ok_met] = MET
    out[none & failed_by] = FAILED
    return out, slacks, open_, sigma


def corner_verdicts(box: PairBox, head: dict, npairs: int, opt) -> np.ndarray:
    """Per pair, :data:`MET`, :data:`FAILED` or :data:`OPEN` from its rows at the corners
    and the nominal point (``head``: :func:`.screen.run_pairs` of ``box.head()``; module
    docstring)."""
    return _verdicts(box, head, npairs, opt)[0]


def _infer(z_rows, t_rows, known, S, sigma, todo):
    """For the rows ``todo`` of one pair, what a monotone constraint says there: +1 met
    (a row known to meet it is no better placed, along its orientation ``sigma`` (nT, d),
    at the same temperature), -1 failed (a row known to fail it is no worse placed), 0
    unknown. ``known``: the rows that may be evidence (inside the box), ``S``: the
    constraint's slack at every row (NaN: not run, no evidence)."""
    out = np.zeros(len(todo), int)
    if not len(known) or not len(todo):
        return out
    Sk = S[known]
    Yt = z_rows[todo] * sigma[t_rows[todo]]            # oriented: larger is better
    Yk = z_rows[known] * sigma[t_rows[known]]
    several = len(sigma) > 1
    met = np.zeros(len(todo), bool)
    failed = np.zeros(len(todo), bool)
    for sel, side in ((Sk >= 0, met), (Sk < 0, failed)):
        if not sel.any():
            continue
        Y = Yk[sel]
        a, b = (Yt, Y) if side is met else (Y, Yt)     # a row no worse / no better placed
        hit = a[:, :1] >= b[:, :1].T if side is met else a[:, :1].T >= b[:, :1]
        for ax in range(1, Yt.shape[1]):
            hit &= (a[:, ax:ax + 1] >= b[:, ax:ax + 1].T) if side is met else \
                (a[:, ax:ax + 1].T >= b[:, ax:ax + 1])
        if several:
            hit &= t_rows[todo][:, None] == t_rows[known][sel][None, :]
        side |= hit.any(axis=1)
    out[met & ~failed] = 1
    out[failed & ~met] = -1
    return out


#: the samples of a pair run in each round of :func:`screen_rows`'s inference (the rest:
#: every sample still unknown)
ROUNDS = (32, 64)


def screen_rows(cfg, box: PairBox, pairs: list, every_sample: bool = False,
                infer: bool = False) -> tuple[dict, np.ndarray, np.ndarray]:
    """The rows of every pair, as :func:`.screen.run_pairs` of the whole box; whether its
    corners left each pair open (its samples run); how many of each pair's
    sample rows were run. Corners first (module docstring); a pair decided by its
    corners has its samples inside the box filled with its verdict (feasible or not, J
    -inf so that its worst J is its corners' and nominal point's, the metrics NaN), and so
    has a sample of an open pair that its constraints' monotonicity decides.
    ``every_sample``: every pair's samples run; ``infer``: an open pair's samples decided
    by its monotone constraints where they can be (module docstring; not the default)."""
    npairs = len(pairs)
    if every_sample or not box.samples or not npairs:
        return run_pairs(cfg, box, pairs), np.ones(npairs, bool), \
            np.full(npairs, box.points - box.corners - 1)
    n, nh = box.points, box.corners + 1
    opt = cfg.optimise
    head = run_pairs(cfg, box.head(), pairs)
    verdict, _, open_, sigma = _verdicts(box, head, npairs, opt)
    sampled = verdict == OPEN
    out = {}
    for k, v in head.items():
        v = np.asarray(v)
        if v.dtype == object:
            full = np.full((npairs, n), "", dtype=object)
        elif v.dtype == bool:
            full = np.zeros((npairs, n), bool)
        else:
            full = np.full((npairs, n), np.nan if v.dtype.kind == "f" else 0, v.dtype)
        full[:, :nh] = v.reshape(npairs, nh)
        out[k] = full
    decided = ~sampled
    out["feasible"][decided, nh:] = (verdict[decided] == MET)[:, None]
    out["objective"][decided, nh:] = -np.inf
    out["reason"][np.flatnonzero(verdict == FAILED)[:, None], np.arange(nh, n)] = "decided"
    samples = np.arange(nh, n)
    outside = box.outside
    inside = np.setdiff1d(samples, outside)
    in_box = np.ones(n, bool)
    in_box[outside] = False
    todo = {int(p): outside for p in np.flatnonzero(decided) if len(outside)}
    # an open pair whose unsettled constraints keep one sign along every axis at every
    # temperature (sigma): its samples inside the box in rounds, the rows its monotone
    # constraints decide filled in, the rest run
    unsettled = {int(p): [k for k in open_ if open_[k][p]] for p in np.flatnonzero(sampled)}
    corner_failed = ~np.asarray(head["feasible"], bool).reshape(npairs, nh)[:, :-1].all(axis=1)
    mono = [p for p, ks in unsettled.items() if infer and corner_failed[p]
            and not any(np.isnan(sigma[k][p]).any() for k in ks)]
    for p in unsettled:
        todo[p] = samples
    unknown, ran = {}, {}
    for p in mono:
        ran[p] = np.zeros(n, bool)
        ran[p][:nh] = True
        todo[p] = np.r_[outside, inside[:ROUNDS[0]]]
        unknown[p] = inside[ROUNDS[0]:]
    temps = {T: i for i, T in enumerate(box.temperatures)}
    t_rows = np.zeros(n, int) if box.Ts is None else np.array([temps[float(T)]
                                                              for T in box.Ts])
    for r in range(len(ROUNDS) + 1):
        _run_into(cfg, box, pairs, todo, out)
        for p in mono:
            if p in todo:
                ran[p][todo[p]] = True
        todo = {}
        for p in mono:
            rows = unknown[p]
            if not len(rows):
                continue
            S = as_evidence(constraint_slacks({c: v[p] for c, v in out.items()}, opt),
                         out["closed"][p])
            evidence = np.flatnonzero(ran[p] & in_box)      # rows run, inside the box
            state = np.ones(len(rows), int)
            for k in unsettled[p]:
                live = np.flatnonzero(state >= 0)        # (a row failed is decided)
                v = _infer(box.Z, t_rows, evidence, S[k], sigma[k][p], rows[live])
                state[live] = np.where(v < 0, -1, np.where(v == 0, 0, state[live]))
            ok, bad = rows[state == 1], rows[state == -1]
            out["feasible"][p, ok] = True
            out["feasible"][p, bad] = False
            out["objective"][p, np.r_[ok, bad]] = -np.inf
            out["reason"][p, bad] = "decided"
            left = rows[state == 0]
            take = left if r + 1 >= len(ROUNDS) else left[:ROUNDS[r + 1]]
            unknown[p] = left[len(take):]
            if len(take):
                todo[p] = take
        if not todo:
            break
    runs = np.where(sampled, 0, len(outside))
    for p in unsettled:
        runs[p] = n - nh if p not in ran else int(ran[p][nh:].sum())
    return {k: v.reshape(npairs * n) for k, v in out.items()}, sampled, runs


def _run_into(cfg, box: PairBox, pairs: list, todo: dict, out: dict) -> None:
    """Run the rows ``todo`` ({pair index: rows of the box}) of the pairs, in one batch,
    into ``out`` (columns (pairs, rows of the box))."""
    who = [p for p, rows in todo.items() if len(rows)]
    if not who:
        return
    rows = [np.asarray(todo[p], int) for p in who]
    cols = run_pairs(cfg, box, [pairs[p] for p in who], rows)
    at = np.r_[0, np.cumsum([len(r) for r in rows])]
    for k, v in cols.items():
        if k not in out:
            continue
        v = np.asarray(v)
        for j, p in enumerate(who):
            out[k][p, rows[j]] = v[at[j]:at[j + 1]]
