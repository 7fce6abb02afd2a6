"""What a screen of many invalid designs no longer pays for, and that it says the same.

- A spring of a kind past its valid range at every angle from the rim to the release is an
  invalid design whatever its stroke does: the kernel does not integrate it (0 steps), as
  the adaptive reference does not, and both report the spring's extremes over
  [theta_closed, theta0] and the same reason.
- Where a spring leaves its range (``statics._leaves``) is found by the kernel's
  ``sc_leaves``: the same numbers, bit for bit, as the numpy arithmetic it replaced.
- The reasons of many rows (``range_messages``) are the texts of ``_message``, row by row.
- A sweep's Parquet strings, written from one join when they are ASCII, read back the same.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import softclose
from softclose.model import elements
from softclose.simulation.kernel import binding
from softclose.simulation import statics
from softclose.config import default_config
from softclose.model.lid import LidModel
from softclose.problem import params_of, resolve
from softclose.simulation.reference import Reference
from softclose.simulation.simulator import Simulator
from softclose.simulation.stroke import StrokeStatus

#: a compression spring whose free length (50 mm) is below the spring's shortest length on
#: the default geometry (52.3 mm): invalid over the whole stroke
WHOLE = {"design.spring_kind": "compression", "design.spring_k": 1500.0,
         "design.spring_preload": 5.0, "design.spring_rest_length": 0.050,
         "design.damper_c": 1500.0}


def test_a_spring_invalid_over_the_whole_stroke_is_not_integrated_and_agrees():
    cfg = default_config().update(WHOLE)
    sim = Simulator.from_config(cfg)
    p = params_of(cfg)
    P = np.tile(p, (3, 1))
    P[1, 1] = 0.056              # beyond its range above some angle: integrated as before
    P[2, 1] = 0.065              # valid over the stroke
    r = sim.run_batch(P)
    assert list(r["status"]) == [StrokeStatus.OUT_OF_RANGE, StrokeStatus.OUT_OF_RANGE,
                                 StrokeStatus.CLOSED]
    assert r["steps"][0] == 0 and r["steps"][1] > 50 and r["steps"][2] > 50
    thc, th0 = cfg.stroke.theta_closed, cfg.stroke.theta0
    assert (r["theta_min"][0], r["theta_max"][0]) == (thc, th0)
    assert "over the whole stroke" in r["reason"][0]
    assert "over the whole stroke" not in r["reason"][1]
    # the same with the early exit off (it is not the early exit), and for one stroke
    r2 = sim.run_batch(P[:1], early_exit=False)
    for k in ("min_spring_length", "max_spring_length", "steps", "status"):
        assert r2[k][0] == r[k][0]
    one = sim.run(p)
    assert one.status is StrokeStatus.OUT_OF_RANGE and one.closing_time is None
    assert one.message == f"invalid design: {r['reason'][0]}"
    # the reference does not integrate it either: the same extremes (to the table's
    # interpolation) and the same reason
    rr = Reference(LidModel.from_config(cfg)).simulate(p)
    assert rr.status is StrokeStatus.OUT_OF_RANGE
    assert rr.min_spring_length == pytest.approx(r["min_spring_length"][0], abs=1e-9)
    assert rr.max_spring_length == pytest.approx(r["max_spring_length"][0], abs=1e-9)
    assert rr.reason == r["reason"][0]
    # the extremes are those of the spring over [theta_closed, theta0]
    th = np.linspace(thc, th0, 2001)
    l = statics.table_coordinate(sim.table)(elements.BY_NAME["spring"], th)
    assert r["min_spring_length"][0] == pytest.approx(l.min(), abs=1e-9)
    assert r["max_spring_length"][0] == pytest.approx(l.max(), abs=1e-9)


def test_rows_with_their_own_points_invalid_throughout_agree_with_a_table_at_them():
    """Per-row points: a placement whose spring is past its free length over the whole
    stroke is skipped with the extremes a simulator built at those points gives."""
    cfg = default_config().update({**WHOLE, "design.spring_rest_length": 0.056})
    sim = Simulator.from_config(cfg)
    p = params_of(cfg)
    pts = {"geometry.spring_anchor[0]": [-0.08, -0.06, -0.045],
           "geometry.spring_anchor[1]": [0.04, 0.02, 0.0]}
    r = sim.run_batch(np.tile(p, (3, 1)), points=pts)
    for i in range(3):
        anchor = (pts["geometry.spring_anchor[0]"][i], pts["geometry.spring_anchor[1]"][i])
        own = Simulator.from_config(cfg.update({"geometry.spring_anchor": anchor}))
        ri = own.run_batch(p[None, :])
        assert r["status"][i] == ri["status"][0]
        assert r["steps"][i] == ri["steps"][0]
        assert r["reason"][i] == ri["reason"][0]
        for k in ("min_spring_length", "max_spring_length"):
            assert r[k][i] == pytest.approx(ri[k][0], rel=1e-9)
    assert r["steps"][0] == 0 and "over the whole stroke" in r["reason"][0]


def _cases(m=4000, G=statics.LEAVE_GRID, seed=7):
    rng = np.random.default_rng(seed)
    lo = rng.uniform(0.0, 0.2, m)
    hi = lo + rng.uniform(0.01, 0.3, m)
    u = np.linspace(0.0, 1.0, G)
    th = lo[:, None] + (hi - lo)[:, None] * u
    th[:, -1] = hi
    x = np.linspace(-1.0, 1.0, G)
    a = rng.normal(size=(m, 4))
    q = a[:, :1] + a[:, 1:2] * x + a[:, 2:3] * x ** 2 + a[:, 3:4] * x ** 3
    q[:50] = 5.0                           # flat: ties everywhere, beyond on the whole grid
    q[50:100, 40] = np.nan                 # a hole
    q[100:200] = np.round(q[100:200], 1)   # plateaus: ties of the worst point
    bound = rng.normal(size=m) * 0.5
    bound[200:250] = -100.0                # beyond on the whole grid
    bound[250:300] = 100.0                 # never beyond
    short = rng.random(m) < 0.5
    bound[:50] = 0.0
    short[:50] = short[200:250] = False    # (above the bound: beyond it everywhere)
    return th, q, bound, short


def leaves_numpy(theta, q, bound, short):
    """The search of ``statics._leaves`` on given angles ``theta`` and values ``q`` (m, G)
    in numpy (as it was before ``sc_leaves``): the second formulation of the kernel's."""
    th, q = np.asarray(theta, float), np.asarray(q, float)
    G = th.shape[1]
    idx = np.arange(G)
    b = np.where(np.asarray(short, bool)[:, None], np.asarray(bound, float)[:, None] - q,
                 q - np.asarray(bound, float)[:, None])
    rows = np.arange(len(th))
    w = np.argmax(b, axis=1)
    dist = np.where(b <= 0, np.abs(idx - w[:, None]), G + 1)
    j = np.argmin(dist, axis=1)
    has = dist[rows, j] <= G
    k = np.clip(np.where(j < w, j + 1, j - 1), 0, G - 1)   # towards the worst point
    bj, bk = b[rows, j], b[rows, k]
    with np.errstate(invalid="ignore", divide="ignore"):
        f = np.where(bk != bj, -bj / (bk - bj), 0.5)       # b crosses 0 between j and k
    edge = np.where(has, th[rows, j] + np.clip(f, 0, 1) * (th[rows, k] - th[rows, j]), np.nan)
    wl, wr = np.clip(w - 1, 0, G - 1), np.clip(w + 1, 0, G - 1)
    c = b[rows, wl] - 2 * b[rows, w] + b[rows, wr]
    with np.errstate(invalid="ignore", divide="ignore"):
        d = np.where((w > 0) & (w < G - 1) & (c < 0), 0.5 * (b[rows, wl] - b[rows, wr]) / c,
                     0.0)
    return edge, th[rows, w] + np.clip(d, -1, 1) * (th[:, 1] - th[:, 0])


