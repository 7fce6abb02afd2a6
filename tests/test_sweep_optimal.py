"""An optimum per grid point (``softclose sweep --optimise``): every point verified, the
default lid's point is the default answer, the spring carries a heavier lid, and the Dask
run gives the same table as the local one."""

from __future__ import annotations

import json

import numpy as np
import pytest

from softclose.cli import main
from softclose.errors import ConfigError
from softclose.model.lid import LidModel
from softclose import optimise
from softclose.sweeps.optimal import optimise_grid, segments
from softclose.problem import as_params

MASSES = [0.4, 0.5, 0.6]


@pytest.fixture(scope="module")
def local(cfg):
    # segments of two: 0.4 by multistart, 0.5 warm from 0.4, 0.6 by multistart
    return optimise_grid(cfg, {"mass.lid": MASSES}, segment=2)


def test_every_point_is_verified_and_the_default_lid_gives_the_default_answer(cfg, local):
    f = local.to_frame()
    assert list(f.columns[:5]) == ["mass.lid", "spring_k", "spring_rest_length", "damper_c",
                                   "objective"]
    assert local.success and f["success"].all() and f["closed"].all()
    np.testing.assert_allclose(f["mass.lid"], MASSES)
    # each optimiser's J agrees with the adaptive reference's J of its design
    assert (f["objective_relative_difference"].abs() < 1e-3).all()
    np.testing.assert_allclose(f["verified_objective"], f["objective"], rtol=1e-3)
    assert list(f["start"]) == ["multistart", "warm from id 0", "multistart"]
    mid = f.iloc[1]                                  # mass.lid 0.5: the default config
    assert mid["objective"] == pytest.approx(0.0228995, rel=1e-5)
    assert mid["spring_k"] == pytest.approx(1914.7, rel=1e-4)
    # the warm-started point equals the multistart optimiser's answer of the same problem
    cold = optimise(cfg)
    assert cold.success
    assert mid["objective"] == pytest.approx(cold.objective, rel=1e-8)
    for k, v in cold.design.items():
        assert mid[k] == pytest.approx(v, rel=1e-6)


def test_the_spring_carries_the_heavier_lid(cfg, local):
    """Physics: at the closed angle the holding-moment limit is active (holding_moment =
    holding_moment_min), so the spring's moment there must cancel the extra gravity moment
    of a heavier lid -- it grows with the mass, by exactly the gravity moment's growth.
    (spring_k alone does not: the optimum trades a softer spring for a longer rest length.)"""
    f = local.to_frame()
    th = cfg.stroke.theta_closed
    spring, gravity = [], []
    for m, k, l0, hm in zip(MASSES, f["spring_k"], f["spring_rest_length"],
                            f["holding_moment"]):
        model = LidModel.from_config(cfg.update({"mass.lid": m}))
        g = float(model.dV(th, as_params([0.0, l0, 0.0, 0.0])))            # gravity alone
        total = float(model.dV(th, as_params([k, l0, 0.0, 0.0])))
        assert total == pytest.approx(hm, abs=1e-9)             # the verified metric
        assert hm == pytest.approx(cfg.optimise.holding_moment_min, abs=1e-7)
        spring.append(g - total)                                 # the moment the spring holds
        gravity.append(g)
    assert np.all(np.diff(spring) > 0.1)                         # N m per 0.1 kg
    np.testing.assert_allclose(np.diff(spring), np.diff(gravity), rtol=1e-6)


@pytest.mark.slow
def test_the_dask_run_gives_the_same_table(cfg, local):
    remote = optimise_grid(cfg, {"mass.lid": MASSES}, segment=2, dask="local:2")
    assert remote.where == "local:2" and remote.success
    a, b = local.to_frame(), remote.to_frame()
    for col in ["mass.lid", "spring_k", "spring_rest_length", "damper_c", "objective",
                "closing_time", "impact_theta_dot", "peak_tip_speed", "holding_moment",
                "verified_objective"]:
        np.testing.assert_allclose(b[col], a[col], rtol=1e-8, err_msg=col)
    assert list(b["start"]) == list(a["start"]) and list(b["success"]) == list(a["success"])


def test_segments_follow_the_last_key_and_depend_on_the_grid_only():
    segs = segments((2, 5), 3)
    assert [s.tolist() for s in segs] == [[0, 1, 2], [3, 4], [5, 6, 7], [8, 9]]
    assert np.array_equal(np.sort(np.concatenate(segments((3, 4, 7)))), np.arange(84))


