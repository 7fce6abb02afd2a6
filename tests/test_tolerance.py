"""The [tolerance] section, the tolerance box and its samples, the sample evaluator, the
yield estimator (on cases whose true yield is known), and Sobol indices on a case whose
answer is known.

Known yields: with only the damper toleranced (uniform ±20 % or normal, spread = 3 sigma) and
a spring stiff enough to keep the lid shut everywhere, a sample fails exactly when its
damper exceeds c*, the damper at which the stroke takes closing_time_max; the closing time
rises monotonically with c. c* is found by root finding on the adaptive reference (CVODES,
independent of the kernel), so the true yield is (c* - c_lo)/(c_hi - c_lo), or
Phi((c* - c)/sigma).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from softclose import cli
from softclose.config import ConfigError, default_config, from_dict, load_config
from softclose.model.lid import LidModel
from softclose.simulation.reference import Reference
from softclose.robust import sensitivity, tolerance_analysis
from softclose.robust.box import box_of
from softclose.robust.evaluate import evaluate
from softclose.robust.stats import percentiles, wilson
from softclose.simulation.simulator import Simulator

OPT = {"spring_k": 1914.7092215178668, "spring_rest_length": 0.07925707423701324,
       "damper_c": 2087.7541030665616}


# -- config --------------------------------------------------------------------------------
def test_default_tolerances():
    tol = default_config().tolerance
    assert [(s.key, s.value, s.relative) for s in tol.spreads] == [
        ("design.spring_k", 0.10, True), ("design.damper_c", 0.20, True),
        ("design.end_damper_c", 0.20, True), ("mass.lid", 0.05, True)]
    # a lid without an end damper (c_e = 0, not chosen by the optimiser): its spread spans
    # nothing and leaves the box, which keeps the three keys (8 corners) of a lid without it
    assert box_of(default_config().with_design(**OPT)).keys == (
        "design.spring_k", "design.damper_c", "mass.lid")
    assert box_of(default_config().with_design(**OPT, end_damper_c=1.0)).half[2] == 0.2
    free = default_config().set("optimise.free", {"design.end_damper_c": [0, 2]})
    assert "design.end_damper_c" in box_of(free).keys
    assert (tol.distribution, tol.required_yield, tol.samples, tol.robust_objective) == \
        ("uniform", 0.99, 10000, "worst")


def test_tolerance_file_and_set(tmp_path):
    f = tmp_path / "t.toml"
    f.write_text('[tolerance]\n"design.damper_c" = 0\n"geometry.pivot_b[0]" = {absolute = 5e-4}\n'
                 'distribution = "normal"\n')
    cfg = load_config(f, ["tolerance.mass.lid=0.02", "tolerance.samples=500"])
    tol = cfg.tolerance
    assert tol.keys == ("design.spring_k", "design.end_damper_c", "mass.lid",
                        "geometry.pivot_b[0]")
    box = box_of(cfg.with_design(**OPT))
    assert box.half == pytest.approx([0.1 * OPT["spring_k"], 0.02 * 0.5, 5e-4])
    assert box.nominal[2] == 0.060 and tol.distribution == "normal" and tol.samples == 500


BAD = [
    ({"design.spring_k": -0.1}, "tolerance.design.spring_k"),
    ({"mass.lid": 1.0}, "tolerance.mass.lid"),
    ({"mass.lid": 1.5}, "tolerance.mass.lid"),
    ({"design.damper_c": 1.01}, "tolerance.design.damper_c"),
    ({"mass.lid": {"absolute": 0.5}}, "tolerance.mass.lid"),
    ({"design.spring_kk": 0.1}, "tolerance.design.spring_kk"),
    ({"simulate.step": 0.1}, "tolerance.simulate.step"),
    ({"geometry.pivot_b": 0.1}, "tolerance.geometry.pivot_b"),
    ({"geometry.pivot_b[2]": 0.1}, "tolerance.geometry.pivot_b[2]"),
    ({"stroke.theta_closed_deg": 0.1}, "tolerance.stroke.theta_closed_deg"),
    ({"mass.lid": "x"}, "tolerance.mass.lid"),
    ({"mass.lid": {"abs": 0.1}}, "tolerance.mass.lid"),
    ({"required_yield": 1.5}, "tolerance.required_yield"),
    ({"required_yield": 0}, "tolerance.required_yield"),
    ({"distribution": "cauchy"}, "tolerance.distribution"),
    ({"samples": 0}, "tolerance.samples"),
    ({"robust_objective": "best"}, "tolerance.robust_objective"),
]


@pytest.mark.parametrize("table,culprit", BAD, ids=[b[1] + str(i) for i, b in enumerate(BAD)])
def test_bad_tolerance_is_one_line_config_error(table, culprit):
    with pytest.raises(ConfigError) as exc:
        from_dict({"tolerance": table})
    msg = str(exc.value)
    assert msg.startswith(culprit) and "\n" not in msg


@pytest.mark.parametrize("command", ["yield", "sensitivity"])
def test_bad_tolerance_exits_2_on_the_command_line(capsys, command):
    rc = cli.main([command, "--set", "tolerance.mass.lid=1.2"])
    out, err = capsys.readouterr()
    assert rc == 2 and out == ""
    assert err.startswith("softclose: error: tolerance.mass.lid") and err.count("\n") == 1


def test_bad_sample_counts_exit_2(capsys):
    assert cli.main(["sensitivity", "--samples", "100"]) == 2
    assert cli.main(["yield", "--samples", "0"]) == 2
    _, err = capsys.readouterr()
    assert err.count("\n") == 2 and "Traceback" not in err


# -- box and samples ----------------------------------------------------------------------
def test_box_corners_and_uniform_samples():
    cfg = default_config().with_design(**OPT)
    box = box_of(cfg)
    C = box.values(box.corners())
    assert len(C) == 8 and len({tuple(r) for r in C}) == 8
    assert np.all((C == box.lo) | (C == box.hi))
    X = box.values(box.draw(20000, 3))
    assert np.all(X >= box.lo) and np.all(X <= box.hi)
    # uniform: mean at the nominal, variance half^2 / 3 (4-sigma statistical tolerance)
    se = box.half / math.sqrt(3 * 20000)
    assert np.all(np.abs(X.mean(axis=0) - box.nominal) < 4 * se)
    assert X.std(axis=0) == pytest.approx(box.half / math.sqrt(3), rel=0.02)


def test_normal_samples_have_the_spread_as_three_sigma():
    cfg = default_config().with_design(**OPT).update({"tolerance.distribution": "normal"})
    box = box_of(cfg)
    Z = box.draw(50000, 1)
    assert Z.std(axis=0) == pytest.approx(1 / 3, rel=0.02)
    # beyond the box (|z| > 1, 3 sigma) in about 0.27 % of the draws per key
    assert np.mean(np.abs(Z) > 1) == pytest.approx(2 * 0.00135, abs=0.0008)


def test_normal_draws_are_truncated_at_the_admissible_range():
    # a 90 % relative spread of the lid mass: z = -1/0.9 is zero mass, 3.3 sigma down
    cfg = default_config().update({"tolerance.mass.lid": 0.9, "tolerance.distribution": "normal"})
    box = box_of(cfg)
    X = box.values(box.draw(200000, 2))
    assert X[:, box.keys.index("mass.lid")].min() > 0


def test_same_samples_for_two_designs():
    """The same unit samples give the same relative deviations and lid masses."""
    c1 = default_config().with_design(**OPT)
    c2 = default_config().with_design(spring_k=9000.0, spring_rest_length=0.056, damper_c=4500.0)
    b1, b2 = box_of(c1), box_of(c2)
    z = b1.draw(100, 5)
    X1, X2 = b1.values(z), b2.values(z)
    assert X1[:, 0] / OPT["spring_k"] == pytest.approx(X2[:, 0] / 9000.0, rel=1e-14)
    assert X1[:, 2] == pytest.approx(X2[:, 2], rel=0, abs=0)


# -- evaluation ---------------------------------------------------------------------------
def test_lid_mass_samples_match_a_model_built_for_that_mass():
    cfg = default_config().with_design(**OPT)
    masses = np.array([0.476, 0.5, 0.52, 0.52])
    cols = evaluate(cfg, ["mass.lid"], masses[:, None])
    for i, m in enumerate(masses):
        r = Simulator.from_config(cfg.update({"mass.lid": float(m)})).run(estimate_error=False)
        for k in ("closing_time", "impact_theta_dot", "peak_tip_speed", "holding_moment"):
            assert cols[k][i] == pytest.approx(getattr(r, k), rel=1e-9, abs=1e-12), (m, k)


def test_geometry_samples_build_their_own_model():
    cfg = default_config().with_design(spring_k=1700.0, spring_rest_length=0.079257,
                                       damper_c=1500.0)
    xs = np.array([[0.0595, 1600.0], [0.0605, 1600.0], [0.0595, 1700.0]])
    cols = evaluate(cfg, ["geometry.pivot_b[0]", "design.spring_k"], xs)
    for i, (x, k) in enumerate(xs):
        c = cfg.update({"geometry.pivot_b[0]": float(x), "design.spring_k": float(k)})
        r = Simulator.from_config(c).run(estimate_error=False)
        assert cols["closing_time"][i] == pytest.approx(r.closing_time, rel=1e-12)
        assert cols["holding_moment"][i] == pytest.approx(r.holding_moment, rel=1e-12)


# -- statistics ---------------------------------------------------------------------------
@pytest.mark.parametrize("k,n", [(0, 10), (3, 10), (10, 10), (4321, 10000), (9990, 10000)])
def test_wilson_interval_matches_scipy(k, n):
    from scipy.stats import binomtest
    ci = binomtest(k, n).proportion_ci(confidence_level=0.95, method="wilson")
    assert wilson(k, n) == pytest.approx((ci.low, ci.high), abs=1e-12)


def test_percentiles_are_sample_values_and_keep_not_closed():
    v = np.array([3.0, 1.0, 2.0, np.inf])
    p = percentiles(v, (1, 50, 99))
    assert p == {"p1": 1.0, "p50": 2.0, "p99": math.inf}


# -- the yield estimator on cases whose true yield is known --------------------------------
K_HELD = 1700.0          # holds the lid shut for every damper (holding moment 0.237 N m)
C_NOM = 3000.0           # closes in ~0.97 s; the box 2400..3600 N s/m straddles c*


@pytest.fixture(scope="module")
def c_star():
    """The damper at which the stroke takes exactly closing_time_max, by the reference."""
    from scipy.optimize import brentq
    cfg = default_config().with_design(spring_k=K_HELD,
                                       spring_rest_length=OPT["spring_rest_length"])
    ref = Reference(LidModel.from_config(cfg))
    p = lambda c: np.array([K_HELD, OPT["spring_rest_length"], c, 0.0])  # noqa: E731
    f = lambda c: ref.simulate(p(c)).closing_time - cfg.optimise.closing_time_max  # noqa: E731
    return brentq(f, 2900.0, 3300.0, xtol=1e-6)


def _damper_only(distribution):
    return default_config().with_design(
        spring_k=K_HELD, spring_rest_length=OPT["spring_rest_length"], damper_c=C_NOM).update(
        {"tolerance.design.spring_k": 0, "tolerance.mass.lid": 0,
         "tolerance.distribution": distribution})


@pytest.mark.parametrize("distribution", ["uniform", "normal"])
def test_yield_estimate_against_the_true_yield(c_star, distribution):
    cfg = _damper_only(distribution)
    n = 20000
    r = tolerance_analysis(cfg, samples=n, seed=11, reference=2)
    half = 0.2 * C_NOM
    if distribution == "uniform":
        y = (c_star - (C_NOM - half)) / (2 * half)
    else:
        y = 0.5 * (1 + math.erf((c_star - C_NOM) / (half / 3) / math.sqrt(2)))
    assert 0.5 < y < 0.7
    assert set(r.failures) == {"too slow"}                  # the only way to fail here
    assert abs(r.yield_ - y) < 4 * math.sqrt(y * (1 - y) / n)
    assert r.yield_ci[0] < y < r.yield_ci[1]
    assert r.samples == n and r.success and not r.meets_required
    # the kernel's verdicts agree with the reference at the samples nearest the boundary
    assert r.reference and all(c["verdicts_agree"] for c in r.reference)
    # percentiles: the median closing time is the stroke at the median damper
    med_c = float(np.median(r.data["X"][:, 0]))
    sim = Simulator.from_config(cfg)
    t_med = sim.run(np.array([K_HELD, OPT["spring_rest_length"], med_c, 0.0]),
                    estimate_error=False).closing_time
    assert r.percentiles["closing_time"]["p50"] == pytest.approx(t_med, abs=2e-3)


def test_yield_json_and_frame():
    cfg = _damper_only("uniform")
    r = tolerance_analysis(cfg, samples=500, seed=1, reference=0)
    j = r.to_json()
    for key in ("yield", "yield_ci", "samples", "percentiles", "failures", "design", "box"):
        assert key in j
    assert j["samples"] == 500 and len(j["yield_ci"]) == 2
    df = r.to_frame()
    assert len(df) == 500 and {"design.damper_c", "closing_time", "feasible"} <= set(df.columns)
    assert df["feasible"].mean() == pytest.approx(r.yield_)


def test_yield_cli_json(capsys):
    import json
    rc = cli.main(["yield", "--json", "--samples", "400", "--seed", "3",
                   "--set", "design.spring_k=1700", "--set", "design.damper_c=3000",
                   "--set", "design.spring_rest_length=0.07925707423701324"])
    out, err = capsys.readouterr()
    j = json.loads(out)
    assert rc == 0 and j["samples"] == 400 and 0 < j["yield"] < 1
    assert j["yield_ci"][0] < j["yield"] < j["yield_ci"][1]


# -- Sobol indices ------------------------------------------------------------------------
def test_sobol_indices_of_an_input_without_effect():
    """With no spring (k = 0) its rest length has no effect: S1 = ST = 0 for it, and the lid
    mass, the only other input, carries all the variance (S1 = ST = 1)."""
    cfg = default_config().with_design(damper_c=500.0).update(
        {"tolerance.design.damper_c": 0, "tolerance.design.spring_rest_length": 0.1})
    r = sensitivity(cfg, samples=256, seed=2)
    assert r.keys == ("mass.lid", "design.spring_rest_length")   # spring_k: no spread at 0
    assert "design.spring_k" in r.message
    for out in ("closing_time", "impact_theta_dot"):
        d = r.indices[out]
        assert d["S1"]["design.spring_rest_length"] == pytest.approx(0.0, abs=1e-12)
        assert d["ST"]["design.spring_rest_length"] == pytest.approx(0.0, abs=1e-12)
        assert d["S1"]["mass.lid"] == pytest.approx(1.0, abs=0.02)
        assert d["ST"]["mass.lid"] == pytest.approx(1.0, abs=0.02)
    assert r.not_closed == 0 and r.evaluations == 256 * 4


def test_sobol_counts_strokes_that_do_not_close(capsys):
    import json
    cfg = default_config().with_design(**OPT)
    r = sensitivity(cfg, samples=64, seed=0)
    cols = evaluate(cfg, r.keys, r.data["X"])
    assert r.not_closed == int((~cols["closed"]).sum()) > 0
    assert r.data["Y"]["closing_time"][~cols["closed"]] == pytest.approx(cfg.stroke.t_max)
    rc = cli.main(["sensitivity", "--json", "--samples", "64",
                   *sum((["--set", f"design.{k}={v}"] for k, v in OPT.items()), [])])
    j = json.loads(capsys.readouterr()[0])
    assert rc == 0 and j["not_closed"] == r.not_closed
    for out in ("closing_time", "impact_theta_dot"):
        assert set(j[out]) == {"S1", "ST", "S1_conf", "ST_conf"}
        assert set(j[out]["S1"]) == {"design.spring_k", "design.damper_c", "mass.lid"}


def test_sensitivity_ignores_a_spread_below_floating_point_resolution():
    """Found by the fuzz test: a spread of 2e-98 on a 0.06 m value leaves lo == hi; that key
    is held fixed (listed as such), the others get their indices, and no SALib error escapes."""
    import softclose
    cfg = softclose.default_config().update(
        {"design.spring_k": 1914.7, "design.spring_rest_length": 0.079257,
         "design.damper_c": 2087.75, "tolerance.geometry.pivot_b[0]": 2.03e-98})
    res = softclose.sensitivity(cfg, samples=16)
    js = res.to_json()
    names = set(js["closing_time"]["S1"])
    assert names == {"design.spring_k", "design.damper_c", "mass.lid"}
    assert "geometry.pivot_b[0]" not in names


def test_a_tolerance_on_friction_works_like_any_key():
    """Friction as the only spread (uniform, +-30 % about f*, the friction at which the stroke
    takes exactly closing_time_max by the reference, with its stick/slip events): the true
    yield is 1/2, and the estimate finds it within its statistical error; every failure is
    'too slow'; the kernel's verdicts agree with the reference nearest the boundary."""
    from scipy.optimize import brentq

    from softclose.problem import params_of
    cfg = default_config().with_design(spring_k=K_HELD,
                                       spring_rest_length=OPT["spring_rest_length"],
                                       damper_c=2600.0)
    ref = Reference(LidModel.from_config(cfg))
    f_star = brentq(lambda f: ref.simulate(params_of(cfg.update({"friction.torque": f})))
                    .closing_time - cfg.optimise.closing_time_max, 0.0, 0.2, xtol=1e-9)
    assert 0.05 < f_star < 0.07
    cfg = cfg.update({"friction.torque": f_star, "tolerance.design.spring_k": 0,
                      "tolerance.design.damper_c": 0, "tolerance.mass.lid": 0,
                      "tolerance.friction.torque": 0.3})
    n = 20000
    r = tolerance_analysis(cfg, samples=n, seed=11, reference=2)
    assert r.keys == ("friction.torque",)
    assert abs(r.yield_ - 0.5) < 4 * math.sqrt(0.25 / n)
    assert r.yield_ci[0] < 0.5 < r.yield_ci[1]
    assert set(r.failures) == {"too slow"}
    assert r.reference and all(c["verdicts_agree"] for c in r.reference)
    # the samples fail exactly above f* (the kernel's threshold: table-limited, ~1e-7 s)
    f = r.data["X"][:, 0]
    feasible = r.to_frame()["feasible"].to_numpy()
    assert np.all(feasible[f < 0.999 * f_star]) and not np.any(feasible[f > 1.001 * f_star])
