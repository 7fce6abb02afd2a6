"""Config (SPEC §6) and its validation through the command line (SPEC §7).

Every kind of bad config gives exit code 2 and exactly one line on stderr that names the
offending key (or file / option), with no traceback, via softclose.cli.main.
(The broad bad-input survey is tests/test_bad_input.py; this file is about the config.)
"""

from __future__ import annotations

import json
import math

import pytest

from conftest import np_closure_all
from softclose import cli
from softclose.config import default_config, from_dict, load_config, to_dict
from softclose.errors import ConfigError
from softclose.model.lid import LidModel
from softclose.problem import as_params

SPEC6 = {
    "geometry": {"lid_length": 0.5, "crank_oa": 0.045, "crank_bc": 0.08,
                 "pivot_b": [0.06, 0.015], "lid_c": [0.012, 0.013], "lid_e": [0.004, 0.014],
                 "lid_g": [0.25, 0.015], "lid_tip": [0.5, 0.0],
                 "spring_anchor": [-0.06, 0.02], "assembly": [18.0, 108.6655, 146.8855]},
    "mass": {"lid": 0.5, "crank_oa": 0.05, "crank_bc": 0.05, "gravity": 9.81},
    "design": {"spring_k": 0.0, "spring_rest_length": 0.05, "damper_c": 0.0,
               "rotary_damper_c": 0.0},
    "stroke": {"theta0_deg": 18.0, "theta_closed_deg": 0.0, "t_max": 5.0},
    # SPEC §6: "step = 0.001 # s; the default is chosen from the work-precision benchmark";
    # the benchmark chose 0.002 s (docs/performance.md), checked in test_default_step_meets_targets
    "simulate": {"integrator": "rk4"},
    "optimise": {"closing_time_max": 1.0, "closing_time_min": 0.0, "holding_moment_min": 0.1,
                 "weight_impact": 1.0, "weight_peak_tip": 0.1, "spring_k": [0.0, 10000.0],
                 "spring_rest_length": [0.02, 0.12], "damper_c": [0.0, 5000.0]},
}


def test_defaults_are_spec6():
    d = to_dict(default_config())
    for section, keys in SPEC6.items():
        for key, v in keys.items():
            if isinstance(v, str):
                assert d[section][key] == v, f"{section}.{key}"
            else:
                assert d[section][key] == pytest.approx(v, rel=1e-15), f"{section}.{key}"
    m = default_config().mass
    assert m.inertia_lid == pytest.approx(0.5 * 0.5 ** 2 / 12)
    assert m.inertia_oa == pytest.approx(0.05 * 0.045 ** 2 / 12)
    assert m.inertia_bc == pytest.approx(0.05 * 0.08 ** 2 / 12)


def test_file_then_overrides(tmp_path):
    f = tmp_path / "c.toml"
    f.write_text('[geometry]\nlid_length = 0.4\n[design]\nspring_k = 100\n'
                 '[simulate]\nintegrator = "gauss4"\n')
    cfg = load_config(f, ["design.spring_k=1e3", "geometry.pivot_b[1]=0.016",
                          "design.damper_c=25", "simulate.step=5e-4"])
    assert cfg.geometry.lid_length == 0.4
    assert cfg.geometry.lid_g == (0.2, 0.015) and cfg.geometry.lid_tip == (0.4, 0.0)  # derived
    assert cfg.mass.inertia_lid == pytest.approx(0.5 * 0.4 ** 2 / 12)
    assert cfg.design.spring_k == 1000.0 and cfg.design.damper_c == 25.0
    assert cfg.geometry.pivot_b == (0.06, 0.016)
    assert cfg.simulate.integrator == "gauss4" and cfg.simulate.step == 5e-4
    # replace() validates like a file
    with pytest.raises(ConfigError, match="design.spring_k"):
        cfg.replace(design={"spring_k": -1.0})


