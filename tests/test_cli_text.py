"""What a new user reads (issue 26): one error prefix, ``--version``, messages that name the
key and list the valid ones, no "-0", a description on every ``--help`` page, an installed
reference (``softclose docs``) instead of a path a pip install does not have, the optimiser's
two J's explained, the closing-time bounds as solved, the robust report's active limits, J's
unit."""

from __future__ import annotations

import argparse
import json

import pytest

from softclose import cli
from softclose.config import KEYS, default_config
from softclose.version import __version__


def _run(capsys, argv):
    rc = cli.main(argv)
    out, err = capsys.readouterr()
    return rc, out, err


def _error(capsys, argv) -> str:
    rc, _, err = _run(capsys, argv)
    lines = err.strip().splitlines()
    assert rc == 2 and len(lines) == 1, err
    assert lines[0].startswith("softclose: error: ")
    assert lines[0].count("softclose:") == 1, lines[0]           # the prefix once
    return lines[0]


def test_an_unknown_command_is_named_once_with_the_nearest(capsys):
    line = _error(capsys, ["optimse"])
    assert line.startswith("softclose: error: unknown command 'optimse' (did you mean "
                           "'optimise'?")
    assert "optimise (optimize)" in line                       # an alias is not a command
    assert _error(capsys, []).startswith("softclose: error: no command given")
    # an option of a command: the command named, the program not twice
    assert _error(capsys, ["yield", "--samples", "x"]).startswith(
        "softclose: error: yield: argument --samples")


def test_version(capsys):
    with pytest.raises(SystemExit) as exc:
        cli.main(["--version"])
    assert exc.value.code == 0
    assert capsys.readouterr()[0].strip() == f"softclose {__version__}"


def test_set_with_a_typo_lists_the_valid_keys_like_a_config_file(capsys, tmp_path):
    line = _error(capsys, ["simulate", "--set", "design.spring_kk=500"])
    assert "unknown config key design.spring_kk; did you mean design.spring_k?" in line
    design_keys = [k.name for k in KEYS if k.section == "design"]
    assert f"(known in [design]: {', '.join(design_keys)})" in line
    path = tmp_path / "c.toml"
    path.write_text("[design]\nspring_kk = 500\n")
    from_file = _error(capsys, ["simulate", "--config", str(path)])
    assert from_file.split("unknown config key ")[1] == line.split("unknown config key ")[1]
    assert "did you mean [design]?" in _error(capsys, ["simulate", "--set", "desgn.spring_k=1"])


def test_a_value_with_a_unit_names_the_key(capsys):
    line = _error(capsys, ["simulate", "--set", "mass.lid=0.5kg"])
    assert line == ("softclose: error: --set mass.lid=0.5kg: cannot read '0.5kg' as a value: "
                    "give the number alone, in kg (--set mass.lid=0.5)")
    # another unit than the key's: no number suggested (2 ms is not 2 s)
    line = _error(capsys, ["simulate", "--set", "simulate.step=2 ms"])
    assert line.endswith("give the number alone, in s, not in ms")


def test_a_quoted_number_is_called_a_string(capsys):
    line = _error(capsys, ["simulate", "--set", 'design.spring_k="500"'])
    assert line == ("softclose: error: design.spring_k: expected a number, got the string "
                    "'500' (without the quotes it is a number: 500)")
    assert "got the string '3'" in _error(capsys, ["simulate", "--set", 'optimise.nodes="3"'])


def test_state_prints_no_negative_zero(capsys):
    rc, text, _ = _run(capsys, ["state", "--theta-deg", "18"])
    assert rc == 0
    assert "phi'       = 0 rad/s   gamma' = 0 rad/s" in text
    assert "tip v      = [0, 0] m/s" in text and "-0 " not in text and "-0]" not in text
    rc, out, _ = _run(capsys, ["state", "--theta-deg", "-0", "--json"])
    assert "-0.0," not in out and json.loads(out)["phi_dot"] == 0.0


def _subparsers():
    parser = cli.build_parser()
    action = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)][0]
    return action.choices


def test_every_command_has_a_description_and_no_path_a_pip_install_lacks():
    for name, p in _subparsers().items():
        assert p.description and len(p.description) > 80, name
        page = p.format_help()
        for path in ("docs/", "README"):   # not in a pip install
            assert path not in page, (name, path)
    top = cli.build_parser().format_help()
    assert "softclose docs keys" in top and "--version" in top


