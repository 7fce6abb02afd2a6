"""The design hand-off (issue 26): a config written back as TOML reads back to the same config;
``softclose optimise --out D`` (and ``--robust``, ``pareto``, ``sweep --optimise``) writes the
design as a config file every command takes with ``--config``; ``yield`` and ``sensitivity``
say which design they analysed, with its nominal lid and J, and say plainly when it has no
spring and no damper."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from softclose import cli
from softclose.config import default_config, load_config, to_dict, to_toml
from softclose.problem import DESIGN_KEYS, METRIC_KEYS, objective
from softclose.robust import tolerance_analysis

#: the default optimum (tests/data/golden.npz has it to every digit; these are its 7-digit
#: quotes, which README and docs/model.md give)
OPTIMUM = {"spring_k": 1914.709, "spring_rest_length": 0.07925707, "damper_c": 2087.754}


def _run(capsys, argv):
    rc = cli.main(argv)
    out, err = capsys.readouterr()
    return rc, out, err


# -- the TOML form of a config ----------------------------------------------------------------
CONFIGS = {
    "defaults": {},
    "a design with every digit": {"design.spring_k": 1914.709221517871,
                                  "design.spring_rest_length": 0.07925707423701318,
                                  "design.damper_c": 2087.754103066556},
    "derived keys given, words, integers": {
        "geometry.lid_tip": [0.49, 0.001], "mass.inertia_lid": 0.0123,
        "simulate.integrator": "radau5", "optimise.nodes": 12, "optimise.hessian":
        "limited-memory", "design.torsion_pivot": "B", "design.torsion_k": 0.5},
    "tolerances: absolute, off, normal": {
        "tolerance.design.spring_k": 0, "tolerance.mass.crank_oa": {"absolute": 0.001},
        "tolerance.geometry.pivot_b[1]": {"absolute": 2e-4}, "tolerance.distribution": "normal",
        "tolerance.samples": 123, "tolerance.required_yield": 0.95},
    "small and large numbers": {"simulate.step": 1e-7, "stroke.t_max": 0.5,
                                "design.spring_k": 1e7, "optimise.holding_moment_min": -0.25,
                                "geometry.pivot_b[0]": 0.1 + 0.2},
}


@pytest.mark.parametrize("values", list(CONFIGS.values()), ids=list(CONFIGS))
def test_a_config_written_as_toml_reads_back_to_the_same_config(tmp_path, values):
    cfg = default_config().update(values)
    path = tmp_path / "c.toml"
    path.write_text(to_toml(cfg, "a header\nof two lines"))
    back = load_config(path)
    assert back == cfg
    assert to_dict(back) == to_dict(cfg)           # every value to the last bit
    text = path.read_text()
    assert text.startswith("# a header\n# of two lines\n")
    assert "[tolerance]" in text and "[design]" in text


def test_a_derived_key_not_given_stays_derived(tmp_path):
    """The inertia of the lid is written as a comment: --set mass.lid on the file moves it
    as it moves the default's (written as a value it would stay at 0.5 kg's)."""
    path = tmp_path / "c.toml"
    path.write_text(to_toml(default_config()))
    assert "# inertia_lid = " in path.read_text()
    heavier = load_config(path, ["mass.lid=0.8"])
    assert heavier.mass.inertia_lid == pytest.approx(0.8 * 0.5 ** 2 / 12, rel=1e-15)


# -- optimise --out D, then yield / sensitivity --config D/design.toml -------------------------
@pytest.fixture(scope="module")
def optimum_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("optimum")
    rc = cli.main(["optimise", "--json", "--out", str(out)])
    assert rc == 0
    return out


def test_optimise_out_writes_the_optimum_as_a_config_file(optimum_dir, capsys):
    payload = json.loads((optimum_dir / "optimise.json").read_text())
    path = optimum_dir / "design.toml"
    cfg = load_config(path)
    # the optimum's spring kind with it (a compression spring on the defaults)
    assert payload["kind"] == "compression"
    assert cfg == default_config().with_design(spring_kind=payload["kind"], **payload["design"])
    for k in DESIGN_KEYS:                          # every digit of the optimum
        assert getattr(cfg.design, k) == payload["design"][k]
        assert getattr(cfg.design, k) == pytest.approx(OPTIMUM[k], rel=1e-6)
    head = path.read_text().splitlines()[:4]
    assert "the optimum of `softclose optimise`" in head[0]
    assert "J = 0.02289983" in head[2] and "holding moment 0.1 N m" in head[2]


def test_yield_of_the_design_file_is_the_optimum_s(optimum_dir, capsys):
    """The issue's "done when": optimise --out D, then yield --config D/design.toml analyses
    the optimum (43 % on the defaults: the README's figure) and says so."""
    path = optimum_dir / "design.toml"
    rc, out, _ = _run(capsys, ["yield", "--config", str(path), "--json"])
    j = json.loads(out)
    assert rc == 0
    assert j["design"] == {k: getattr(load_config(path).design, k) for k in DESIGN_KEYS}
    assert j["yield"] == pytest.approx(0.4319, abs=1e-4)
    assert j["yield_ci"] == pytest.approx([0.4222, 0.4416], abs=1e-4)
    assert j["warnings"] == [] and j["nominal"]["bare"] is False
    n = j["nominal"]                               # the optimum's own lid: on its limits
    assert n["closing_time"] == pytest.approx(1.0, abs=1e-5)
    assert n["holding_moment"] == pytest.approx(0.1, abs=1e-6)
    assert n["objective"] == pytest.approx(0.0228998, rel=1e-4)
    assert n["objective"] == objective(default_config().optimise, n["impact_theta_dot"],
                                       n["peak_tip_speed"])
    rc, text, _ = _run(capsys, ["yield", "--config", str(path)])
    assert f"design (from {path}): spring_k = 1914.709 N/m" in text
    assert "yield 43.19 %" in text and "no spring" not in text
    assert "J = 0.0228998; meets every constraint" in text


def test_sensitivity_of_the_design_file_states_the_design(optimum_dir, capsys):
    path = optimum_dir / "design.toml"
    rc, out, _ = _run(capsys, ["sensitivity", "--config", str(path), "--samples", "64",
                               "--json"])
    j = json.loads(out)
    assert rc == 0 and j["warnings"] == [] and j["fixed"] == []
    assert j["keys"] == ["design.spring_k", "design.damper_c", "mass.lid"]
    assert j["nominal"]["objective"] == pytest.approx(0.0228998, rel=1e-4)


def test_yield_on_the_defaults_says_the_design_has_no_spring_and_no_damper(capsys):
    rc, text, _ = _run(capsys, ["yield", "--samples", "200"])
    assert rc == 0
    assert "design (the defaults): spring_k = 0 N/m" in text
    assert "NOTE: this design has no spring and no damper" in text
    assert "softclose optimise --out D, then softclose yield --config D/design.toml" in text
    assert "design.spring_k ±10 % (of 0: no spread)" in text
    # J of the slamming lid: 1 s² x (4.1558 rad/s)² + 0.1 s²/m² x (2.1500 m/s)²
    assert "J = 17.7326" in text
    rc, out, _ = _run(capsys, ["sensitivity", "--samples", "16", "--json"])
    j = json.loads(out)
    assert j["warnings"] and "no spring and no damper" in j["warnings"][0]
    assert j["fixed"] == ["design.spring_k", "design.damper_c"]
    # any spring or damper is a design: no note
    rc, out, _ = _run(capsys, ["yield", "--samples", "50", "--json", "--set",
                               "design.rotary_damper_c=0.01"])
    assert json.loads(out)["warnings"] == []


def test_yield_percentiles_of_J_and_the_tip_speeds_are_the_samples():
    cfg = default_config().with_design(**OPTIMUM)
    r = tolerance_analysis(cfg, samples=500, seed=3, reference=0)
    df = r.to_frame()
    closed = df["closed"].to_numpy(bool)
    for key in ("objective", "peak_tip_speed", "impact_tip_speed"):
        v = np.sort(df[key].to_numpy(float)[closed])
        for q in (1, 50, 99):                      # inverted CDF: a sample value
            k = max(int(math.ceil(q / 100 * len(v))) - 1, 0)
            assert r.percentiles[key][f"p{q}"] == v[k], (key, q)


def test_every_line_of_yield_is_printed_once(capsys):
    """The three adaptive-reference checks of a one-key box read the same at 3 digits: each
    line of the report is a distinct point (it printed one line three times)."""
    rc, text, _ = _run(capsys, ["yield"])
    lines = text.splitlines()
    assert len(lines) == len(set(lines)), text
    checks = [ln for ln in lines if "adaptive reference at the" in ln]
    assert len(checks) == 3
    assert "at the sample nearest the boundary" in checks[0]
    assert "at the 2nd sample nearest the boundary" in checks[1]


# -- the other optimisers ------------------------------------------------------------------
@pytest.mark.slow
def test_robust_out_writes_the_robust_design(tmp_path, capsys):
    rc, out, _ = _run(capsys, ["optimise", "--robust", "--json", "--out", str(tmp_path)])
    j = json.loads(out)
    assert rc == 0
    cfg = load_config(tmp_path / "design.toml")
    assert {k: getattr(cfg.design, k) for k in DESIGN_KEYS} == j["design"]
    assert str(tmp_path / "design.toml") in j["files"]
    y = tolerance_analysis(cfg, reference=0)       # the same draw as the robust report's
    assert y.yield_ == j["yield"] and y.yield_ >= 0.99


def test_pareto_out_writes_each_point_s_design(tmp_path, capsys):
    rc, out, _ = _run(capsys, ["pareto", "--closing-times", "0.6:1:2", "--json",
                               "--out", str(tmp_path)])
    j = json.loads(out)
    assert rc == 0
    import pandas as pd
    table = pd.read_csv(tmp_path / "pareto.csv")
    for i, pt in enumerate(j["points"]):
        path = tmp_path / "designs" / f"design_{i:02d}.toml"
        assert pt["design_file"] == str(path) and table["design_file"][i] == \
            f"designs/design_{i:02d}.toml"
        cfg = load_config(path)
        assert cfg.optimise.closing_time_max == pt["closing_time_max"]
        assert {k: getattr(cfg.design, k) for k in DESIGN_KEYS} == pt["design"]


def test_optimal_grid_out_writes_each_point_s_design(tmp_path, capsys):
    rc, out, _ = _run(capsys, ["sweep", "--optimise", "--grid", "mass.lid=[0.45, 0.55]",
                               "--json", "--out", str(tmp_path)])
    j = json.loads(out)
    assert rc == 0
    for i, row in enumerate(j["rows"]):
        cfg = load_config(tmp_path / "designs" / f"design_{i}.toml")
        assert cfg.mass.lid == row["mass.lid"]
        assert {k: getattr(cfg.design, k) for k in DESIGN_KEYS} == \
            {k: row[k] for k in DESIGN_KEYS}
        assert cfg.mass.inertia_lid == pytest.approx(row["mass.lid"] * 0.25 / 12, rel=1e-15)


def test_design_config_of_the_results(default_optimum):
    """The library's side of the hand-off: every result gives its design as a config."""
    r = default_optimum
    c = r.design_config()
    assert {k: getattr(c.design, k) for k in DESIGN_KEYS} == r.design
    assert tolerance_analysis(c, samples=200, reference=0).design == r.design
    assert set(METRIC_KEYS) <= set(tolerance_analysis(c, samples=20).nominal)