def test_the_kernels_leaves_are_the_numpy_arithmetic_bit_for_bit():
    th, q, bound, short = _cases()
    e1, w1 = binding.leaves(th, q, bound, short)
    e0, w0 = leaves_numpy(th, q, bound, short)
    assert np.array_equal(e1, e0, equal_nan=True)
    assert np.array_equal(w1, w0, equal_nan=True)
    assert np.isnan(e1[:50]).all() and np.isnan(e1[200:250]).all()   # beyond throughout
    assert np.isfinite(e1[300:]).mean() > 0.3


def test_a_spring_leaving_its_range_is_located_where_it_crosses():
    """An analytic case: q = theta on [0, 1] leaves bound 0.3 (above) at 0.3 and is worst
    at 1 (the end); below bound 0.3 (short) it leaves at 0.3 and is worst at 0."""
    th = np.tile(np.linspace(0.0, 1.0, statics.LEAVE_GRID), (2, 1))
    e, w = binding.leaves(th, th.copy(), [0.3, 0.3], [False, True])
    assert e == pytest.approx([0.3, 0.3], abs=1e-15)
    assert list(w) == [1.0, 0.0]


def test_the_reasons_of_many_rows_are_each_rows_text():
    cfg = default_config().update({"design.spring_min_length": 0.0312345,
                                   "design.spring_max_length": 0.09})
    sp = elements.BY_NAME["spring"]
    rng = np.random.default_rng(3)
    n = 3000
    kinds = rng.choice([-1.0, 0.0, 1.0], n)
    P = {"spring_kind": kinds, "spring_rest_length": rng.uniform(0.01, 0.1, n)}
    short = rng.random(n) < 0.5
    edge = np.where(rng.random(n) < 0.3, np.nan, rng.uniform(-0.1, 0.4, n))
    worst = rng.uniform(-0.1, 0.4, n)
    excess = rng.exponential(0.01, n)
    excess[:40] = 0.0012345                                   # a rounding tie
    got = sp.range_messages(P, resolve(cfg).lid.mounting, np.arange(n), short, edge, worst,
                            excess)
    want = [sp._message(float(kinds[i]), float(P["spring_rest_length"][i]), bool(short[i]),
                        cfg.design, None if math.isnan(edge[i]) else math.degrees(edge[i]),
                        math.degrees(worst[i]), float(excess[i])) for i in range(n)]
    assert got == want
    assert len({g.split(" than")[0] for g in got}) == 4         # every case came up


