"""The first second: what is built from a config is kept on disk (softclose.buildcache) and
gives the same numbers; a damaged or stale entry is ignored; the optimiser's NLP compiled to C
gives the same optimum; a command line builds only its own parser."""

from __future__ import annotations

import os
import time
from pathlib import Path

import numpy as np
import pytest

import softclose
from softclose import buildcache
from softclose.config import from_dict, to_dict
from softclose.simulate import Simulator


@pytest.fixture
def cache(tmp_path, monkeypatch):
    """A fresh cache folder of this test."""
    monkeypatch.setenv(buildcache.ENV_FOLDER, str(tmp_path))
    return tmp_path


def _clear_memory():
    import importlib
    oc = importlib.import_module("softclose.optimiser.cache")
    verify = importlib.import_module("softclose.optimiser.verify")
    importlib.import_module("softclose.model")._SHARED.clear()
    oc.forget()
    verify._CHECKERS.clear()


def _strokes(sim):
    rng = np.random.default_rng(4)
    P = np.column_stack([rng.uniform(0, 1e4, 200), rng.uniform(0.02, 0.12, 200),
                         rng.uniform(0, 5000, 200), np.zeros(200)])
    r = sim.run_batch(P)
    return np.column_stack([r[k] for k in ("closing_time", "impact_theta_dot",
                                           "peak_tip_speed", "min_spring_length",
                                           "holding_moment")])


def test_a_loaded_model_and_table_give_the_same_numbers(cache, cfg):
    built = Simulator(cfg)
    first = Simulator(cfg, cached=True)                 # built and stored
    assert len(list(cache.glob("*/model-*.bin"))) == 1
    assert len(list(cache.glob("*/table-*.bin"))) == 1
    loaded = Simulator(cfg, cached=True)                # loaded
    assert "_serialised" in loaded.model.__dict__ and "ode" not in loaded.model.__dict__
    assert np.array_equal(loaded.table.cc, built.table.cc)
    for sim in (first, loaded):
        assert np.array_equal(_strokes(sim), _strokes(built), equal_nan=True)
    a, b = built.run(trajectory=True), loaded.run(trajectory=True)
    assert a.to_json() == b.to_json()
    for k in a.trajectory:
        assert np.array_equal(a.trajectory[k], b.trajectory[k]), k
    assert loaded.model.state(0.1, -1.0) == built.model.state(0.1, -1.0)


