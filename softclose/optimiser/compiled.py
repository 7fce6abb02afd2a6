"""The optimiser's NLPs compiled to C, kept in the build cache (:mod:`softclose.buildcache`):
built once per structure, in the foreground, with a line on stderr saying what is built
(:func:`compiling`, ``softclose prepare``), loaded by ``nlpsol`` from the library when the cache
holds one. A library is keyed by the NLP's structure, the C compiler (its ``--version``) and
the flags; a damaged or foreign one is dropped and built again. Two processes that would
compile one NLP do not both compile it: the second waits for the first's build
(:func:`build_lock`) and loads its library. The compiler runs in a process group of its own
that ends with the command (:func:`softclose.buildcache.run_compiler`)."""

from __future__ import annotations

import contextlib
import os
import sys
from functools import lru_cache
from pathlib import Path

from ..buildcache import (_prune, _remove, _touch, _write_atomic, base, folder, key_of, load,
                          run_compiler, store, sweep_temporaries, whole_library)

#: compiler flags of the NLP: -O1 compiles the default NLP in ~10 s and solves 2.3x faster
#: than the virtual machine (-O2: 50 s to compile, 3.4x; -O0: 4 s, 1.5x)
CFLAGS = ("-O1", "-shared", "-fPIC")
#: compiler flags of the robust optimiser's scenario NLPs: their C is several times the
#: optimiser's, which -O1 compiles in minutes; at -O0 (12 s for `optimise --robust`'s 9 MB)
#: their solves run ~1.3-2x faster than the virtual machine. The co-design's first stage
#: (the points free in every scenario: 62 MB) is the exception and is never compiled: its
#: C evaluates the derivatives ~2x more slowly than the virtual machine's thread maps
#: (:attr:`softclose.robust.nlp.ScenarioStructure.prepared`)
SCENARIO_CFLAGS = ("-O0", "-shared", "-fPIC", "-pthread")


def compiler() -> str:
    """The C compiler: ``$CC``, else ``cc``."""
    return os.environ.get("CC") or "cc"


@lru_cache(maxsize=8)
def _toolchain(cc: str, flags: tuple) -> str | None:
    """A key of the compiler ``cc`` (the first line of its ``--version``) and ``flags``; None
    when there is no such compiler."""
    version = compiler_version(cc)
    return None if version is None else key_of(cc, version, flags)[:12]


def compiler_version(cc: str) -> str | None:
    """The first line of ``cc --version`` ("" when it prints nothing), None when there is no
    such compiler. Asked once per compiler file: the line is remembered in the cache folder
    under the file's path, size and time (``compiler-*.txt``), so that a command that loads
    a compiled NLP starts no process."""
    path = _which(cc)
    if path is None:
        return None
    root = base()
    memo = None
    try:
        real = os.path.realpath(path)
        st = os.stat(real)
        if root is not None:
            stamp = key_of(cc, path, real, st.st_size, st.st_mtime_ns, st.st_ino)
            memo = root / f"compiler-{stamp}.txt"
            return memo.read_text().removesuffix("\n")
    except OSError:
        pass
    import subprocess
    try:
        out = subprocess.run([cc, "--version"], capture_output=True, text=True, timeout=30,
                             stdin=subprocess.DEVNULL)
    except (OSError, subprocess.SubprocessError):
        return None
    lines = (out.stdout or out.stderr).strip().splitlines()
    version = lines[0] if lines else ""
    if memo is not None:
        try:
            if root.is_dir():
                _write_atomic(memo, (version + "\n").encode())
                _prune(root, "compiler-*.txt")
        except OSError:
            pass
    return version


def _which(cmd: str) -> str | None:
    """The executable file ``cmd`` names (on the PATH unless it names a folder), as
    ``shutil.which`` finds it on POSIX (without importing shutil and its compressors)."""
    folders = [""] if os.path.dirname(cmd) else \
        (os.environ.get("PATH") or os.defpath).split(os.pathsep)
    for d in folders:
        path = os.path.join(d, cmd)
        if os.path.isfile(path) and os.access(path, os.X_OK):
            return path
    return None


