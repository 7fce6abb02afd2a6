"""Temperature as a scenario dimension (SPEC §12): the robust design and the catalog selection
meet every constraint at every tolerance corner at every sign-off temperature.

A scenario is (z, T): the NLP's map p = a p_design + b at T is (a f, b f), f the parameters'
factors at T -- checked here against strokes run at T by the simulator itself; the robust
design of the issue's command is re-simulated corner by corner at each temperature by the
adaptive reference, independently of the optimiser's own verification."""

from __future__ import annotations

import itertools
import json

import numpy as np
import pytest

from softclose import cli
from softclose.config import default_config
from softclose.problem import (CONSTRAINT_TOL, PARAM_KEYS, VERIFY_RTOL, at_temperature,
                               objective, params_of)
from softclose.robust import scenarios
from softclose.robust.box import box_of
from softclose.robust.evaluate import evaluate, simulator, with_values
from softclose.robust.nlp import model_config
from softclose.robust.policy import OBJ_RTOL
from softclose.simulation.reference import Reference

SPREADS = {"design.spring_k": 0.10, "design.damper_c": 0.20, "mass.lid": 0.05}
#: the issue's sign-off: a silicone-oil damper (-0.5 %/K) at 0, 23 and 40 °C
COLD_HOT = {"operating.temperatures_c": [0.0, 23.0, 40.0],
            "design.damper_temperature_coeff": -0.005}
DESIGN = {"design.spring_kind": "compression", "design.spring_k": 4600.0,
          "design.spring_rest_length": 0.0585, "design.damper_c": 4500.0}


#: a gas strut (F1 20 N, 70 mm extended): its force follows its gas, not a coil's wire
STRUT = {"design.spring_kind": "gas_strut", "design.spring_preload": 20.0,
         "design.spring_rest_length": 0.07, "design.damper_c": 3000.0}


@pytest.mark.parametrize("design", [DESIGN, STRUT], ids=["coil", "gas_strut"])
def test_a_scenario_at_a_temperature_is_the_stroke_at_that_temperature(design):
    """maps(box, z, f) on the design's p at the reference temperature gives the p the
    simulator runs at T for the corner's config: the same strokes to 1e-12 (the factors
    of the design's spring kind: a coil spring's wire, a gas strut's gas)."""
    cfg = scenarios.at_reference(default_config().update({**COLD_HOT, **design}))
    assert cfg.operating.temperature_c == cfg.operating.reference_temperature_c == 23.0
    assert scenarios.temperatures(cfg) == (0.0, 23.0, 40.0)
    box = box_of(cfg)
    for T, z in itertools.product((0.0, 40.0), ([1.0, -1.0, 1.0], [-1.0, 1.0, -1.0])):
        f = scenarios.factors(cfg, T)
        assert f is not None and np.any(f != 1.0)
        a, b, vals = scenarios.maps(box, z, f)
        p = a * params_of(cfg) + b                      # what the scenario NLP simulates
        mine = simulator(model_config(cfg, vals)).run(p, estimate_error=False)
        corner = with_values(at_temperature(cfg, T), dict(zip(box.keys, box.values(z)[0])))
        theirs = simulator(corner).run(params_of(corner), estimate_error=False)
        assert mine.closed and theirs.closed
        for k in ("closing_time", "impact_theta_dot", "peak_tip_speed", "holding_moment"):
            assert getattr(mine, k) == pytest.approx(getattr(theirs, k), rel=1e-12, abs=1e-15)
        # the start sweep's rows (the same map, evaluated at the reference temperature)
        d = [cfg.design.spring_k, cfg.design.spring_rest_length, cfg.design.damper_c]
        keys, X = scenarios.scenario_rows(box, [d], [scenarios.Scenario(tuple(z), "", T)], cfg)
        cols = evaluate(cfg, keys, X)
        assert cols["closing_time"][0] == pytest.approx(theirs.closing_time, rel=1e-12)
    # the damper's factor at 0 °C is exp(0.005 * 23): thicker oil, a slower lid; the
    # preload's is the wire's (1 + 2.5e-4 * 23) or the gas's 273.15 / 296.15
    f0 = scenarios.factors(cfg, 0.0)
    assert f0[2] == pytest.approx(np.exp(0.005 * 23.0), rel=1e-15)
    preload = PARAM_KEYS.index("spring_preload")
    assert f0[preload] == pytest.approx(273.15 / 296.15 if design is STRUT
                                        else 1 + 2.5e-4 * 23.0, rel=1e-15)


