"""The compiled stroke kernel (``_kernel.c``) and the coefficient table it reads.

"Skip what a scene doesn't need": with the geometry fixed, the equation of motion
depends on theta only through eight coefficients (:data:`softclose.dynamics.COEFFS`), so
no closure is solved per step. :class:`CoefficientTable` evaluates them and their exact
theta-derivatives (CasADi AD) on a uniform grid once, as cubic Hermite pieces; the
interpolation error is measured at every cell midpoint and kept in ``max_rel_error``.

The kernel is built by ``pip install`` as the extension ``softclose._kernel``; in a source
checkout without it, it is compiled once with the system C compiler into a cache folder.
Calls go through ctypes, which releases the GIL, so batches run on all cores in threads.
"""

from __future__ import annotations

import ctypes
import hashlib
import math
import os
import subprocess
import sys
import sysconfig
import tempfile
import threading
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

from .dynamics import COEFFS
from .errors import NumericalError
from .integrators import Method

#: output columns of the kernel, in order
OUT_FIELDS = ("status", "closing_time", "impact_theta_dot", "impact_tip_speed",
              "peak_tip_speed", "min_spring_length", "max_spring_length", "steps",
              "energy_rise", "theta_min", "theta_dot_max", "theta_max")
STATUS = {0: "closed", 1: "not closed", 2: "unstable", 3: "left the tabulated range",
          4: "non-finite", 5: "implicit solve failed"}

_lib = None
_lock = threading.Lock()
_SRC = Path(__file__).with_name("_kernel.c")


def _compile_fallback() -> Path:
    src = _SRC.read_bytes()
    tag = hashlib.sha256(src).hexdigest()[:16]
    cache = Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache")) / "softclose"
    lib = cache / f"_kernel_{tag}.so"
    if lib.exists():
        return lib
    cache.mkdir(parents=True, exist_ok=True)
    cc = os.environ.get("CC", "cc")
    inc = sysconfig.get_paths()["include"]
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / lib.name
        cmd = [cc, "-O3", "-shared", "-fPIC", f"-I{inc}", str(_SRC), "-o", str(out), "-lm"]
        try:
            subprocess.run(cmd, check=True, capture_output=True)
        except (OSError, subprocess.CalledProcessError) as exc:
            raise NumericalError(
                "the stroke kernel is not built and could not be compiled "
                f"({exc}); reinstall softclose with `pip install .` on a machine with a C compiler"
            ) from None
        os.replace(out, lib)
    return lib


def load():
    """The ctypes handle of the kernel (built extension, else compiled on first use)."""
    global _lib
    with _lock:
        if _lib is not None:
            return _lib
        path = None
        try:
            from . import _kernel  # noqa: F401  (built by pip install)
            path = Path(_kernel.__file__)
        except ImportError:
            path = _compile_fallback()
        lib = ctypes.CDLL(str(path))
        dp, lp = ctypes.POINTER(ctypes.c_double), ctypes.POINTER(ctypes.c_long)
        d, l = ctypes.c_double, ctypes.c_long
        lib.sc_strokes.argtypes = [dp, dp, dp, d, d, d, d, l, dp, dp]
        lib.sc_strokes.restype = None
        lib.sc_stroke_traj.argtypes = [dp, dp, dp, d, d, d, d, dp, dp, dp, l, lp]
        lib.sc_stroke_traj.restype = None
        lib.sc_step.argtypes = [dp, dp, dp, dp, d, dp, dp]
        lib.sc_step.restype = ctypes.c_int
        assert lib.sc_nout() == len(OUT_FIELDS)
        _lib = lib
        return lib


def _ptr(a: np.ndarray):
    return a.ctypes.data_as(ctypes.POINTER(ctypes.c_double))


