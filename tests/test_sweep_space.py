"""Samples (Sobol, Latin hypercube, random): their defining properties, reproducibility,
independence of the chunk size; and every bad input of grids, samples and the command line
refused with one line (exit 2) before anything is written."""

from __future__ import annotations

import json

import numpy as np
import pytest

from softclose.cli import main
from softclose.config import default_config
from softclose.errors import ConfigError
from softclose.simulation.simulator import Simulator
from softclose.sweeps import columns, sample, sweep
from softclose.sweeps.space import Range, Sample, make_sample, parse_range


def _space(sampler, n, d=3, seed=5):
    return Sample(tuple(Range(f"design.k{j}", 0.0, 1.0) for j in range(d)), n, sampler, seed)


@pytest.mark.parametrize("sampler", ["sobol", "lhs", "random"])
def test_points_do_not_depend_on_how_they_are_cut(sampler):
    s = _space(sampler, 300)
    whole = s.unit(0, 300)
    parts = np.vstack([s.unit(a, min(a + 37, 300)) for a in range(0, 300, 37)])
    assert np.array_equal(whole, parts)
    assert np.array_equal(s.points([5, 6, 250]), whole[[5, 6, 250]])
    assert np.all((whole >= 0) & (whole < 1))
    # the seed decides the draw
    assert np.array_equal(_space(sampler, 300).unit(0, 300), whole)
    assert not np.array_equal(_space(sampler, 300, seed=6).unit(0, 300), whole)


def test_sobol_points_are_balanced():
    """Scrambled Sobol: with n = 2^m, every interval [i/n, (i+1)/n) of each coordinate holds
    exactly one point, and every 2-D box of side 1/4 x 1/4 of 64 points holds 4."""
    u = _space("sobol", 64).unit(0, 64)
    for j in range(3):
        assert np.array_equal(np.sort(np.floor(u[:, j] * 64)), np.arange(64))
    cells = np.floor(u[:, 0] * 4) * 4 + np.floor(u[:, 1] * 4)
    assert np.array_equal(np.bincount(cells.astype(int), minlength=16), np.full(16, 4))


def test_latin_hypercube_strata():
    """Each of the n strata of each coordinate holds exactly one point (any n)."""
    u = _space("lhs", 97).unit(0, 97)
    for j in range(3):
        assert np.array_equal(np.sort(np.floor(u[:, j] * 97)), np.arange(97))


def test_ranges_linear_and_log():
    s = make_sample({"design.spring_k": (500, 9500), "design.damper_c": (10, 1000, "log")},
                    1024, "sobol", 1, default_config())
    X = s.points(np.arange(1024))
    assert X[:, 0].min() >= 500 and X[:, 0].max() < 9500
    assert X[:, 1].min() >= 10 and X[:, 1].max() < 1000
    # log-uniform: each decade holds half the points (balanced Sobol: to one point)
    assert abs(int((X[:, 1] < 100).sum()) - 512) <= 1
    # linear: each half of the range holds half the points
    assert abs(int((X[:, 0] < 5000).sum()) - 512) <= 1


def test_sample_rows_are_strokes():
    cfg = default_config()
    r = sample(cfg, {"design.spring_k": (500, 4000), "design.damper_c": (100, 4000, "log"),
                     "design.spring_rest_length": (0.06, 0.09)}, 64, sampler="lhs", seed=3)
    f = r.to_frame()
    assert list(f.columns) == columns(r.keys) and np.array_equal(f["id"], np.arange(64))
    assert r.kind == "sample" and r.success and r.computed == 64
    sim = Simulator.from_config(cfg)
    for i in (0, 31, 63):
        k, c, l0 = (f[key][i] for key in r.keys)
        s = sim.run(np.array([k, l0, c, 0.0]), estimate_error=False)
        assert s.closed == f["closed"][i]
        if s.closed:
            assert s.closing_time == f["closing_time"][i]
            assert s.peak_tip_speed == f["peak_tip_speed"][i]
    again = sample(cfg, {"design.spring_k": (500, 4000), "design.damper_c": (100, 4000, "log"),
                         "design.spring_rest_length": (0.06, 0.09)}, 64, sampler="lhs", seed=3,
                   chunk=10)
    assert again.to_frame().equals(f)
    assert r.plot()          # binned maps of a sample


@pytest.mark.parametrize("args, words", [
    (({"design.damper_c": (100, 10)}, 16), "must be below HI"),
    (({"design.damper_c": (0, 10, "log")}, 16), "log range needs LO > 0"),
    (({"design.damper_c": (-1, 10, "log")}, 16), "cannot reach or cross zero"),
    (({"design.damper_c": (1, 10)}, 0), "N must be positive"),
    (({"design.damper_c": (1, 10)}, -4), "N must be positive"),
    (({"design.damper_c": (1, 10)}, 2.5), "whole number"),
    (({"design.damper_c": (1, 10, "ln")}, 8), "(lo, hi, 'log')"),
    (({"design.bogus": (1, 10)}, 8), "design.bogus"),
    (({"mass.lid": (-1, 10)}, 8), "mass.lid"),
    (({}, 8), "at least one range"),
])
def test_bad_sample_api(args, words):
    with pytest.raises(ConfigError, match=words.replace("(", r"\(").replace(")", r"\)")):
        sample(default_config(), *args)


