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
- **anything else** (some corners met, or monotonicity not shown): every sample is run, as
  when each pair is sampled.

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

A decided pair's worst J is over its corners and nominal point (J's largest value over
the box where J too is monotone in it; on the shipped catalogs the same as over the
samples); its reason is its corners' (as when every sample is run: corners decide it).
"""

from __future__ import annotations

import itertools

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


def corner_verdicts(box: PairBox, head: dict, npairs: int, opt) -> np.ndarray:
    """Per pair, :data:`MET`, :data:`FAILED` or :data:`OPEN` from its rows at the corners
    and the nominal point (``head``: :func:`.screen.run_pairs` of ``box.head()``; module
    docstring)."""
    nh, nc = box.corners + 1, box.corners
    nT = max(len(box.temperatures), 1)
    per_T = nc // nT
    d = box.dim
    F = np.asarray(head["feasible"], bool).reshape(npairs, nh)
    met = F[:, :nc].all(axis=1)
    none = ~F[:, :nc].any(axis=1)
    ok_met = met.copy()
    failed_by = np.zeros(npairs, bool)
    for S in constraint_slacks(head, opt).values():
        S = S.reshape(npairs, nh)
        corners = S[:, :nc]
        w = np.max([wobble(corners[:, t * per_T:(t + 1) * per_T], d) for t in range(nT)],
                   axis=0)
        with np.errstate(invalid="ignore"):
            lowest, highest = corners.min(axis=1), corners.max(axis=1)
            ok_met &= (lowest > MARGIN * w) & ~(S[:, nc] < lowest - w)
            failed_by |= (highest < -MARGIN * w) & ~(S[:, nc] > highest + w)
    out = np.full(npairs, OPEN)
    out[ok_met] = MET
    out[none & failed_by] = FAILED
    return out


def screen_rows(cfg, box: PairBox, pairs: list, every_sample: bool = False
                ) -> tuple[dict, np.ndarray]:
    """The rows of every pair, as :func:`.screen.run_pairs` of the whole box, and whether
    each pair's samples were run. Corners first (module docstring); a pair decided by its
    corners has its samples inside the box filled with its verdict (feasible or not, J
    -inf so that its worst J is its corners' and nominal point's, the metrics NaN).
    ``every_sample``: every pair's samples run."""
    npairs = len(pairs)
    if every_sample or not box.samples or not npairs:
        return run_pairs(cfg, box, pairs), np.ones(npairs, bool)
    n, nh = box.points, box.corners + 1
    head = run_pairs(cfg, box.head(), pairs)
    verdict = corner_verdicts(box, head, npairs, cfg.optimise)
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
    for who, rows in ((np.flatnonzero(sampled), np.arange(nh, n)),
                      (np.flatnonzero(decided), box.outside)):
        if not len(who) or not len(rows):
            continue
        cols = run_pairs(cfg, box.part(rows), [pairs[i] for i in who])
        for k, v in cols.items():
            v = np.asarray(v).reshape(len(who), len(rows))
            out[k][who[:, None], rows[None, :]] = v
    return {k: v.reshape(npairs * n) for k, v in out.items()}, sampled
