"""Nothing of softclose runs behind the user's back: a command leaves no process behind.

Each command runs as a subprocess in a fresh cache folder with a mark of this test in its
environment (every process it could start inherits the environment, also one started in a
session of its own); one second after it returns, no process carrying the mark, or whose
command line names softclose and that folder, may be alive. ``optimise`` runs twice: the
second use of an NLP is when a compilation used to start in the background. A signal to the
command alone while its C compiler runs ends the compiler and what it started, and leaves
none of their temporary files.
"""

from __future__ import annotations

import os
import subprocess
import sys
import time
import uuid
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

pytestmark = pytest.mark.skipif(not Path("/proc/self/environ").exists(),
                                reason="scans /proc (Linux)")


def _ancestors() -> set[int]:
    out, pid = set(), os.getpid()
    while pid > 1:
        out.add(pid)
        try:
            stat = Path(f"/proc/{pid}/stat").read_text()
        except OSError:
            break
        pid = int(stat.rsplit(")", 1)[1].split()[1])
    return out


def _marked(mark: str, folder: str) -> list[str]:
    """The live processes (not this one nor its parents) that carry ``mark`` in their
    environment, or whose command line names softclose and ``folder``."""
    mine = _ancestors()
    found = []
    for d in Path("/proc").iterdir():
        if not d.name.isdigit() or int(d.name) in mine:
            continue
        try:
            cmd = (d / "cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
            try:
                env = (d / "environ").read_bytes()
            except OSError:
                env = b""
            state = (d / "stat").read_text().rsplit(")", 1)[1].split()[0]
        except OSError:                # (gone meanwhile)
            continue
        if state == "Z":               # (a zombie is not running; its parent reaps it)
            continue
        if mark.encode() in env or ("softclose" in cmd and folder in cmd):
            found.append(f"{d.name}: {cmd.strip()}")
    return found


@pytest.mark.slow      # every command in a fresh process (~1 min): the README's full run
def test_no_process_outlives_a_command(tmp_path):
    cache = tmp_path / "cache"
    mark = f"softclose-test-{uuid.uuid4().hex}"
    env = {**os.environ, "SOFTCLOSE_CACHE": str(cache), "SOFTCLOSE_TEST_MARK": mark,
           "PYTHONPATH": str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", "")}
    for argv in (["optimise"], ["optimise"], ["simulate"], ["prepare"], ["optimise"]):
        r = subprocess.run([sys.executable, "-m", "softclose", *argv], capture_output=True,
                           text=True, env=env, cwd=tmp_path, timeout=900)
        assert r.returncode == 0, f"softclose {' '.join(argv)}: {r.stderr[-2000:]}"
        time.sleep(1.0)
        left = _marked(mark, str(cache))
        assert not left, f"softclose {' '.join(argv)} left processes running: {left}"
    # and the only compiled NLP is the one prepare built, in the foreground
    assert len(list(cache.glob("*/nlp-*.so"))) == 1


def _compiling(cache: Path, mark: str, pid: int) -> bool:
    """Whether the command ``pid`` compiles: a build folder in the cache and a process of
    the command besides itself."""
    return bool(list(cache.glob("*/.build-*"))) and any(
        not p.startswith(f"{pid}:") for p in _marked(mark, "/nonexistent"))


@pytest.mark.slow      # builds a model, then compiles until interrupted (~5-10 s each)
@pytest.mark.parametrize("sig", ["SIGINT", "SIGTERM", "SIGKILL"])
def test_an_interrupted_compile_leaves_nothing(tmp_path, sig):
    """A signal to ``softclose prepare`` alone (as a supervisor sends it, not Ctrl-C to the
    terminal's group) while the C compiler runs: exit 130 (SIGINT, SIGTERM) with one line,
    the compiler and what it started are gone one second later (also after SIGKILL: on
    Linux the compiler dies with its parent), and its temporary files with them."""
    import signal as signals
    cache, tmp = tmp_path / "cache", tmp_path / "tmp"
    tmp.mkdir()
    mark = f"softclose-test-{uuid.uuid4().hex}"
    env = {**os.environ, "SOFTCLOSE_CACHE": str(cache), "SOFTCLOSE_TEST_MARK": mark,
           "TMPDIR": str(tmp),
           "PYTHONPATH": str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", "")}
    proc = subprocess.Popen([sys.executable, "-m", "softclose", "prepare"], env=env,
                            cwd=tmp_path, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            text=True)
    deadline = time.monotonic() + 300
    while not _compiling(cache, mark, proc.pid) and time.monotonic() < deadline:
        assert proc.poll() is None, proc.stderr.read()
        time.sleep(0.1)
    time.sleep(1.0)                       # (well inside the compile: ~10 s at -O1)
    assert proc.poll() is None, "the compile ended before the signal"
    proc.send_signal(getattr(signals, sig))
    err = proc.communicate(timeout=60)[1]
    time.sleep(1.0)
    left = _marked(mark, str(cache))
    assert not left, f"{sig}: processes left running: {left}"
    assert list(tmp.iterdir()) == [], "the compiler's temporary files were left"
    if sig == "SIGKILL":
        assert proc.returncode == -9
        return
    assert proc.returncode == 130, err
    assert err.endswith(f"...\nsoftclose: interrupted ({'Ctrl-C' if sig == 'SIGINT' else sig}); "
                        "what was finished is kept\n"), err
    assert not list(cache.glob("*/.build-*")), "the build folder was left"