def test_design_keys_are_refused(cfg, tmp_path, capsys):
    with pytest.raises(ConfigError, match="--optimise picks the design"):
        optimise_grid(cfg, {"design.damper_c": [100.0, 200.0]})
    code = main(["sweep", "--optimise", "--grid", "mass.lid=[0.4, 0.5]", "--grid",
                 "design.spring_k=1000:2000:3", "--out", str(tmp_path)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1
    assert err[0] == ("softclose: error: --grid design.spring_k: --optimise picks the design; "
                      "sweep only non-design keys (e.g. mass.lid, geometry.lid_length)")


def test_robust_only_with_optimise(tmp_path, capsys):
    code = main(["sweep", "--robust", "--grid", "mass.lid=[0.4, 0.5]", "--out", str(tmp_path)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "--robust: only with --optimise" in err[0]


def test_command_line_writes_the_table_and_the_map(tmp_path, capsys):
    out = tmp_path / "opt"
    assert main(["sweep", "--optimise", "--grid", "mass.lid=[0.5]", "--out", str(out),
                 "--json"]) == 0
    payload = json.loads(capsys.readouterr().out)
    assert payload["success"] and payload["points"] == 1
    row = payload["rows"][0]
    assert row["mass.lid"] == 0.5 and row["success"] is True
    assert row["objective"] == pytest.approx(0.0228995, rel=1e-5)
    lines = (out / "optimal.csv").read_text().splitlines()
    assert lines[0].split(",")[:5] == ['"mass.lid"', '"spring_k"', '"spring_rest_length"',
                                       '"damper_c"', '"objective"']
    assert len(lines) == 2 and float(lines[1].split(",")[4]) == row["objective"]
    assert (out / "optimal.png").stat().st_size > 10_000


def test_a_cluster_lost_mid_grid_keeps_the_finished_points(cfg, tmp_path, monkeypatch, capsys):
    """The Dask cluster stops after the first segment: that segment's points are kept in the
    table (verified as usual), the rest are "not computed", and the command says why with
    exit 3 (not 130: nobody pressed Ctrl-C)."""
    import contextlib

    from softclose.sweeps import optimal as optimal_grid
    from softclose.sweeps import distributed

    @contextlib.contextmanager
    def fake_connect(dask):
        yield None

    def failing_map(client, fn, tasks, label="task"):
        tasks = iter(tasks)
        tag, args = next(tasks)
        yield tag, fn(*args)[:1]           # one point came back, then the cluster went
        raise distributed.ClusterLost("--dask tcp://x:1: the scheduler was lost")

    monkeypatch.setattr(distributed, "connect", fake_connect)
    monkeypatch.setattr(distributed, "map_tasks", failing_map)
    res = optimal_grid.optimise_grid(cfg, {"mass.lid": [0.5, 0.6]}, dask="tcp://x:1")
    assert res.lost.endswith("the scheduler was lost")
    assert list(res.columns["success"]) == [True, False]
    assert res.columns["message"][1] == "not computed"
    assert res.columns["objective"][0] == pytest.approx(0.0228995, rel=1e-5)
    assert not res.success and "1 finished points of 2 are kept" in res.message
    code = main(["sweep", "--optimise", "--grid", "mass.lid=[0.5, 0.6]", "--dask", "tcp://x:1",
                 "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 3 and len(err) == 1 and "the scheduler was lost" in err[0]
    rows = (tmp_path / "o" / "optimal.csv").read_text().splitlines()
    assert len(rows) == 3 and "not computed" in rows[2]


@pytest.mark.slow
def test_robust_optimum_per_lid_mass_is_the_robust_optimiser_s_and_verified(cfg):
    """`sweep --optimise --robust` over lid masses: each point is the robust design of that
    lid (the same as softclose.optimise(..., robust=True) there: checked at the first, the
    points run the same code), verified scenario by scenario by the adaptive reference, with
    its Monte Carlo yield at least the required."""
    res = optimise_grid(cfg, {"mass.lid": [0.4, 0.6]}, robust=True)
    assert res.success and res.verified == 2
    alone = optimise(cfg.update({"mass.lid": 0.4}), robust=True)
    assert alone.success
    for k in ("spring_k", "spring_rest_length", "damper_c"):
        assert res.columns[k][0] == pytest.approx(alone.design[k], rel=1e-6)
    for i in range(2):
        assert res.columns["yield"][i] >= cfg.tolerance.required_yield
        assert res.columns["yield_ci_low"][i] <= res.columns["yield"][i] <= 1.0
        # the table's metrics are the reference's, every one of them present
        for k in ("closing_time", "impact_tip_speed", "min_spring_length", "max_spring_length"):
            assert np.isfinite(res.columns[k][i]), k
        assert res.columns["closing_time"][i] <= cfg.optimise.closing_time_max
    # the heavier lid needs the longer rest length (spring and damper at their bounds)
    assert res.columns["spring_rest_length"][1] > res.columns["spring_rest_length"][0]