def test_the_default_has_one_scenario_temperature_and_no_factors():
    cfg = default_config()
    assert scenarios.at_reference(cfg) is cfg
    assert scenarios.temperatures(cfg) == (23.0,)
    assert scenarios.factors(cfg, 23.0) is None
    box = box_of(cfg)
    scen = scenarios.initial_scenarios(box, cfg)
    assert len(scen) == 9 and scen[0].origin == "nominal"
    assert all(s.temperature_c == 23.0 for s in scen)
    assert [scenarios.label(box, s.z, s.temperature_c, (23.0,)) for s in scen[:1]] == ["nominal"]
    # temperature_c alone (no list) is the one sign-off temperature
    hot = scenarios.at_reference(cfg.update({"operating.temperature_c": 40.0}))
    assert hot.operating.temperature_c == 23.0 and scenarios.temperatures(hot) == (40.0,)


@pytest.fixture(scope="module")
def cold_hot_run():
    args = ["optimise", "--robust", "--json", "--set", "operating.temperatures_c=[0, 23, 40]",
            "--set", "design.damper_temperature_coeff=-0.005"]
    return args


@pytest.mark.slow
def test_the_issue_command_meets_every_corner_at_every_temperature(capsys, cold_hot_run):
    """softclose optimise --robust at 0, 23 and 40 °C with a silicone-oil damper: the design
    it returns, re-simulated by the adaptive reference at every corner of the box at every
    temperature, meets every constraint; its worst-case J is the worst of them."""
    rc = cli.main(cold_hot_run)
    out, _ = capsys.readouterr()
    assert rc == 0
    j = json.loads(out)
    assert j["success"] and j["temperatures"] == [0.0, 23.0, 40.0]
    assert j["limiting_temperature_c"] in (0.0, 23.0, 40.0)
    d = j["design"]
    cfg = default_config().update(COLD_HOT)
    o = cfg.optimise
    worst, margins = 0.0, {}
    for T in (0.0, 23.0, 40.0):
        for sk, sc, sm in itertools.product((-1, 1), repeat=3):
            c = at_temperature(cfg.update({
                "design.spring_kind": j["kind"],
                "design.spring_k": d["spring_k"] * (1 + sk * SPREADS["design.spring_k"]),
                "design.spring_rest_length": d["spring_rest_length"],
                "design.damper_c": d["damper_c"] * (1 + sc * SPREADS["design.damper_c"]),
                "mass.lid": cfg.mass.lid * (1 + sm * SPREADS["mass.lid"])}), T)
            r = Reference.from_config(c).simulate()
            where = (T, sk, sc, sm)
            assert r.closed, where
            assert o.closing_time_min <= r.closing_time <= o.closing_time_max * (1 + 1e-6), where
            assert r.holding_moment >= o.holding_moment_min - CONSTRAINT_TOL, where
            assert r.theta_min >= c.stroke.theta_closed - 1e-12, where
            if r.theta_dot_max is not None:
                assert r.theta_dot_max <= CONSTRAINT_TOL, where
            worst = max(worst, objective(o, r.impact_theta_dot, r.peak_tip_speed))
            margins[T] = min(margins.get(T, np.inf),
                             (o.closing_time_max - r.closing_time) / o.closing_time_max,
                             (r.holding_moment - o.holding_moment_min) / o.holding_moment_min)
    # the worst case over corners x temperatures is the optimiser's (no corner left out
    # exceeds it by more than the corner check's OBJ_RTOL)
    assert j["objective"] == pytest.approx(worst, rel=VERIFY_RTOL + OBJ_RTOL)
    # the cold damper is the thickest: the slowest corner is at 0 °C, and it binds
    assert j["limiting_temperature_c"] == min(margins, key=margins.get) == 0.0
    assert margins[0.0] < 1e-4 < margins[40.0]


SPRINGS = """\
part,kind,rate_N_per_m,free_length_m,preload_N,min_length_m,max_length_m,rate_tolerance,free_length_tolerance_m
C-60-5000,compression,5000,0.060,0,0.030,,0.1,0.0009
"""
DAMPERS = """\
part,kind,c,pivot,c_tolerance
D-2500,dashpot,2500,,0.2
D-3250,dashpot,3250,,0.2
"""