def _cannot_close_at_theta0(tmp_path):
    """crank_bc = 0.1 closes only above ~26 deg: assemble it at 70 deg, release at 18 deg."""
    geo = from_dict({"geometry": {"crank_bc": 0.1, "assembly": [70.0, 0.0, 0.0]}}).geometry
    roots = np_closure_all(math.radians(70.0), geo.crank_oa, geo.crank_bc, geo.pivot_b,
                           geo.lid_c)
    assert not np_closure_all(math.radians(18.0), geo.crank_oa, geo.crank_bc, geo.pivot_b,
                              geo.lid_c)
    phi, gamma = roots[0]
    return ["--set", "geometry.crank_bc=0.1",
            "--set", f"geometry.assembly=[70.0, {math.degrees(phi)!r}, {math.degrees(gamma)!r}]"]


def _file(tmp_path, text, name="bad.toml"):
    p = tmp_path / name
    p.write_text(text)
    return ["--config", str(p)]


BAD = [
    # (id, argv builder, substrings the one-line message must contain)
    ("unknown-section-set", lambda t: ["--set", "geometri.lid_length=0.4"], ["geometri"]),
    ("unknown-section-file", lambda t: _file(t, "[springs]\nk = 1\n"), ["springs"]),
    ("unknown-key-set", lambda t: ["--set", "design.spring_kk=10"], ["design.spring_kk"]),
    ("unknown-key-file", lambda t: _file(t, "[mass]\nlid_mass = 0.5\n"), ["mass.lid_mass"]),
    ("wrong-type-string", lambda t: ["--set", 'design.spring_k="stiff"'], ["design.spring_k"]),
    ("wrong-type-bool", lambda t: ["--set", "mass.lid=true"], ["mass.lid"]),
    ("wrong-type-vector", lambda t: ["--set", "geometry.pivot_b=0.06"], ["geometry.pivot_b"]),
    ("wrong-length-vector", lambda t: ["--set", "geometry.assembly=[18, 108]"],
     ["geometry.assembly"]),
    ("wrong-type-file", lambda t: _file(t, '[stroke]\nt_max = "long"\n'), ["stroke.t_max"]),
    ("wrong-choice", lambda t: ["--set", "simulate.integrator=rk5"], ["simulate.integrator"]),
    ("wrong-int", lambda t: ["--set", "optimise.nodes=2.5"], ["optimise.nodes"]),
    ("zero-length", lambda t: ["--set", "geometry.crank_oa=0"], ["geometry.crank_oa"]),
    ("negative-length", lambda t: ["--set", "geometry.lid_length=-0.5"], ["geometry.lid_length"]),
    ("zero-mass", lambda t: ["--set", "mass.lid=0"], ["mass.lid"]),
    ("negative-mass", lambda t: ["--set", "mass.crank_bc=-0.05"], ["mass.crank_bc"]),
    ("zero-inertia", lambda t: ["--set", "mass.inertia_lid=0.0"], ["mass.inertia_lid"]),
    ("nan", lambda t: ["--set", "design.damper_c=nan"], ["design.damper_c"]),
    ("negative-damper", lambda t: ["--set", "design.damper_c=-1"], ["design.damper_c"]),
    ("no-closure-at-assembly", lambda t: ["--set", "geometry.crank_bc=0.1"], ["crank_bc"]),
    ("no-closure-at-theta0", _cannot_close_at_theta0, ["geometry", "crank_bc", "theta"]),
    ("assembly-cranks-in-line", lambda t: ["--set", "geometry.assembly=[18, 10, 190]"],
     ["geometry.assembly"]),
    ("theta0-equal-closed", lambda t: ["--set", "stroke.theta0_deg=0"], ["stroke.theta0_deg"]),
    ("theta0-below-closed", lambda t: ["--set", "stroke.theta0_deg=5",
                                       "--set", "stroke.theta_closed_deg=10"],
     ["stroke.theta0_deg"]),
    ("set-no-equals", lambda t: ["--set", "design.spring_k"], ["design.spring_k"]),
    ("set-no-section", lambda t: ["--set", "spring_k=5"], ["spring_k"]),
    ("set-bad-value", lambda t: ["--set", "design.spring_k=[1,"], ["[1,"]),
    ("set-index-not-vector", lambda t: ["--set", "design.spring_k[0]=1"], ["design.spring_k"]),
    ("set-index-out-of-range", lambda t: ["--set", "geometry.pivot_b[2]=1"],
     ["geometry.pivot_b"]),
    ("bad-toml", lambda t: _file(t, "[design\nspring_k = \n", "broken.toml"), ["broken.toml"]),
    ("missing-file", lambda t: ["--config", str(t / "nowhere" / "missing.toml")],
     ["missing.toml"]),
]


