"""`softclose sweep`: grid parsing, agreement with single strokes, CSV, feasibility, Ctrl-C."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from softclose import sweep as sw
from softclose.cli import main
from softclose.config import default_config
from softclose.errors import ConfigError
from softclose.simulate import Simulator

ROOT = Path(__file__).resolve().parents[1]
GRID = ["design.spring_k=0:2000:9", "design.damper_c=0:5000:9",
        "design.spring_rest_length=0.02:0.12:5"]


@pytest.fixture(scope="module")
def design_sweep(tmp_path_factory):
    out = tmp_path_factory.mktemp("sweep")
    res, files = sw.sweep(default_config(), GRID, out)
    return res, files, out


@pytest.mark.parametrize("spec, words", [
    ("design.spring_k", "KEY=START:STOP:COUNT"),
    ("design.spring_k=0:10", "KEY=START:STOP:COUNT"),
    ("design.spring=0:10:3", "not a numeric config key"),
    ("simulate.integrator=0:1:2", "not a numeric config key"),
    ("design.spring_k=a:10:3", "must be numbers"),
    ("design.spring_k=0:10:0", "positive integer"),
    ("design.spring_k=0:10:2.5", "positive integer"),
    ("design.spring_k=0:10:1", "COUNT = 1"),
    ("design.spring_k=-5:10:3", "design.spring_k"),
    ("mass.lid=0:1:3", "mass.lid"),
    ("geometry.spring_anchor[2]=0:1:3", "not a numeric config key"),
])
def test_bad_grid_strings(spec, words):
    with pytest.raises(ConfigError, match=words.replace("[", r"\[")):
        sw.parse_grid([spec], default_config())


def test_duplicate_key_and_cli_exit_code(tmp_path, capsys):
    with pytest.raises(ConfigError, match="swept twice"):
        sw.parse_grid(["design.damper_c=0:1:2", "design.damper_c=0:2:2"])
    code = main(["sweep", "--grid", "design.bogus=0:1:2", "--out", str(tmp_path), "--json"])
    assert code == 2
    err = capsys.readouterr()
    assert "design.bogus" in json.loads(err.out)["error"]
    assert "Traceback" not in err.err


def test_csv_columns_and_objective(design_sweep):
    res, files, out = design_sweep
    csvp = out / "sweep.csv"
    header = csvp.read_text().splitlines()[0].split(",")
    assert header == [a.split("=")[0] for a in GRID] + list(sw.METRICS) + [
        "objective", "feasible", "status", "reason"]
    c = sw.read_csv(csvp)
    assert len(c["closed"]) == 9 * 9 * 5
    o = default_config().optimise
    J = o.weight_impact * c["impact_theta_dot"] ** 2 + o.weight_peak_tip * c["peak_tip_speed"] ** 2
    closed = c["closed"]
    np.testing.assert_allclose(c["objective"][closed], J[closed], rtol=1e-14)
    assert np.all(np.isnan(c["objective"][~closed]))
    # gravity-only row reproduces SPEC §8
    i = np.nonzero((c["design.spring_k"] == 0) & (c["design.damper_c"] == 0))[0][0]
    assert abs(c["closing_time"][i] - 0.1491478) < 1e-7
    assert abs(c["impact_theta_dot"][i] + 4.155764) < 1e-6
    assert abs(c["impact_tip_speed"][i] - 2.150045) < 1e-6


def test_feasibility_reasons(design_sweep):
    res, _, out = design_sweep
    c = sw.read_csv(out / "sweep.csv")
    o = default_config().optimise
    feas = c["feasible"]
    # the reasons are exactly the SPEC §5 constraints
    closed = c["closed"]
    slow = closed & (c["closing_time"] > o.closing_time_max)
    loose = c["holding_moment"] < o.holding_moment_min
    assert np.array_equal(feas, closed & ~slow & ~loose & ~(c["reason"] == "rebound"))
    assert np.all(c["reason"][~closed] != "")
    assert np.all(np.char.startswith(c["reason"][~closed].astype(str), "not closed"))
    assert np.all(c["reason"][slow & ~loose] == "too slow") and slow.any()
    assert loose.any() and (~closed).any() and feas.any()
    # the best point is feasible and has the least objective among feasible rows
    b = res.best
    assert res.cols["feasible"][b]
    assert res.cols["objective"][b] == np.nanmin(np.where(feas, c["objective"], np.nan))
    s = sw.summary(res)
    assert s["feasible"] == int(feas.sum())
    assert sum(s["infeasible_reasons"].values()) == int((~feas).sum())


def test_rows_agree_with_single_strokes(design_sweep):
    """Random rows against Simulator.run (the `simulate` path), to its accuracy."""
    res, _, out = design_sweep
    c = sw.read_csv(out / "sweep.csv")
    rng = np.random.default_rng(7)
    cfg = default_config()
    sim = Simulator(cfg)
    for i in rng.choice(len(c["closed"]), 12, replace=False):
        k, cd, l0 = (c[key][i] for key in ("design.spring_k", "design.damper_c",
                                            "design.spring_rest_length"))
        r = sim.run(np.array([k, l0, cd, 0.0]))
        assert r.closed == c["closed"][i]
        for key in sw.METRICS[1:]:
            v = getattr(r, key)
            if v is None:
                assert math.isnan(c[key][i])
                continue
            tol = 1e-12 + (r.accuracy or {}).get(key, 0.0) or 1e-12
            assert abs(v - c[key][i]) <= max(tol, 1e-12 * abs(v)), (key, v, c[key][i])


def test_rows_agree_with_simulate_cli(design_sweep):
    res, _, out = design_sweep
    c = sw.read_csv(out / "sweep.csv")
    rng = np.random.default_rng(3)
    idx = [i for i in rng.permutation(len(c["closed"])) if c["closed"][i]][:2]
    for i in idx:
        sets = [f"design.spring_k={float(c['design.spring_k'][i])!r}",
                f"design.damper_c={float(c['design.damper_c'][i])!r}",
                f"design.spring_rest_length={float(c['design.spring_rest_length'][i])!r}"]
        cmd = [sys.executable, "-m", "softclose", "simulate", "--json"]
        for s in sets:
            cmd += ["--set", s]
        p = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT)
        assert p.returncode == 0, p.stderr
        m = json.loads(p.stdout)
        for key in ("closing_time", "impact_theta_dot", "impact_tip_speed", "peak_tip_speed",
                    "holding_moment"):
            assert abs(m[key] - c[key][i]) <= 1e-12 * max(1.0, abs(m[key])), key


def test_figures_written_with_masks(design_sweep):
    res, files, out = design_sweep
    names = sorted(f.name for f in files if f.suffix == ".png")
    assert len(names) == 3  # one per pair of swept keys
    for f in files:
        assert f.stat().st_size > 10_000


def test_geometry_and_mass_keys_and_invalid_geometry(tmp_path):
    cfg = default_config()
    grid = ["geometry.spring_anchor[0]=-0.08:-0.04:3", "mass.lid=0.4:0.6:2",
            "design.spring_k=0:800:3"]
    res, _ = sw.sweep(cfg, grid, tmp_path, figures=False)
    assert res.done.all() and res.cols["closed"].any()
    for i in (0, 7, 17):
        x, m, k = res.X[i]
        c2 = cfg.replace(geometry={"spring_anchor": [x, cfg.geometry.spring_anchor[1]]},
                         mass={"lid": m})
        r = Simulator(c2).run(np.array([k, c2.design.spring_rest_length, 0, 0]),
                              estimate_error=False)
        assert abs(r.closing_time - res.cols["closing_time"][i]) < 1e-13
        assert abs(r.peak_tip_speed - res.cols["peak_tip_speed"][i]) < 1e-13
    # a crank too long for the loop to close: invalid rows with the reason, no crash
    res, files = sw.sweep(cfg, ["geometry.crank_oa=0.045:0.6:3", "design.damper_c=0:100:2"],
                          tmp_path / "bad")
    st = res.cols["status"]
    assert (st == "invalid").sum() >= 2 and (st == "closed").sum() == 2
    assert all("geometry" in r for r in res.cols["reason"][st == "invalid"])
    c = sw.read_csv(tmp_path / "bad" / "sweep.csv")
    assert len(c["status"]) == 6 and not c["feasible"][c["status"] == "invalid"].any()


def test_ctrl_c_keeps_computed_rows(tmp_path, monkeypatch):
    calls = {"n": 0}
    orig = Simulator.run_batch

    def flaky(self, P, threads=None):
        calls["n"] += 1
        if calls["n"] == 3:
            raise KeyboardInterrupt
        return orig(self, P, threads)
    monkeypatch.setattr(sw, "CHUNK", 50)
    monkeypatch.setattr(Simulator, "run_batch", flaky)

    class A:
        grid = ["design.spring_k=0:1000:20", "design.damper_c=0:3000:10"]
        out = str(tmp_path)
        json = True
    o = sw.command(default_config(), A())
    assert o.exit_code == 130 and o.payload["interrupted"]
    c = sw.read_csv(tmp_path / "sweep.csv")
    assert len(c["closed"]) == 100 == o.payload["computed"]
    assert not np.isnan(c["peak_tip_speed"]).any()


def test_progress_bar_only_on_tty(tmp_path, capsys):
    code = main(["sweep", "--grid", "design.damper_c=0:1000:5", "--out", str(tmp_path)])
    cap = capsys.readouterr()
    assert code == 0 and "sweep [" not in cap.err  # stderr is not a terminal under pytest
    assert (tmp_path / "profile_design_damper_c.png").exists()
    sw._Progress(10, True).update(5, force=True)
    assert "designs/s" in capsys.readouterr().err