def test_docs_prints_every_key_with_its_default(capsys):
    rc, text, _ = _run(capsys, ["docs", "keys"])
    assert rc == 0
    for k in KEYS:
        assert f"  {k.name} = " in text, k.full
    assert "  lid = 0.5 kg" in text and "  spring_k = 0 N/m" in text
    rc, text, _ = _run(capsys, ["docs"])
    for head in ("commands (softclose COMMAND --help for each):", "[tolerance]",
                 "the design problem (softclose optimise):", "files the commands write"):
        assert head in text
    assert "J = (impact theta' / 1 rad/s)² + (peak tip speed / 3.16 m/s)²" in text
    assert _error(capsys, ["docs", "nope"]).startswith("softclose: error: docs: argument TOPIC")


@pytest.fixture(scope="module")
def optimise_text():
    import io
    from contextlib import redirect_stdout
    buf = io.StringIO()
    with redirect_stdout(buf):
        assert cli.main(["optimise"]) == 0
    return buf.getvalue()


def test_optimise_says_why_its_two_js_differ(optimise_text):
    text = optimise_text
    assert "objective J = 0.02289949 (the optimiser's: its own discretisation" in text
    assert ("each J as its solve ended, before the best answer was refined and its "
            "closing-time bound corrected (notes)") in text
    assert "J = 0.022899356" in text          # the starts' J, before the correction


def test_optimise_problem_line_gives_the_closing_time_bounds_as_solved(optimise_text):
    line = [ln for ln in optimise_text.splitlines() if ln.startswith("  problem:")][0]
    assert ("J = 1 s²·impact_theta_dot² + 0.1 s²/m²·peak_tip_speed² (dimensionless)") in line
    assert ("0 s <= closing_time <= 1 s (solved as [0.001, 0.999995672] s: closing_time_min "
            "raised to the NLP's floor of 1 ms; closing_time_max corrected for the NLP's "
            "discretisation error (note))") in line
    note = [ln for ln in optimise_text.splitlines() if "solved with [" in ln][0]
    assert "[0.001, 0.999995672] s" in note        # the note and the problem line agree


def test_pareto_figure_states_j_s_unit():
    import softclose
    fr = softclose.front(default_config(), [0.8, 1.0])
    fig = fr.plot()
    label = fig.axes[0].get_ylabel()
    assert label == "J = 1 s²·θ'² + 0.1 s²/m²·v_peak² [dimensionless]"


@pytest.mark.slow
def test_the_robust_report_names_what_limits_it(capsys):
    """The idealised spring's robust design sits at its spring and damper bounds and on
    closing_time_max in its stiff, damped, light corner: the text and the JSON say so, with
    dJ (checked against the robust optimum re-solved with each limit relaxed). The default
    (a compression spring) sits on its free length's lower bound: the stroke's longest
    length, where the spring would start to pull."""
    import softclose
    rc, out, _ = _run(capsys, ["optimise", "--robust", "--json"])
    act = {a["name"]: a for a in json.loads(out)["active"]}
    assert rc == 0 and json.loads(out)["kind"] == "compression"
    assert act["spring_rest_length"]["bound"] == "lower"
    assert act["spring_rest_length"]["value"] == pytest.approx(0.0584337386, abs=1e-9)
    linear = ["--set", 'optimise.spring_kinds=["linear"]']
    rc, out, _ = _run(capsys, ["optimise", "--robust", "--json", *linear])
    j = json.loads(out)
    assert rc == 0
    act = {a["name"]: a for a in j["active"]}
    assert set(act) == {"spring_k", "damper_c", "closing_time_max"}
    assert act["spring_k"]["bound"] == act["damper_c"]["bound"] == "upper"
    assert act["spring_k"]["value"] == 10000 and act["damper_c"]["value"] == 5000
    assert act["closing_time_max"]["scenarios"] == ["spring_k +10 %, damper_c +20 %, "
                                                    "mass.lid -5 %"]
    cfg = default_config().set("optimise.spring_kinds", ["linear"])
    J0 = j["objective"]
    for key, relaxed, step in (("spring_k", [0.0, 10100.0], 100.0),
                               ("damper_c", [0.0, 5050.0], 50.0),
                               ("closing_time_max", 1.01, 0.01)):
        r = softclose.optimise(cfg.set(f"optimise.{key}", relaxed), robust=True)
        assert r.success
        assert r.objective - J0 == pytest.approx(act[key]["dJ"] * step, rel=0.05), key
    rc, text, _ = _run(capsys, ["optimise", "--robust", *linear])
    assert "  what limits the design (dJ: change of the worst-case J per unit relaxation" in text
    assert "    spring_k at its upper bound 10000 N/m: dJ = -2.4" in text
    assert ("closing_time_max at its upper limit 1 s: dJ = -0.129 per s of relaxation (1 % more "
            "room changes J by -1.3 %); holds in 1 of 9 scenarios: spring_k +10 %, damper_c "
            "+20 %, mass.lid -5 %") in text
