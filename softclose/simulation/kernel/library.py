"""The kernel's shared library: the extension ``pip install`` builds, or in a source checkout
``_kernel.c`` compiled once into the cache folder (:mod:`softclose.buildcache`); loaded
through ctypes with its functions' signatures, and its layout checked against
:data:`~softclose.simulation.kernel.layout.LAYOUT`."""

from __future__ import annotations

import ctypes
import os
import threading
from pathlib import Path

from ...errors import NumericalError
from .layout import HEADER_NAME, KERNEL_ABI, LAYOUT, OUT_FIELDS

_lib = None
_lock = threading.Lock()
#: the kernel's C source
SOURCE = Path(__file__).with_name("_kernel.c")
#: the layout header it includes (generated: :func:`softclose.simulation.kernel.layout.header`)
HEADER = Path(__file__).with_name(HEADER_NAME)


def source_bytes() -> bytes:
    """The kernel's source as compiled: ``_kernel.c`` and its layout header."""
    return SOURCE.read_bytes() + HEADER.read_bytes()


def source_tag() -> str:
    """The tag of this kernel's source (BLAKE2b of ``_kernel.c`` and its layout header, 8
    bytes in hex): the one setup.py compiles into the extension (``sc_source_tag``)."""
    from ...buildcache import _blake2b
    return _blake2b(source_bytes(), digest_size=8).hexdigest()


#: compiler flags of the kernel compiled in a source checkout (as setup.py's)
KERNEL_CFLAGS = ("-O3", "-shared", "-fPIC")


def _fallback_name() -> str:
    """The file name of the kernel compiled from this ``_kernel.c`` with this compiler
    (``$CC`` or ``cc``) and :data:`KERNEL_CFLAGS`: any change gives another file."""
    import hashlib  # (what only a source checkout needs is imported here, not at start-up)
    cc = os.environ.get("CC") or "cc"
    tag = hashlib.sha256(source_bytes() + repr((cc, KERNEL_CFLAGS)).encode()).hexdigest()
    return f"_kernel_{tag[:16]}.so"


def _compile(out: Path) -> None:
    """Compile ``_kernel.c`` into ``out`` (NumericalError, one line, when it cannot be)."""
    import sysconfig

    from ... import buildcache
    cc = os.environ.get("CC") or "cc"
    inc = sysconfig.get_paths()["include"]
    cmd = [cc, *KERNEL_CFLAGS, f"-I{inc}", str(SOURCE), "-o", str(out), "-lm"]
    # in a process group of its own that ends with this process (an interrupt, a signal)
    try:
        code, said = buildcache.run_compiler(cmd, Path(out).parent)
    except OSError as exc:
        code, said = -1, str(exc)
    if code != 0:
        raise NumericalError(
            "the stroke kernel is not built and could not be compiled "
            f"({said.strip()[-300:] or f'exit {code}'}); reinstall softclose with "
            "`pip install .` on a machine with a C compiler")


def _compile_fallback() -> tuple[Path, bool]:
    """The kernel of a source checkout: (its library, whether it is kept). Kept in the cache
    folder of :mod:`softclose.buildcache` (``SOFTCLOSE_CACHE``, else
    ``$XDG_CACHE_HOME/softclose`` or ``~/.cache/softclose``), compiled there once: into a
    temporary file named with this process's id, then moved into place (two processes
    compiling at once both succeed; one killed midway leaves a temporary file that is never
    read and is removed once it is gone). With the cache off, or a folder that cannot be
    written (a read-only home: one note on stderr), it is compiled into a temporary folder
    for this process only (not kept: the caller removes it once loaded)."""
    from ... import buildcache
    name = _fallback_name()
    root = buildcache.base()
    if root is not None:
        lib = root / name
        if lib.exists():
            if buildcache.whole_library(lib):
                return lib, True
            buildcache._remove(lib)           # truncated or damaged: compiled again
        if buildcache.writable(root):
            buildcache.sweep_temporaries(root)
            tmp = root / f".{name}.{os.getpid()}.tmp"
            try:
                _compile(tmp)
                os.replace(tmp, lib)
                return lib, True
            except OSError as exc:        # (the folder went away or filled up)
                buildcache.note_unwritable(root, exc)
            finally:
                buildcache._remove(tmp)
    import tempfile
    out = Path(tempfile.mkdtemp(prefix="softclose-kernel-")) / name
    _compile(out)
    return out, False