@pytest.mark.parametrize("damage", [b"", b"not an entry", None, "truncated"])
def test_a_damaged_entry_is_ignored_and_rebuilt(cache, cfg, damage):
    Simulator(cfg, cached=True)
    for path in cache.glob("*/*.bin"):
        if damage is None:            # a valid entry of the wrong arrays
            kind, key = path.stem.split("-", 1)
            buildcache.store(kind, key, {"numbers": np.array([1.0]), "cc": np.zeros((2, 2))})
        else:
            data = path.read_bytes()
            path.write_bytes(data[:len(data) // 2] if damage == "truncated" else damage)
    sim = Simulator(cfg, cached=True)
    assert np.array_equal(_strokes(sim), _strokes(Simulator(cfg)), equal_nan=True)
    again = Simulator(cfg, cached=True)                # rebuilt and stored again
    assert "_serialised" in again.model.__dict__


def test_another_version_of_the_software_reads_nothing(cache, cfg, monkeypatch):
    Simulator(cfg, cached=True)
    before = buildcache.folder()
    src = Path(softclose.__file__).with_name("version.py")
    st = src.stat()
    buildcache.fingerprint.cache_clear()
    buildcache._folder.cache_clear()
    try:
        os.utime(src, ns=(st.st_atime_ns, st.st_mtime_ns + 10**9))   # an edited source
        after = buildcache.folder()
        assert after != before and not list(after.glob("*.bin"))
    finally:
        os.utime(src, ns=(st.st_atime_ns, st.st_mtime_ns))
        buildcache.fingerprint.cache_clear()
        buildcache._folder.cache_clear()
    assert buildcache.folder() == before


def test_the_cache_can_be_turned_off(monkeypatch, cfg):
    monkeypatch.setenv(buildcache.ENV_FOLDER, "off")
    assert buildcache.folder() is None
    sim = Simulator(cfg, cached=True)
    assert "_serialised" not in sim.model.__dict__


def test_the_second_use_of_an_nlp_compiles_it_in_the_background(cache, cfg, compiles_started):
    started = compiles_started
    from softclose.optimiser.cache import get_nlp
    _clear_memory()
    get_nlp(cfg)                        # first use: remembered, nothing compiled
    assert not started and list(cache.glob("*/seen-*"))
    _clear_memory()
    get_nlp(cfg)                        # second use (another process): compile it
    assert len(started) == 1 and started[0][1:3] == ["-m", "softclose.optimiser.compile"]
    lock = Path(started[0][3])
    assert lock.exists()
    spec = __import__("json").loads(lock.read_text())
    assert from_dict(spec["config"]) == cfg and spec["nodes"] == cfg.optimise.nodes
    _clear_memory()
    get_nlp(cfg)                        # being compiled (the lock): not again
    assert len(started) == 1
    other = cfg.set("mass.lid", 0.6)    # nor another NLP while one compiles
    get_nlp(other)
    _clear_memory()
    get_nlp(other)
    assert len(started) == 1
    old = time.time() - buildcache.STALE_LOCK - 10
    os.utime(lock, (old, old))          # a compiler that died long ago
    _clear_memory()
    get_nlp(cfg)
    assert len(started) == 2
    _clear_memory()


def test_compilations_asked_for_while_one_runs_wait_their_turn(cache, cfg, monkeypatch,
                                                               compiles_started):
    """While one NLP compiles, the second use of another queues it (at most MAX_PENDING);
    the running compilation's end hands the lock to the oldest waiting one (exec, the lock
    held), and to none once none waits."""
    started = compiles_started
    import json
    for _ in range(2):                                # the first NLP: compiling
        assert not buildcache.request_nlp("first", {"nodes": 1}) or len(started) == 1
    lock = Path(started[0][3])
    assert lock.exists() and len(started) == 1
    for i in range(buildcache.MAX_PENDING + 2):       # more, while it runs: queued
        for _ in range(2):
            assert not buildcache.request_nlp(f"k{i}", {"nodes": i}, "softclose.robust.compile")
        if i < buildcache.MAX_PENDING:                # (the order they were asked in)
            os.utime(buildcache.folder() / f"pending-k{i}", (time.time() + i,) * 2)
    waiting = sorted(p.name for p in buildcache.folder().glob("pending-*"))
    assert waiting == [f"pending-k{i}" for i in range(buildcache.MAX_PENDING)]
    assert len(started) == 1
    execs = []

    class Exec(Exception):
        """exec does not return: this process became the next compilation"""

    monkeypatch.chdir(cache)                          # (restored after the test)

    def execv(exe, argv):
        assert os.getcwd() == buildcache.package_root()   # the same package (below)
        execs.append(argv)
        raise Exec
    monkeypatch.setattr(os, "execv", execv)

    def end():
        try:
            buildcache.chain(lock)
        except Exec:
            pass
    (buildcache.folder() / "nlp-k0.so").write_bytes(b"")   # k0 got compiled meanwhile
    end()                                             # the first one ends: k1 is next
    assert execs[-1][1:] == ["-m", "softclose.robust.compile", str(lock)]
    assert json.loads(lock.read_text()) == {"key": "k1", "nodes": 1}
    assert not (buildcache.folder() / "pending-k0").exists()
    for _ in range(buildcache.MAX_PENDING - 2):
        end()
    assert json.loads(lock.read_text())["key"] == f"k{buildcache.MAX_PENDING - 1}"
    end()                                             # none waits: the lock goes
    assert not lock.exists() and not list(buildcache.folder().glob("pending-*"))
    assert len(execs) == buildcache.MAX_PENDING - 1


def test_a_background_compilation_imports_this_same_package(cache, tmp_path, monkeypatch):
    """A command run in a clone with the package installed from it (the README's set-up)
    must start its compilation where ``python -m`` finds the installed package, not the
    clone's ``softclose/`` beside it: that one has another fingerprint, so its library
    would go to a cache folder nobody reads, asked for again on every run."""
    import subprocess
    import sys
    monkeypatch.setenv(buildcache.ENV_COMPILE, "1")
    clone = tmp_path / "clone"
    (clone / "softclose").mkdir(parents=True)
    (clone / "softclose" / "__init__.py").write_text("# another copy of the package\n")
    monkeypatch.chdir(clone)
    started = []

    class Popen:
        def __init__(self, cmd, **kw):
            started.append((cmd, kw))
    with monkeypatch.context() as m:
        m.setattr(subprocess, "Popen", Popen)
        for _ in range(2):
            buildcache.request_nlp("k", {"nodes": 1})
    (cmd, kw), = started
    assert cmd[1:3] == ["-m", "softclose.optimiser.compile"]
    probe = [sys.executable, "-c", "import softclose; print(softclose.__file__)"]

    def imported_from(cwd):
        out = subprocess.run(probe, cwd=cwd, env=kw["env"], capture_output=True, text=True,
                             check=True).stdout.strip()
        return Path(out).resolve()
    assert imported_from(clone) == (clone / "softclose" / "__init__.py").resolve()  # the trap
    assert imported_from(kw.get("cwd")) == Path(softclose.__file__).resolve()


@pytest.mark.slow
def test_the_compiled_nlp_gives_the_same_optimum(cache, cfg, monkeypatch):
    """The NLP compiled to C (a few seconds here) solves to the same optimum as CasADi's
    virtual machine, and a damaged library is dropped, never an error."""
    monkeypatch.setenv(buildcache.ENV_COMPILE, "1")
    import shutil
    if shutil.which(os.environ.get("CC", "cc")) is None:
        pytest.skip("no C compiler")
    from softclose.optimiser.cache import build_nlp, get_nlp, nlp_key
    _clear_memory()
    vm = softclose.optimise(cfg)
    nlp = get_nlp(cfg)
    assert nlp.library is None
    key = buildcache.key_of("nlp", nlp_key(cfg))
    assert buildcache.compile_nlp(build_nlp(cfg, nlp.N, nlp.M).solver, key) is not None
    _clear_memory()
    nlp = get_nlp(cfg)
    assert nlp.library is not None and nlp.build_time < 0.5
    fast = softclose.optimise(cfg)
    for k in vm.design:
        assert fast.design[k] == pytest.approx(vm.design[k], rel=1e-12, abs=0)
    assert fast.objective == pytest.approx(vm.objective, rel=1e-12)
    assert fast.success and fast.verification.objective == pytest.approx(
        vm.verification.objective, rel=1e-12)
    assert [r["iterations"] for r in fast.starts] == [r["iterations"] for r in vm.starts]
    # interval and f of a loaded NLP are built on first use, the same functions
    x, p = np.array([0.2, -1.0]), softclose.problem.params_of(cfg, fast.design)
    assert np.allclose(np.asarray(nlp.f(x, p)), np.asarray(build_nlp(cfg, 10, 4).f(x, p)),
                       rtol=0, atol=1e-14)
    _clear_memory()
    # a command loads it (another process: this one has the library mapped) ...
    import json
    import subprocess
    import sys

    def command():
        r = subprocess.run([sys.executable, "-m", "softclose", "optimise", "--json"],
                           capture_output=True, text=True,
                           env={**os.environ, buildcache.ENV_COMPILE: "0"})
        assert r.returncode == 0, r.stderr
        return json.loads(r.stdout)
    out = command()
    assert out["solver"]["build_time"] < 0.5
    assert out["design"] == pytest.approx(fast.design, rel=1e-12)
    # ... and a damaged library is dropped, the NLP built again: the same answer
    lib = buildcache.compiled_nlp(key)
    tmp = lib.with_suffix(".new")
    tmp.write_bytes(b"\x7fELF damaged")
    os.replace(tmp, lib)
    out = command()
    assert out["design"] == pytest.approx(vm.design, rel=1e-12)
    assert buildcache.compiled_nlp(key) is None


def test_a_config_round_trip_keeps_the_nlp(cfg):
    from softclose.optimiser.cache import nlp_key
    c = cfg.set("mass.lid", 0.6).set("design.spring_k", 1200.0)
    assert nlp_key(from_dict(to_dict(c))) == nlp_key(c)


def test_a_command_line_builds_its_own_parser_only():
    from softclose.cli import COMMANDS, build_parser
    full = build_parser()
    names = set(full._subparsers._group_actions[0].choices)
    assert names == set(COMMANDS)
    for name in names:
        one = build_parser([name])
        choices = one._subparsers._group_actions[0].choices
        assert name in choices and len(choices) < len(names)
        # the same options as in the full parser
        assert choices[name].format_usage() == \
            full._subparsers._group_actions[0].choices[name].format_usage()


def test_the_folders_of_other_versions_are_pruned(tmp_path):
    """A new version of the software keeps the KEEP_VERSIONS most recently used folders of
    the others (and any used within the hour: another process may be using it); the rest
    go, and nothing that is not a version folder is touched."""
    import time
    now = time.time()
    old = []
    for i in range(buildcache.KEEP_VERSIONS + 3):
        p = tmp_path / f"{i:016x}"
        (p / "sub").mkdir(parents=True)
        (p / "sub" / "model-x.bin").write_bytes(b"0")
        age = 7200.0 + 60.0 * i          # the larger i, the longer unused
        os.utime(p, (now - age, now - age))
        old.append(p)
    recent = tmp_path / "ffffffffffffffff"       # beyond the count, but used a minute ago
    recent.mkdir()
    os.utime(recent, (now - 60.0, now - 60.0))
    other = tmp_path / "notes"                   # not a version folder
    other.mkdir()
    os.utime(other, (now - 1e6, now - 1e6))
    current = tmp_path / "0123456789abcdef"
    current.mkdir()
    gone = buildcache.prune_versions(tmp_path, keep=current)
    # the recent one counts among the KEEP_VERSIONS most recent: the oldest four go
    assert sorted(gone) == sorted(old[buildcache.KEEP_VERSIONS - 1:])
    assert all(not p.exists() for p in gone)
    assert all(p.exists() for p in old[:buildcache.KEEP_VERSIONS - 1])
    assert recent.exists() and other.exists() and current.exists()
