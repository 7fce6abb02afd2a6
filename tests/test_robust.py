"""Robust design: the scenario NLP's answer checked corner by corner against the adaptive
reference (simulated here, independently of the optimiser's own verification), its yield
against the nominal optimum's on the same samples, the interior worst-case search, the
mean objective, and the report of a tolerance box no design can meet."""

from __future__ import annotations

import itertools
import json

import numpy as np
import pytest

from softclose import cli
from softclose.config import default_config
from softclose.model.lid import LidModel
from softclose.problem import (CONSTRAINT_TOL, DESIGN_KEYS, VERIFY_RTOL, agreement_tolerance,
                               objective)
from softclose.simulation.reference import Reference
from softclose.robust import optimise_robust, tolerance_analysis
from softclose.robust import policy, scenarios, solve
from softclose.robust.box import box_of
from softclose.robust.evaluate import evaluate
from softclose.optimiser.discretisation import discretisation

SPREADS = {"design.spring_k": 0.10, "design.damper_c": 0.20, "mass.lid": 0.05}


@pytest.fixture(scope="module")
def robust(default_robust):
    return default_robust


#: the idealised problem: a spring that pushes and pulls through its free length
LINEAR = {"optimise.spring_kinds": ["linear"]}


@pytest.fixture(scope="module")
def robust_linear():
    return optimise_robust(default_config().update(LINEAR))


def _corner_config(cfg, design, signs):
    """The lid of one corner of the default box: the drawn design with its spring and
    damper off by ±10 % and ±20 %, the lid mass by ±5 %."""
    sk, sc, sm = signs
    k, c = design["spring_k"], design["damper_c"]
    return cfg.update({"design.spring_k": k * (1 + sk * SPREADS["design.spring_k"]),
                       "design.spring_rest_length": design["spring_rest_length"],
                       "design.damper_c": c * (1 + sc * SPREADS["design.damper_c"]),
                       "mass.lid": cfg.mass.lid * (1 + sm * SPREADS["mass.lid"])})


def test_every_corner_holds_in_the_adaptive_reference(robust):
    cfg = default_config()
    o = cfg.optimise
    assert robust.success, robust.message
    worst = 0.0
    for signs in itertools.product((-1, 1), repeat=3):
        c = _corner_config(cfg, robust.design, signs)
        model = LidModel.from_config(c)
        r = Reference(model).simulate(model.params())
        assert r.closed, signs
        assert o.closing_time_min <= r.closing_time <= o.closing_time_max * (1 + 1e-6), signs
        assert r.holding_moment >= o.holding_moment_min - CONSTRAINT_TOL, signs
        assert r.theta_min >= c.stroke.theta_closed - 1e-12, signs
        if r.theta_dot_max is not None:
            assert r.theta_dot_max <= CONSTRAINT_TOL, signs
        assert model.theta_ddot(c.stroke.theta0, 0.0) <= 0.0       # moves down at release
        worst = max(worst, objective(o, r.impact_theta_dot, r.peak_tip_speed))
    # the worst case is a corner here: the NLP's worst-case J is the reference's
    assert robust.objective == pytest.approx(worst, rel=VERIFY_RTOL)
    # and the nominal design alone misses: its spring + 10 %, damper + 20 % corner is too slow
    nom = robust.nominal["design"]
    model = LidModel.from_config(_corner_config(cfg, nom, (1, 1, -1)))
    r = Reference(model).simulate(model.params())
    assert not r.closed or r.closing_time > o.closing_time_max


def test_yields_on_the_same_samples(robust):
    y, n = robust.yield_result, robust.yield_result.samples
    assert y.yield_ >= default_config().tolerance.required_yield
    assert robust.nominal_yield.yield_ < 0.6 < y.yield_
    assert robust.nominal_yield.samples == n == default_config().tolerance.samples
    # the nominal design's yield is the tolerance analysis of that design on the same draw
    again = tolerance_analysis(default_config(), design=robust.nominal["design"], samples=n,
                               seed=0, reference=0)
    assert again.yield_ == robust.nominal["yield"]
    assert again.failures == robust.nominal["failures"]


