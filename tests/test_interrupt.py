"""Ctrl-C anywhere ends a command with one line and exit code 130, and keeps what was finished
(issue 15) -- tested with a real SIGINT in a ``softclose`` subprocess.

A small driver runs ``softclose.cli.main`` in the subprocess while a watcher thread looks at
the main thread's stack every 2 ms; once the stack has been inside the named place for 30 ms
(an Ipopt solve, a CVODES reference integration, the C stroke kernel, a matplotlib figure)
it sends SIGINT to its own process, so the signal lands exactly there. The sweep test instead
waits for the first finished chunk on disk, then interrupts from outside, as a terminal would.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

DRIVER = r'''
import os, signal, sys, threading, time
where, stamp, argv = sys.argv[1], sys.argv[2], sys.argv[3:]
sep = os.sep


def inside(frames):
    """frames: (file, function) from the top of the main thread's stack down."""
    files = [f for f, _ in frames]
    top = files[0] if files else ""
    if "<module>" in [n for _, n in frames[:-1]]:      # importing a module: not there yet
        return False
    if where == "ipopt":
        return top.endswith(sep.join(("casadi", "casadi.py"))) and \
            any(sep.join(("softclose", "optimis")) in f and "solve" in n   # optimise(r)/
                for f, n in frames)
    if where == "cvodes":
        return top.endswith(sep.join(("casadi", "casadi.py"))) and \
            any(f.endswith(sep.join(("simulation", "reference.py"))) for f in files)
    if where == "kernel":
        return any(f.endswith(sep.join(("kernel", "binding.py"))) and n == "run_strokes"
                   for f, n in frames)
    if where == "figure":
        return sep.join(("matplotlib", "")) in top and \
            any(sep.join(("present", "figures", "")) in f and n.startswith(("plot_", "save"))
                for f, n in frames)
    raise SystemExit(f"unknown place {where}")


def stacks():
    """(file, function) lists of the main thread's stack, then of every other thread's."""
    me, main_id = threading.get_ident(), threading.main_thread().ident
    out = []
    for ident, f in sorted(sys._current_frames().items(), key=lambda kv: kv[0] != main_id):
        frames = []
        while f is not None and ident != me:
            frames.append((f.f_code.co_filename, f.f_code.co_name))
            f = f.f_back
        out.append(frames)
    return out


def watch():
    since, seen = None, 0
    while True:
        all_stacks = stacks()
        # the kernel may run in worker threads; every other place is in the main thread
        if any(inside(fr) for fr in (all_stacks if where == "kernel" else all_stacks[:1])):
            since = since or time.monotonic()
            seen += 1
            # 30 ms on end there; the reference's CVODES calls last a few ms each (it runs on
            # through 16 grid nodes a call): the fifth look that finds the stack inside one
            if time.monotonic() - since > 0.03 or (where == "cvodes" and seen >= 5):
                with open(stamp, "w") as fh:
                    fh.write(repr(time.monotonic()))
                os.kill(os.getpid(), signal.SIGINT)
                return
        else:
            since = None
        time.sleep(0.002)


threading.Thread(target=watch, daemon=True).start()
from softclose.cli import main
code = main(argv)
with open(stamp + ".end", "w") as fh:
    fh.write(repr(time.monotonic()))
