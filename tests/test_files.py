"""Every file softclose reads or writes: one line naming the file when it cannot, nothing
half-written left behind (softclose.files), and the C compiler a process of the command.

Reading: a config (and so a design file), a catalog and a fit data file that is not UTF-8,
binary, a folder or unreadable gives exit 2 and one line naming it; a UTF-8 byte order mark
is accepted everywhere. Writing: a folder (or a read-only file) where an ``--out`` file goes
is refused before any work; files are replaced whole (a failing or interrupted writer
leaves the earlier file and no temporary file). The compiler's process group ends with the
command (an interrupt, or the command killed outright on Linux); builds of one NLP wait for
each other.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import threading
import time
from pathlib import Path

import pytest

from softclose import buildcache, files, interrupt
from softclose.cli import main
from softclose.config import load_config
from softclose.errors import ConfigError

ROOT = Path(__file__).resolve().parents[1]

LATIN1 = "# Deckel für Mülleimer\n[mass]\nlid = 0.5\n".encode("latin-1")
BINARY = b"\x7fELF\x02\x01\x01\x00" + bytes(range(256)) * 4


def one_error_line(capsys, code, rc, *words) -> str:
    err = capsys.readouterr().err
    lines = [x for x in err.splitlines() if x.strip()]
    assert rc == code, err
    assert len(lines) == 1 and lines[0].startswith("softclose: error:"), err
    assert "Traceback" not in err
    for w in words:
        assert w in lines[0], lines[0]
    return lines[0]


# -- reading ------------------------------------------------------------------------------------
@pytest.mark.parametrize("content,words", [
    (LATIN1, ("not UTF-8", "line 1, column 11", "save it as UTF-8")),
    (BINARY, ("binary content", "TOML config file")),
    ("[mass]\nlid = 0.5\n".encode("utf-16"), ("binary content",)),      # (NUL bytes)
])
def test_a_config_that_is_not_utf8_text_is_one_line(tmp_path, capsys, content, words):
    path = tmp_path / "bad.toml"
    path.write_bytes(content)
    rc = main(["simulate", "--config", str(path)])
    one_error_line(capsys, 2, rc, str(path), *words)


def test_a_config_folder_is_one_line(tmp_path, capsys):
    (tmp_path / "conf.toml").mkdir()
    rc = main(["simulate", "--config", str(tmp_path / "conf.toml")])
    one_error_line(capsys, 2, rc, "is a folder", "TOML config file")


@pytest.mark.skipif(os.geteuid() == 0, reason="root reads a file without read permission")
def test_an_unreadable_config_is_one_line(tmp_path, capsys):
    path = tmp_path / "c.toml"
    path.write_text("[mass]\nlid = 0.5\n")
    path.chmod(0)
    rc = main(["simulate", "--config", str(path)])
    one_error_line(capsys, 2, rc, "cannot read", "permissions")


def test_a_config_with_a_byte_order_mark_is_read(tmp_path):
    plain, bom = tmp_path / "plain.toml", tmp_path / "bom.toml"
    text = "# a lid\n[mass]\nlid = 0.61\n"
    plain.write_text(text)
    bom.write_bytes(b"\xef\xbb\xbf" + text.encode())
    assert load_config(bom) == load_config(plain)
    assert load_config(bom).mass.lid == 0.61


def test_a_catalog_and_a_data_file_are_read_the_same_way(tmp_path, capsys):
    springs = tmp_path / "springs.csv"
    springs.write_bytes("# Federn für Deckel\npart,kind,rate\n".encode("latin-1"))
    rc = main(["select", "--springs", str(springs)])
    one_error_line(capsys, 2, rc, str(springs), "not UTF-8")
    data = tmp_path / "stroke.csv"
    data.write_bytes(BINARY)
    rc = main(["fit", str(data), "--free", "design.damper_c"])
    one_error_line(capsys, 2, rc, str(data), "binary content")


def test_read_text_says_where_the_first_bad_byte_is(tmp_path):
    p = tmp_path / "x.toml"
    p.write_bytes(b"\xef\xbb\xbfa = 1\nb = '\xe9'\n")
    with pytest.raises(ConfigError, match=r"byte 0xe9 at line 2, column 6"):
        files.read_text(p)
    p.write_bytes(b"\xef\xbb\xbfa = 1\n")
    assert files.read_text(p) == "a = 1\n"


# -- writing ------------------------------------------------------------------------------------
def test_a_folder_where_design_toml_goes_is_refused_before_the_work(tmp_path, capsys):
    out = tmp_path / "D"
    (out / "design.toml").mkdir(parents=True)
    t0 = time.perf_counter()
    rc = main(["optimise", "--out", str(out)])
    took = time.perf_counter() - t0
    one_error_line(capsys, 2, rc, "design.toml", "is a folder")
    assert took < 5.0, f"{took:.1f} s: the optimiser ran before the check"
    assert sorted(p.name for p in out.iterdir()) == ["design.toml"]


def test_a_folder_where_the_trajectory_goes_is_refused(tmp_path, capsys):
    out = tmp_path / "D"
    (out / "stroke_trajectory.csv").mkdir(parents=True)
    rc = main(["simulate", "--out", str(out)])
    one_error_line(capsys, 2, rc, "stroke_trajectory.csv", "is a folder")
    assert sorted(p.name for p in out.iterdir()) == ["stroke_trajectory.csv"]


def test_a_file_where_a_folder_goes_is_refused(tmp_path, capsys):
    out = tmp_path / "P"
    out.mkdir()
    (out / "designs").write_text("not a folder")
    rc = main(["pareto", "--out", str(out), "--closing-times", "0.1:0.2:2"])
    one_error_line(capsys, 2, rc, "designs", "is a file where softclose makes a folder")


@pytest.mark.skipif(os.geteuid() == 0, reason="root may replace any file (os.access is True)")
def test_a_read_only_design_file_is_refused_before_the_work(tmp_path, capsys):
    out = tmp_path / "D"
    out.mkdir()
    (out / "design.toml").write_text("# kept\n")
    (out / "design.toml").chmod(0o444)
    rc = main(["optimise", "--out", str(out)])
    one_error_line(capsys, 2, rc, "read-only")
    assert (out / "design.toml").read_text() == "# kept\n"


def test_check_targets_refuses_a_read_only_file(tmp_path, monkeypatch):
    """(As root too: os.access answers as a user would be answered.)"""
    (tmp_path / "a.csv").write_text("x")
    monkeypatch.setattr(files.os, "access", lambda p, mode: False)
    with pytest.raises(ConfigError, match="a.csv is read-only"):
        files.check_targets(tmp_path, ["a.csv"])
    files.check_targets(tmp_path, ["b.csv"])          # (a new file: fine)


def test_a_write_that_fails_leaves_the_earlier_file_whole(tmp_path):
    path = tmp_path / "design.toml"
    files.write_text(path, "old = 1\n")

    def half(p):
        Path(p).write_text("new = ")
        raise OSError(28, "No space left on device")

    with pytest.raises(ConfigError, match=r"design.toml: cannot write \(No space left"):
        files.write_with(path, half)
    assert path.read_text() == "old = 1\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["design.toml"]

    def interrupted(p):
        Path(p).write_text("new = ")
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        files.write_with(path, interrupted)
    assert path.read_text() == "old = 1\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["design.toml"]
    files.write_text(path, "new = 2\n")
    assert path.read_text() == "new = 2\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["design.toml"]


def test_the_temporary_file_keeps_the_suffix(tmp_path):
    """(matplotlib and Pillow choose the format by the suffix)"""
    t = files.temporary(tmp_path / "stroke_animation.gif")
    assert t.parent == tmp_path and t.suffix == ".gif" and t.name.startswith(".")
    assert str(os.getpid()) in t.name


def test_simulate_out_writes_no_temporary_file(tmp_path, capsys):
    out = tmp_path / "S"
    assert main(["simulate", "--out", str(out), "--set", "stroke.t_max=0.3"]) == 0
    names = sorted(p.name for p in out.iterdir())
    assert "stroke_trajectory.csv" in names and "stroke_animation.gif" in names
    assert not [n for n in names if n.startswith(".")], names


# -- the interrupt line -------------------------------------------------------------------------
def test_the_interrupt_line_starts_on_a_new_line(monkeypatch, capsys):
    """An unfinished progress line (``building the NLP ...``) is ended before the message."""
    import softclose.config as config

    def building(*a, **k):
        print("softclose: building the NLP X (C, -O1) ...", end="", file=sys.stderr,
              flush=True)
        raise KeyboardInterrupt

    monkeypatch.setattr(config, "load_config", building)
    assert main(["state", "--theta-deg", "30"]) == 130
    err = capsys.readouterr().err
    assert err == ("softclose: building the NLP X (C, -O1) ...\n"
                   "softclose: interrupted (Ctrl-C); what was finished is kept\n")


def test_sigterm_is_an_interrupt(monkeypatch, capsys):
    import softclose.config as config

    def terminated(*a, **k):
        os.kill(os.getpid(), signal.SIGTERM)
        time.sleep(5)

    monkeypatch.setattr(config, "load_config", terminated)
    t0 = time.perf_counter()
    try:
        assert main(["state", "--theta-deg", "30"]) == 130
    finally:
        interrupt._pending.clear()     # (what the last guard noted: not for the next test)
    assert time.perf_counter() - t0 < 2
    assert capsys.readouterr().err == ("softclose: interrupted (SIGTERM); what was finished "
                                       "is kept\n")
    assert signal.getsignal(signal.SIGTERM) is not interrupt._handler


# -- the compiler -------------------------------------------------------------------------------
#: a stand-in for a compiler: a driver that starts a child of its own (as cc starts cc1) and
#: leaves a temporary file in $TMPDIR
FAKE_CC = ["sh", "-c", 'echo x > "$TMPDIR/cc_fake.s"; sleep 60 & echo $! > child; wait']


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    stat = Path(f"/proc/{pid}/stat")
    return not (stat.exists() and stat.read_text().rsplit(")", 1)[1].split()[0] == "Z")


def test_the_compiler_runs_in_the_build_folder_and_says_why_it_failed(tmp_path):
    code, said = buildcache.run_compiler(["sh", "-c", 'echo "$TMPDIR"; echo oops >&2; exit 3'],
                                         tmp_path)
    assert code == 3 and said.split() == [str(tmp_path), "oops"]


@pytest.mark.skipif(not Path("/proc").exists(), reason="reads /proc (Linux)")
def test_an_interrupt_ends_the_compiler_and_what_it_started(tmp_path):
    timer = threading.Timer(1.0, os.kill, (os.getpid(), signal.SIGINT))
    timer.start()
    t0 = time.perf_counter()
    with pytest.raises(KeyboardInterrupt):
        buildcache.run_compiler(FAKE_CC, tmp_path)
    assert time.perf_counter() - t0 < 1.0 + buildcache.END_WITHIN + 1.0
    child = int((tmp_path / "child").read_text())
    time.sleep(0.2)
    assert not _alive(child), "the compiler's own child outlived the interrupt"


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="PR_SET_PDEATHSIG (Linux)")
def test_the_compiler_dies_with_a_killed_command(tmp_path):
    """softclose killed outright (SIGKILL: no handler runs): the compiler's group goes too."""
    script = textwrap.dedent(f"""
        import sys
        sys.path.insert(0, {str(ROOT)!r})
        from pathlib import Path
        from softclose.buildcache import run_compiler
        run_compiler({FAKE_CC!r}, Path({str(tmp_path)!r}))
    """)
    proc = subprocess.Popen([sys.executable, "-c", script])
    deadline = time.monotonic() + 30
    while not (tmp_path / "child").exists() and time.monotonic() < deadline:
        time.sleep(0.05)
    child = int((tmp_path / "child").read_text())
    assert _alive(child)
    proc.kill()
    proc.wait()
    deadline = time.monotonic() + 3
    while _alive(child) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not _alive(child), "the compiler outlived its killed parent"


