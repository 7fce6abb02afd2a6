"""Sweeps on Dask (a LocalCluster of two worker processes on this machine): the same rows as
the local run, a worker killed mid-sweep loses and doubles nothing, an unreachable scheduler
is one line and exit 2 within seconds."""

from __future__ import annotations

import logging
import time
from collections import Counter

import numpy as np
import pytest

distributed = pytest.importorskip("distributed")

from softclose.cli import main  # noqa: E402
from softclose.sweeps import make_grid  # noqa: E402
from softclose.sweeps.distributed import mapper  # noqa: E402
from softclose.sweeps.run import run  # noqa: E402

#: a grid with a non-design key (one simulator per lid mass) and some infeasible designs
GRID = ["--grid", "design.spring_k=500:9500:8", "--grid",
        "design.spring_rest_length=[0.05, 0.07, 0.09]", "--grid", "mass.lid=[0.4, 0.6]"]


def test_dask_local_gives_the_rows_of_the_local_run(tmp_path, capsys):
    """``--dask local:2`` writes the same sweep.csv, byte for byte, as the local run (six
    chunks of 8 designs, finished in whatever order the workers return them)."""
    a, b = tmp_path / "local", tmp_path / "dask"
    assert main(["sweep", *GRID, "--chunk", "8", "--out", str(a)]) == 0
    assert main(["sweep", *GRID, "--chunk", "8", "--out", str(b), "--dask", "local:2"]) == 0
    text_a, text_b = (a / "sweep.csv").read_text(), (b / "sweep.csv").read_text()
    rows = text_a.splitlines()
    assert len(rows) == 1 + 8 * 3 * 2
    assert text_b == text_a
    # a real mix: feasible designs and two reasons, two lid masses (two simulators)
    assert ",true," in text_a and "not closed" in text_a and "not held shut" in text_a


@pytest.fixture(scope="module")
def cluster():
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None, silence_logs=logging.ERROR) as lc, \
            distributed.Client(lc) as client:
        yield lc, client


def _same_rows(a, b) -> None:
    for k, v in a.columns.items():
        w = b.columns[k]
        if v.dtype.kind == "f":
            np.testing.assert_array_equal(w, v, err_msg=k)
        else:
            assert list(w) == list(v), k


def test_a_running_scheduler_by_its_address(cfg, cluster):
    """An address (not a Client): softclose connects, checks that the workers import the
    same softclose, and gets the local rows (two lid masses: one simulator each)."""
    lc, _ = cluster
    grid = make_grid({"design.spring_k": np.linspace(500, 9500, 30), "mass.lid": [0.4, 0.6]},
                     cfg)
    with mapper(lc.scheduler_address) as m:
        remote = run(cfg, grid, chunk=8, mapper=m)
    assert remote.computed == 60
    _same_rows(run(cfg, grid, chunk=8), remote)


def test_a_worker_lost_mid_sweep_loses_and_doubles_nothing(cfg, cluster):
    """Kill one worker process after the first chunk comes back: the scheduler reruns its
    task elsewhere, every id arrives exactly once and the rows equal the local run's."""
    lc, client = cluster
    axes = {"design.spring_k": np.linspace(500, 9500, 40),
            "design.spring_rest_length": np.linspace(0.05, 0.09, 20),
            "design.damper_c": np.linspace(100, 4000, 10)}
    grid = make_grid(axes, cfg)
    local = run(cfg, grid, chunk=400)
    seen = Counter()
    killed = []

    with mapper(client) as m:
        def killing(cfg_dict, keys, tasks, threads=None):
            for c, cols in m(cfg_dict, keys, tasks, threads):
                seen.update(cols["id"].tolist())
                if not killed:      # both workers are busy now: end one of them hard
                    name = next(iter(lc.workers))
                    killed.append(name)
                    client.sync(lc.workers[name].kill)
                yield c, cols

        remote = run(cfg, grid, chunk=400, mapper=killing)
    assert killed
    assert remote.computed == grid.n and not remote.interrupted
    assert sorted(seen) == list(range(grid.n)) and set(seen.values()) == {1}
    _same_rows(local, remote)
    # the kill did hit work in progress: some chunk was processed twice by the scheduler
    log = lc.scheduler.transition_log
    processing = Counter(t.key for t in log if t.finish == "processing"
                         and str(t.key).startswith("softclose-chunk-"))
    assert max(processing.values()) >= 2


def test_unreachable_scheduler_is_one_line_and_exit_2(tmp_path, capsys):
    t0 = time.perf_counter()
    code = main(["sweep", "--grid", "design.spring_k=[1000, 2000]", "--out", str(tmp_path / "a"),
                 "--dask", "tcp://127.0.0.1:1"])
    elapsed = time.perf_counter() - t0
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and elapsed < 10.0
    assert len(err) == 1 and err[0].startswith("softclose: error: ")
    assert "tcp://127.0.0.1:1" in err[0]
    # a malformed address never tries to connect
    assert main(["sweep", "--grid", "design.spring_k=[1000, 2000]", "--out", str(tmp_path / "b"),
                 "--dask", "local:0"]) == 2
    assert "local:N" in capsys.readouterr().err