def test_robust_json_keys(robust):
    j = json.loads(json.dumps(robust.to_json(), allow_nan=False))
    for key in ("success", "design", "objective", "closing_time", "impact_theta_dot",
                "verification", "yield", "yield_ci", "samples", "scenarios", "nominal"):
        assert key in j, key
    assert set(j["design"]) == set(DESIGN_KEYS)
    assert {"design", "yield", "yield_ci"} <= set(j["nominal"])
    assert j["yield_ci"][0] <= j["yield"] <= j["yield_ci"][1]
    assert len(j["scenarios"]) == 9 and j["scenarios"][0]["label"] == "nominal"
    assert all(s["verified"] for s in j["scenarios"])
    df = robust.to_frame()
    assert len(df) == 9 and "mass.lid" in df.columns


@pytest.mark.slow
def test_interior_search_recovers_a_missing_worst_case():
    """Without its worst corner in the scenario set, the first solve violates that corner;
    the Monte Carlo search and local ascent must find it, add it and re-solve."""
    cfg = default_config()
    box = box_of(cfg)
    missing = (1.0, 1.0, -1.0)          # spring +10 %, damper +20 %, lid -5 %: slowest
    scen = [s for s in scenarios.initial_scenarios(box) if s.z != missing]
    disc = discretisation(cfg)
    N, M = disc.nodes, disc.substeps
    start, _ = solve.start_design(cfg, box, np.array([s.z for s in scen]))
    rounds: list = []
    prob, run = solve.solve_box(cfg, 1.0, scen, N, M, start, 0, [], rounds, _Quiet())
    assert run.success
    assert len(rounds) >= 2 and rounds[0]["search"]["violating"] > 0
    added = [s.z for s in prob.scenarios if s.origin.startswith("Monte Carlo")]
    assert added and max(np.max(np.abs(np.subtract(z, missing))) for z in added[-1:]) < 1e-2
    assert rounds[-1]["search"]["violating"] == 0
    design = dict(zip(DESIGN_KEYS, map(float, run.design)))
    c = cfg.with_design(**design)
    b = box_of(c)
    cols = evaluate(c, b.keys, b.values(np.array([missing])))
    assert cols["feasible"][0]
    assert cols["closing_time"][0] <= cfg.optimise.closing_time_max * (1 + 1e-6)


class _Quiet:
    def update(self, *a, **k):
        pass


@pytest.mark.slow
def test_mean_objective_minimises_the_mean():
    cfg = default_config().update({"tolerance.robust_objective": "mean"})
    mean = optimise_robust(cfg, samples=2000)
    assert mean.success, mean.message
    Js = [s["objective"] for s in mean.scenarios]
    assert mean.objective == pytest.approx(np.mean(Js), rel=1e-12)
    # the worst-case design is feasible for the mean problem, so its mean J is no better
    worst = optimise_robust(default_config(), samples=2000)
    Jw = [s["objective"] for s in worst.scenarios]
    assert mean.objective <= np.mean(Jw) * (1 + 1e-6)
    assert max(Js) >= worst.objective * (1 - 1e-6)


@pytest.mark.slow
def test_no_design_over_the_box_is_reported_with_what_would_do(capsys):
    """A closing-time window of 0.7..0.9 s cannot hold with the damper ±20 %: closing time
    roughly scales with the damper, and 0.9/0.7 < 1.2/0.8."""
    args = ["optimise", "--robust", "--json", "--set", "optimise.closing_time_min=0.7",
            "--set", "optimise.closing_time_max=0.9", "--set", "tolerance.samples=1000"]
    rc = cli.main(args)
    out, err = capsys.readouterr()
    assert rc == 3
    assert err.startswith("softclose: error: no design meets every constraint over the "
                          "tolerance box") and err.count("\n") == 1
    j = json.loads(out)
    inf = j["infeasibility"]
    assert inf["constraint"] in ("closing_time_max", "closing_time_min")
    assert "damper_c" in inf["scenario"] and 0 < inf["feasible_scale"] < 1
    assert "by" in inf["detail"] and "spreads up to" in j["message"]
    # the spreads it names can be met: the robust problem at that scale has a solution
    scale = inf["feasible_scale"]
    cfg = default_config().update({"optimise.closing_time_min": 0.7,
                                   "optimise.closing_time_max": 0.9,
                                   **{f"tolerance.{k}": v * scale for k, v in SPREADS.items()},
                                   "tolerance.samples": 1000})
    ok = optimise_robust(cfg)
    assert ok.success, ok.message


def _png_whole(path) -> bool:
    data = path.read_bytes()
    return data.startswith(b"\x89PNG\r\n\x1a\n") and data.endswith(b"IEND\xaeB`\x82")