# -- builds of one NLP wait for each other --------------------------------------------------------
def test_a_second_build_of_one_nlp_waits(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("SOFTCLOSE_CACHE", str(tmp_path))
    from softclose.optimiser import compiled
    holder = textwrap.dedent(f"""
        import sys, time
        sys.path.insert(0, {str(ROOT)!r})
        from softclose.optimiser.compiled import build_lock
        with build_lock("k1", what="X"):
            print("held", flush=True)
            time.sleep(1.5)
    """)
    proc = subprocess.Popen([sys.executable, "-c", holder], stdout=subprocess.PIPE, text=True,
                            env={**os.environ, "SOFTCLOSE_CACHE": str(tmp_path)})
    assert proc.stdout.readline().strip() == "held"
    t0 = time.perf_counter()
    with compiled.build_lock("k1", what="X"):
        waited = time.perf_counter() - t0
    proc.wait()
    assert 0.5 < waited < 10
    err = capsys.readouterr().err
    assert err.startswith("softclose: waiting for another build of the NLP X (C, -O1) ...")
    t0 = time.perf_counter()
    with compiled.build_lock("k1", what="X"):      # free now: at once, silently
        assert time.perf_counter() - t0 < 0.5
    with compiled.build_lock("k2", what="Y"):      # another NLP: not held
        pass
    assert capsys.readouterr().err == ""


def test_a_lock_of_a_killed_build_is_free(tmp_path, monkeypatch):
    monkeypatch.setenv("SOFTCLOSE_CACHE", str(tmp_path))
    from softclose.optimiser import compiled
    holder = textwrap.dedent(f"""
        import os, sys
        sys.path.insert(0, {str(ROOT)!r})
        from softclose.optimiser.compiled import build_lock
        with build_lock("k1"):
            print("held", flush=True)
            os.kill(os.getpid(), 9)
    """)
    proc = subprocess.Popen([sys.executable, "-c", holder], stdout=subprocess.PIPE, text=True,
                            env={**os.environ, "SOFTCLOSE_CACHE": str(tmp_path)})
    assert proc.stdout.readline().strip() == "held"
    proc.wait()
    t0 = time.perf_counter()
    with compiled.build_lock("k1"):
        assert time.perf_counter() - t0 < 0.5


def test_the_reliability_section_quotes_the_reader(tmp_path, monkeypatch, capsys):
    """docs/internals.md's example line is what the reader says of a Latin-1 comment."""
    monkeypatch.chdir(tmp_path)
    Path("lid.toml").write_bytes(LATIN1)
    assert main(["simulate", "--config", "lid.toml"]) == 2
    said = capsys.readouterr().err.strip().removeprefix("softclose: error: ")
    docs = " ".join((ROOT / "docs" / "internals.md").read_text().split())
    assert f"e.g. `{said}`" in docs


def test_a_signal_after_the_command_leaves_its_exit_code():
    """The command line's process: SIGTERM or SIGINT landing once the command has ended
    (while it prints or exits) is ignored -- no kill, no traceback, the command's code."""
    script = textwrap.dedent(f"""
        import os, signal, sys
        sys.path.insert(0, {str(ROOT)!r})
        from softclose import interrupt
        interrupt.handle_until_exit()
        with interrupt.guard():
            pass
        os.kill(os.getpid(), signal.SIGTERM)
        os.kill(os.getpid(), signal.SIGINT)
        print("still here")
        sys.exit(3)
    """)
    r = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                       timeout=60)
    assert (r.returncode, r.stdout, r.stderr) == (3, "still here\n", "")


@pytest.mark.parametrize("ends_with, code", [("sys.exit(130)", -signal.SIGINT),
                                             ("interrupt.exit_program(130)", 130)])
def test_a_ctrl_c_caught_during_an_import_leaves_exit_code_130(ends_with, code, tmp_path):
    """CPython ends a program run with ``python -m`` by SIGINT (-2) when a KeyboardInterrupt
    was raised inside code that exec() ran from a string (a dataclass's generated methods
    while a module is imported), even though the program caught it; the command line
    therefore ends through interrupt.exit_program, which keeps the command's code (130)."""
    (tmp_path / "program.py").write_text(textwrap.dedent(f"""
        import sys
        sys.path.insert(0, {str(ROOT)!r})
        from softclose import interrupt
        try:
            exec("raise KeyboardInterrupt")
        except KeyboardInterrupt:
            print("caught")
        {ends_with}
    """))
    r = subprocess.run([sys.executable, "-m", "program"], capture_output=True, text=True,
                       timeout=60, env={**os.environ, "PYTHONPATH": str(tmp_path)})
    assert (r.returncode, r.stdout) == (code, "caught\n"), r.stderr