def toolchain(flags: tuple = CFLAGS) -> str | None:
    """:func:`_toolchain` of this process's compiler."""
    return _toolchain(compiler(), tuple(flags))


def _library(where: Path, key: str, flags: tuple) -> Path | None:
    tools = toolchain(flags)
    return None if tools is None else where / f"nlp-{key}-{tools}.so"


def compiled_nlp(key: str, flags: tuple = CFLAGS) -> Path | None:
    """The compiled library of the NLP ``key`` (by this compiler, with ``flags``), if it is
    built (a damaged one is removed: it is compiled again when asked)."""
    where = folder()
    if where is None:
        return None
    path = _library(where, key, flags)
    if path is not None and path.exists():
        if not whole_library(path):
            _remove(path)
            return None
        _touch(path)
        return path
    return None


def forget_nlp(key: str, flags: tuple = CFLAGS) -> None:
    """Remove a compiled NLP that could not be loaded (it is compiled again when asked)."""
    where = folder()
    path = _library(where, key, flags) if where is not None else None
    if path is not None:
        _remove(path)


_compiling: list = []


@contextlib.contextmanager
def compiling():
    """Inside the block, every NLP built (:func:`load_or_build`) is compiled now, in the
    foreground, into the cache, and its library used (``softclose prepare``)."""
    _compiling.append(True)
    try:
        yield
    finally:
        _compiling.pop()


def will_compile() -> bool:
    """Whether an NLP built now is compiled (inside :func:`compiling`, with a cache)."""
    return bool(_compiling) and folder() is not None


#: what this process did with NLPs, for ``softclose prepare``'s report: the libraries it
#: compiled and loaded (paths), the NLPs it could not compile (their names)
compiled: list = []
loaded: list = []
failed: list = []
#: ... and the NLPs it left to CasADi's virtual machine, whose C is slower (their names)
interpreted: list = []


def build_interpreted(build, what: str = ""):
    """``build()``: an NLP that is never compiled, as its C evaluates more slowly than
    CasADi's virtual machine (measured per structure: ``softclose bench --structures``);
    inside :func:`compiling` it is noted in :data:`interpreted` for ``softclose prepare``
    to say so."""
    nlp = build()
    if will_compile():
        interpreted.append(what)
    return nlp


def load_or_build(disk: str, restore, build, what: str = "", flags: tuple = CFLAGS):
    """The NLP kept as ``disk``: ``restore(library, meta)`` when its compiled library is in
    the cache (a damaged or foreign library is dropped), else ``build()`` -- built
    symbolically. Inside :func:`compiling`, a built NLP is compiled (``flags``; ``what``
    names it on stderr) and its library loaded. The one way the optimiser's and the robust
    optimiser's NLPs are kept."""
    nlp = _restored(disk, compiled_nlp(disk, flags), restore, flags, loaded)
    if nlp is not None:
        return nlp
    if not will_compile():
        return build()
    with build_lock(disk, flags, what):     # (another process may be building it: wait)
        nlp = _restored(disk, compiled_nlp(disk, flags), restore, flags, loaded)
        if nlp is not None:
            return nlp
        nlp = build()
        store("nlpmeta", disk, nlp.meta())
        out = _restored(disk, compile_nlp(nlp.solver, disk, flags, what), restore, flags,
                        compiled)
        if out is not None:
            return out
        failed.append(what or disk)
    return nlp


def kept_structure(store: dict, key: tuple, kind: str, restore, build, what: str = "",
                   flags: tuple = CFLAGS, compile_it: bool = True):
    """The NLP structure of ``key`` (of ``kind``: the build cache's name), kept in ``store``
    for this process: built once by :func:`load_or_build` (``restore(library, meta)`` its
    compiled library, or ``build()``, compiled with ``flags`` inside :func:`compiling`), or
    by :func:`build_interpreted` when ``compile_it`` is false. The one way the nominal and
    the scenario NLPs' structures are kept: ``st.key`` is ``key``, ``st.disk`` the build
    cache's key."""
    if key not in store:
        disk = key_of(kind, key)
        st = load_or_build(disk, restore, build, what, flags) if compile_it else \
            build_interpreted(build, what)
        st.key, st.disk = key, disk
        store[key] = st
    return store[key]


