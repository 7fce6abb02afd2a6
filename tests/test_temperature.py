"""Operating temperature (SPEC §12): a design's values are given at the reference
temperature; a stroke at another one sees every damper's coefficient × exp(β ΔT) and a coil
spring's rate and preload × (1 − γ_G ΔT). The same stroke with the values moved by hand is
the same stroke, bit for bit; the defaults change nothing; the optimiser refuses another
temperature in one line."""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from softclose import LidModel, Reference, Simulator, sweep
from softclose.config import default_config
from softclose.errors import ConfigError
from softclose.model.temperature import parameter_factors
from softclose.problem import PARAM_KEYS, params_of, resolve


def factors_of(cfg):
    """The parameters' factors at ``cfg``'s operating temperature (a coil spring's design)."""
    f = parameter_factors(resolve(cfg).temperatures)
    return None if f is None else f[0]


ROOT = Path(__file__).resolve().parents[1]
#: a spring and all three dampers, so every law is exercised
DESIGN = {"design.spring_k": 1500.0, "design.spring_rest_length": 0.07,
          "design.damper_c": 600.0, "design.rotary_damper_c": 0.02,
          "design.end_damper_c": 0.5, "design.end_damper_angle_deg": 6.0}


def lid(**operating):
    cfg = default_config().update(DESIGN)
    return cfg.update({f"operating.{k}": v for k, v in operating.items()})


def by_hand(cfg, T, beta, gamma=2.5e-4):
    """The design's p with its values moved to T by hand (T_ref = 23 °C)."""
    p = params_of(cfg).copy()
    i = {k: PARAM_KEYS.index(k) for k in PARAM_KEYS}
    for k in ("damper_c", "rotary_damper_c", "end_damper_c"):
        p[i[k]] *= math.exp(beta * (T - 23.0))
    for k in ("spring_k", "spring_preload", "torsion_k"):
        p[i[k]] *= 1.0 - gamma * (T - 23.0)
    return p


def test_at_the_reference_temperature_nothing_moves():
    assert factors_of(default_config()) is None
    assert factors_of(lid(temperature_c=40.0, reference_temperature_c=40.0)) is None


def test_the_datasheet_damper_and_the_steel_wire():
    """A rotary damper rated 6.5 s at 23 °C took 7.3 s at 0 °C and 6.0 s at 40 °C (a maker's
    data; closing time ∝ c): β = -0.005 /K fits both to ~1 %. Steel wire (EN 10270-1):
    γ_G = 2.5e-4 /K, so at -20 °C a rate is 1.01075 times its 23 °C value."""
    i = PARAM_KEYS.index
    for T, ratio in ((0.0, 7.3 / 6.5), (40.0, 6.0 / 6.5)):
        f = factors_of(lid(temperature_c=T).update(
            {"design.damper_temperature_coeff": -0.005}))
        assert f[i("rotary_damper_c")] == pytest.approx(ratio, rel=0.012)
        assert f[i("damper_c")] == f[i("end_damper_c")] == f[i("rotary_damper_c")]
    f = factors_of(lid(temperature_c=-20.0))
    assert f[i("spring_k")] == pytest.approx(1.01075, rel=1e-12)
    assert f[i("spring_preload")] == f[i("torsion_k")] == f[i("spring_k")]
    assert f[i("spring_rest_length")] == 1.0 and f[i("damper_c")] == 1.0   # β = 0


@pytest.mark.parametrize("T", [-20.0, 60.0])
def test_a_stroke_at_temperature_is_the_stroke_of_the_moved_values(T):
    beta = -0.005
    hot = lid(temperature_c=T).update({"design.damper_temperature_coeff": beta})
    ref = lid()
    moved = by_hand(ref, T, beta)
    a = Simulator.from_config(hot).run(params_of(hot))
    b = Simulator.from_config(ref).run(moved)
    assert a.closed and b.closed
    assert a.closing_time == b.closing_time and a.impact_tip_speed == b.impact_tip_speed
    A = Simulator.from_config(hot).run_batch(np.tile(params_of(hot), (3, 1)))
    assert A["closing_time"][0] == a.closing_time
    # the adaptive reference too, and the kernel agrees with it at the method's accuracy
    model = LidModel.from_config(ref)
    ra, rb = Reference(model).simulate(params_of(hot), resolve(hot)), Reference(model).simulate(moved)
    assert ra.closing_time == rb.closing_time
    assert a.closing_time == pytest.approx(ra.closing_time, rel=1e-4)
    # the accuracy estimate is that of the moved stroke (the half step at the same
    # temperature), and the reference is within it
    assert a.accuracy == b.accuracy
    assert abs(a.closing_time - ra.closing_time) <= 10 * a.accuracy["closing_time"] + 1e-9
    assert a.accuracy["closing_time"] < 1e-7
    # and the temperature matters: colder dampers are stronger, the lid closes later
    base = Simulator.from_config(ref).run(params_of(ref))
    assert (a.closing_time > base.closing_time) == (T < 23.0)