def test_bad_sampler_and_axes_api():
    with pytest.raises(ConfigError, match="unknown sampler 'halton'"):
        sample(default_config(), {"design.damper_c": (1, 10)}, 8, sampler="halton")
    with pytest.raises(ConfigError, match="values must be finite"):
        sweep(default_config(), {"design.damper_c": [1.0, np.nan]})
    with pytest.raises(ConfigError, match="no values"):
        sweep(default_config(), {"design.damper_c": []})
    with pytest.raises(ConfigError, match="at least one config key"):
        sweep(default_config(), {})
    with pytest.raises(ConfigError, match="1-D"):
        sweep(default_config(), {"design.damper_c": [[1, 2], [3, 4]]})
    with pytest.raises(ConfigError, match=r"--range 'design.damper_c=5:1'"):
        parse_range("design.damper_c=5:1")


def _refused(capsys, argv, words, folder=None):
    code = main(argv)
    out, err = capsys.readouterr()
    lines = err.strip().splitlines()
    assert code == 2, (code, err)
    assert len(lines) == 1 and lines[0].startswith("softclose: error: "), err
    assert "Traceback" not in out + err
    assert words in lines[0], lines[0]
    if folder is not None:
        assert not folder.exists()           # refused before the folder was made


@pytest.mark.parametrize("argv, words", [
    (["--sample", "0", "--range", "design.damper_c=1:10"], "N must be positive"),
    (["--sample", "-5", "--range", "design.damper_c=1:10"], "N must be positive"),
    (["--sample", "8", "--range", "design.damper_c=10:1"], "must be below HI"),
    (["--sample", "8", "--range", "design.damper_c=0:10:log"], "log range needs LO > 0"),
    (["--sample", "8", "--range", "design.damper_c=-3:10:log"], "cross zero"),
    (["--sample", "8", "--range", "design.damper_c=1:10:cubic"], "may only be 'log'"),
    (["--sample", "8", "--range", "design.damper_c=1"], "KEY=LO:HI"),
    (["--sample", "8"], "--range"),
    (["--sample", "8", "--range", "design.damper_c=1:10", "--sampler", "halton"], "halton"),
    (["--sample", "8", "--range", "design.damper_c=1:10", "--format", "xlsx"], "xlsx"),
    (["--sample", "8", "--range", "design.damper_c=1:10", "--range", "design.damper_c=1:5"],
     "given twice"),
    (["--grid", "design.damper_c=1:10:3", "--sample", "8"], "--grid and --sample"),
    (["--grid", "design.damper_c=1:10:3", "--range", "design.damper_c=1:10"], "--range"),
    (["--grid", "design.damper_c=1:10:3", "--seed", "3"], "--sampler/--seed"),
    (["--grid", "design.damper_c=1:10:3", "--chunk", "0"], "--chunk"),
    (["--grid", "design.damper_c=1:10:3:log", "--grid", "design.spring_k=0:1:0"], "COUNT"),
])
def test_bad_command_lines(capsys, tmp_path, argv, words):
    out = tmp_path / "o"
    _refused(capsys, ["sweep", *argv, "--out", str(out)], words, folder=out)


def test_out_is_checked_before_any_work(capsys, tmp_path):
    f = tmp_path / "file"
    f.write_text("x")
    _refused(capsys, ["sweep", "--grid", "design.damper_c=1:10:3", "--out", str(f)],
             "is not a folder")
    assert f.read_text() == "x"
    _refused(capsys, ["sweep", "--grid", "design.damper_c=1:10:3"], "--out")


def test_json_errors_are_strict_json(capsys, tmp_path):
    assert main(["sweep", "--sample", "0", "--range", "design.damper_c=1:10", "--json",
                 "--out", str(tmp_path / "o")]) == 2
    out, _ = capsys.readouterr()
    assert json.loads(out)["exit_code"] == 2


def test_step_budget_is_checked_before_any_work(capsys, tmp_path):
    """Designs x steps a stroke is bounded (config.BATCH_STEP_BUDGET), at the smallest swept
    step: a sweep that would run for days is refused at once."""
    cfg = default_config().update({"simulate.step": 1e-6})          # 5e6 steps a stroke
    axes = {"design.spring_k": np.linspace(0, 2000, 200),
            "design.damper_c": np.linspace(0, 1, 100)}
    with pytest.raises(ConfigError, match="above the budget"):
        sweep(cfg, axes)                                              # 2e4 x 5e6 = 1e11
    with pytest.raises(ConfigError, match="above the budget"):
        sample(default_config(), {"simulate.step": (1e-6, 1e-3, "log")}, 20_000)
    out = tmp_path / "o"
    _refused(capsys, ["sweep", "--grid", "design.spring_k=0:2000:100", "--grid",
                      "simulate.step=[1e-6, 0.002]", "--grid", "design.damper_c=0:1:100",
                      "--out", str(out)], "above the budget", folder=out)
