"""Sweeps on Dask (a LocalCluster of two worker processes on this machine): the same rows as
the local run, a worker killed mid-sweep loses and doubles nothing, an unreachable scheduler
is one line and exit 2 within seconds and writes nothing, a scheduler or all workers killed
mid-sweep keep the finished chunks for a resume."""

from __future__ import annotations

import contextlib
import json
import logging
import os
import subprocess
import sys
import time
from collections import Counter
from pathlib import Path

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
    assert remote.computed == 60, f"lost: {m.lost}; interrupted: {remote.interrupted}"
    _same_rows(run(cfg, grid, chunk=8), remote)


def test_one_failed_poll_of_the_scheduler_is_not_a_lost_cluster(cfg, cluster, monkeypatch):
    """distributed can fail one call on a passing comm state (seen once in CI: an
    AssertionError from Client.nthreads mid-sweep, and the sweep ended with a chunk
    missing); the mapper asks again a second later and every row arrives."""
    import softclose.sweeps.distributed as sd
    lc, client = cluster
    real, calls = sd.workers_of, []

    def flaky(c):
        calls.append(1)
        if len(calls) == 1:
            raise AssertionError("a passing comm state")
        return real(c)
    monkeypatch.setattr(sd, "workers_of", flaky)
    grid = make_grid({"design.spring_k": np.linspace(500, 9500, 30), "mass.lid": [0.4, 0.6]},
                     cfg)
    with mapper(client) as m:
        remote = run(cfg, grid, chunk=4, mapper=m)
    assert calls and remote.computed == 60 and m.lost is None and not remote.interrupted
    _same_rows(run(cfg, grid, chunk=4), remote)


def test_public_sweep_and_sample_take_the_same_dask_option(cfg, cluster):
    """``softclose.sweep(..., dask=...)`` and ``sample(..., dask=...)`` (a Client, or an
    address) give the local rows; the result says nothing was lost."""
    from softclose import sample, sweep
    lc, client = cluster
    axes = {"design.spring_k": np.linspace(500, 9500, 12), "mass.lid": [0.4, 0.6]}
    remote = sweep(cfg, axes, chunk=8, dask=client)
    assert remote.success and remote.lost is None and remote.to_json()["lost"] is None
    _same_rows(sweep(cfg, axes, chunk=8), remote)
    ranges = {"design.spring_k": (500, 9500), "design.damper_c": (10, 4000, "log")}
    _same_rows(sample(cfg, ranges, 64, chunk=16),
               sample(cfg, ranges, 64, chunk=16, dask=lc.scheduler_address))


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


def test_unreachable_scheduler_leaves_out_as_it_was(tmp_path, capsys, monkeypatch):
    """The connection comes before anything is written: a new folder is not left behind,
    and a folder holding a finished sweep keeps it whole (manifest complete, table
    unchanged), so the next plain run into it works. (The refusal itself, with its 5 s
    timeout, is the test above: here the timeout is 1 s.)"""
    from softclose.sweeps import distributed as D
    monkeypatch.setattr(D, "CONNECT_TIMEOUT", 1.0)
    grid = ["--grid", "design.spring_k=[1000, 2000]"]
    new = tmp_path / "new"
    assert main(["sweep", *grid, "--out", str(new), "--dask", "tcp://127.0.0.1:1"]) == 2
    assert not new.exists()
    done = tmp_path / "done"
    assert main(["sweep", *grid, "--out", str(done)]) == 0
    before = {p.name: p.read_bytes() for p in done.iterdir() if p.is_file()}
    assert {"manifest.json", "sweep.csv"} <= set(before)
    capsys.readouterr()
    code = main(["sweep", "--grid", "design.spring_k=[3000, 4000]", "--out", str(done),
                 "--dask", "tcp://127.0.0.1:1"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "tcp://127.0.0.1:1" in err[0]
    assert {p.name: p.read_bytes() for p in done.iterdir() if p.is_file()} == before
    assert main(["sweep", "--grid", "design.spring_k=[3000, 4000]", "--out", str(done)]) == 0
    assert "3000" in (done / "sweep.csv").read_text()


# -- a cluster that dies mid-sweep ------------------------------------------------------------
ROOT = Path(__file__).resolve().parents[1]

#: runs ``softclose sweep`` and SIGKILLs the given processes (the scheduler, or every worker)
#: as soon as the second chunk is back; a cluster without workers is given up after 1 s
DRIVER = r'''
import os, signal, sys
pids, argv = [int(p) for p in sys.argv[1].split(",")], sys.argv[2:]
import softclose.sweeps.distributed as D
D.NO_WORKERS_TIMEOUT = 1.0
plain = D.map_tasks


def killing(*args, **kwargs):
    for n, item in enumerate(plain(*args, **kwargs), 1):
        if n == 2:
            for pid in pids:
                os.kill(pid, signal.SIGKILL)
        yield item


D.map_tasks = killing
from softclose.cli import main
sys.exit(main(argv))
'''

#: 4800 designs in 24 chunks of 200 (three lid masses: three simulators per worker)
BIG = ["--grid", "design.spring_k=500:9500:40", "--grid", "design.damper_c=100:4000:40",
       "--grid", "mass.lid=[0.4, 0.5, 0.6]", "--chunk", "200"]


def _env():
    env = dict(os.environ)
    env["PYTHONPATH"] = str(ROOT) + os.pathsep + env.get("PYTHONPATH", "")
    return env


@pytest.fixture
def processes(tmp_path):
    """A scheduler and two worker processes (no nannies: a killed worker stays dead)."""
    info = tmp_path / "scheduler.json"
    quiet = dict(stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=_env())
    sched = subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_scheduler", "--host",
                              "127.0.0.1", "--port", "0", "--no-dashboard", "--scheduler-file",
                              str(info)], **quiet)
    procs = [sched]
    try:
        deadline = time.monotonic() + 60
        while not info.exists() and time.monotonic() < deadline:
            time.sleep(0.05)
        address = json.loads(info.read_text())["address"]
        procs += [subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_worker",
                                    address, "--nthreads", "1", "--no-nanny",
                                    "--no-dashboard"], **quiet) for _ in range(2)]
        with distributed.Client(address, timeout=30) as client:
            client.wait_for_workers(2, timeout=60)
        yield address, sched, procs[1:]
    finally:
        for p in procs:
            p.kill()
            p.wait()


