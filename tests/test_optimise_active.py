"""What limits the design (issue 12 item 7): the active bounds and constraints, with dJ from
Ipopt's multipliers checked against finite differences -- the problem re-optimised with the
limit relaxed and tightened by a small amount."""

from __future__ import annotations

import json

import pytest

from softclose.cli import main
from softclose.optimiser import optimise


def active(r) -> dict:
    return {a.name: a for a in r.active}


def central_difference(cfg, section_values, h, starts=1) -> float:
    """(J(+h) - J(-h)) / 2h of the optimiser's objective, one key moved by +-h."""
    (key, v0), = section_values.items()
    J = [optimise(cfg.replace(optimise={key: v}), starts=starts).objective
         for v in (v0 + h, v0 - h)]
    return (J[0] - J[1]) / (2 * h)


def test_default_active_set_and_prices(cfg):
    r = optimise(cfg, starts=1)
    a = active(r)
    assert set(a) == {"closing_time_max", "holding_moment_min"}
    ct, hm = a["closing_time_max"], a["holding_moment_min"]
    assert (ct.bound, ct.value, ct.unit) == ("upper", 1.0, "s")
    assert (hm.bound, hm.value, hm.unit) == ("lower", 0.1, "N m")
    # dJ per unit relaxation: more time (+) and a lower holding moment (-) both lower J
    dJ_dT = central_difference(cfg, {"closing_time_max": 1.0}, 2e-3)
    assert ct.dJ == pytest.approx(dJ_dT, rel=2e-2)
    assert ct.dJ < 0
    dJ_dhm = central_difference(cfg, {"holding_moment_min": 0.1}, 2e-4)
    assert hm.dJ == pytest.approx(-dJ_dhm, rel=2e-2)       # relaxing = lowering the minimum
    assert hm.dJ < 0


@pytest.mark.slow
def test_heavy_lid_is_limited_by_the_rest_length(cfg):
    """Lid mass 0.75 kg: the optimum sits at spring_rest_length = 0.12 m, its upper bound."""
    heavy = cfg.set("mass.lid", 0.75)
    r = optimise(heavy, starts=2)
    assert r.success, r.message
    a = active(r)
    assert "spring_rest_length" in a
    l0 = a["spring_rest_length"]
    assert (l0.bound, l0.value, l0.unit, l0.kind) == ("upper", 0.12, "m", "bound")
    assert r.design["spring_rest_length"] == pytest.approx(0.12, rel=1e-7)
    h = 2e-4
    J = [optimise(heavy.replace(optimise={"spring_rest_length": [0.02, 0.12 + s]}),
                  starts=2).objective for s in (h, -h)]
    assert l0.dJ == pytest.approx((J[0] - J[1]) / (2 * h), rel=2e-2)
    assert l0.dJ < 0


def test_active_in_text_and_json(capsys):
    code = main(["optimise", "--json", "--set", "mass.lid=0.75", "--set", "optimise.starts=2"])
    out = json.loads(capsys.readouterr().out)
    assert code == 0
    names = {a["name"]: a for a in out["active"]}
    assert names["spring_rest_length"]["bound"] == "upper"
    assert names["spring_rest_length"]["value"] == 0.12
    assert set(names["spring_rest_length"]) >= {"name", "bound", "value", "dJ"}
    code = main(["optimise", "--set", "mass.lid=0.75", "--set", "optimise.starts=2"])
    text = capsys.readouterr().out
    assert "spring_rest_length at its upper bound 0.12 m" in text
