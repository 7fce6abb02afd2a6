"""One cache folder, robust: the stroke kernel of a source checkout and the built models and
NLPs share it (SOFTCLOSE_CACHE); with one that cannot be written a command works uncached
with one note on stderr; a corrupt entry is rebuilt; what a killed build leaves behind is
never read and is cleaned up; two processes at once sharing the folder both succeed, and
compile an NLP once (the second waits for the first's build).

Each case runs in fresh interpreters (the kernel is loaded once per process)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

#: a fresh interpreter: load the kernel, run a stroke, build (and keep) a model: the
#: library it loaded, or "extension" when the package's built extension is used
PROBE = r"""
import sys
from softclose.simulation.kernel import binding, library
from softclose.config import default_config
from softclose.simulation.simulator import Simulator
ext = library._built_extension()
binding.load()
r = Simulator.from_config(default_config(), cached=True).run()
assert r.closed, r
print("extension" if ext is not None else library._fallback_name())
"""


def _env(**extra) -> dict:
    env = {k: v for k, v in os.environ.items()
           if k not in ("SOFTCLOSE_CACHE", "XDG_CACHE_HOME")}
    env["PYTHONPATH"] = str(ROOT) + os.pathsep + env.get("PYTHONPATH", "")
    env.update(extra)
    return env


def _probe(env, **kw) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", PROBE], capture_output=True, text=True,
                          env=env, timeout=600, **kw)


def _needs_fallback(out: str) -> None:
    if out.strip() == "extension":
        pytest.skip("the package's built extension is used: no kernel is compiled")


def _unwritable(tmp_path: Path) -> Path:
    """A folder that cannot be made or written: beneath a plain file (root may write
    anywhere, so chmod alone would not do), or read-only when not root."""
    if os.geteuid() != 0:
        ro = tmp_path / "read-only"
        ro.mkdir()
        ro.chmod(0o555)
        return ro / "home"
    blocker = tmp_path / "a-file"
    blocker.write_text("not a folder")
    return blocker / "home"


@pytest.mark.slow      # compiles the kernel from its source (~15 s)
def test_a_cache_folder_that_cannot_be_written_works_uncached_with_one_note(tmp_path):
    home = _unwritable(tmp_path)
    for env in (_env(HOME=str(home)), _env(SOFTCLOSE_CACHE=str(home / "cache"))):
        r = _probe(env)
        assert r.returncode == 0, r.stderr[-3000:]
        assert "Traceback" not in r.stderr
        notes = [ln for ln in r.stderr.splitlines() if ln.strip()]
        assert len(notes) == 1 and notes[0].startswith("softclose: note: the cache folder") \
            and "cannot be written" in notes[0], r.stderr
        assert not home.exists()
    # the command line too: the same one note, the command's own output on stdout
    r = subprocess.run([sys.executable, "-m", "softclose", "simulate"], capture_output=True,
                       text=True, env=_env(HOME=str(home)), timeout=600)
    assert r.returncode == 0 and "Traceback" not in r.stderr, r.stderr[-3000:]
    assert len([ln for ln in r.stderr.splitlines() if ln.strip()]) == 1, r.stderr
    assert r.stdout.strip()


@pytest.mark.slow      # compiles the kernel from its source (~15 s)
def test_a_corrupt_kernel_is_compiled_again(tmp_path):
    cache = tmp_path / "cache"
    env = _env(SOFTCLOSE_CACHE=str(cache))
    r = _probe(env)
    assert r.returncode == 0, r.stderr[-3000:]
    _needs_fallback(r.stdout)
    lib = cache / r.stdout.strip()
    assert lib.exists() and not r.stderr.strip()
    for bad in (b"", b"\x7fELF truncated", lib.read_bytes()[:4096]):
        lib.write_bytes(bad)
        r = _probe(env)
        assert r.returncode == 0 and "Traceback" not in r.stderr, r.stderr[-3000:]
        data = lib.read_bytes()
        assert data.startswith(b"\x7fELF") and len(data) > 50_000


def _dead_pid() -> int:
    p = subprocess.Popen([sys.executable, "-c", "pass"])
    p.wait()
    return p.pid


def test_what_a_killed_build_leaves_is_ignored_and_cleaned_up(tmp_path):
    """A build killed midway leaves only files named with its pid: never read, nothing
    waits for them, and they are removed (those of a live process are left alone)."""
    from softclose import buildcache
    cache = tmp_path / "cache"
    cache.mkdir()
    dead, alive = _dead_pid(), os.getpid()
    name = subprocess.run([sys.executable, "-c", "from softclose.simulation.kernel import library; "
                           "print(library._fallback_name())"], capture_output=True,
                          text=True, env=_env(), check=True).stdout.strip()
    left = [cache / f".{name}.{dead}.tmp", cache / f".model-abc.{dead}.tmp"]
    for p in left:
        p.write_bytes(b"\x7fELF half written")
    mine = cache / f".{name}.{alive}.tmp"
    mine.write_bytes(b"being written")
    r = _probe(_env(SOFTCLOSE_CACHE=str(cache)))
    assert r.returncode == 0, r.stderr[-3000:]
    version = next(p for p in cache.iterdir() if p.is_dir())
    # a compilation of an NLP killed midway, in the version folder
    build = version / f".build-k.{dead}"
    build.mkdir()
    (build / "nlp_k.c").write_text("/* half */")
    tmp = version / f".nlp-k-x.so.{dead}.tmp"
    tmp.write_bytes(b"half")
    assert set(buildcache.sweep_temporaries(version)) == {build, tmp}
    r = _probe(_env(SOFTCLOSE_CACHE=str(cache)))
    assert r.returncode == 0, r.stderr[-3000:]
    assert not any(p.exists() for p in left) and mine.exists()
    assert not build.exists() and not tmp.exists()


def test_two_processes_at_once_share_the_cache(tmp_path):
    """Two commands started together on an empty cache both compile the kernel and build
    the model; both succeed, and the folder holds one whole copy of each, no temporaries."""
    cache = tmp_path / "cache"
    env = _env(SOFTCLOSE_CACHE=str(cache))
    procs = [subprocess.Popen([sys.executable, "-c", PROBE], stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True, env=env) for _ in range(2)]
    outs = [p.communicate(timeout=600) for p in procs]
    for p, (out, err) in zip(procs, outs):
        assert p.returncode == 0, err[-3000:]
    assert not list(cache.rglob(".*")), list(cache.rglob(".*"))
    if outs[0][0].strip() != "extension":
        lib = cache / outs[0][0].strip()
        assert lib.read_bytes().startswith(b"\x7fELF")
        assert len(list(cache.glob("_kernel_*.so"))) == 1
    version = next(p for p in cache.iterdir() if p.is_dir())
    assert len(list(version.glob("model-*.bin"))) == 1
    r = _probe(env)                    # and a third process loads what they kept
    assert r.returncode == 0 and not r.stderr.strip(), r.stderr[-3000:]


@pytest.mark.slow        # two compiles of the default NLP at once (~15 s on an idle machine)
def test_two_prepares_at_once_compile_each_nlp_once(tmp_path):
    """Two ``softclose prepare`` on one empty cache: the second waits for the first's build
    (its line says so) and loads the library, instead of compiling the same NLP again."""
    import time
    env = _env(SOFTCLOSE_CACHE=str(tmp_path / "cache"))
    t0 = time.perf_counter()
    procs = [subprocess.Popen([sys.executable, "-m", "softclose", "prepare"], env=env,
                              cwd=tmp_path, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                              text=True) for _ in range(2)]
    errs = [p.communicate(timeout=900)[1] for p in procs]
    assert [p.returncode for p in procs] == [0, 0], errs
    built = [e for e in errs if "building the NLP" in e]
    waited = [e for e in errs if "waiting for another build of the NLP" in e]
    assert len(built) == 1 and len(waited) == 1, errs
    assert len(list((tmp_path / "cache").glob("*/nlp-*.so"))) == 1
    assert "Traceback" not in "".join(errs)
    assert time.perf_counter() - t0 < 900