def test_a_sweep_over_temperature_runs_each_stroke_at_its_temperature():
    cfg = lid().update({"design.damper_temperature_coeff": -0.005})
    res = sweep(cfg, {"operating.temperature_c": [-20.0, 23.0, 60.0]})
    df = res.to_frame().sort_values("operating.temperature_c")
    for T, t in zip(df["operating.temperature_c"], df["closing_time"]):
        one = Simulator.from_config(cfg.update({"operating.temperature_c": float(T)})).run(params_of(cfg))
        assert t == pytest.approx(one.closing_time, rel=1e-12)
    assert df["closing_time"].is_monotonic_decreasing


def test_the_tolerance_boxs_strokes_run_at_each_configs_temperature():
    """The cached simulators of the tolerance box are one per temperature: a yield at 0 °C
    after one at 23 °C runs its strokes at 0 °C (and back)."""
    from softclose.robust.box import box_of
    from softclose.robust.evaluate import evaluate
    cfg = lid().update({"design.damper_temperature_coeff": -0.005})
    for T in (23.0, 0.0, 23.0, 40.0):
        c = cfg.update({"operating.temperature_c": T})
        box = box_of(c)
        got = evaluate(c, box.keys, box.values(np.zeros((1, box.dim))))["closing_time"][0]
        assert got == pytest.approx(Simulator.from_config(c).run().closing_time, rel=1e-12)


def test_the_optimiser_designs_at_the_reference_temperature():
    from softclose.optimiser import optimise
    with pytest.raises(ConfigError, match=r"^operating\.temperature_c: the optimiser works at "
                                          r"the reference temperature"):
        optimise(lid(temperature_c=-20.0))
    r = subprocess.run([sys.executable, "-m", "softclose", "optimise", "--set",
                        "operating.temperature_c=-20"], capture_output=True, text=True,
                       cwd=ROOT)
    assert r.returncode == 2 and r.stderr.count("\n") == 1
    assert "operating.temperature_c" in r.stderr


@pytest.mark.parametrize("key, value", [("operating.temperature_c", -300.0),
                                        ("operating.reference_temperature_c", 1e4),
                                        ("design.damper_temperature_coeff", 1.0)])
def test_out_of_range_temperatures_are_refused_in_one_line(key, value):
    with pytest.raises(ConfigError, match=rf"^{key}"):
        default_config().update({key: value})


def test_yield_at_each_sign_off_temperature_and_jointly(capsys, tmp_path):
    """``operating.temperatures_c``: the yield at each temperature equals
    tolerance_analysis at that temperature (the same samples), the joint yield counts the
    lids that pass at all of them (no more than the lowest), and ``softclose yield`` gives
    both (JSON ``temperatures``)."""
    import json
    from softclose.cli import main
    from softclose.robust import tolerance_analysis, yield_by_temperature
    cfg = lid().update({"design.damper_temperature_coeff": -0.005,
                        "operating.temperatures_c": [0.0, 40.0],
                        "tolerance.design.damper_c": 0.2, "tolerance.samples": 300})
    t = yield_by_temperature(cfg, reference=0)
    assert t.temperatures == (0.0, 40.0) and t.samples == 300
    for T, r in zip(t.temperatures, t.results):
        alone = tolerance_analysis(cfg.replace(operating={"temperature_c": T}), reference=0)
        assert r.yield_ == alone.yield_ and r.failures == alone.failures
    both = np.asarray(t.results[0].data["cols"]["feasible"], bool) & \
        np.asarray(t.results[1].data["cols"]["feasible"], bool)
    assert t.yield_ == both.mean() <= min(r.yield_ for r in t.results)
    assert t.limiting == min(zip(t.results, t.temperatures), key=lambda x: x[0].yield_)[1]
    cfgfile = tmp_path / "lid.toml"
    from softclose.config import to_toml
    cfgfile.write_text(to_toml(cfg))
    rc = main(["yield", "--config", str(cfgfile), "--json"])
    out = json.loads(capsys.readouterr().out)
    assert rc == (0 if t.meets_required else 3)
    assert out["yield"] == t.yield_ and [x["temperature_c"] for x in out["temperatures"]] == \
        [0.0, 40.0]
    assert [x["yield"] for x in out["temperatures"]] == [r.yield_ for r in t.results]
