"""Further design variables (``[optimise.free]``, ``--free KEY=LO:HI``).

Checked against what must hold whatever the NLP does: a preload of a compression spring is
a shift of its free length (T = -F0 + k (l - l0) = k (l - (l0 + F0/k))), so freeing it cannot
lower J and every optimum keeps l0 + F0/k; a variable whose bounds meet is the fixed value;
more freedom never costs; and every answer is verified by the reference.
"""

from __future__ import annotations

import json

import pytest

from softclose import cli
from softclose.config import ConfigError, default_config, load_config, to_dict
from softclose.optimiser import optimise

#: the default problem's optimum (SPEC §8): J and the compression spring's free length
J_DEFAULT, L0_DEFAULT = 0.0228995, 0.0792571


def test_free_table_is_read_and_checked(tmp_path):
    f = tmp_path / "c.toml"
    f.write_text('[optimise.free]\n"design.spring_preload" = [0, 200]\n'
                 'design.rotary_damper_c = [0, 2]\n')
    cfg = load_config(f)
    assert cfg.optimise.free == (("design.rotary_damper_c", 0.0, 2.0),
                                 ("design.spring_preload", 0.0, 200.0))
    assert load_config(f, ["optimise.free.design.torsion_k=[0, 1]"]).optimise.free[2] == \
        ("design.torsion_k", 0.0, 1.0)
    assert to_dict(cfg)["optimise"]["free"] == {"design.rotary_damper_c": [0.0, 2.0],
                                                "design.spring_preload": [0.0, 200.0]}
    assert default_config().optimise.free is None
    for bad, words in (({"geometry.pivot_b[0]": [0, 1]}, "placement"),
                       ({"design.spring_k": [0, 1]}, "optimise.spring_k"),
                       ({"design.spring_preload": [5, 1]}, "exceeds"),
                       ({"design.spring_preload": [-1, 1]}, "non-negative"),
                       ({"design.spring_kind": [0, 1]}, "cannot be a design variable"),
                       ({"design.torsion_k": [0, 1e300]}, "admissible range"),
                       ([0, 1], "table")):
        with pytest.raises(ConfigError, match=words):
            default_config().set("optimise.free", bad)


@pytest.mark.parametrize("arg,words", [("design.spring_preload=5:1", "exceeds"),
                                       ("design.spring_preload=a:1", "not a number"),
                                       ("design.spring_preload", "KEY=LO:HI"),
                                       ("mass.lid=0:1", "cannot be a design variable")])
def test_bad_free_option_is_a_one_line_error(arg, words, capsys):
    assert cli.main(["optimise", "--free", arg]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and words in err


def test_free_preload_trades_with_the_free_length():
    cfg = default_config().update({"optimise.free": {"design.spring_preload": [0, 200]}})
    r = optimise(cfg)
    assert r.success and r.kind == "compression"
    d = r.design
    assert set(d) == {"spring_k", "spring_rest_length", "damper_c", "spring_preload"}
    assert r.objective == pytest.approx(J_DEFAULT, rel=2e-6)
    # the same spring law: free length + preload / rate is the idealised optimum's
    assert d["spring_rest_length"] + d["spring_preload"] / d["spring_k"] == \
        pytest.approx(L0_DEFAULT, abs=2e-6)
    assert r.part.preload == d["spring_preload"] and r.row()["spring_preload"] == \
        d["spring_preload"]


@pytest.mark.slow
def test_collapsed_bounds_are_the_fixed_value_and_freedom_never_costs():
    base = default_config().update({"design.rotary_damper_pivot": "A",
                                    "optimise.damper_c": [0.0, 300.0],
                                    "optimise.spring_kinds": ["compression"]})
    fixed = optimise(base.set("design.rotary_damper_c", 0.2))
    pinned = optimise(base.update({"design.rotary_damper_c": 0.7, "optimise.free":
                                   {"design.rotary_damper_c": [0.2, 0.2]}}))
    free = optimise(base.set("optimise.free", {"design.rotary_damper_c": [0.0, 1.0]}))
    assert fixed.success and pinned.success and free.success
    assert pinned.design["rotary_damper_c"] == 0.2
    assert pinned.objective == pytest.approx(fixed.objective, rel=1e-7)
    for k in ("spring_k", "spring_rest_length", "damper_c"):
        assert pinned.design[k] == pytest.approx(fixed.design[k], rel=1e-5)
    assert free.objective <= fixed.objective * (1 + 1e-9)
    assert 0.0 <= free.design["rotary_damper_c"] <= 1.0


def test_cli_reports_the_free_variables(capsys):
    assert cli.main(["optimise", "--json", "--free", "design.torsion_k=0:2", "--set",
                     "optimise.spring_k=[0, 500]"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert 0 <= out["design"]["torsion_k"] <= 2 and out["success"]


@pytest.mark.slow
def test_the_robust_design_chooses_a_free_value_too(capsys):
    """A free design value beside k, l0, c is a variable of the scenario NLP: the robust
    design with the preload free in [0, 10] N reports it, and is no worse than with the
    preload fixed at the config's 0 (which the box contains)."""
    assert cli.main(["optimise", "--robust", "--json", "--free",
                     "design.spring_preload=0:10"]) == 0
    free = json.loads(capsys.readouterr().out)
    assert cli.main(["optimise", "--robust", "--json"]) == 0
    fixed = json.loads(capsys.readouterr().out)
    assert free["success"] and 0.0 <= free["design"]["spring_preload"] <= 10.0
    assert free["objective"] <= fixed["objective"] * (1 + 1e-6)
