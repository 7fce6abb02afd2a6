"""The first second: what is built from a config is kept on disk (softclose.buildcache) and
gives the same numbers; a damaged or stale entry is ignored; the optimiser's NLP compiled to C
gives the same optimum; a command line builds only its own parser and imports only what it
uses (the structure is tested here; the times are `softclose bench`'s start-up rows)."""

from __future__ import annotations

import os
import time
from pathlib import Path

import numpy as np
import pytest

import softclose
from softclose import buildcache
from softclose.optimiser import compiled
from softclose.config import from_dict, to_dict
from softclose.simulation.simulator import Simulator


@pytest.fixture
def cache(tmp_path, monkeypatch):
    """A fresh cache folder of this test."""
    monkeypatch.setenv(buildcache.ENV_FOLDER, str(tmp_path))
    return tmp_path


def _clear_memory():
    import importlib
    oc = importlib.import_module("softclose.optimiser.cache")
    verify = importlib.import_module("softclose.optimiser.verify")
    importlib.import_module("softclose.model.lid")._SHARED.clear()
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
    built = Simulator.from_config(cfg)
    first = Simulator.from_config(cfg, cached=True)                 # built and stored
    assert len(list(cache.glob("*/model-*.bin"))) == 1
    assert len(list(cache.glob("*/table-*.bin"))) == 1
    loaded = Simulator.from_config(cfg, cached=True)                # loaded
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
    Simulator.from_config(cfg, cached=True)
    for path in cache.glob("*/*.bin"):
        if damage is None:            # a valid entry of the wrong arrays
            kind, key = path.stem.split("-", 1)
            buildcache.store(kind, key, {"numbers": np.array([1.0]), "cc": np.zeros((2, 2))})
        else:
            data = path.read_bytes()
            path.write_bytes(data[:len(data) // 2] if damage == "truncated" else damage)
    sim = Simulator.from_config(cfg, cached=True)
    assert np.array_equal(_strokes(sim), _strokes(Simulator.from_config(cfg)), equal_nan=True)
    again = Simulator.from_config(cfg, cached=True)                # rebuilt and stored again
    assert "_serialised" in again.model.__dict__


def test_another_version_of_the_software_reads_nothing(cache, cfg, monkeypatch):
    Simulator.from_config(cfg, cached=True)
    before = buildcache.folder()
    buildcache.fingerprint.cache_clear()
    buildcache._folder.cache_clear()
    try:
        with monkeypatch.context() as m:                 # edited sources
            m.setattr(buildcache, "source_digest", lambda root: "0" * 32)
            after = buildcache.folder()
            assert after != before and not list(after.glob("*.bin"))
    finally:
        buildcache.fingerprint.cache_clear()
        buildcache._folder.cache_clear()
    assert buildcache.folder() == before


def test_the_sources_are_known_by_their_contents_not_their_times(cache, tmp_path):
    """The same sources installed again (new times) keep the cache; an edit does not."""
    import shutil
    root = tmp_path / "pkg"
    shutil.copytree(Path(softclose.__file__).parent, root,
                    ignore=shutil.ignore_patterns("__pycache__", "*.so"))
    first = buildcache.source_digest(root)
    assert list(cache.glob("sources-*.txt"))            # remembered under the files' times
    src = root / "version.py"
    st = src.stat()
    os.utime(src, ns=(st.st_atime_ns, st.st_mtime_ns + 10**9))     # reinstalled: new times
    assert buildcache.source_digest(root) == first
    src.write_text(src.read_text() + "# edited\n")
    assert buildcache.source_digest(root) != first
    src.write_text(src.read_text().removesuffix("# edited\n"))
    assert buildcache.source_digest(root) == first


def test_the_compiler_and_its_flags_are_part_of_a_librarys_key(cache, monkeypatch):
    import shutil
    if shutil.which("cc") is None:
        pytest.skip("no C compiler")
    a = compiled.toolchain(compiled.CFLAGS)
    assert a is not None and a != compiled.toolchain(compiled.SCENARIO_CFLAGS)
    monkeypatch.setenv("CC", "no-such-compiler-here")
    assert compiled.toolchain() is None
    assert compiled.compiled_nlp("k") is None


def test_the_cache_can_be_turned_off(monkeypatch, cfg):
    monkeypatch.setenv(buildcache.ENV_FOLDER, "off")
    assert buildcache.folder() is None
    sim = Simulator.from_config(cfg, cached=True)
    assert "_serialised" not in sim.model.__dict__


def test_using_an_nlp_compiles_nothing_and_starts_no_process(cache, cfg, monkeypatch):
    """An NLP used again and again (in other processes) is built symbolically each time;
    nothing is compiled, nothing started: compiling is only done when asked for."""
    import subprocess
    compiled.toolchain()             # (the compiler's --version: asked once, then remembered)
    started = []
    monkeypatch.setattr(subprocess, "Popen", lambda *a, **k: started.append(a))
    from softclose.optimiser.cache import get_nlp
    for _ in range(3):
        _clear_memory()
        assert get_nlp(cfg).library is None
    assert not started
    assert not [p.name for p in cache.glob("*/*") if not p.name.startswith(
        ("model-", "table-", "fit-", "nlpmeta-"))]


def test_prepare_compiles_in_the_foreground_saying_what(cache, cfg, monkeypatch, capfd):
    """optimiser.cache.prepare compiles here and now (one line on stderr naming the NLP and
    the seconds), nothing is left in the cache folder but the library and its numbers, and
    the next use loads it (and its build's lock). Compiling stubbed: the compiler's argument
    list is checked."""
    import shutil
    if shutil.which(os.environ.get("CC", "cc")) is None:
        pytest.skip("no C compiler")
    from softclose.optimiser.cache import get_nlp, nlp_key, prepare
    runs = []
    real = compiled.run_compiler

    def fake(cmd, where):
        cmd = [str(c) for c in cmd]
        runs.append(cmd)             # a library, but not of the NLP: an empty one
        return real([cmd[0], "-shared", "-fPIC", "-x", "c", os.devnull, "-o",
                     cmd[cmd.index("-o") + 1]], where)
    monkeypatch.setattr(compiled, "run_compiler", fake)
    lib = prepare(cfg)
    err = capfd.readouterr().err
    assert lib is not None and lib.exists() and len(runs) == 1
    assert runs[0][1:4] == list(compiled.CFLAGS)
    assert err.startswith("softclose: building the NLP of the optimiser (")
    assert "(C, -O1) ..." in err and err.rstrip().endswith(" s")
    left = {p.name.split("-")[0] for p in lib.parent.iterdir()}
    assert {"nlp", "nlpmeta"} <= left <= {"model", "table", "fit", "nlp", "nlpmeta",
                                          "locks"}, left
    assert prepare(cfg) == lib and len(runs) == 1         # compiled already
    key = buildcache.key_of("nlp", nlp_key(cfg))
    assert compiled.compiled_nlp(key) == lib
    _clear_memory()
    assert get_nlp(cfg).library is None                   # a foreign library: dropped
    assert compiled.compiled_nlp(key) is None


@pytest.mark.slow
def test_the_compiled_nlp_gives_the_same_optimum(cache, cfg, monkeypatch):
    """The NLP compiled to C (a few seconds here) solves to the same optimum as CasADi's
    virtual machine, and a damaged library is dropped, never an error."""
    import shutil
    if shutil.which(os.environ.get("CC", "cc")) is None:
        pytest.skip("no C compiler")
    from softclose.optimiser.cache import build_nlp, get_nlp, nlp_key, prepare
    _clear_memory()
    vm = softclose.optimise(cfg)
    nlp = get_nlp(cfg)
    assert nlp.library is None
    key = buildcache.key_of("nlp", nlp_key(cfg))
    assert prepare(cfg) is not None
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
                           capture_output=True, text=True)
        assert r.returncode == 0, r.stderr
        return json.loads(r.stdout)
    out = command()
    assert out["solver"]["build_time"] < 0.5
    assert out["design"] == pytest.approx(fast.design, rel=1e-12)
    # ... and a damaged library is dropped, the NLP built again: the same answer
    lib = compiled.compiled_nlp(key)
    tmp = lib.with_suffix(".new")
    tmp.write_bytes(b"\x7fELF damaged")
    os.replace(tmp, lib)
    out = command()
    assert out["design"] == pytest.approx(vm.design, rel=1e-12)
    assert compiled.compiled_nlp(key) is None


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


def test_prepare_refuses_without_a_cache_or_a_compiler(monkeypatch, capsys, tmp_path):
    """`softclose prepare` with nothing to keep the libraries in, or no compiler: one line,
    exit 2, nothing run."""
    from softclose.cli import main
    monkeypatch.setenv(buildcache.ENV_FOLDER, "off")
    assert main(["prepare"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("softclose: error: there is no cache folder")
    monkeypatch.setenv(buildcache.ENV_FOLDER, str(tmp_path))
    monkeypatch.setenv("CC", "no-such-compiler-here")
    assert main(["prepare"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "no C compiler 'no-such-compiler-here'" in err[0]


def test_a_kept_fit_gives_the_same_numbers(cache, cfg):
    """The optimiser's Chebyshev fit of a lid, kept beside the model, reads back to the
    fitted numbers bit for bit; a damaged entry is fitted again."""
    from softclose.optimiser.cache import get_model, kept_fit
    from softclose.optimiser.interval import ChebyshevFit, gas_nlp, nlp_elements
    _clear_memory()
    model, els = get_model(cfg), nlp_elements(cfg)
    fresh = ChebyshevFit(model, els=els, gas=gas_nlp(cfg))
    stored = kept_fit(model, els, False, gas_nlp(cfg))         # fitted and stored
    assert len(list(cache.glob("*/fit-*.bin"))) == 1
    loaded = kept_fit(model, els, False, gas_nlp(cfg))         # read back
    assert not hasattr(loaded, "exact")
    for f in (stored, loaded):
        assert f.names == fresh.names and f.degree == fresh.degree
        assert (f.lo, f.hi, f.max_rel_error) == (fresh.lo, fresh.hi, fresh.max_rel_error)
        assert np.array_equal(f.coef, fresh.coef)
    for path in cache.glob("*/fit-*.bin"):
        path.write_bytes(b"damaged")
    assert np.array_equal(kept_fit(model, els, False, gas_nlp(cfg)).coef, fresh.coef)


def test_the_compilers_version_is_asked_once(cache, monkeypatch):
    """The compiler's ``--version`` keys its libraries; it is asked once per compiler file,
    then read from the cache folder: a command that loads a compiled NLP starts no
    process."""
    import subprocess
    if compiled._which(compiled.compiler()) is None:
        pytest.skip("no C compiler")
    first = compiled.compiler_version(compiled.compiler())
    assert first and list(cache.glob("compiler-*.txt"))

    def refused(*a, **k):
        raise AssertionError("a process was started")
    monkeypatch.setattr(subprocess, "run", refused)
    assert compiled.compiler_version(compiled.compiler()) == first
    assert compiled.compiler_version("no-such-compiler-here") is None


def _modules_after(*args: str) -> set:
    """The modules a command line (``softclose ARGS``, run in a process of its own) has
    imported when it returns."""
    import json
    import subprocess
    import sys
    code = ("import sys, io, contextlib, json\n"
            "from softclose.cli import main\n"
            "with contextlib.redirect_stdout(io.StringIO()):\n"
            f"    code = main({list(args)!r})\n"
            "print(json.dumps([code, sorted(sys.modules)]))")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    code, modules = json.loads(r.stdout)
    assert code == 0, r.stderr
    return set(modules)


#: what no command that draws, tabulates or writes nothing needs
HEAVY = ("pandas", "matplotlib", "scipy", "dask", "distributed", "pyarrow", "fpdf",
         "numpy.ma", "numpy.polynomial")


def test_simulate_imports_only_what_it_uses():
    """``softclose simulate --json`` loads none of the libraries a table, a figure, a sweep
    or a report needs, no standard of the coil spring it does not design, no feature of the
    package and nothing that would start a process (the start-up this keeps is measured by
    ``softclose bench``'s start-up rows)."""
    loaded = _modules_after("simulate", "--json")
    assert [m for m in HEAVY if m in loaded] == []
    assert not [m for m in loaded if m.startswith(("softclose.optimiser", "softclose.robust",
                                                   "softclose.sweeps", "softclose.catalog",
                                                   "softclose.signoff", "softclose.bench",
                                                   "softclose.present.figures"))]
    assert "softclose.coil_spring.design" not in loaded
    assert "softclose.coil_spring.materials" in loaded
    assert not {"subprocess", "shutil", "bz2", "lzma"} & loaded


def test_the_command_line_imports_only_the_commands_it_runs():
    import subprocess
    import sys
    code = ("import sys, softclose.cli\n"
            "print(' '.join(sorted(m for m in sys.modules)))")
    loaded = set(subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                                check=True).stdout.split())
    assert [m for m in HEAVY if m in loaded] == []
    assert [m for m in loaded if m.startswith("softclose.cli.") and m != "softclose.cli.common"] \
        == []


@pytest.mark.slow
def test_optimise_imports_only_what_it_uses():
    """``softclose optimise --json`` solves and verifies without a table, a figure or a
    sweep's libraries, and without numpy.ma (np.unique(x) would import it: ~60 ms)."""
    loaded = _modules_after("optimise", "--json")
    assert [m for m in HEAVY if m in loaded and m != "numpy.polynomial"] == []
    assert not [m for m in loaded if m.startswith(("softclose.sweeps", "softclose.catalog",
                                                   "softclose.signoff",
                                                   "softclose.present.figures"))]
