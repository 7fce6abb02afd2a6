"""The optimum with a coil spring one can order (SPEC §14): ``optimise`` with
``spring.material`` given designs the spring that realises its rate and free length, solves
again at the wound spring's own rate, and the reference verifies that answer."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

import softclose
from softclose import cli, default_config

#: the default optimum without a spring made to order (docs/numbers.md)
J_IDEAL = 0.0228995


@pytest.fixture(scope="module")
def ordered():
    return softclose.optimise(default_config().update({"spring.material": "EN10270-1-SH"}))


def test_the_optimum_comes_with_its_spring_every_check_met_and_verified(ordered):
    res = ordered
    assert res.success and res.verification.ok and res.kind == "compression"
    coil = res.part.coil
    assert coil["ok"] and all(c["ok"] for c in coil["checks"])
    # the design's rate is the wound spring's own, R = G d^4 / (8 D^3 n), EN 13906-1 by hand
    d, D, n = coil["wire_d"], coil["coil_d"], coil["active_coils"]
    assert res.design["spring_k"] == pytest.approx(81500e6 * d ** 4 / (8 * D ** 3 * n),
                                                   rel=1e-12)
    assert n * 4 == round(n * 4)                       # a quarter coil
    assert coil["free_length"] == pytest.approx(res.design["spring_rest_length"], rel=1e-12)
    # making it buildable costs J, a little
    assert J_IDEAL <= res.objective <= 1.02 * J_IDEAL
    assert any(n.startswith("made to order:") for n in res.notes)
    assert "made to order: wire" in res.part.text()
    # docs/parts.md quotes the part and the price in J
    page = (Path(__file__).resolve().parents[1] / "docs" / "parts.md").read_text()
    for line in res.part.text().splitlines()[:2]:
        assert f"  to buy: {line}\n" in page or f"  {line}\n" in page, line
    assert f"0.0228995 to {res.objective:.6g}" in page


def test_no_spring_in_the_space_is_no_design_with_the_checks_that_fail(capsys):
    code = cli.main(["optimise", "--set", 'spring.material="EN10270-1-SH"', "--set",
                     "spring.max_outer_d=0.012"])
    err = capsys.readouterr().err
    assert code == 3
    assert "no coil spring made to order realises the optimum" in err and "buckling" in err


def test_without_a_material_nothing_is_wound():
    assert not softclose.optimise.__module__.startswith("x")     # (the API is the CLI's)
    from softclose.optimiser.made_to_order import made_to_order
    cfg = default_config()
    assert not made_to_order(cfg)
    assert made_to_order(cfg.update({"spring.material": "EN10270-1-DH"}))
    assert not made_to_order(cfg.update({"spring.material": "EN10270-1-DH",
                                         "spring.wire_d": 0.002, "spring.coil_d": 0.02,
                                         "spring.active_coils": 5.0}))
    assert math.isfinite(J_IDEAL)