class CoefficientTable:
    """Cubic Hermite table of the geometric coefficients over ``model.theta_range``."""

    #: interpolation error aimed for; cells are refined (x4) up to MAX_CELLS to reach it
    TARGET_REL_ERROR = 1e-10
    MAX_CELLS = 1 << 15

    def __init__(self, model, cell_deg: float = 0.1):
        lo, hi = model.theta_range
        n = max(16, int(math.ceil((hi - lo) / math.radians(cell_deg))))
        while True:
            self._build(model, lo, hi, n)
            if self.max_rel_error <= self.TARGET_REL_ERROR or 4 * n > self.MAX_CELLS:
                break
            n *= 4  # near a toggle the coefficients vary fast: refine the grid

    def _build(self, model, lo, hi, n):
        h = (hi - lo) / n
        nodes = np.linspace(lo, hi, n + 1)
        f = model.coeffs.map(n + 1)
        v, dv = (np.asarray(a) for a in f(nodes))           # (NC, n+1) each
        f0, f1, d0, d1 = v[:, :-1], v[:, 1:], dv[:, :-1] * h, dv[:, 1:] * h
        cc = np.stack([f0, d0, 3 * (f1 - f0) - 2 * d0 - d1, 2 * (f0 - f1) + d0 + d1], axis=-1)
        self.cc = np.ascontiguousarray(cc.transpose(1, 0, 2))  # (ncell, NC, 4)
        self.meta = np.array([n, lo, h], float)
        self.lo, self.hi, self.h, self.ncell = lo, hi, h, n
        # interpolation error at the cell midpoints, relative to each coefficient's scale
        mid = 0.5 * (nodes[:-1] + nodes[1:])
        exact = np.asarray(model.coeffs.map(n)(mid)[0])
        interp = (self.cc[:, :, 0] + 0.5 * self.cc[:, :, 1] + 0.25 * self.cc[:, :, 2]
                  + 0.125 * self.cc[:, :, 3]).T
        scale = np.maximum(np.abs(v).max(axis=1, keepdims=True), 1e-300)
        self.max_rel_error = float((np.abs(interp - exact) / scale).max())
        if not np.all(np.isfinite(self.cc)):
            bad = COEFFS[int(np.nonzero(~np.isfinite(self.cc).all(axis=(0, 2)))[0][0])]
            raise NumericalError(f"the coefficient {bad} is not finite on the stroke range; "
                                 "the geometry is at or near a toggle position")

    def evaluate(self, theta) -> np.ndarray:
        """Interpolated coefficients at angles ``theta`` (shape (len, NC))."""
        th = np.atleast_1d(np.asarray(theta, float))
        x = np.clip((th - self.lo) / self.h, 0, self.ncell)
        i = np.minimum(x.astype(int), self.ncell - 1)
        s = (x - i)[:, None]
        q = self.cc[i]
        return q[..., 0] + s * (q[..., 1] + s * (q[..., 2] + s * q[..., 3]))


def run_strokes(table: CoefficientTable, method: Method, step: float, t_max: float,
                theta0: float, theta_closed: float, designs: np.ndarray,
                threads: int | None = None) -> np.ndarray:
    """Metrics of strokes for rows of ``designs`` = (k, l0, c, c_rot, energy_tol).

    Returns an array (n, len(OUT_FIELDS)). Work is split across threads.
    """
    lib = load()
    designs = np.ascontiguousarray(designs, float)
    n = len(designs)
    out = np.empty((n, len(OUT_FIELDS)))
    tab = method.packed()
    cpus = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    threads = threads or min(cpus or 1, 8)
    threads = max(1, min(threads, n // 64 or 1))

    def work(a, b):
        lib.sc_strokes(_ptr(table.meta), _ptr(table.cc), _ptr(tab), step, t_max, theta0,
                       theta_closed, b - a, _ptr(designs[a:b]), _ptr(out[a:b]))

    if threads == 1:
        work(0, n)
    else:
        # more chunks than threads: strokes differ in length (a slammed lid takes 150 steps,
        # a heavily damped one thousands), so equal halves would leave one core idle
        chunks = max(threads, min(8 * threads, n // 64))
        bounds = np.linspace(0, n, chunks + 1).astype(int)
        with ThreadPoolExecutor(threads) as ex:
            list(ex.map(lambda ab: work(*ab), zip(bounds[:-1], bounds[1:])))
    return out


def run_stroke_trajectory(table, method, step, t_max, theta0, theta_closed, design):
    """One stroke with its trajectory: (metrics row, array of (t, theta, theta'))."""
    lib = load()
    design = np.ascontiguousarray(design, float)
    cap = int(math.ceil(t_max / step)) + 3
    traj = np.empty((cap, 3))
    out = np.empty(len(OUT_FIELDS))
    nt = ctypes.c_long(0)
    lib.sc_stroke_traj(_ptr(table.meta), _ptr(table.cc), _ptr(method.packed()), step, t_max,
                       theta0, theta_closed, _ptr(design), _ptr(out), _ptr(traj), cap,
                       ctypes.byref(nt))
    return out, traj[:nt.value].copy()


def kernel_step(table, method, design, h, x0) -> np.ndarray:
    """One step of the kernel (for tests)."""
    lib = load()
    x1 = np.empty(2)
    d = np.ascontiguousarray(np.r_[design[:4], 0.0], float)
    st = lib.sc_step(_ptr(table.meta), _ptr(table.cc), _ptr(method.packed()), _ptr(d), h,
                     _ptr(np.ascontiguousarray(x0, float)), _ptr(x1))
    if st:
        raise NumericalError(f"kernel step failed: {STATUS.get(st, st)}")
    return x1