def test_yield_and_sensitivity_write_their_table_and_figure(tmp_path, capsys):
    """``--out DIR``: yield_samples.csv + yield_histograms.png and sobol.csv + sobol.png, in
    that order in the JSON's file list; the tables hold the numbers the command reports
    (the yield is the feasible fraction of the written samples, the same as a run in this
    process with the same seed; the Sobol table has the reported indices)."""
    import pandas as pd
    design = ["--set", "design.spring_k=1700", "--set", "design.damper_c=3000",
              "--set", "design.spring_rest_length=0.07925707423701324"]
    out = tmp_path / "yield"
    rc = cli.main(["yield", "--json", "--samples", "300", "--seed", "5", "--out", str(out),
                   *design])
    j = json.loads(capsys.readouterr()[0])
    assert rc == 0
    assert j["files"] == [str(out / "yield_samples.csv"), str(out / "yield_histograms.png")]
    df = pd.read_csv(out / "yield_samples.csv")
    assert len(df) == 300 and df["feasible"].mean() == pytest.approx(j["yield"], abs=0)
    cfg = default_config().update({"design.spring_k": 1700, "design.damper_c": 3000,
                                   "design.spring_rest_length": 0.07925707423701324})
    here = tolerance_analysis(cfg, samples=300, seed=5).to_frame()
    assert list(df.columns) == list(here.columns)
    np.testing.assert_allclose(df["closing_time"], here["closing_time"], rtol=1e-15)
    assert _png_whole(out / "yield_histograms.png")

    out = tmp_path / "sobol"
    rc = cli.main(["sensitivity", "--json", "--samples", "16", "--out", str(out), *design])
    j = json.loads(capsys.readouterr()[0])
    assert rc == 0
    assert j["files"] == [str(out / "sobol.csv"), str(out / "sobol.png")]
    df = pd.read_csv(out / "sobol.csv")
    assert len(df) == 2 * 3
    for row in df.itertuples():
        for s in ("S1", "ST", "S1_conf", "ST_conf"):
            assert getattr(row, s) == pytest.approx(j[row.output][s][row.key], rel=1e-15)
    assert _png_whole(out / "sobol.png")


def _reference_of(cfg, design, values):
    """The adaptive reference (CVODES) of one scenario: the drawn design with the
    scenario's toleranced values (absolute) set."""
    c = cfg.update({**{f"design.{k}": v for k, v in design.items()}, **values})
    model = LidModel.from_config(c)
    return Reference(model).simulate(model.params())


@pytest.mark.parametrize("weight_peak_tip", [None, 0.0])
def test_every_scenario_reports_its_own_peak(robust_linear, weight_peak_tip):
    """Each scenario's peak tip speed (and so its J) is the NLP's own sub-step and Hermite
    maximum, not its epigraph variable: with weight_peak_tip = 0 nothing pins that variable
    (it ended near 9e4 m/s), and in worst-case mode nothing pins it in a scenario that is
    not the worst (0.88 against 0.52 m/s at the nominal lid). Compared, scenario by
    scenario, with a reference simulation of its own."""
    cfg = default_config().update(LINEAR)
    if weight_peak_tip is None:
        res = robust_linear
    else:
        cfg = cfg.update({"optimise.weight_peak_tip": weight_peak_tip})
        res = optimise_robust(cfg, samples=1000)
    assert res.success, res.message
    assert res.design["spring_k"] == pytest.approx(10000, rel=1e-6)
    assert res.design["damper_c"] == pytest.approx(5000, rel=1e-6)
    assert res.design["spring_rest_length"] == pytest.approx(0.056036, rel=1e-4)
    for s in res.scenarios:
        r = _reference_of(cfg, res.design, s["values"])
        pk = s["metrics"]["peak_tip_speed"]
        assert abs(pk - r.peak_tip_speed) <= agreement_tolerance("peak_tip_speed",
                                                                 r.peak_tip_speed), s["label"]
        J = objective(cfg.optimise, r.impact_theta_dot, r.peak_tip_speed)
        assert s["objective"] == pytest.approx(J, rel=VERIFY_RTOL), s["label"]
        assert s["verified"] and all(a["ok"] for a in s["agreement"].values()), s["label"]
    # the worst-case objective is the largest scenario J, each with its own peak
    assert res.objective == max(s["objective"] for s in res.scenarios)