def test_select_a_pair_that_holds_at_23_fails_cold(tmp_path):
    """With a silicone-oil damper (-0.5 %/K) the dashpot of 3250 N s/m is 12 % thicker at
    0 °C: the spring's slow corner (rate +10 %, free length +0.9 mm, c +20 %) closes within
    the second at 23 °C and not at 0 °C. Selected at 23 °C alone the pair is feasible, at 0
    and 23 °C it is not (at that corner at 0 °C, confirmed by the adaptive reference) and the
    thinner damper ranks first."""
    from softclose.catalog.ranking import select
    sp, dp = tmp_path / "springs.csv", tmp_path / "dampers.csv"
    sp.write_text(SPRINGS)
    dp.write_text(DAMPERS)
    base = default_config().update({"tolerance.mass.lid": 0.0,
                                    "design.damper_temperature_coeff": -0.005})
    warm = {e["damper"]: e for e in select(base, sp, dp, samples=64, verify=2).ranking}
    assert warm["D-3250"]["feasible"] and warm["D-3250"]["verified"]
    assert "limiting_temperature_c" not in warm["D-3250"]
    both = select(base.update({"operating.temperatures_c": [0.0, 23.0]}), sp, dp, samples=64,
                  verify=2)
    j = json.loads(json.dumps(both.to_json(), allow_nan=False))
    assert [e["damper"] for e in j["ranking"]] == ["D-2500", "D-3250"]
    first, cold = j["ranking"]
    for key in ("spring", "damper", "feasible", "yield", "worst_objective", "design",
                "verified"):
        assert key in first and key in cold
    assert first["feasible"] and first["verified"] and not cold["feasible"]
    assert cold["verified"]                          # the reference agrees at every corner
    assert cold["limiting_temperature_c"] == 0.0 and "at 0 °C" in cold["reason"]
    assert cold["yield"] < warm["D-3250"]["yield"] + 1e-12
    bad = [c for c in both.ranking[1]["reference"]["corners"] if not c["ok"]]
    assert bad and all(c["label"].endswith("at 0 °C") for c in bad)
    # independently: that corner at 0 °C, by the reference, is too slow; at 23 °C it is not
    corner = base.update({"design.spring_kind": "compression", "design.spring_k": 5500.0,
                          "design.spring_rest_length": 0.0609,
                          "design.damper_c": 3250.0 * 1.2})
    o = base.optimise
    assert Reference.from_config(at_temperature(corner, 0.0)).simulate().closing_time \
        > o.closing_time_max
    assert Reference.from_config(corner).simulate().closing_time < o.closing_time_max


def test_operating_temperature_is_a_sweep_key():
    """A grid over operating.temperature_c: each row is the stroke of the design at that
    temperature (the simulator's own, to 1e-12), and the damper thickens the cold."""
    from softclose.simulation.simulator import Simulator
    from softclose.sweeps import sweep
    cfg = default_config().update({**DESIGN, "design.damper_temperature_coeff": -0.005})
    temps = np.array([-10.0, 23.0, 50.0])
    res = sweep(cfg, {"operating.temperature_c": temps})
    df = res.to_frame()
    ct = np.asarray(df["closing_time"], float)
    for T, t in zip(temps, ct):
        c = at_temperature(cfg, T)
        r = Simulator.from_config(c).run(params_of(c), estimate_error=False)
        assert t == pytest.approx(r.closing_time, rel=1e-12)
    assert ct[0] > ct[1] > ct[2]


@pytest.mark.slow
def test_one_other_temperature_moves_the_spring_by_its_factor(default_robust):
    """``operating.temperature_c = -10`` alone, no damper law: the one sign-off temperature
    multiplies the spring's rate by 1 + 2.5e-4 x 33 and touches nothing else, so the robust
    design given at 23 °C is the default one with its rate divided by that factor (the
    strokes are the same), its worst-case J the same, and -10 °C limits it."""
    from softclose.robust import optimise_robust
    cold = optimise_robust(default_config().update({"operating.temperature_c": -10.0}))
    assert cold.success, cold.message
    g = 1 + 2.5e-4 * 33.0
    ref = default_robust.design
    assert cold.design["spring_k"] == pytest.approx(ref["spring_k"] / g, rel=1e-5)
    assert cold.design["damper_c"] == pytest.approx(ref["damper_c"], rel=1e-5)
    assert cold.design["spring_rest_length"] == pytest.approx(ref["spring_rest_length"],
                                                              rel=1e-6)
    assert cold.objective == pytest.approx(default_robust.objective, rel=1e-5)
    assert cold.temperatures == (-10.0,) and cold.limiting_temperature_c == -10.0
    assert default_robust.temperatures == (23.0,)
    assert default_robust.limiting_temperature_c == 23.0
    # the design the result hands on keeps the stroke temperature it was asked for
    assert cold.design_config().operating.temperature_c == -10.0
