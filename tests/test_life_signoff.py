"""The end of life as a sign-off state (SPEC §17), like a temperature: simulate reports each
state's stroke, yield each state's and the joint yield, the report's matrix has end-of-life
columns and its verdict names the state, and the robust design meets every constraint at
every corner in both states (slow)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import softclose
from softclose.config import default_config, load_config
from softclose.problem import (END_OF_LIFE, at_state, condition_parts, sign_off_conditions,
                               sign_off_states)

ROOT = Path(__file__).resolve().parents[1]
CHEST = ROOT / "examples" / "lids" / "chest_lid.toml"
#: the makers' figures (FIELD-NOTES, "End of life"): a strut at -10 %, dampers at -15 %
WORN = {"life.strut_force_loss": 0.10, "life.damper_change": -0.15}


def test_the_states_and_conditions_of_a_config():
    cfg = default_config()
    assert sign_off_states(cfg) == ("new",) and sign_off_conditions(cfg) == (23.0,)
    worn = cfg.update({"life.damper_change": -0.15, "operating.temperatures_c": [0.0, 40.0]})
    assert sign_off_states(worn) == ("new", "end_of_life")
    assert [condition_parts(c) for c in sign_off_conditions(worn)] == [
        (0.0, None), (40.0, None), (0.0, "end_of_life"), (40.0, "end_of_life")]
    assert END_OF_LIFE > 150.0          # above every admissible temperature


def test_simulate_reports_the_end_of_life_beside_the_new_lid():
    cfg = load_config(CHEST).update(WORN)
    res = softclose.simulate(cfg, hand_force=True)
    (s0, new), (s1, old) = res.states
    assert (s0, s1) == ("new", "end_of_life") and new is not old
    assert new.closing_time == res.closing_time
    alone = softclose.simulate(at_state(cfg, "end_of_life"))
    assert old.closing_time == alone.closing_time
    assert old.closing_time < new.closing_time            # a weaker strut, faded dampers
    out = res.to_json()["states"]
    assert [x["state"] for x in out] == ["new", "end_of_life"]
    assert out[1]["closing_time"] == alone.closing_time and out[1]["opening_force"] > \
        out[0]["opening_force"]
    assert "end of life: closes in" in res.text()
    assert softclose.simulate(load_config(CHEST), hand_force=True).states == ()


def test_yield_per_state_and_jointly():
    from softclose.robust import tolerance_analysis, yield_by_temperature
    cfg = load_config(CHEST).update({**WORN, "tolerance.samples": 200,
                                     "optimise.closing_time_max": 2.0})
    t = yield_by_temperature(cfg, reference=0)
    assert len(t.results) == 2
    alone = tolerance_analysis(at_state(cfg, "end_of_life"), reference=0)
    assert t.results[1].yield_ == alone.yield_
    states = t.state_yields()
    assert [s["state"] for s in states] == ["new", "end_of_life"]
    assert t.yield_ <= min(s["yield"] for s in states)
    js = t.to_json()
    assert [x["state"] for x in js["temperatures"]] == ["new", "end_of_life"]
    assert js["limiting_state"] in ("new", "end_of_life") and js["states"] == states


def test_the_report_names_the_end_of_life_when_only_it_fails(tmp_path):
    """The chest lid opens with 7.99 N new, 8.68 N with its strut at -10 %: with a limit of
    8.3 N it passes new and fails old, and the verdict says so."""
    cfg = load_config(CHEST).update({**WORN, "optimise.opening_force_max": 8.3,
                                     "optimise.closing_time_max": 2.0,
                                     "tolerance.samples": 100,
                                     "tolerance.required_yield": 1e-6})
    r = softclose.report(cfg)
    cols = r.matrix["columns"]
    assert "23 °C" in cols and "23 °C at the end of life" in cols
    assert r.matrix["cells"]["opening_force_max"]["23 °C"]["ok"]
    assert not r.matrix["cells"]["opening_force_max"]["23 °C at the end of life"]["ok"]
    assert not r.success
    assert r.message.startswith("This design passes new but FAILS at the end of life")
    assert r.limiting_state == "end_of_life" and r.to_json()["states"] == ["new", "end_of_life"]
    new_only = softclose.report(load_config(CHEST).update(
        {"optimise.opening_force_max": 8.3, "optimise.closing_time_max": 2.0,
         "tolerance.samples": 100, "tolerance.required_yield": 1e-6}))
    assert new_only.success and new_only.limiting_state is None


@pytest.mark.slow
def test_the_robust_design_meets_every_constraint_at_every_corner_of_both_states():
    cfg = default_config().update({"life.damper_change": -0.15,
                                   "life.spring_relaxation": 0.03})
    r = softclose.optimise(cfg, robust=True)
    assert r.success, r.message
    assert r.states == ("new", "end_of_life") and r.limiting_state in r.states
    js = r.to_json()
    assert js["states"] == ["new", "end_of_life"] and "limiting_state" in js
    scen = js["scenarios"]
    corners = [s for s in scen if s["z"] and all(abs(v) == 1.0 for v in s["z"])]
    for state in ("new", "end_of_life"):     # every corner of the box, in each state
        mine = [s for s in corners if s.get("state") == state]
        assert len(mine) == 2 ** len(scen[0]["z"])
        assert all(s["verified"] for s in mine)
        for s in mine:                        # the reference's numbers meet each constraint
            ref = s["reference"]
            assert ref["closed"] and ref["closing_time"] <= 1.0 + 1e-7
            assert ref["holding_moment"] >= 0.1 - 1e-7
    # the relaxed compression spring stays valid: its relaxed free length covers the stroke
    d = r.design
    from softclose.model.life import shut_coordinates
    from softclose.problem import resolve
    ls = shut_coordinates(softclose.LidModel(resolve(cfg)))["spring"]
    assert (0.97 * d["spring_rest_length"] + 0.03 * ls) >= js["max_spring_length"] - 1e-9
    assert r.corner_check["worst_margin"] >= -1e-7


def test_life_state_is_a_sweep_key():
    from softclose import sweep
    cfg = load_config(CHEST).update(WORN)
    res = sweep(cfg, {"life.state": ["new", "end_of_life"]})
    df = res.to_frame()
    assert list(df["life.state"]) == ["new", "end_of_life"]
    for state, t in zip(df["life.state"], df["closing_time"]):
        one = softclose.simulate(cfg.update({"life.state": state}))
        assert t == pytest.approx(one.closing_time, rel=1e-12)
    assert df["closing_time"].iloc[1] < df["closing_time"].iloc[0]


def test_select_screens_and_verifies_both_states():
    """A strut and a dashpot that close the lid no faster than 0.6 s new are too fast once the
    dashpot has faded 40 %: select judges every corner new and at the end of life, names the
    state a pair fails in, and counts a sample towards the yield when it holds in both."""
    from softclose.catalog.files import read_dampers, read_springs
    cat = ROOT / "examples" / "catalogs"
    springs = [s for s in read_springs(cat / "springs.csv").parts
               if s.part in ("GS-070-F020", "CS-068-00500")]
    dampers = [d for d in read_dampers(cat / "dampers.csv").parts
               if d.part in ("DP-5000", "RD-A-1")]
    cfg = default_config().update({"optimise.closing_time_min": 0.6})
    worn = cfg.update({"life.damper_change": -0.4, "life.spring_relaxation": 0.05})
    new = {(e["spring"], e["damper"]): e for e in
           softclose.select(cfg, springs, dampers, samples=64, verify=1).ranking}
    old = {(e["spring"], e["damper"]): e for e in
           softclose.select(worn, springs, dampers, samples=64, verify=1).ranking}
    pair = ("GS-070-F020", "DP-5000")
    assert old[pair]["limiting_state"] == "end_of_life"
    assert old[pair]["reason"].endswith("at the end of life") and not old[pair]["feasible"]
    assert "end of life" not in new[pair]["reason"] and "limiting_state" not in new[pair]
    for k in new:                      # both states: never a better yield than new alone
        assert old[k]["yield"] <= new[k]["yield"]
