"""``softclose select`` with gas struts: a catalog strut row is the gas strut the model
simulates (SPEC §10, §12), judged over its own box (F1 ± force_tolerance, the extended length
± its tolerance), its friction band the strut's friction; a damper's temperature
coefficient column is its ``design.damper_temperature_coeff``."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from softclose.config import default_config

from conftest import run_cli as _run, write_file as _write

#: two struts of one series (60 mm extended, 20 mm stroke, F1 10 N, K 1.2); the second's
#: friction band (300 N, F_R 150 N) holds the lid where it is released
STRUTS = """\
part,kind,rate_N_per_m,free_length_m,preload_N,min_length_m,max_length_m,rate_tolerance,free_length_tolerance_m,progression,friction_band_N,force_tolerance
GS-60-F10,gas_strut,,0.060,10,0.040,,,0.0015,1.2,3,0.07
GS-60-F10-sticky,gas_strut,,0.060,10,0.040,,,0.0015,1.2,300,0.07
"""
DAMPERS = """\
part,kind,c,pivot,c_tolerance,temperature_coeff_per_K
DP-6000,dashpot,6000,,0.2,-0.005
"""
DATA = Path(__file__).resolve().parent / "data"


def _cfg():
    return default_config().update({"tolerance.mass.lid": 0.0})


def _tension(cfg, length: float) -> float:
    """The spring element's tension at ``length`` with cfg's design (N; < 0 pushes)."""
    from softclose.model.elements import PARAM_NAMES
    from softclose.model.elements.springs import Spring
    from softclose.robust.evaluate import params_of
    P = dict(zip(PARAM_NAMES, (float(x) for x in params_of(cfg))))
    return float(Spring().tension(length, P))


def test_a_strut_row_is_the_gas_strut_the_model_simulates(tmp_path):
    """F1 at full extension, K F1 at full compression (the element's own tension); K from
    the progression column, or from the rate (1 + rate s / F1) in an old catalog."""
    from softclose.catalog import read_springs
    e = read_springs(_write(tmp_path, "s.csv", STRUTS)).parts[0]
    assert (e.spring_kind, e.stroke, e.progression, e.friction, e.force_tolerance) == \
        ("gas_strut", 0.020, 1.2, 1.5, 0.07)
    assert e.rate == pytest.approx(10 * 0.2 / 0.020, rel=1e-12)     # F1 (K - 1) / s
    cfg = default_config().update({f"design.{k}": v for k, v in e.design().items()})
    assert _tension(cfg, 0.060) == pytest.approx(-10.0, rel=1e-12)
    assert _tension(cfg, 0.040) == pytest.approx(-1.2 * 10.0, rel=1e-12)
    # halfway: the isothermal gas law, F1 / (1 - (1 - 1/K) x / s)
    assert _tension(cfg, 0.050) == pytest.approx(-10.0 / (1 - (1 - 1 / 1.2) / 2), rel=1e-12)
    assert cfg.design.strut_friction == 1.5             # half the friction band
    # an old catalog (no progression, friction or force tolerance column) still loads: K
    # from its rate over the stroke, no friction, F1 to ±10 %
    old = next(p for p in read_springs(DATA / "catalog_springs.csv").parts
               if p.part == "G-70-F20")
    assert (old.spring_kind, old.stroke, old.friction, old.force_tolerance) == \
        ("gas_strut", 0.025, 0.0, 0.1)
    assert old.progression == pytest.approx(1 + 300 * 0.025 / 20, rel=1e-12)
    c = default_config().update({f"design.{k}": v for k, v in old.design().items()})
    assert _tension(c, 0.045) == pytest.approx(-20 * 1.375, rel=1e-12)
    assert _tension(c, 0.045) - _tension(c, 0.070) == pytest.approx(-300 * 0.025, rel=1e-12)


def test_bad_strut_rows_are_reported_by_line_and_column(tmp_path):
    from softclose.catalog import read_dampers, read_springs
    head, good = STRUTS.splitlines()[:2]
    bad = [head, good,
           "X1,gas_strut,,0.060,10,,,,0.0015,1.2,3,0.07",        # line 3: no compressed length
           "X2,gas_strut,,0.060,10,0.040,,,0.0015,7,3,0.07",     # line 4: K above 5
           "X3,gas_strut,,0.060,10,0.040,,,0.0015,,3,0.07",      # line 5: no rate, no K
           "X4,gas_strut,,0.060,0,0.040,,,0.0015,1.2,3,0.07",    # line 6: F1 = 0
           "X5,compression,500,0.060,0,0.030,,0.1,0.0009,,3,",   # line 7: a coil's friction
           "X6,gas_strut,,0.060,10,0.040,,,0.0015,1.2,-1,0.07",  # line 8: negative band
           "X7,gas_strut,,0.060,10,0.040,,,0.0015,1.2,3,1.5"]    # line 9: tolerance >= 1
    cat = read_springs(_write(tmp_path, "bad.csv", "\n".join(bad) + "\n"))
    assert [p.part for p in cat.parts] == ["GS-60-F10"]
    w = cat.warnings
    assert len(w) == 7
    assert "line 3, column min_length_m: a gas strut needs its compressed length" in w[0]
    assert "line 4, column progression" in w[1] and "within [1, 5], got 7" in w[1]
    assert "line 5, column rate_N_per_m: missing value" in w[2]
    assert "line 6, column preload_N" in w[3]
    assert "line 7, column friction_band_N: a compression spring has no" in w[4]
    assert "line 8, column friction_band_N" in w[5]
    assert "line 9, column force_tolerance" in w[6]
    d = read_dampers(_write(tmp_path, "d.csv", DAMPERS + "DP-X,dashpot,6000,,0.2,0.5\n"))
    assert d.parts[0].temperature_coeff == -0.005 and len(d.parts) == 1
    assert "line 3, column temperature_coeff_per_K" in d.warnings[0]


def test_select_ranks_struts_and_the_pair_config_simulates_as_verified(tmp_path):
    """select --out: the strut is ranked over its own box and verified by the reference; the
    written pair config (pairs/01_*.toml) is the strut (its F1, stroke, progression,
    friction; F1's spread its force tolerance) and the damper (its temperature coefficient);
    ``softclose simulate`` of it at the box's corner gives the reference's J there, and at
    its nominal point the kernel's closing time. The sticky strut fails with the reason."""
    from softclose.catalog.screen import pair_box
    s = _write(tmp_path, "s.csv", STRUTS)
    d = _write(tmp_path, "d.csv", DAMPERS)
    cfgfile = _write(tmp_path, "cfg.toml", "[tolerance]\n\"mass.lid\" = 0.0\n")
    code, out = _run("select", "--springs", str(s), "--dampers", str(d), "--config",
                     str(cfgfile), "--samples", "16", "--verify", "2", "--json", "--out",
                     str(tmp_path / "o"))
    assert code == 0, out
    R = json.loads(out)["ranking"]
    best, sticky = R
    assert best["spring"] == "GS-60-F10" and best["feasible"] and best["verified"] is True
    assert best["design"]["spring_kind"] == "gas_strut"
    assert best["design"]["strut_friction"] == 1.5
    ref = best["reference"]
    assert ref["feasible"] and len(ref["corners"]) == 8
    labels = [c["label"] for c in ref["corners"]]
    assert labels[0] == "F1 -7 %, free length -1.5 mm, c -20 %"
    # the strut that sticks: infeasible, the reason says where the lid stops (the
    # kernel's), the reference says the friction holds it
    assert not sticky["feasible"] and sticky["yield"] == 0.0
    assert "not closed: the lid stops at theta = 18 deg" in sticky["reason"]
    assert "held by friction" in sticky["reference"]["reason"]
    # the pair's config, as the sign-off report reads it
    toml = sorted((tmp_path / "o" / "pairs").glob("01_*.toml"))[0]
    code, sim = _run("simulate", "--config", str(toml), "--json")
    assert code == 0
    assert json.loads(sim)["closing_time"] == pytest.approx(
        best["nominal"]["closing_time"], rel=2e-3)
    from softclose.config import load_config
    import softclose
    c = load_config(str(toml))
    assert (c.design.spring_kind, c.design.spring_preload, c.design.strut_stroke,
            c.design.strut_progression, c.design.strut_friction,
            c.design.damper_temperature_coeff) == ("gas_strut", 10.0, 0.02, 1.2, 1.5, -0.005)
    spreads = {x.key: x for x in c.tolerance.spreads}
    assert "design.spring_k" not in spreads
    assert spreads["design.spring_preload"].value == 0.07
    assert spreads["design.spring_rest_length"].half_width(0.06) == pytest.approx(0.0015)
    # the reference's J at the corner (F1 -7 %, L -1.5 mm, c -20 %) is simulate's there
    corner = c.update({"design.spring_preload": 10 * 0.93,
                       "design.spring_rest_length": 0.060 - 0.0015,
                       "design.damper_c": 6000 * 0.8})
    r = softclose.simulate(corner)
    from softclose.problem import objective
    J = float(objective(c.optimise, r.impact_theta_dot, r.peak_tip_speed))
    assert J == pytest.approx(ref["corners"][0]["objective"], rel=1e-6)
    # the box's first axis of a strut is its F1 (its rate carries no spread)
    assert pair_box(_cfg(), 0).Z[0, 0] == -1.0


def test_a_strut_and_its_damper_at_another_temperature(tmp_path):
    """The catalog's damper coefficient column moves c with temperature, the strut's gas
    moves F1: the pair config's stroke at 0 °C is the one with c exp(beta dT) and F1 tau
    set by hand at the reference temperature."""
    import softclose
    from softclose.catalog import pair_config, select
    from softclose.model.temperature import gas_factor
    cfg = _cfg()
    r = select(cfg, _write(tmp_path, "s.csv", STRUTS.splitlines()[0] + "\n"
                           + STRUTS.splitlines()[1] + "\n"),
               _write(tmp_path, "d.csv", DAMPERS), samples=0, verify=0)
    c = pair_config(cfg, r.best)
    cold = softclose.simulate(c.update({"operating.temperature_c": 0.0}))
    tau = gas_factor(0.0, 23.0)
    byhand = softclose.simulate(c.update({
        "design.damper_c": 6000 * math.exp(-0.005 * (0.0 - 23.0)),
        "design.spring_preload": 10 * tau, "design.damper_temperature_coeff": 0.0}))
    assert cold.closing_time == pytest.approx(byhand.closing_time, rel=1e-9)
    assert cold.closing_time > softclose.simulate(c).closing_time     # thicker oil


def test_the_damper_column_is_its_temperature_coefficient_at_every_temperature(tmp_path):
    """Screened at 0 and 23 °C, a damper whose row gives temperature_coeff_per_K = -0.005 is
    judged as the same damper without the column in a config with
    design.damper_temperature_coeff = -0.005, number for number; without a coefficient the
    cold corners differ."""
    from softclose.catalog import select
    cfg = _cfg().update({"operating.temperatures_c": [0.0, 23.0]})
    strut = _write(tmp_path, "s.csv", "\n".join(STRUTS.splitlines()[:2]) + "\n")
    with_col = _write(tmp_path, "d.csv", DAMPERS)
    plain = _write(tmp_path, "p.csv", "part,kind,c,pivot,c_tolerance\nDP-6000,dashpot,6000,,0.2\n")
    a = select(cfg, strut, with_col, samples=16, verify=0).best
    b = select(cfg.update({"design.damper_temperature_coeff": -0.005}), strut, plain,
               samples=16, verify=0).best
    c = select(cfg, strut, plain, samples=16, verify=0).best
    for k in ("feasible", "yield", "worst_objective", "corners_feasible"):
        assert a[k] == b[k], k
    assert a["worst_objective"] != c["worst_objective"]
    assert a["design"]["damper_temperature_coeff"] == -0.005