# -- more keys than MAX_CORNERS corners: the NLP starts from a subset, every corner checked --

#: five toleranced keys (32 corners > MAX_CORNERS) at small spreads, all kernel columns
#: (a rotary damper of 0.004 N m s/rad ± 50 %)
MANY = {"design.spring_k": 0.03, "design.damper_c": 0.05, "mass.lid": 0.03,
        "design.spring_rest_length": 0.01, "design.rotary_damper_c": 0.5}


def _many_config():
    return default_config().update({"design.rotary_damper_c": 0.004,
                                    **{f"tolerance.{k}": v for k, v in MANY.items()}})


def _corner_columns(cfg, design):
    """Every corner of cfg's box at ``design``, simulated whole in the kernel (no early
    cut), enumerated here independently of the optimiser's own corner check."""
    c = cfg.with_design(**design)
    b = box_of(c)
    Z = np.array(list(itertools.product((-1.0, 1.0), repeat=b.dim)))
    assert np.all(b.half > 0)
    return evaluate(c, b.keys, b.nominal + b.half * Z)


@pytest.mark.parametrize("d", range(1, 16))
def test_fractional_factorial_is_orthogonal(d):
    """Resolution >= III: every column balanced, every pair orthogonal (X^T X = n I), n the
    smallest power of two above d, no two runs alike."""
    X = scenarios.fractional_factorial(d)
    n = len(X)
    assert X.shape == (n, d) and n == 2 ** int(np.ceil(np.log2(d + 1)))
    assert set(np.unique(X)) == {-1.0, 1.0}
    assert np.array_equal(X.T @ X, n * np.eye(d))
    assert len({tuple(r) for r in X}) == n


@pytest.mark.slow
def test_many_keys_start_from_a_few_corners_and_every_corner_holds():
    cfg = _many_config()
    d = len(MANY)
    assert 2 ** d > policy.MAX_CORNERS
    res = optimise_robust(cfg, samples=1000)
    assert res.success, res.message
    S = len(res.scenarios)
    assert S == res.solver["scenarios"] == res.corner_check["scenarios"] < 2 ** d + 1
    assert res.corner_check["corners"] == 2 ** d and res.corner_check["breaking"] == []
    assert any(f"{S} scenarios instead of {2 ** d + 1}" in n for n in res.notes)
    assert all(s["verified"] for s in res.scenarios)
    # every corner of the box, simulated here: closes in the window, holds shut, no rebound
    o = cfg.optimise
    cols = _corner_columns(cfg, res.design)
    assert np.all(cols["feasible"]), cols["reason"]
    assert np.all(cols["closing_time"] <= o.closing_time_max * (1 + 1e-6))
    assert np.all(cols["holding_moment"] >= o.holding_moment_min - CONSTRAINT_TOL)
    # and the worst-case J is the worst corner's (kernel, default step: ~1e-6)
    assert res.objective == pytest.approx(np.max(cols["objective"]), rel=VERIFY_RTOL)


def test_corner_check_adds_the_corners_a_subset_misses():
    """From the nominal lid alone, the Monte Carlo search and the corner check must add the
    binding corners until every one of the 32 holds; the NLP never gets all of them."""
    cfg = _many_config()
    box = box_of(cfg)
    disc = discretisation(cfg)
    N, M = disc.nodes, disc.substeps
    nominal = [scenarios.Scenario(tuple([0.0] * box.dim), "nominal")]
    start, _ = solve.start_design(cfg, box, np.array([s.z for s in scenarios.initial_scenarios(
        box, cfg, [[1914.7, 0.079257, 2087.75]])]))
    rounds: list = []
    prob, run = solve.solve_box(cfg, 1.0, nominal, N, M, start, 0, [], rounds, _Quiet())
    assert run.success
    first = rounds[0]["corner_check"]
    assert first["violating"] > 0 and first["added"]
    assert any(s.origin.startswith("corner check") for s in prob.scenarios)
    assert len(prob.scenarios) < 2 ** box.dim + 1
    last = rounds[-1]["corner_check"]
    assert last["violating"] == 0 and not last["added"]
    cols = _corner_columns(cfg, dict(zip(DESIGN_KEYS, map(float, run.design))))
    assert np.all(cols["feasible"]), cols["reason"]