@pytest.mark.parametrize("command", ["state", "simulate"])
@pytest.mark.parametrize("case", BAD, ids=[b[0] for b in BAD])
def test_bad_config_one_line_exit_2(capsys, tmp_path, case, command):
    _, build, needles = case
    argv = [command] + (["--theta-deg", "18"] if command == "state" else []) + build(tmp_path)
    rc = cli.main(argv)
    out, err = capsys.readouterr()
    assert rc == 2, (out, err)
    lines = err.strip("\n").split("\n")
    assert len(lines) == 1, err
    assert "Traceback" not in err and "Traceback" not in out
    assert out == ""
    for n in needles:
        assert n in lines[0], lines[0]


def test_bad_config_json_mode(capsys):
    rc = cli.main(["simulate", "--json", "--set", "mass.lid=-1"])
    out, err = capsys.readouterr()
    assert rc == 2
    assert len(err.strip().splitlines()) == 1 and "mass.lid" in err
    obj = json.loads(out)
    assert obj["exit_code"] == 2 and "mass.lid" in obj["error"]


def test_toggle_inside_the_stroke_is_rejected():
    """A chain whose loop closes only above ~26 deg (crank_bc = 0.1), assembled and released
    at 60 deg, closing at 10 deg: the toggle in between is reported, never crossed."""
    geo = dict(crank_bc=0.1)
    g = from_dict({"geometry": {**geo, "assembly": [60.0, 0.0, 0.0]}}).geometry
    closes = lambda d: bool(np_closure_all(math.radians(d), g.crank_oa, g.crank_bc,  # noqa: E731
                                           g.pivot_b, g.lid_c))
    assert closes(60.0) and not closes(10.0)
    phi, gamma = np_closure_all(math.radians(60.0), g.crank_oa, g.crank_bc, g.pivot_b,
                                g.lid_c)[0]
    cfg = from_dict({"geometry": {**geo, "assembly": [60.0, math.degrees(phi),
                                                      math.degrees(gamma)]},
                     "stroke": {"theta0_deg": 60.0, "theta_closed_deg": 10.0}})
    with pytest.raises(ConfigError) as exc:
        LidModel.from_config(cfg)
    msg = str(exc.value)
    assert "toggle" in msg and "\n" not in msg
    # the message names an angle of the stroke at which the loop does not close
    import re
    where = float(re.search(r"theta = (-?[0-9.]+) deg", msg).group(1))
    assert 10.0 <= where <= 60.0 and not closes(where)


def test_default_step_meets_targets():
    """The default step is the benchmark's choice: on a stiff corner of the design box it still
    meets the simulation accuracy targets against the adaptive reference."""
    import numpy as np
    from softclose import LidModel, Reference, Simulator
    cfg = default_config()
    assert cfg.simulate.step == 0.002
    model = LidModel.from_config(cfg)
    p = as_params([1e4, 0.02, 5000.0, 0.0])
    r, R = Simulator.from_config(cfg, model).run(p), Reference(model).simulate(p)
    assert abs(r.closing_time - R.closing_time) <= 1e-7
    assert abs(r.impact_theta_dot - R.impact_theta_dot) <= 1e-6
    assert abs(r.peak_tip_speed - R.peak_tip_speed) <= 1e-6 * R.peak_tip_speed