def test_parquet_strings_round_trip_ascii_and_not(tmp_path):
    pa = pytest.importorskip("pyarrow")
    from softclose.sweeps.store import _arrow
    for values in (["held open", "", "invalid", "x" * 300], ["θ = 1°", "", "a"],
                   ["a", 3, None]):
        arr = _arrow(np.array(values, dtype=object), pa.string(), False)
        assert arr.to_pylist() == [str(v) for v in values]


def test_a_sweep_of_invalid_placements_reads_as_before():
    """The sweep's rows over a box where most placements are invalid: the statuses and
    reasons of the whole-stroke-invalid rows are the reference's kind of reason."""
    cfg = default_config().update({**WHOLE, "design.spring_rest_length": 0.05843374,
                                   "design.spring_k": 4920.026, "design.damper_c": 4932.998})
    res = softclose.sweep(cfg, {"geometry.spring_anchor[0]": [-0.09, -0.06, -0.03],
                                "geometry.lid_e[0]": [-0.006, 0.019, 0.044]})
    f = res.to_frame()
    whole = [r for r in f["reason"] if "over the whole stroke" in r]
    assert whole and all(r.startswith("the compression spring (it only pushes)")
                         for r in whole)
    assert set(f["status"]) <= {"invalid", "closed", "not closed"}