def _load_fallback():
    """The ctypes handle of the kernel of a source checkout (:func:`_compile_fallback`); a
    kept library that does not load (corrupt, truncated) is removed and compiled again."""
    import shutil
    for attempt in (0, 1):
        path, kept = _compile_fallback()
        try:
            return ctypes.CDLL(str(path))
        except OSError:
            if not kept or attempt:
                raise
            try:
                path.unlink()
            except OSError:
                pass
        finally:
            if not kept:                  # (mapped: the file is not needed any more)
                shutil.rmtree(path.parent, ignore_errors=True)


def _built_extension() -> Path | None:
    """The extension built by pip install, if it is current: the same ABI, compiled from the
    source beside it (its ``sc_source_tag`` is :func:`source_tag`: by content, never by file
    times -- an installed package's files carry the wheel's times, and an edited
    ``_kernel.c`` in a checkout is compiled afresh)."""
    try:
        from . import _kernel  # noqa: F401  (built by pip install)
    except ImportError:
        return None
    path = Path(_kernel.__file__)
    try:
        lib = ctypes.CDLL(str(path))
        if lib.sc_abi() != KERNEL_ABI:
            return None
        lib.sc_source_tag.restype = ctypes.c_char_p
        if SOURCE.exists() and lib.sc_source_tag().decode() != source_tag():
            return None
    except (OSError, AttributeError):
        return None
    return path


def load():
    """The ctypes handle of the kernel (built extension, else compiled on first use)."""
    global _lib
    with _lock:
        if _lib is not None:
            return _lib
        path = _built_extension()
        lib = ctypes.CDLL(str(path)) if path is not None else _load_fallback()
        dp, lp = ctypes.POINTER(ctypes.c_double), ctypes.POINTER(ctypes.c_long)
        d, l = ctypes.c_double, ctypes.c_long
        lib.sc_strokes.argtypes = [dp, dp, dp, dp, dp, dp, dp, d, d, d, d, l, l, dp, l, dp]
        lib.sc_strokes.restype = None
        lib.sc_stroke_traj.argtypes = [dp, dp, dp, dp, dp, dp, dp, d, d, d, d, l, dp, l, dp, dp,
                                       l, lp]
        lib.sc_stroke_traj.restype = None
        lib.sc_step.argtypes = [dp, dp, dp, dp, dp, dp, dp, d, dp, dp]
        lib.sc_step.restype = ctypes.c_int
        lib.sc_point_columns.argtypes = [dp, dp, dp, l, dp, l, dp, l, dp]
        lib.sc_point_columns.restype = None
        lib.sc_point_grid.argtypes = [dp, dp, l, dp, l, dp, l, l, dp, dp]
        lib.sc_point_grid.restype = None
        lib.sc_point_opening.argtypes = [dp, dp, l, dp, dp, l, dp, dp, lp, dp, dp]
        lib.sc_point_opening.restype = None
        lib.sc_leaves.argtypes = [l, l, dp, dp, dp, dp, dp, dp]
        lib.sc_leaves.restype = None
        check_layout(lib)
        _lib = lib
        return lib


def check_layout(lib) -> None:
    """NumericalError (one line, naming the first difference) unless the kernel's layout --
    ABI, table columns, element columns, row and output columns, range columns -- is this
    module's :data:`LAYOUT`: a mismatch is a clear error, never wrong numbers."""
    try:
        lib.sc_layout.restype = ctypes.c_char_p
        theirs = lib.sc_layout().decode()
    except AttributeError:
        theirs = f"abi={lib.sc_abi()}"
    if lib.sc_nout() == len(OUT_FIELDS) and theirs == LAYOUT:
        return
    ours = dict(part.split("=", 1) for part in LAYOUT.split(";"))
    got = dict(part.split("=", 1) for part in theirs.split(";") if "=" in part)
    what = next((f"{k}: the kernel has {got.get(k)!r}, softclose/simulation/kernel/binding.py {v!r}"
                 for k, v in ours.items() if got.get(k) != v), "the output width")
    raise NumericalError(f"the stroke kernel does not match softclose/simulation/kernel/binding.py ({what}); "
                         "reinstall softclose (pip install .)")
