"""Per-row attachment points (issue 23, item 3): the kernel takes each row's own spring and
dashpot points (lengths from the table's pose pieces), so a sample over placements needs
no model per value.

Checks: rows with points against a simulator built at those points (every metric, status
and reason; the row's pieces are those of a table at the points, so they agree to the
rounding of the node values -- measured 0 to 4e-13 relative, asserted at 1e-9, the
tables' interpolation level the issue allows); a few placements against the adaptive
reference at its accuracy targets; rows without points bit for bit as before (no point
columns, NaN point columns, the config's own points, in a batch mixed with point rows);
the early exit with point rows (the same metrics with and without it for every method, the
energy margin on the rest of every exited stroke); the scalar and SIMD paths bit for bit;
sweeps, samples, the tolerance analysis with a placement key; bad points reported per row.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import softclose
from softclose.simulation.kernel import binding
from softclose.config import default_config
from softclose.config.free import PLACEMENT_KEYS
from softclose.errors import ConfigError
from softclose.problem import ERROR_KEYS, params_of, resolve, target
from softclose.simulation.reference import Reference
from softclose.robust.evaluate import evaluate, slow_keys
from softclose.simulation.simulator import Simulator
from softclose.simulation.stroke import StrokeStatus

from kernel_checks import energy_rise_ratio, scalar_strokes

#: the issue's placement box (the co-design's --free bounds), m
BOX = {"geometry.spring_anchor[0]": (-0.09, -0.03), "geometry.spring_anchor[1]": (-0.01, 0.05),
       "geometry.lid_e[0]": (-0.006, 0.044), "geometry.lid_e[1]": (0.004, 0.024)}
#: a dashpot box around pin C and the pivot O
DASH = {"geometry.dashpot_anchor[0]": (-0.01, 0.01), "geometry.dashpot_anchor[1]": (-0.01, 0.01),
        "geometry.dashpot_lid[0]": (0.0, 0.03), "geometry.dashpot_lid[1]": (0.0, 0.03)}
#: the README's robust optimum (a compression spring)
ROBUST = {"design.spring_k": 4920.026, "design.spring_rest_length": 0.05843374,
          "design.damper_c": 4932.998, "design.spring_kind": "compression"}
#: the metrics and kernel columns compared with a simulator at the points
KEYS = ("closing_time", "impact_theta_dot", "impact_tip_speed", "peak_tip_speed",
        "min_spring_length", "max_spring_length", "holding_moment", "opening_force",
        "theta_min", "theta_max", "theta_dot_max", "stop_theta", "energy_rise", "engage_time",
        "engage_theta_dot")
RTOL = 1e-9
COL = {name: i for i, name in enumerate(binding.OUT_FIELDS)}


def draw(box: dict, n: int, seed: int) -> dict:
    rng = np.random.default_rng(seed)
    return {k: rng.uniform(lo, hi, n) for k, (lo, hi) in box.items()}


#: design variants at each placement: (config changes, lid mass or None)
VARIANTS = (
    ({"design.spring_k": 1914.709, "design.spring_rest_length": 0.07925707,
      "design.damper_c": 2087.754}, None),                              # linear spring
    (ROBUST, None),                                                      # compression
    ({**ROBUST, "design.spring_preload": 20.0, "design.spring_k": 2000.0,
      "design.spring_rest_length": 0.09}, 0.55),                          # preload, lid mass
    ({"design.spring_kind": "extension", "design.spring_preload": 5.0, "design.spring_k": 800.0,
      "design.spring_rest_length": 0.02, "design.damper_c": 3000.0,
      "design.damper_one_way": True}, None),                              # one-way damper
    ({"design.spring_k": 3000.0, "design.spring_rest_length": 0.06, "design.damper_c": 1500.0,
      "friction.torque": 0.05}, 0.45),                                    # friction
    ({"design.spring_k": 1914.709, "design.spring_rest_length": 0.07925707,
      "design.damper_c": 800.0, "design.end_damper_c": 0.4,
      "design.end_damper_angle_deg": 6.0}, None),                         # end damper
)


def _compare(res, i, other, j, where):
    assert int(res["status"][i]) == int(other["status"][j]), where
    assert res["reason"][i] == other["reason"][j], where
    assert res["stop_reason"][i] == other["stop_reason"][j], where
    for k in KEYS:
        a, b = float(res[k][i]), float(other[k][j])
        if math.isnan(b):
            assert math.isnan(a), (where, k, a, b)
            continue
        assert a == pytest.approx(b, rel=RTOL, abs=1e-15), (where, k, a, b)


@pytest.mark.parametrize("with_dashpot", [False, True])
def test_points_match_a_model_at_those_points(with_dashpot):
    """60 placements (spring points in the issue's box, or spring and dashpot points) x 6
    design variants (one with an end damper: its engagement too): every metric, status and
    reason equal to a simulator of the config with those points (360 rows in one batch a
    variant)."""
    n = 30
    pts = draw(BOX, n, 1 + with_dashpot)
    if with_dashpot:
        pts.update(draw(DASH, n, 7))
    worst = 0.0
    statuses = set()
    fresh, fresh_cfgs = [], []
    for i in range(n):
        c = default_config().update({k: float(v[i]) for k, v in pts.items()})
        fresh.append(Simulator.from_config(c))
        fresh_cfgs.append(c)
    for changes, mass in VARIANTS:
        cfg = default_config().update(changes)
        sim = Simulator.from_config(cfg)
        P = np.tile(params_of(cfg), (n, 1))
        res = sim.run_batch(P, lid_mass=mass, points=pts)
        res["opening_force"] = sim.opening_forces(P, mass, res["points"])
        for i in range(n):
            other_sim = fresh[i]
            case = resolve(fresh_cfgs[i].update(changes))    # (same geometry: same table)
            other_sim.case, other_sim.stroke = case, case.stroke
            other = other_sim.run_batch(P[i:i + 1], lid_mass=mass)
            other["opening_force"] = other_sim.opening_forces(P[i:i + 1], mass)
            _compare(res, i, other, 0, (changes, i))
            statuses.add(int(res["status"][i]))
            for k in KEYS:
                a, b = float(res[k][i]), float(other[k][0])
                if not math.isnan(b) and b != 0:
                    worst = max(worst, abs(a - b) / abs(b))
    # the batch covers closing, open, invalid (a spring beyond its free length) strokes
    assert {StrokeStatus.CLOSED, StrokeStatus.NOT_CLOSED, StrokeStatus.OUT_OF_RANGE} <= statuses
    assert worst < RTOL


def test_points_against_the_reference():
    """Three placements: the kernel's stroke at per-row points against the adaptive reference
    of a model at those points, within the accuracy targets (as the fixed-step simulator at a
    model's own points is)."""
    cfg = default_config().update({"design.spring_k": 1914.709,
                                   "design.spring_rest_length": 0.07925707,
                                   "design.damper_c": 2087.754})
    sim = Simulator.from_config(cfg)
    pts = {"geometry.spring_anchor[0]": [-0.08, -0.07, -0.035],
           "geometry.spring_anchor[1]": [0.0, 0.03, 0.045],
           "geometry.lid_e[0]": [0.03, 0.0, 0.04], "geometry.lid_e[1]": [0.02, 0.015, 0.022]}
    P = np.tile(params_of(cfg), (3, 1))
    res = sim.run_batch(P, points=pts)
    for i in range(3):
        c = cfg.update({k: v[i] for k, v in pts.items()})
        R = Reference(softclose.model.lid.LidModel.from_config(c)).simulate(P[i])
        assert res["closed"][i] and R.closed
        for k in ERROR_KEYS:
            assert abs(res[k][i] - getattr(R, k)) <= target(k, getattr(R, k)), (i, k)
        assert res["min_spring_length"][i] == pytest.approx(R.min_spring_length, rel=1e-8)
        assert res["max_spring_length"][i] == pytest.approx(R.max_spring_length, rel=1e-8)


def test_rows_without_points_bit_identical(sim):
    """No point columns, NaN point columns, the config's own points (given whole, or one
    component): the same bits; and in a batch mixed with point rows (lanes shared)."""
    rng = np.random.default_rng(3)
    n = 200
    P = np.tile(sim.case.p, (n, 1))
    P[:, 0] = rng.uniform(500, 9500, n)
    P[:, 1] = rng.uniform(0.05, 0.09, n)
    P[:, 2] = rng.uniform(100, 4000, n)
    base = sim.run_batch(P)
    own = sim.table.own_points
    mixed = np.full((n, 8), np.nan)
    mixed[::2, :4] = np.column_stack([rng.uniform(lo, hi, n // 2) for lo, hi in BOX.values()])
    for points in (np.full(8, np.nan), own, {"geometry.lid_e[0]": own[2]}, mixed):
        res = sim.run_batch(P, points=points)
        rows = slice(None) if points is not mixed else slice(1, None, 2)
        for k in binding.OUT_FIELDS + ("holding_moment",):
            assert np.array_equal(res[k][rows], base[k][rows], equal_nan=True), k
        assert list(res["reason"][rows]) == list(base["reason"][rows])
    assert np.array_equal(sim.opening_forces(P, points=mixed)[1::2],
                          sim.opening_forces(P)[1::2])


def _point_designs(sim, n=96, seed=5):
    """Designs with their own points that often stay open (a weak spring, strong damping),
    as the kernel's rows (with the lid-mass and point columns)."""
    rng = np.random.default_rng(seed)
    P = np.tile(sim.case.p, (n, 1))
    P[:, 0] = rng.uniform(500, 9500, n)
    P[:, 1] = rng.uniform(0.05, 0.09, n)
    P[:, 2] = rng.uniform(100, 4000, n)
    pts = draw(BOX, n, seed)
    X = binding.point_rows(sim.table, pts, n)
    D = np.column_stack([binding.kernel_rows(P), sim.energy_tol(P, None, X), np.full(n, np.nan),
                         X])
    return P, X, D


def _strokes(sim, D, early=True):
    st = sim.stroke
    return binding.run_strokes(sim.table, sim.method, sim.step, st.t_max, st.theta0,
                              st.theta_closed, D, early_exit=early)


FINAL = ("status", "closing_time", "impact_theta_dot", "impact_tip_speed", "peak_tip_speed",
         "min_spring_length", "max_spring_length", "theta_min", "theta_max", "theta_dot_max",
         "energy_rise", "stop_reason")


@pytest.mark.parametrize("integrator,step", [("rk4", 2e-3), ("euler_cromer", 5e-4),
                                             ("gauss4", 2e-3), ("radau5", 4e-3)])
def test_early_exit_with_points(cfg, model, integrator, step):
    """Point rows: every final column the same with and without the early exit, for each
    method; and on the rest of every exited stroke the energy (from the row's own lengths)
    never rises above E + delta, the margin the rule rests on."""
    sim = Simulator.from_config(cfg, model, integrator=integrator, step=step)
    st = cfg.stroke
    P, X, D = _point_designs(sim, 64 if integrator in ("gauss4", "radau5") else 96)
    on, off = _strokes(sim, D, True), _strokes(sim, D, False)
    for key in FINAL:
        assert np.array_equal(on[:, COL[key]], off[:, COL[key]], equal_nan=True), key
    ex = np.nonzero((on[:, COL["status"]] == 1)
                    & (on[:, COL["stop_time"]] < st.t_max * (1 - 1e-12)))[0]
    assert len(ex) >= 8
    worst = 0.0
    for i in ex[:12]:
        _, tr = binding.run_stroke_trajectory(sim.table, sim.method, step, st.t_max, st.theta0,
                                             st.theta_closed, D[i], early_exit=False)
        c = sim.table.evaluate(tr[:, 1])
        l = binding.point_lengths(sim.table, tr[:, 1], np.tile(X[i], (len(tr), 1)))["l"]
        E = 0.5 * c[:, 0] * tr[:, 2] ** 2 + c[:, 2] + 0.5 * P[i, 0] * (l - P[i, 1]) ** 2
        scale = abs(c[0, 2]) + 0.5 * P[i, 0] * (l[0] - P[i, 1]) ** 2 + abs(E[0])
        worst = max(worst, energy_rise_ratio(E, tr[:, 0], int(on[i, COL["steps"]]), st.t_max,
                                             step, scale, i))
    assert worst < 0.9


def test_scalar_and_simd_agree_on_point_rows(sim):
    """SC_SCALAR=1 (the lane-by-lane code) gives the same bits on point rows, mixed with
    rows without points and with a lid-mass column; and one row at a time the same too."""
    P, X, D = _point_designs(sim, 96, 11)
    D[::3, -8:] = np.nan                                   # some rows without points
    D[::5, binding._NP + 1] = 0.55                          # some at another lid mass
    ec = binding.DESIGN_COLUMNS.index("end_damper_c")       # some with an end damper
    D[1::4, ec], D[1::4, ec + 1] = 0.3, math.radians(7.0)
    on = _strokes(sim, D)
    assert np.array_equal(scalar_strokes(D), on, equal_nan=True)
    one = np.vstack([_strokes(sim, D[i:i + 1]) for i in range(0, 96, 13)])
    assert np.array_equal(one, on[::13], equal_nan=True)


def test_placement_keys_are_fast_keys():
    assert slow_keys(list(PLACEMENT_KEYS) + ["mass.lid", "geometry.crank_oa"]) == \
        ["geometry.crank_oa"]


def test_sample_over_placement_keys_matches_simulate():
    """A sample over the four placement keys: each row as softclose.simulation.simulator of the config
    with that row's points (metrics, status, reason)."""
    cfg = default_config().update({"design.spring_k": 1914.709,
                                   "design.spring_rest_length": 0.07925707,
                                   "design.damper_c": 2087.754})
    res = softclose.sample(cfg, BOX, 64, seed=2)
    df = res.to_frame()
    assert set(df["status"]) >= {"closed"}
    for i in range(0, 64, 8):
        row = df.iloc[i]
        r = softclose.simulate(cfg.update({k: float(row[k]) for k in BOX}))
        assert (row["status"] == "closed") == r.closed
        for k in ("closing_time", "impact_theta_dot", "peak_tip_speed", "min_spring_length",
                  "max_spring_length", "holding_moment", "opening_force"):
            v = getattr(r, k)
            if v is None:
                assert math.isnan(row[k])
            else:
                assert row[k] == pytest.approx(v, rel=RTOL, abs=1e-15), (i, k)


def test_grid_over_placement_keys_matches_a_model_per_value():
    """A grid over lid_e[1] x spring_anchor[0] (slow with a model per value): every row as the sweep of the same grid, one model a row."""
    cfg = default_config().update(ROBUST)
    axes = {"geometry.lid_e[1]": np.linspace(0.004, 0.024, 4),
            "geometry.spring_anchor[0]": np.linspace(-0.09, -0.03, 3)}
    fast = softclose.sweep(cfg, axes).to_frame()
    for i, row in fast.iterrows():
        c = cfg.update({k: float(row[k]) for k in axes})
        one = softclose.sweep(c, {"design.spring_k": [ROBUST["design.spring_k"]]}).to_frame()
        assert row["status"] == one["status"][0] and row["reason"] == one["reason"][0]
        for k in ("closing_time", "peak_tip_speed", "min_spring_length", "max_spring_length",
                  "holding_moment", "opening_force", "objective"):
            a, b = row[k], one[k][0]
            assert (math.isnan(a) and math.isnan(b)) or a == pytest.approx(b, rel=RTOL), k


def test_tolerance_on_a_placement_key():
    """[tolerance] on geometry.lid_e[0] and spring_anchor[1] beside the spring: the Monte
    Carlo columns equal a simulator per sample at its points; the yield runs at kernel speed
    (no model per sample)."""
    cfg = default_config().update({**ROBUST, "tolerance.geometry.lid_e[0]": 0.002,
                                   "tolerance.geometry.spring_anchor[1]": 0.002})
    keys = ["design.spring_k", "geometry.lid_e[0]", "geometry.spring_anchor[1]"]
    rng = np.random.default_rng(4)
    X = np.column_stack([rng.uniform(4500, 5300, 12), rng.uniform(0.002, 0.006, 12),
                         rng.uniform(0.018, 0.022, 12)])
    cols = evaluate(cfg, keys, X)
    for i in range(12):
        c = cfg.update({k: float(X[i, j]) for j, k in enumerate(keys)})
        one = evaluate(c, ["design.damper_c"], [[c.design.damper_c]])
        for k in ("closing_time", "peak_tip_speed", "min_spring_length", "holding_moment",
                  "opening_force", "objective"):
            a, b = cols[k][i], one[k][0]
            assert (math.isnan(a) and math.isnan(b)) or a == pytest.approx(b, rel=RTOL), k
        assert cols["reason"][i] == one["reason"][0]
    r = softclose.tolerance_analysis(cfg, samples=512, reference=0)
    assert set(r.box) >= {"geometry.lid_e[0]", "geometry.spring_anchor[1]"}
    assert 0.0 < r.yield_ <= 1.0


def test_analyses_take_a_co_designs_points_with_its_design():
    """``design=`` as a co-design's result gives it (the points named as the optimiser names
    them, an end damper's keys): the yield and the Sobol indices are those of the config at
    that design and those points, not of the config's own points."""
    cfg = default_config()
    design = {"spring_k": 1900.0, "spring_rest_length": 0.08, "damper_c": 2100.0,
              "lid_e[0]": 0.010, "spring_anchor[1]": 0.015, "end_damper_c": 0.5,
              "end_damper_angle_deg": 5.0}
    at = cfg.update({"geometry.lid_e[0]": 0.010, "geometry.spring_anchor[1]": 0.015,
                     "design.end_damper_c": 0.5, "design.end_damper_angle_deg": 5.0}
                    ).with_design(spring_k=1900.0, spring_rest_length=0.08, damper_c=2100.0)
    a = softclose.tolerance_analysis(cfg, samples=64, reference=0, design=design)
    b = softclose.tolerance_analysis(at, samples=64, reference=0)
    assert a.yield_ == b.yield_
    np.testing.assert_array_equal(a.data["cols"]["objective"], b.data["cols"]["objective"])
    mine = softclose.tolerance_analysis(cfg.with_design(spring_k=1900.0, spring_rest_length=0.08,
                                                        damper_c=2100.0),
                                        samples=64, reference=0)
    assert not np.array_equal(mine.data["cols"]["objective"], a.data["cols"]["objective"])
    s = softclose.sensitivity(cfg, samples=8, design=design)
    t = softclose.sensitivity(at, samples=8)
    cols = ["output", "key", "S1", "ST"]         # (the _conf columns: SALib's bootstrap)
    assert s.to_frame()[cols].equals(t.to_frame()[cols])


def _point_on_path(sim, theta):
    """E's world position at the lid angle theta (default points)."""
    import casadi as ca
    return np.asarray(sim.model.kin(ca.vertcat(theta, 0.0))[7]).ravel()


def test_a_vanishing_length_is_reported_per_row(sim):
    """A spring anchor on the path of its lid point (the length passes through zero during
    the stroke): that row is reported as a failed stroke with a reason naming the points,
    never a number; the other rows are untouched. Out-of-range points are refused (run_batch
    and a sweep: ConfigError naming the key)."""
    st = sim.stroke
    E = _point_on_path(sim, st.theta0 - 0.05)             # on the way down from the release
    cfg = default_config().update({"design.spring_k": 500.0,      # (it pulls the lid by)
                                   "design.spring_rest_length": 0.005,
                                   "design.damper_c": 2087.754})
    s = Simulator.from_config(cfg)
    P = np.tile(params_of(cfg), (3, 1))
    pts = {"geometry.spring_anchor[0]": [-0.06, E[0], -0.05],
           "geometry.spring_anchor[1]": [0.02, E[1], 0.01]}
    res = s.run_batch(P, points=pts)
    assert res["status"][0] == StrokeStatus.CLOSED and res["status"][2] == StrokeStatus.CLOSED
    bad = StrokeStatus(int(res["status"][1]))
    assert bad is StrokeStatus.OUT_OF_RANGE or not bad.ok
    why = res["reason"][1] if bad is StrokeStatus.OUT_OF_RANGE else \
        s.diagnose(bad, P[1], points=res["points"][1])
    assert "length vanishes" in why and "spring_anchor" in why
    with pytest.raises(ConfigError, match=r"geometry.lid_e\[1\]"):
        s.run_batch(P, points={"geometry.lid_e[1]": [0.0, 11.0, 0.0]})
    out = softclose.sweep(cfg, {"geometry.spring_anchor[0]": [E[0], -0.06],
                                "geometry.spring_anchor[1]": [E[1]]}).to_frame()
    row = out[out["geometry.spring_anchor[0]"] == E[0]].iloc[0]
    assert row["status"] not in ("closed", "not closed") and "length vanishes" in row["reason"]
    assert math.isnan(row["closing_time"]) and math.isnan(row["peak_tip_speed"])
    ok = out[out["geometry.spring_anchor[0]"] == -0.06].iloc[0]
    assert ok["status"] == "closed" and np.isfinite(ok["closing_time"])
    with pytest.raises(ConfigError, match=r"spring_anchor\[0\].*outside the admissible"):
        softclose.sweep(cfg, {"geometry.spring_anchor[0]": [-0.06, 12.0]})