@pytest.mark.slow
@pytest.mark.parametrize("dies", ["scheduler", "workers"])
def test_a_cluster_that_dies_mid_sweep_keeps_the_finished_chunks(tmp_path, capsys, processes,
                                                                 dies):
    """SIGKILL the scheduler (or both workers) once two chunks are back: exit 3 with one
    line that names the scheduler and the resume command, the finished chunks are in
    sweep.csv, and the resumed sweep (here, without Dask) is byte for byte the local run."""
    address, sched, workers = processes
    out = tmp_path / "sweep"
    driver = tmp_path / "driver.py"
    driver.write_text(DRIVER)
    pids = [sched.pid] if dies == "scheduler" else [w.pid for w in workers]
    proc = subprocess.run([sys.executable, str(driver), ",".join(map(str, pids)), "sweep",
                           *BIG, "--out", str(out), "--dask", address],
                          capture_output=True, text=True, timeout=240, env=_env(),
                          cwd=tmp_path)
    err = [ln for ln in proc.stderr.splitlines() if ln.strip()]
    assert "Traceback" not in proc.stderr, proc.stderr[-3000:]
    assert proc.returncode == 3, f"exit {proc.returncode}\n{proc.stderr[-3000:]}"
    assert len(err) == 1 and err[0].startswith("softclose: error: "), proc.stderr
    assert address in err[0] and f"softclose sweep --resume {out}" in err[0], err[0]
    assert ("connection" if dies == "scheduler" else "every Dask worker") in err[0], err[0]
    assert json.loads((out / "manifest.json").read_text())["complete"] is False
    ids = np.loadtxt(out / "sweep.csv", delimiter=",", skiprows=1, usecols=0, dtype=np.int64)
    assert 2 * 200 <= ids.size < 4800 and np.unique(ids).size == ids.size
    assert set(Counter((ids // 200).tolist()).values()) == {200}     # whole chunks only
    assert main(["sweep", "--resume", str(out)]) == 0
    assert main(["sweep", *BIG, "--out", str(tmp_path / "local")]) == 0
    assert (out / "sweep.csv").read_text() == (tmp_path / "local" / "sweep.csv").read_text()


def test_an_address_where_something_else_listens_is_one_line_and_exit_2(tmp_path, capsys):
    """A port where another server listens: one that accepts and says nothing (Dask's
    handshake would wait for ever) and one that greets in its own protocol (Dask would read
    the greeting as a frame length). Both are exit 2 naming the address, within 10 s, and
    write nothing."""
    import socket
    import threading

    def serve(greeting: bytes):
        srv = socket.create_server(("127.0.0.1", 0))
        held = []

        def accept():
            with contextlib.suppress(OSError):
                while True:
                    conn, _ = srv.accept()
                    held.append(conn)
                    if greeting:
                        conn.sendall(greeting)

        threading.Thread(target=accept, daemon=True).start()
        return srv, held, f"tcp://127.0.0.1:{srv.getsockname()[1]}"

    for greeting, says in ((b"", "did not answer as a Dask scheduler"),
                           (b"SSH-2.0-OpenSSH_9.6\r\n" * 4, "is not a Dask scheduler")):
        srv, held, address = serve(greeting)
        try:
            out = tmp_path / f"out{len(greeting)}"
            t0 = time.perf_counter()
            code = main(["sweep", "--grid", "design.spring_k=[1000, 2000]", "--out", str(out),
                         "--dask", address])
            elapsed = time.perf_counter() - t0
        finally:
            srv.close()
            for conn in held:
                conn.close()
        err = capsys.readouterr().err.strip().splitlines()
        assert code == 2 and elapsed < 10.0, (code, elapsed)
        assert len(err) == 1 and address in err[0] and says in err[0], err
        assert not out.exists()