@contextlib.contextmanager
def build_lock(key: str, flags: tuple = CFLAGS, what: str = ""):
    """Hold the lock of the NLP ``key``'s build (with ``flags``) in the cache for the block:
    a second process that would compile the same NLP waits here (a line on stderr says it
    waits for another build, and how long it waited), then loads what the first built. A
    file lock (``filelock``: the system's lock on the file, released when the holder exits
    or dies); without a cache, or where the lock file cannot be made, no lock."""
    from filelock import FileLock, Timeout
    where = folder()
    lock = None
    if where is not None:
        try:
            (where / "locks").mkdir(exist_ok=True)
            lock = FileLock(str(where / "locks" / f"nlp-{key}-{key_of(flags)[:8]}.lock"))
            try:
                lock.acquire(timeout=0)
            except Timeout:
                import time
                level = next((f for f in flags if f.startswith("-O")), "")
                print(f"softclose: waiting for another build of the NLP"
                      f"{' ' + what if what else ''} (C, {level}) ...", end="",
                      file=sys.stderr, flush=True)
                t0 = time.perf_counter()
                lock.acquire()
                print(f" {time.perf_counter() - t0:.1f} s", file=sys.stderr, flush=True)
        except OSError:          # (a lock file that cannot be made: build without one)
            lock = None
    try:
        yield
    finally:
        if lock is not None:
            lock.release()


def _restored(disk: str, lib, restore, flags: tuple, into: list):
    """``restore(lib, meta)`` of the NLP ``disk``'s library ``lib`` (noted in ``into``), or
    None: no library, no meta, or a damaged or foreign one (dropped)."""
    meta = load("nlpmeta", disk) if lib is not None else None
    if meta is None:
        return None
    try:
        nlp = restore(lib, meta)
    except Exception:   # noqa: BLE001  (a damaged or foreign library: build anew)
        forget_nlp(disk, flags)
        return None
    into.append(lib)
    return nlp


def compile_nlp(solver, key: str, flags: tuple = CFLAGS, what: str = "") -> Path | None:
    """Generate the C of ``solver``'s functions, compile it (``flags``) and put the library
    in the cache as the NLP ``key`` (here and now: seconds to minutes, with a line on
    stderr: ``building the NLP WHAT (C, -O1) ... 12.3 s``). None when there is no cache or
    no compiler (said on that line)."""
    import shutil
    import time
    where = folder()
    if where is None:
        return None
    cc = compiler()
    level = next((f for f in flags if f.startswith("-O")), "")
    head = f"softclose: building the NLP{' ' + what if what else ''} (C, {level}) ..."
    print(head, end="", file=sys.stderr, flush=True)
    t0 = time.perf_counter()
    path = _library(where, key, flags)
    if path is None:
        print(f" no C compiler ({cc}): not compiled", file=sys.stderr, flush=True)
        return None
    sweep_temporaries(where)
    tmp = where / f".build-{key}.{os.getpid()}"       # (a killed build: removed later)
    try:
        shutil.rmtree(tmp, ignore_errors=True)
        tmp.mkdir()
        old = os.getcwd()
        try:
            os.chdir(tmp)                     # CasADi writes the file where it stands
            solver.generate_dependencies(f"nlp_{key}.c", {"with_header": False})
        finally:
            os.chdir(old)
        src, out = tmp / f"nlp_{key}.c", tmp / path.name
        try:
            code, said = run_compiler([cc, *flags, src, "-o", out, "-lm"], tmp)
        except OSError as exc:
            code, said = -1, str(exc)
        if code != 0:
            why = said.strip().splitlines()
            print(f" failed ({why[-1] if why else f'exit code {code}'}): not compiled",
                  file=sys.stderr, flush=True)
            return None
        os.replace(out, path)
    except OSError as exc:
        print(f" failed ({exc}): not compiled", file=sys.stderr, flush=True)
        return None
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    print(f" {time.perf_counter() - t0:.1f} s", file=sys.stderr, flush=True)
    _prune(where, "nlp-*.so")
    return path