def test_too_many_slow_keys_are_refused(capsys):
    """Each corner check simulates all 2^d corners; keys that need a model per value make
    that 2^d models: more than MAX_SLOW_KEYS of them are refused before any work."""
    keys = ["mass.crank_oa", "mass.crank_bc", "mass.gravity", "geometry.crank_oa",
            "geometry.crank_bc", "geometry.lid_length", "geometry.pivot_b[0]",
            "geometry.pivot_b[1]", "geometry.lid_c[0]"]
    assert len(keys) > policy.MAX_SLOW_KEYS
    args = ["optimise", "--robust"]
    for k in keys:
        args += ["--set", f"tolerance.{k}=0.001"]
    assert cli.main(args) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "need a model per value" in err and "at most 8" in err


def test_the_default_robust_design_is_a_spring_one_can_buy(robust, robust_linear):
    """With the default spring kinds the robust design is a compression spring that stays
    shorter than its free length in every corner of the box (the adaptive reference checks
    every scenario and would call a stroke past it invalid); buildability costs: its worst J
    is above the idealised double-acting spring's, and the extension spring can do no better
    than the damper alone."""
    assert robust.success, robust.message
    assert robust.kind == "compression"
    kinds = {r["kind"]: r for r in robust.kinds}
    assert kinds["compression"]["success"] and kinds["extension"]["objective"] is not None
    assert kinds["extension"]["objective"] > 2 * robust.objective
    assert robust_linear.kind == "linear" and robust_linear.objective < robust.objective
    assert robust.objective == pytest.approx(0.1255, rel=2e-2)
    part = robust.part
    assert part.kind == "compression"
    assert part.free_length >= part.working_length[1] - 1e-12      # never past its free length
    assert part.free_length == pytest.approx(robust.design["spring_rest_length"])
    assert part.largest_force == pytest.approx(
        robust.design["spring_k"] * (part.free_length - part.working_length[0]), rel=1e-9)
    for s in robust.scenarios:
        assert s["verified"], s["label"]
        r = _reference_of(default_config().set("design.spring_kind", "compression"),
                          robust.design, s["values"])
        assert r.ok and r.max_spring_length <= robust.design["spring_rest_length"] + 1e-12


@pytest.mark.slow
def test_a_trial_stopped_at_its_iteration_cap_counts_as_not_shown_feasible(monkeypatch):
    """The diagnosis' bisection counts a trial only when Ipopt solves it within
    TRIAL_MAX_ITER iterations: with a cap of 1 no scenario NLP solves a trial, so only the
    kernel sweep's certificates count (x0.3125 here) -- the scale comes out lower than the
    x0.390625 of the full solves (80 iterations), never higher."""
    from softclose.robust import infeasible
    monkeypatch.setattr(infeasible, "TRIAL_MAX_ITER", 1)
    cfg = default_config().update({"optimise.closing_time_min": 0.7,
                                   "optimise.closing_time_max": 0.9,
                                   "optimise.spring_kinds": ["compression"],
                                   "tolerance.samples": 200})
    r = optimise_robust(cfg)
    assert not r.success
    scale = r.infeasibility["feasible_scale"]
    assert 0.25 <= scale < 0.390625
    assert f"spreads up to x{scale:.2f} of the configured ones" in r.message


def test_only_the_kept_kind_is_verified_and_its_report_is_the_whole_one(robust):
    """optimise_robust verifies and reports the kind it keeps only: a kind's deferred report
    (defer=True, then finish()) is its whole report (report=True), and the kind not kept
    says it was not verified."""
    from softclose.optimiser.kinds import kind_config
    from softclose.robust.design import optimise_robust_kind
    cfg = default_config()
    c, why = kind_config(cfg, "compression", robust=True)
    assert why is None
    lean, finish = optimise_robust_kind(c, defer=True)
    full = finish()
    assert lean.design == full.design == robust.design and lean.objective == full.objective
    assert full.success == robust.success and full.message == robust.message
    assert [s["label"] for s in full.scenarios] == [s["label"] for s in robust.scenarios]
    assert full.nominal["objective"] == robust.nominal["objective"]
    assert full.nominal_yield.yield_ == robust.nominal_yield.yield_
    assert lean.scenarios == [] and lean.verification is None
    rows = {r["kind"]: r for r in robust.kinds}
    assert rows["extension"]["message"].startswith("not verified by the reference") \
        or not rows["extension"]["success"]
