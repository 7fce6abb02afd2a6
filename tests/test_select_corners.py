"""``select`` screens corners first (:mod:`softclose.catalog.corners`): the pairs their
corners decide get no samples, and the ranking is the one of every pair sampled.

The comparison is with ``select(..., every_sample=True)`` (each pair at its corners, its
nominal point and every Monte Carlo sample, as the corners-first screening's reference):
the same order, the same verdicts, yields, worst J and reasons, pair by pair, on the
shipped illustrative catalogs (a slice of them by default; all of them in the slow test),
with the normal distribution (whose samples beyond the box are run for every pair) and with
two sign-off temperatures.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from softclose.config import default_config

CATALOG = Path(__file__).resolve().parents[1] / "examples" / "catalogs"


def _catalogs(every: int):
    from softclose.catalog import read_dampers, read_springs
    springs = read_springs(CATALOG / "springs.csv").parts
    return springs[::every], read_dampers(CATALOG / "dampers.csv").parts


def _same_ranking(cfg, springs, dampers, samples=256):
    from softclose.catalog import select
    first = select(cfg, springs, dampers, samples=samples, verify=0)
    every = select(cfg, springs, dampers, samples=samples, verify=0, every_sample=True)
    assert [(e["spring"], e["damper"]) for e in first.ranking] == \
        [(e["spring"], e["damper"]) for e in every.ranking]
    for a, b in zip(first.ranking, every.ranking):
        for k in ("feasible", "yield", "worst_objective", "reason", "corners_feasible"):
            assert a[k] == b[k], (a["spring"], a["damper"], k)
        for k, v in a["nominal"].items():      # (the opening effort's batch: last digit)
            w = b["nominal"][k]
            assert v == w or math.isclose(v, w, rel_tol=1e-12) or math.isnan(v) and \
                math.isnan(w), k
        assert b["sampled"]
    sc = first.screening
    assert sc["method"] == "corners first" and every.screening["method"] == "every sample"
    assert sc["decided_by_corners"] + sc["sampled"] == first.pairs == len(first.ranking)
    assert sc["met_every_corner"] + sc["failed_every_corner"] == sc["decided_by_corners"]
    assert every.screening["sampled"] == every.pairs
    # every pair met at every corner and every pair failed at every one was decided by its
    # corners on these catalogs (their constraints monotone over the boxes); the rest sampled
    met = sum(1 for e in every.ranking if e["corners_feasible"] == e["corners"])
    failed = sum(1 for e in every.ranking if e["corners_feasible"] == 0)
    assert sc["met_every_corner"] == met
    assert sc["failed_every_corner"] <= failed
    decided = [e for e in first.ranking if not e["sampled"]]
    assert all(e["yield"] in (0.0, 1.0) for e in decided)
    return first, every


def test_corners_first_ranks_as_every_sample_on_a_slice_of_the_shipped_catalogs():
    """Every eighth shipped spring x every shipped damper (442 pairs)."""
    first, _ = _same_ranking(default_config(), *_catalogs(8))
    sc = first.screening
    assert sc["met_every_corner"] > 0 and sc["failed_every_corner"] > 0 and sc["sampled"] > 0
    assert "corners first:" in first.text() and "sampled" in first.to_json()["screening"]


@pytest.mark.parametrize("values", [{"tolerance.distribution": "normal"},
                                    {"operating.temperatures_c": [5.0, 40.0]}],
                         ids=["normal", "two temperatures"])
def test_corners_first_ranks_as_every_sample_with_normal_spreads_and_temperatures(values):
    first, _ = _same_ranking(default_config().update(values), *_catalogs(13), samples=128)
    assert first.screening["decided_by_corners"] > 0


@pytest.mark.slow
def test_corners_first_ranks_as_every_sample_on_the_shipped_catalogs():
    """All 3,445 pairs; the counts docs/parts.md quotes."""
    first, _ = _same_ranking(default_config(), *_catalogs(1))
    assert first.pairs == 3445
    sc = first.screening
    assert (sc["decided_by_corners"], sc["met_every_corner"], sc["failed_every_corner"],
            sc["sampled"]) == (2856, 1666, 1190, 589)
    assert sc["sample_rows_run"] == 150784 and sc["sample_rows_every"] == 881920
    assert ("corners first: 2856 pairs decided by their corners (1666 meet every one, 1190 "
            "fail every one), 589 sampled (150784 of 881920 sample strokes run)") \
        in first.text()


def _spy(monkeypatch):
    """The rows :func:`softclose.catalog.corners.screen_rows` runs, per call (pairs, rows
    in all)."""
    import softclose.catalog.corners as C
    calls = []
    real = C.run_pairs

    def run_pairs(cfg, box, pairs, rows=None):
        calls.append((len(pairs), len(pairs) * box.points if rows is None else
                      sum(len(r) for r in rows)))
        return real(cfg, box, pairs, rows)
    monkeypatch.setattr(C, "run_pairs", run_pairs)
    return calls


def test_a_pair_failing_every_corner_has_yield_0_and_one_meeting_every_corner_1(monkeypatch):
    """Two pairs of the shipped catalogs decided by their corners: one too slow at every
    corner, one meeting every corner; only their corners and nominal points are run, and
    running every sample says the same (yield 0, yield 1; the same worst J and reason)."""
    from softclose.catalog.corners import screen_rows
    from softclose.catalog.screen import pair_box, summarise
    cfg = default_config()
    springs, dampers = _catalogs(1)
    box = pair_box(cfg, 64)
    every, _, _ = screen_rows(cfg, box, [(s, d) for s in springs[::9] for d in dampers],
                              True)
    sm = summarise(box, every, len(springs[::9]) * len(dampers))
    pairs = [(s, d) for s in springs[::9] for d in dampers]
    cc = sm["corner_count"]
    fail = next(p for p in range(len(pairs)) if cc[p] == 0 and sm["reason"][p] == "too slow")
    meet = next(p for p in range(len(pairs)) if cc[p] == box.corners)
    assert sm["yield"][fail] == 0.0 and sm["yield"][meet] == 1.0
    calls = _spy(monkeypatch)
    cols, sampled, runs = screen_rows(cfg, box, [pairs[fail], pairs[meet]])
    assert not sampled.any() and not runs.any()
    assert calls == [(2, 2 * (box.corners + 1))]     # the corners and nominal point alone
    first = summarise(box, cols, 2)
    assert list(first["yield"]) == [0.0, 1.0]
    assert first["reason"] == [sm["reason"][fail], ""]
    for k in ("worst_objective", "corner_count", "fail_row"):
        assert first[k][0] == sm[k][fail] and first[k][1] == sm[k][meet], k


def test_a_pair_meeting_some_corners_is_sampled(monkeypatch):
    """Pairs meeting some corners: every sample run by default; with ``infer=True`` those
    whose unsettled constraints are monotone run only some samples (in rounds: the rest
    decided by a sample run that meets or fails the constraint and is no better or no
    worse placed along its orientation), the same yields and worst J here."""
    from softclose.catalog.corners import screen_rows
    from softclose.catalog.screen import pair_box, summarise
    cfg = default_config()
    springs, dampers = _catalogs(1)
    box = pair_box(cfg, 128)
    pairs = [(s, d) for s in springs[::9] for d in dampers]
    every, _, _ = screen_rows(cfg, box, pairs, True)
    sm = summarise(box, every, len(pairs))
    some = [p for p in range(len(pairs)) if 0 < sm["corner_count"][p] < box.corners]
    _, _, runs = screen_rows(cfg, box, [pairs[p] for p in some])
    assert (runs == box.samples).all()
    calls = _spy(monkeypatch)
    cols, sampled, runs = screen_rows(cfg, box, [pairs[p] for p in some], infer=True)
    assert sampled.all() and calls[0] == (len(some), len(some) * (box.corners + 1))
    assert sum(c[1] for c in calls[1:]) == runs.sum() <= len(some) * box.samples
    assert runs.min() < box.samples                  # some samples decided without a run
    first = summarise(box, cols, len(some))
    assert list(first["yield"]) == [sm["yield"][p] for p in some]
    assert list(first["worst_objective"]) == [sm["worst_objective"][p] for p in some]


def _head(box, ct, hm=1.0, closed=True):
    """Columns of the corners and nominal point of one pair with the closing time ``ct(z)``
    (z the unit point) and holding moment ``hm(z)``; every other constraint met."""
    Z = box.Z[:box.corners + 1]
    n = len(Z)
    ctv = np.array([ct(z) for z in Z], float)
    hmv = np.array([hm(z) if callable(hm) else hm for z in Z], float)
    cl = np.full(n, closed)
    cols = {"closing_time": ctv, "holding_moment": hmv, "theta_dot_max": np.full(n, -0.05),
            "closed": cl, "status": np.zeros(n, int), "lo": np.full(n, np.nan),
            "hi": np.full(n, np.nan), "min_spring_length": np.full(n, 0.05),
            "max_spring_length": np.full(n, 0.06), "opening_force": np.full(n, 3.0)}
    opt = default_config().optimise
    cols["feasible"] = cl & (ctv <= opt.closing_time_max) & (hmv >= opt.holding_moment_min)
    return cols


@pytest.mark.parametrize("ct, hm, verdict", [
    (lambda z: 0.5 + 0.1 * z[0] + 0.05 * z[1], 1.0, "met"),            # monotone, met
    (lambda z: 0.5 + 0.3 * z[0] * z[1], 1.0, "open"),           # its slope's sign turns
    (lambda z: 1.5 + 0.1 * z[0] - 0.2 * z[2], 1.0, "failed"),          # too slow everywhere
    (lambda z: 0.9 + 0.2 * z[0], 1.0, "open"),                         # too slow at half
    (lambda z: 1.0 + 0.2 * z[0], lambda z: 0.3 * z[0], "open"),        # too slow / not held
    (lambda z: 0.5 + 0.1 * z[0] + 1e-4 * z[0] * z[1], 1.0, "met"),      # a wobble of 2e-4 s
])
def test_corner_verdicts_where_the_slacks_are_and_are_not_monotone(ct, hm, verdict):
    """The verdicts on made-up corner values (d = 4: rate, free length, c, the lid's mass):
    a slack whose edge differences keep their sign along every axis decides the pair; one
    whose sign turns (z0 z1: along z0 it rises where z1 = 1 and falls where z1 = -1) leaves
    it open; so does a pair whose corners fail different constraints."""
    from softclose.catalog.corners import FAILED, MET, OPEN, corner_verdicts
    from softclose.catalog.screen import pair_box
    cfg = default_config()
    box = pair_box(cfg, 8)
    assert box.dim == 4
    v = corner_verdicts(box, _head(box, ct, hm), 1, cfg.optimise)
    assert v[0] == {"met": MET, "open": OPEN, "failed": FAILED}[verdict]


def test_wobble_is_zero_for_a_monotone_slack_and_its_sign_turn_otherwise():
    import itertools
    from softclose.catalog.corners import wobble
    C = np.array(list(itertools.product((-1.0, 1.0), repeat=3)))
    assert wobble((1 + C @ [0.1, -0.2, 0.0])[None], 3)[0] == 0.0
    # z0 z1: along z0 the edges rise by 2 (z1 = 1) and fall by 2 (z1 = -1), likewise along
    # z1; along z2 it is flat
    assert wobble((C[:, 0] * C[:, 1])[None], 3)[0] == pytest.approx(4.0)
    assert wobble(np.array([[np.inf] * 8]), 3)[0] == 0.0           # no limit: flat
    assert wobble(np.r_[np.nan, np.ones(7)][None], 3)[0] == math.inf
