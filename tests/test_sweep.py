"""Sweeps: grid parsing, agreement with single strokes, the table's columns, feasibility,
figures, Ctrl-C (see also test_sweep_space.py and test_sweep_resume.py)."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from softclose.cli import main
from softclose.config import default_config
from softclose.errors import ConfigError
from softclose.problem import METRIC_KEYS
from softclose.simulation.simulator import Simulator
from softclose.sweeps import columns, recompute, sweep
from softclose.sweeps import store
from softclose.sweeps.space import parse_grid

ROOT = Path(__file__).resolve().parents[1]
GRID = ["design.spring_k=0:2000:9", "design.damper_c=0:5000:9",
        "design.spring_rest_length=0.02:0.12:5"]
AXES = {"design.spring_k": np.linspace(0, 2000, 9), "design.damper_c": np.linspace(0, 5000, 9),
        "design.spring_rest_length": np.linspace(0.02, 0.12, 5)}


@pytest.fixture(scope="module")
def design_sweep(tmp_path_factory):
    """The grid through the command line (CSV and maps) and through the API."""
    out = tmp_path_factory.mktemp("sweep")
    argv = ["sweep", "--out", str(out), "--json"]
    for g in GRID:
        argv += ["--grid", g]
    assert main(argv) == 0
    return sweep(default_config(), AXES), out, store.read_csv(out / "sweep.csv")


@pytest.mark.parametrize("spec, words", [
    ("design.spring_k", "KEY=START:STOP:COUNT"),
    ("design.spring_k=0:10", "KEY=START:STOP:COUNT"),
    ("design.spring=0:10:3", "not a numeric config key"),
    ("simulate.integrator=0:1:2", "not a numeric config key"),
    ("design.spring_k=a:10:3", "START must be a number"),
    ("design.spring_k=0:10:0", "positive integer"),
    ("design.spring_k=0:10:2.5", "positive integer"),
    ("design.spring_k=0:10:1", "COUNT = 1"),
    ("design.spring_k=5:5:3", "START = STOP"),
    ("design.spring_k=-5:10:3", "design.spring_k"),
    ("mass.lid=0:1:3", "mass.lid"),
    ("geometry.spring_anchor[2]=0:1:3", "not a numeric config key"),
    ("design.damper_c=0:4000:5:log", "log spacing needs START > 0"),
    ("design.damper_c=-1:4000:5:log", "cannot reach or cross zero"),
    ("design.damper_c=1:4000:5:lin", "may only be 'log'"),
    ("design.damper_c=[1, 2, 2]", "repeated"),
    ("design.damper_c=[]", "non-empty array"),
    ("design.damper_c=[1, true]", "array of numbers"),
    ("design.damper_c=[1, 2", "TOML array"),
    ("design.damper_c=[1, -2]", "design.damper_c"),
])
def test_bad_grid_strings(spec, words):
    with pytest.raises(ConfigError, match=words.replace("[", r"\[")):
        parse_grid([spec], default_config())


def test_grid_forms():
    g = parse_grid(["design.damper_c=10:1000:3:log", "design.spring_k=[300, 100.5, 2e3]",
                    "mass.lid=0.4:0.6:3"], default_config())
    np.testing.assert_allclose(g.values[0], [10, 100, 1000], rtol=1e-14)
    assert g.values[0][0] == 10 and g.values[0][-1] == 1000
    assert list(g.values[1]) == [300, 100.5, 2000]     # explicit values, in the given order
    np.testing.assert_allclose(g.values[2], [0.4, 0.5, 0.6], rtol=1e-15)
    assert g.log == (True, False, False) and g.n == 27
    # ids run in C order over the keys as given (the last key fastest)
    X = g.points(np.arange(27))
    assert np.array_equal(X[1], [10, 300, 0.5]) and np.array_equal(X[3], [10, 100.5, 0.4])
    assert np.array_equal(X[26], [1000, 2000, 0.6])


def test_duplicate_key_and_cli_exit_code(tmp_path, capsys):
    with pytest.raises(ConfigError, match="swept twice"):
        parse_grid(["design.damper_c=0:1:2", "design.damper_c=0:2:2"])
    code = main(["sweep", "--grid", "design.bogus=0:1:2", "--out", str(tmp_path / "o"),
                 "--json"])
    assert code == 2
    err = capsys.readouterr()
    assert "design.bogus" in json.loads(err.out)["error"]
    assert "Traceback" not in err.err
    assert not (tmp_path / "o").exists()          # refused before the folder was made


def test_columns_objective_and_reference_row(design_sweep):
    res, out, c = design_sweep
    header = (out / "sweep.csv").read_text().splitlines()[0].replace('"', "").split(",")
    keys = [a.split("=")[0] for a in GRID]
    assert header == ["id"] + keys + list(METRIC_KEYS) + [
        "objective", "feasible", "status", "reason"] == columns(keys)
    assert np.array_equal(c["id"], np.arange(9 * 9 * 5))
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


def test_api_equals_cli_table(design_sweep):
    """The API result (axes in another order: other ids) holds the same numbers."""
    res, _, c = design_sweep
    f = res.to_frame()
    keys = ["design.spring_k", "design.damper_c", "design.spring_rest_length"]
    a = f.sort_values(keys).reset_index(drop=True)
    order = np.lexsort([c[k] for k in reversed(keys)])
    for k in keys + list(METRIC_KEYS) + ["objective", "feasible", "status", "reason"]:
        x, y = np.asarray(a[k]), np.asarray(c[k])[order]
        if x.dtype.kind == "f":
            assert np.array_equal(x, y, equal_nan=True), k
        else:
            assert list(x) == list(y), k


def test_feasibility_reasons(design_sweep):
    res, _, c = design_sweep
    o = default_config().optimise
    feas = c["feasible"]
    closed = c["closed"]
    slow = closed & (c["closing_time"] > o.closing_time_max)
    loose = c["holding_moment"] < o.holding_moment_min
    assert np.array_equal(feas, closed & ~slow & ~loose & ~(c["reason"] == "rebound"))
    assert np.all(c["reason"][~closed] != "")
    assert np.all(np.char.startswith(c["reason"][~closed].astype(str), "not closed"))
    assert np.all(c["reason"][slow & ~loose] == "too slow") and slow.any()
    assert loose.any() and (~closed).any() and feas.any()
    # a stroke that stays open says why, as the kernel classifies it (its well or barrier)
    sim = Simulator.from_config(default_config())
    open_ = np.flatnonzero(c["status"] == "not closed")
    P = np.column_stack([c["design.spring_k"][open_], c["design.spring_rest_length"][open_],
                         c["design.damper_c"][open_], np.zeros(len(open_))])
    why = sim.run_batch(P)["reason"]
    assert np.all(why != "") and any(w.startswith("held open at theta = ") for w in why)
    assert list(c["reason"][open_]) == [f"not closed ({w})" for w in why]
    assert res.reasons["not closed"] == (~closed).sum()
    # the best point is feasible and has the least objective among feasible rows
    b = res.best
    assert b["feasible"]
    assert b["objective"] == np.nanmin(np.where(feas, c["objective"], np.nan))
    s = res.to_json()
    assert s["feasible"] == int(feas.sum()) == res.feasible
    assert sum(s["infeasible_reasons"].values()) == int((~feas).sum())
    json.dumps(s, allow_nan=False)


def test_rows_agree_with_single_strokes(design_sweep):
    """Random rows against Simulator.run (the `simulate` path), to its accuracy."""
    res, out, c = design_sweep
    rng = np.random.default_rng(7)
    sim = Simulator.from_config(default_config())
    for i in rng.choice(len(c["closed"]), 12, replace=False):
        k, cd, l0 = (c[key][i] for key in ("design.spring_k", "design.damper_c",
                                            "design.spring_rest_length"))
        r = sim.run(np.array([k, l0, cd, 0.0]))
        assert r.closed == c["closed"][i]
        for key in METRIC_KEYS[1:]:
            v = getattr(r, key)
            if v is None:
                assert math.isnan(c[key][i])
                continue
            assert abs(v - c[key][i]) <= 1e-12 * max(1.0, abs(v)), (key, v, c[key][i])


def test_rows_recomputed_by_id(design_sweep):
    res, _, _ = design_sweep
    ids = np.array([0, 17, 404, 211])
    again = recompute(default_config(), res.space, ids)
    for j, i in enumerate(ids):
        row = res.row(int(i))
        for k in columns(res.keys):
            a, b = row[k], again[k][j]
            if isinstance(a, float) or a is None:
                assert (a is None and np.isnan(b)) or a == b, k
            else:
                assert a == b, k


def test_rows_agree_with_simulate_cli(design_sweep):
    res, _, c = design_sweep
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


def test_result_is_immutable(design_sweep):
    res, _, _ = design_sweep
    with pytest.raises(ValueError):
        res.columns["objective"][0] = 0.0
    with pytest.raises(TypeError):
        res.columns["objective"] = None
    with pytest.raises(AttributeError):
        res.points = 3
    assert res.success and res.message == "" and res.computed == res.points == 405


def test_a_lost_cluster_is_a_failed_result_that_says_why(design_sweep):
    import dataclasses
    res, _, _ = design_sweep
    lost = dataclasses.replace(res, lost="the Dask scheduler tcp://h:8786 was lost")
    assert not lost.success and lost.message.startswith("the Dask scheduler tcp://h:8786")
    assert "405 of 405 designs" in lost.message and lost.to_json()["lost"] == lost.lost
    assert res.success and res.lost is None


def test_result_pickles_and_stays_read_only(design_sweep):
    """A result can be sent to another process (a Dask worker, a notebook's)."""
    import pickle
    res, _, _ = design_sweep
    back = pickle.loads(pickle.dumps(res))
    for k, v in res.columns.items():
        assert np.array_equal(back.columns[k], v, equal_nan=v.dtype.kind == "f"), k
    assert dict(back.best) == dict(res.best) and dict(back.reasons) == dict(res.reasons)
    assert back.space.keys == res.space.keys and back.points == res.points
    with pytest.raises(ValueError):
        back.columns["objective"][0] = 0.0


def test_chunking_does_not_change_rows():
    cfg = default_config()
    axes = {"design.spring_k": np.linspace(0, 3000, 7), "design.damper_c": [0.0, 800, 2500]}
    a, b = sweep(cfg, axes), sweep(cfg, axes, chunk=4, threads=1)
    for k in columns(a.keys):
        x, y = a.columns[k], b.columns[k]
        assert np.array_equal(x, y, equal_nan=x.dtype.kind == "f"), k
    assert a.best == b.best


def test_figures_written_with_units_and_round_ticks(design_sweep):
    res, out, _ = design_sweep
    names = sorted(p.name for p in out.glob("*.png"))
    assert names == ["map_design_damper_c__design_spring_rest_length.png",
                     "map_design_spring_k__design_damper_c.png",
                     "map_design_spring_k__design_spring_rest_length.png"]
    for p in out.glob("*.png"):
        assert p.stat().st_size > 10_000
    figs = res.plot()
    fig = figs["map_design_spring_k__design_damper_c"]
    b = res.best
    title = fig._suptitle.get_text()
    assert f"design.spring_rest_length = {b['design.spring_rest_length']:.4g} m" in title
    bars = [a for a in fig.axes if getattr(a, "_colorbar", None) is not None]
    axes = [a for a in fig.axes if a not in bars]
    assert axes[2].get_xlabel() == "spring stiffness k [N/m]"
    assert axes[0].get_ylabel() == "damper c [N s/m]"
    assert len(bars) == 4
    for bar in bars:
        assert "[" in bar.get_ylabel()
        ticks = [float(t.get_text()) for t in bar.get_yticklabels()]
        assert 2 <= len(ticks) <= 8
        for t in ticks:   # round numbers: 1, 2, 2.5 or 5 times a power of ten (or 0)
            m = abs(t) / 10 ** math.floor(math.log10(abs(t))) if t else 1.0
            assert any(abs(m - r) < 1e-9 for r in (1, 1.5, 2, 2.5, 3, 4, 5, 6, 7, 7.5, 8, 9)), t
    # contour lines carry labels
    assert any(len(getattr(a, "texts", [])) for a in axes)


def test_geometry_and_mass_keys_and_invalid_geometry():
    cfg = default_config()
    res = sweep(cfg, {"geometry.spring_anchor[0]": np.linspace(-0.08, -0.04, 3),
                      "mass.lid": [0.4, 0.6], "design.spring_k": [0.0, 400, 800]})
    assert res.success and res.columns["closed"].any()
    for i in (0, 7, 17):
        row = res.row(i)
        x, m, k = (row[key] for key in res.keys)
        c2 = cfg.replace(geometry={"spring_anchor": [x, cfg.geometry.spring_anchor[1]]},
                         mass={"lid": m})
        r = Simulator.from_config(c2).run(np.array([k, c2.design.spring_rest_length, 0, 0]),
                              estimate_error=False)
        assert abs(r.closing_time - row["closing_time"]) < 1e-13
        assert abs(r.peak_tip_speed - row["peak_tip_speed"]) < 1e-13
    # a crank too long for the loop to close: invalid rows with the reason, no crash
    res = sweep(cfg, {"geometry.crank_oa": np.linspace(0.045, 0.6, 3),
                      "design.damper_c": [0.0, 100.0]})
    st = res.columns["status"]
    assert (st == "invalid").sum() >= 2 and (st == "closed").sum() == 2
    assert all("geometry" in r for r in res.columns["reason"][st == "invalid"])
    assert not res.columns["feasible"][st == "invalid"].any()
    assert res.reasons["invalid"] == (st == "invalid").sum()


def test_ctrl_c_keeps_finished_chunks(tmp_path, monkeypatch):
    """Ctrl-C while the third chunk (ids 100..149) runs: the first two are kept. (Chunks run
    in threads, several at once: the third is told by its first spring_k, not by the order
    of the calls.)"""
    orig = Simulator.run_batch
    third = np.linspace(0, 1000, 20)[10]

    def flaky(self, P, threads=None, **kw):
        if P[0, 0] == third:
            raise KeyboardInterrupt
        return orig(self, P, threads, **kw)
    monkeypatch.setattr(Simulator, "run_batch", flaky)
    axes = {"design.spring_k": np.linspace(0, 1000, 20),
            "design.damper_c": np.linspace(0, 3000, 10)}
    res = sweep(default_config(), axes, chunk=50)
    assert res.interrupted and not res.success and res.computed == 100
    assert np.array_equal(res.columns["id"], np.arange(100))
    assert "interrupted" in res.message
    code = main(["sweep", "--grid", "design.spring_k=0:1000:20", "--grid",
                 "design.damper_c=0:3000:10", "--chunk", "50", "--out", str(tmp_path), "--json"])
    assert code == 130
    c = store.read_csv(tmp_path / "sweep.csv")
    assert np.array_equal(c["id"], np.arange(100))
    assert not np.isnan(c["peak_tip_speed"]).any()
    assert not list(tmp_path.glob("*.png"))     # no maps of a partial sweep
    m = json.loads((tmp_path / "manifest.json").read_text())
    assert m["complete"] is False


def test_progress_line_only_on_a_terminal(tmp_path, capsys):
    code = main(["sweep", "--grid", "design.damper_c=0:1000:5", "--out", str(tmp_path)])
    cap = capsys.readouterr()
    assert code == 0 and "sweep [" not in cap.err  # stderr is not a terminal under pytest
    assert (tmp_path / "profile_design_damper_c.png").exists()
    res = sweep(default_config(), {"design.damper_c": [0.0, 500.0]}, progress=True)
    assert res.success and "sweep [" not in capsys.readouterr().err


def test_binned_summary_is_the_best_over_the_other_keys(design_sweep):
    """What the maps of a streamed sweep are drawn from, against the full table."""
    res, _, _ = design_sweep
    shape = res.space.shape
    feas = res.columns["feasible"].reshape(shape)
    J = np.where(feas, res.columns["objective"].reshape(shape), np.inf)
    b = res.bins
    for g, other in (((0, 1), 2), ((0, 2), 1), ((1, 2), 0)):
        best = J.min(axis=other)
        assert np.array_equal(b.grid(g, "objective"),
                              np.where(np.isfinite(best), best, np.nan), equal_nan=True)
        assert np.array_equal(b.grid(g, "feasible"), feas.sum(axis=other))
        assert b.grid(g, "count").sum() == res.points
        # the kept metrics are those of the cell's best design
        ids = b.grid(g, "id")
        for cell in zip(*np.nonzero(ids >= 0)):
            row = res.row(int(ids[cell]))
            assert row["objective"] == b.grid(g, "objective")[cell]
            assert row["peak_tip_speed"] == b.grid(g, "peak_tip_speed")[cell]


def test_the_command_draws_the_maps_itself_and_starts_no_process(tmp_path, monkeypatch):
    """The maps are drawn by the command's own process, after the sweep: nothing is forked
    or started (nothing is left running when it ends)."""
    import os
    import subprocess

    import softclose.present.figures.sweep as fs

    def no(*a, **k):
        raise AssertionError("a process was started")
    monkeypatch.setattr(os, "fork", no)
    monkeypatch.setattr(subprocess, "Popen", no)
    parent = os.getpid()
    real = fs.save_maps
    drawn_here = []

    def save(figs, out, *rest):
        assert os.getpid() == parent
        drawn_here.extend(figs)
        return real(figs, out, *rest)
    monkeypatch.setattr(fs, "save_maps", save)
    argv = ["sweep", "--out", str(tmp_path), "--json"]
    for g in GRID:
        argv += ["--grid", g]
    assert main(argv) == 0
    pngs = sorted(p.name for p in tmp_path.glob("*.png"))
    assert len(pngs) == 3 and sorted(f"{n}.png" for n in drawn_here) == pngs
    assert all(p.stat().st_size > 10_000 for p in tmp_path.glob("*.png"))


# -- a swept lid mass runs in the kernel's lid-mass column, not a model per value ------------
def _per_mass_reference(cfg, masses, P):
    """The metric columns, closed and feasible flags of the rows ``P`` at lid masses
    ``masses`` the old way: one config and Simulator (model, table) per distinct mass."""
    from softclose.problem import infeasibility
    ref = {k: np.full(len(P), np.nan) for k in METRIC_KEYS[1:]}
    ref["closed"] = np.zeros(len(P), bool)
    ref["feasible"] = np.zeros(len(P), bool)
    for m in np.unique(masses):
        rows = np.nonzero(masses == m)[0]
        sim = Simulator.from_config(cfg.update({"mass.lid": float(m)}))
        r = sim.run_batch(P[rows])
        r["opening_force"] = sim.opening_forces(P[rows])
        ok = (r["status"] == 0) | (r["status"] == 1)
        for k in METRIC_KEYS[1:]:
            ref[k][rows] = np.where(ok | (k in ("holding_moment", "opening_force")), r[k],
                                    np.nan)
        ref["closed"][rows] = r["closed"]
        ref["feasible"][rows] = infeasibility(cfg.optimise, r["closed"], r["closing_time"],
                                              r["holding_moment"], r["theta_dot_max"]) == ""
    return ref


def test_lid_mass_sweep_agrees_with_a_model_per_mass(monkeypatch):
    from softclose.sweeps import chunks
    cfg = default_config().update({"design.damper_c": 2087.75,
                                   "design.spring_rest_length": 0.079257})
    masses = [0.3, 0.43, cfg.mass.lid, 0.61, 0.9]     # 0.5: the table's own mass
    ks = np.linspace(0.0, 4000.0, 9)
    built = []
    real_init = Simulator.__init__

    def counting_init(self, c, *a, **kw):
        built.append(c.lid.mass.lid)
        real_init(self, c, *a, **kw)
    monkeypatch.setattr(Simulator, "__init__", counting_init)
    chunks._sims.clear()
    res = sweep(cfg, {"mass.lid": masses, "design.spring_k": ks}, chunk=16)
    monkeypatch.undo()
    assert built == [cfg.mass.lid]       # one model and table for all the masses
    col = res.columns
    m = col["mass.lid"]
    P = np.tile([0.0, cfg.design.spring_rest_length, cfg.design.damper_c, 0.0], (len(m), 1))
    P[:, 0] = col["design.spring_k"]
    ref = _per_mass_reference(cfg, m, P)
    own = m == cfg.mass.lid
    for k in METRIC_KEYS[1:]:
        a, b = ref[k], col[k]
        assert np.array_equal(np.isnan(a), np.isnan(b)), k
        assert np.array_equal(a[own], b[own], equal_nan=True), k   # bit for bit
        f = ~np.isnan(a)
        # measured: at most 1.5e-14 relative over this grid (2.1e-13 over 3,000 random designs)
        assert np.all(np.abs(a[f] - b[f]) <= 1e-12 * np.abs(a[f])), k
    assert np.array_equal(ref["closed"], col["closed"])
    assert np.array_equal(ref["feasible"], col["feasible"])
    # the grid is not trivial: closed and open strokes, feasible and infeasible, every mass
    assert col["closed"].any() and not col["closed"].all()
    assert col["feasible"].any() and not col["feasible"].all()
    assert set(m) == set(masses)


def test_lid_mass_refused_by_the_config_is_invalid_for_that_row_only():
    from softclose.sweeps.chunks import evaluate_chunk
    cfg = default_config().update({"design.damper_c": 2087.75,
                                   "design.spring_rest_length": 0.079257})
    X = np.array([[0.5, 1900.0], [2000.0, 1900.0], [0.0, 1900.0], [0.7, 1900.0]])
    out = evaluate_chunk(cfg.raw, ["mass.lid", "design.spring_k"], np.arange(4), X)
    assert list(out["status"]) == ["closed", "invalid", "invalid", "closed"]
    for i, m in ((1, 2000.0), (2, 0.0)):   # the config's own one-line message for the value
        with pytest.raises(ConfigError) as exc:
            cfg.update({"mass.lid": m})
        assert out["reason"][i] == str(exc.value) and "mass.lid" in out["reason"][i]
        assert math.isnan(out["closing_time"][i]) and not out["feasible"][i]
    one = evaluate_chunk(cfg.raw, ["mass.lid", "design.spring_k"], [3], X[3:])
    assert one["closing_time"][0] == out["closing_time"][3]
    # a refusal inside the range: an absolute [tolerance] spread of the lid mass refuses the
    # masses it would take to zero, exactly as the config does
    tol = cfg.replace(tolerance={"mass.lid": {"absolute": 0.35}})
    X = np.array([[0.3, 1900.0], [0.35, 1900.0], [0.36, 1900.0], [0.9, 1900.0]])
    out = evaluate_chunk(tol.raw, ["mass.lid", "design.spring_k"], np.arange(4), X)
    assert list(out["status"] == "invalid") == [True, True, False, False]
    for i in (0, 1):
        with pytest.raises(ConfigError) as exc:
            tol.update({"mass.lid": X[i, 0]})
        assert out["reason"][i] == str(exc.value) and "tolerance.mass.lid" in str(exc.value)
    plain = evaluate_chunk(cfg.raw, ["mass.lid", "design.spring_k"], np.arange(4), X)
    for k in ("closing_time", "peak_tip_speed", "holding_moment", "status", "reason"):
        a, b = out[k][2:], plain[k][2:]
        assert np.array_equal(a, b, equal_nan=a.dtype.kind == "f"), k  # no stroke changes


def test_lid_mass_sweep_diagnoses_a_failed_stroke_at_its_own_mass():
    from softclose.sweeps.chunks import evaluate_chunk
    cfg = default_config()
    X = np.array([[0.05, 1e5, 1e5], [0.2, 1e5, 1e5]])   # the table is built at 0.5 kg
    out = evaluate_chunk(cfg.raw, ["mass.lid", "design.spring_k", "design.damper_c"],
                         np.arange(2), X)
    for i, (m, k, c) in enumerate(X):
        sim = Simulator.from_config(cfg.update({"mass.lid": m}))
        p = np.array([k, cfg.design.spring_rest_length, c, 0.0])
        r = sim.run_batch(p[None, :])
        assert out["status"][i] == "unstable" and r["status"][0] == 2
        assert out["reason"][i] == sim.diagnose(r["status"][0], p)
    assert out["reason"][0] != out["reason"][1]       # the stable step depends on the mass


def test_categories_of_rows():
    """Each row's category: feasible (-1), the first reason that applies, "not closed" for
    a stroke's own diagnosis, "invalid" by the status whatever the reason says, and "not
    integrated" for the method's failures."""
    from softclose.problem import CATEGORIES, categorise
    rows = [("closed", "", -1), ("closed", "too slow", CATEGORIES.index("too slow")),
            ("closed", "rebound", CATEGORIES.index("rebound")),
            ("not closed", "not closed (held open at theta = 12.3 deg)",
             CATEGORIES.index("not closed")),
            ("not closed", "not closed", CATEGORIES.index("not closed")),
            ("invalid", "the compression spring (it only pushes) would be longer than its "
             "free length 58.43 mm over the whole stroke, by up to 1.00 mm (at theta = 2.0 "
             "deg)", CATEGORIES.index("invalid")),
            ("invalid", "too slow", CATEGORIES.index("invalid")),
            ("invalid", "not closed (x)", CATEGORIES.index("invalid")),
            ("failed", "the step diverged: use a smaller simulate.step",
             CATEGORIES.index("not integrated"))]
    status = np.array([r[0] for r in rows] * 3, dtype=object)
    reason = np.array([r[1] for r in rows] * 3, dtype=object)
    assert categorise(status, reason).tolist() == [r[2] for r in rows] * 3
    assert categorise(np.array([], dtype=object), np.array([], dtype=object)).tolist() == []


def test_local_map_evaluates_chunks_at_once_and_yields_them_in_order(monkeypatch):
    """As many chunks at once as kernel threads, one thread each (one chunk's Python runs
    beside the others' kernels); fewer chunks than threads share them; the first chunk is
    yielded first even when it finishes last; a chunk's error reaches the caller."""
    import threading
    import time

    from softclose.sweeps import run as runner
    running, most, shares, lock = [0], [0], {}, threading.Lock()

    def fake(cfg_dict, keys, ids, X, threads=None):
        with lock:
            running[0] += 1
            most[0] = max(most[0], running[0])
            shares[int(ids[0]) // 10] = threads
        time.sleep(0.2 if ids[0] == 0 else 0.05)      # the first chunk is the slowest
        with lock:
            running[0] -= 1
        if ids[0] == 40:
            raise ValueError("chunk 4 failed")
        return {"id": ids}
    monkeypatch.setattr(runner, "evaluate_chunk", fake)
    tasks = [(c, np.arange(10 * c, 10 * c + 10), None) for c in range(4)]
    got = [c for c, cols in runner.local_map({}, [], iter(tasks), threads=2)]
    assert got == [0, 1, 2, 3] and most[0] == 2 and set(shares.values()) == {1}
    shares.clear()
    got = [c for c, cols in runner.local_map({}, [], iter(tasks[:1]), threads=4)]
    assert got == [0] and shares == {0: 4}               # one chunk: every thread
    shares.clear()
    list(runner.local_map({}, [], iter(tasks[:2]), threads=4))
    assert shares == {0: 2, 1: 2}
    bad = runner.local_map({}, [], iter(tasks + [(4, np.arange(40, 50), None)]), threads=2)
    with pytest.raises(ValueError, match="chunk 4 failed"):
        list(bad)


def test_parquet_parts_encode_only_the_status_as_a_dictionary(tmp_path):
    """A part file keeps every value (NaN where a metric has none), and only the status
    column is dictionary-encoded (a dictionary on numbers that hardly repeat cost time)."""
    pq = pytest.importorskip("pyarrow.parquet")
    res = sweep(default_config(), {"design.spring_k": [0.0, 900.0, 5000.0],
                                   "design.damper_c": [0.0, 2000.0]})
    sink = store.ParquetSink(tmp_path, res.keys)
    path = sink.write(0, dict(res.columns))
    meta = pq.ParquetFile(path).metadata.row_group(0)
    dict_cols = {meta.column(j).path_in_schema for j in range(meta.num_columns)
                 if "RLE_DICTIONARY" in meta.column(j).encodings
                 or "PLAIN_DICTIONARY" in meta.column(j).encodings}
    assert dict_cols == {"status"}
    back = pq.read_table(path).to_pydict()
    for k, v in res.columns.items():
        got = np.asarray(back[k], dtype=v.dtype)
        if v.dtype.kind == "f":
            assert np.array_equal(got, v, equal_nan=True), k
        else:
            assert got.tolist() == v.tolist(), k