sys.exit(code)
'''


def _env():
    env = dict(os.environ)
    env["PYTHONPATH"] = str(ROOT) + os.pathsep + env.get("PYTHONPATH", "")
    return env


def interrupt_at(where: str, argv: list[str], tmp_path: Path, timeout: float = 300):
    """Run ``softclose argv`` and Ctrl-C it once its stack is at ``where``: (exit code,
    stderr, seconds from the signal to the end of main)."""
    driver = tmp_path / "driver.py"
    driver.write_text(DRIVER)
    stamp = tmp_path / "stamp"
    proc = subprocess.run([sys.executable, str(driver), where, str(stamp), *argv],
                          capture_output=True, text=True, timeout=timeout, env=_env(),
                          cwd=tmp_path)
    assert stamp.exists(), (f"softclose {' '.join(argv)} ended (exit {proc.returncode}) "
                            f"before reaching {where}; stderr:\n{proc.stderr[-2000:]}")
    end = Path(str(stamp) + ".end")
    latency = float(end.read_text()) - float(stamp.read_text()) if end.exists() else None
    return proc.returncode, proc.stderr, latency


def assert_one_line_130(code: int, stderr: str, what: str) -> None:
    lines = [ln for ln in stderr.splitlines() if ln.strip()]
    assert "Traceback" not in stderr, f"{what}: traceback\n{stderr[-3000:]}"
    assert code == 130, f"{what}: exit code {code}, expected 130\n{stderr[-3000:]}"
    assert len(lines) == 1 and "interrupted" in lines[0], \
        f"{what}: expected one line saying it was interrupted, got:\n{stderr[-3000:]}"


def test_ctrl_c_during_an_ipopt_solve(tmp_path):
    """CasADi swallows a KeyboardInterrupt raised inside Ipopt (the solve ends with
    NonIpopt_Exception_Thrown): the multistart must still stop, at once."""
    code, err, latency = interrupt_at(
        "ipopt", ["optimise", "--set", "optimise.starts=60"], tmp_path)
    assert_one_line_130(code, err, "optimise interrupted in Ipopt")
    assert latency is not None and latency < 5.0, f"took {latency} s to stop"


def test_ctrl_c_during_a_reference_integration(tmp_path):
    """CVODES turns the interrupt into a RuntimeError ('rhs failed: KeyboardInterrupt'),
    which the reference reports as a numerical failure: it must be exit 130, not 3."""
    code, err, latency = interrupt_at(
        "cvodes", ["optimise", "--set", "optimise.starts=1"], tmp_path)
    assert_one_line_130(code, err, "optimise interrupted in its verification")
    assert latency is not None and latency < 5.0, f"took {latency} s to stop"


#: a lid that a spring holds open: every stroke runs to t_max (20 s, 10^4 steps)
_LONG_STROKES = ["--set", "design.spring_k=2000", "--set", "design.spring_rest_length=0.1",
                 "--set", "stroke.t_max=20"]


@pytest.mark.parametrize("spreads", [["--set", "tolerance.mass.lid=0"], []],
                         ids=["one kernel batch", "batches per lid mass"])
def test_ctrl_c_during_a_stroke_batch(tmp_path, spreads):
    """Interrupted while the C kernel runs a Monte Carlo batch (worker threads, ctypes): the
    calls in progress finish, the queued ones are dropped, the command stops (a toleranced
    lid mass batches the strokes per mass: that loop must stop too)."""
    code, err, latency = interrupt_at(
        "kernel", ["yield", "--samples", "20000", *_LONG_STROKES, *spreads], tmp_path)
    assert_one_line_130(code, err, "yield interrupted in the stroke kernel")
    assert latency is not None and latency < 20.0, f"took {latency:.1f} s to stop"


def _png_complete(path: Path) -> bool:
    data = path.read_bytes()
    return data.startswith(b"\x89PNG\r\n\x1a\n") and data.endswith(b"IEND\xaeB`\x82")


def test_ctrl_c_during_a_figure(tmp_path):
    """Interrupted while matplotlib draws: exit 130, and every file left is whole (the
    trajectory CSV written before the figure is kept)."""
    out = tmp_path / "out"
    code, err, _ = interrupt_at("figure", ["simulate", "--out", str(out)], tmp_path)
    assert_one_line_130(code, err, "simulate --out interrupted in a figure")
    csv = list(out.glob("*.csv"))
    assert csv and all(f.stat().st_size > 0 for f in csv), "the finished trajectory is lost"
    broken = [f.name for f in out.glob("*.png") if not _png_complete(f)]
    assert not broken, f"partly written figures left behind: {broken}"


def test_ctrl_c_during_a_sweep_keeps_finished_chunks(tmp_path):
    """A real SIGINT from outside once the first chunk is on disk: exit 130, the finished
    chunks stay (readable, whole), and the folder says the sweep is unfinished."""
    pq = pytest.importorskip("pyarrow.parquet")
    out = tmp_path / "sweep"
    argv = [sys.executable, "-m", "softclose", "sweep", "--grid",
            "design.spring_k=0:5000:600", "--grid", "design.damper_c=0:5000:600",
            "--format", "parquet", "--chunk", "4000", "--out", str(out)]
    proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=_env(), cwd=tmp_path)
    deadline = time.monotonic() + 240
    parts = []
    while time.monotonic() < deadline and proc.poll() is None:
        parts = [p for p in out.rglob("*.parquet") if p.is_file()]
        if parts:
            break
        time.sleep(0.01)
    assert proc.poll() is None, "the sweep ended before its first chunk could be interrupted"
    assert parts, "no chunk was written within 240 s"
    proc.send_signal(signal.SIGINT)
    stdout, stderr = proc.communicate(timeout=120)
    assert "Traceback" not in stderr, stderr[-3000:]
    assert proc.returncode == 130, f"exit {proc.returncode}\n{stderr[-3000:]}"
    assert len([ln for ln in stderr.splitlines() if ln.strip()]) <= 1, stderr
    parts = [p for p in out.rglob("*.parquet") if p.is_file()]
    assert parts, "the finished chunks were not kept"
    rows = sum(pq.read_table(p).num_rows for p in parts)
    assert 0 < rows < 600 * 600 and rows % 4000 == 0, rows
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest.get("complete") is False


def test_sigint_handler_swaps_for_the_block_and_restores():
    """The handler is in place inside the block (a real SIGINT is ignored under SIG_IGN,
    raises KeyboardInterrupt under Python's default handler), the previous one is back
    afterwards -- also when the block raises -- and another thread leaves it alone."""
    import threading

    from softclose.interrupt import sigint_handler

    def mine(signum, frame):
        raise AssertionError("the swapped-out handler ran")

    previous = signal.signal(signal.SIGINT, mine)
    try:
        with sigint_handler(signal.SIG_IGN):
            assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(0.01)                   # handlers run here: ignored
        assert signal.getsignal(signal.SIGINT) is mine
        with pytest.raises(KeyboardInterrupt):
            with sigint_handler(signal.default_int_handler):
                os.kill(os.getpid(), signal.SIGINT)
                time.sleep(1.0)                # the KeyboardInterrupt ends the wait
        assert signal.getsignal(signal.SIGINT) is mine
        seen = []

        def elsewhere():
            with sigint_handler(signal.SIG_IGN):
                seen.append(signal.getsignal(signal.SIGINT))

        t = threading.Thread(target=elsewhere)
        t.start()
        t.join()
        assert seen == [mine]
    finally:
        signal.signal(signal.SIGINT, previous)


def test_a_swallowed_ctrl_c_stops_the_multistart_before_its_next_start(monkeypatch):
    """Ctrl-C noted (Ipopt swallowed its KeyboardInterrupt, and no re-send came): the
    optimiser's multistart raises it before the next start, not after the remaining ones."""
    from softclose import interrupt
    from softclose.config import default_config
    from softclose.optimiser import optimiser as opt
    solved = []
    real = opt.solve_start

    def counting(plan, i):
        out = real(plan, i)
        solved.append(i)
        if len(solved) == 2:           # Ctrl-C landed in the second start's solve
            interrupt._pending.set()
        return out
    monkeypatch.setattr(opt, "solve_start", counting)
    quiet = interrupt._quiet.is_set()
    interrupt._quiet.clear()
    try:
        with pytest.raises(KeyboardInterrupt):
            opt.optimise_kind(default_config().update({"optimise.starts": 6}), verify=False)
    finally:
        interrupt._pending.clear()
        if quiet:
            interrupt._quiet.set()
    assert solved == [0, 1]


def test_inside_a_solver_call_ctrl_c_is_noted_and_raised_when_it_returns():
    """Under the guard a real SIGINT raises KeyboardInterrupt at once in plain Python code;
    inside ``solving()`` (a CasADi solver call) it is only noted -- nothing is raised into
    CasADi -- and raised as the block ends."""
    from softclose import interrupt
    with pytest.raises(KeyboardInterrupt):
        with interrupt.guard():
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(1.0)                    # the KeyboardInterrupt ends the wait
    assert interrupt.interrupted()
    reached = []
    with pytest.raises(KeyboardInterrupt):
        with interrupt.guard():
            with interrupt.solving():
                os.kill(os.getpid(), signal.SIGINT)
                time.sleep(0.05)               # the handler runs here: noted only
                reached.append(interrupt.stop_requested())
    assert reached == [True] and interrupt.interrupted()
    assert not interrupt.stop_requested()      # the guard has ended


@pytest.mark.parametrize("compiled", [False, pytest.param(True, marks=pytest.mark.slow)],
                         ids=["virtual machine", "compiled"])
def test_ipopt_stops_at_its_next_iteration_through_its_iteration_callback(
        compiled, monkeypatch, tmp_path):
    """The solvers carry nlpsol's ``iteration_callback``: once a stop is requested, Ipopt
    ends with User_Requested_Stop at its next iteration -- also a solver loaded from a
    compiled library."""
    import shutil

    from softclose import buildcache, interrupt
    from softclose.config import default_config
    from softclose.optimiser import optimiser as opt
    from softclose.optimiser.cache import forget, prepare
    if compiled and shutil.which(os.environ.get("CC", "cc")) is None:
        pytest.skip("no C compiler")
    monkeypatch.setenv(buildcache.ENV_FOLDER, str(tmp_path))
    cfg = default_config().update({"optimise.nodes": 4, "optimise.substeps": 2})
    forget()
    try:
        plan = opt.plan_kind(cfg, 1)
        if compiled:                    # (11 s)
            assert prepare(plan.cfg, plan.disc.nodes, plan.disc.substeps) is not None
            forget()
            plan = opt.plan_kind(cfg, 1)
        assert (plan.nlp.library is not None) == compiled
        calls = []

        def stop():
            calls.append(1)
            return len(calls) >= 3
        monkeypatch.setattr(interrupt, "stop_requested", stop)
        r, _ = opt.solve_start(plan, 0)
    finally:
        forget()
    assert r.status == "User_Requested_Stop" and len(calls) == 3 and r.iterations <= 3
