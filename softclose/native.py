"""The compiled stroke kernel (``_kernel.c``) and the coefficient table it reads.

"Skip what a scene doesn't need": with the geometry fixed, the equation of motion
depends on theta only through coefficients (:data:`softclose.dynamics.COEFFS`: the inertia,
the seed's elements' columns, the tip's lever; and, when a stroke has one of the elements
added since, their columns :data:`softclose.dynamics.EXTRA_COEFFS` in a second table), so
no closure is solved per step. :class:`CoefficientTable` evaluates them and their exact
theta-derivatives (CasADi AD) on a uniform grid once, as cubic Hermite pieces; the
interpolation error is measured at every cell midpoint and kept in ``max_rel_error``.

Design rows
-----------
:func:`run_strokes` integrates one stroke per row of a float array (:data:`DESIGN_COLUMNS`)::

    the parameter vector p (:data:`softclose.elements.PARAMS`: k (N/m), l0 (m), c (N s/m),
    c_rot (N m s/rad), then the elements' added since), energy_tol (J)[, lid_mass (kg)]

The kernel takes p in SI (an angle given in degrees in radians: :func:`kernel_rows`
converts); its laws are the registry's (:mod:`softclose.elements`), stated once in the
element section of ``_kernel.c``.

``energy_tol`` is the energy rise that flags the stroke unstable (and the margin of the
early exit, below). ``lid_mass`` is the lid's mass for that row; NaN, or a missing column,
means the table's own mass (``table.lid_mass``). The coefficients M, dM, Vg, dVg are affine
in the lid's mass (M = m |dG1/dtheta|^2 + I_lid + cranks, Vg = g (m y_G1 + cranks), with
I_lid = m L^2 / 12 when it is derived, or fixed when ``mass.inertia_lid`` is configured), so
a row's coefficients are ``c(m0) + (m - m0) dc/dm`` with dc/dm from
:attr:`CoefficientTable.mass_derivative`: 10^5 Monte Carlo samples of ``mass.lid`` need no
model rebuild. A row at the table's mass never reads that table (bit-identical results).

Early exit -- why it is exact
-----------------------------
With V the elements' potential (gravity and the springs) and E = M theta'^2 / 2 + V, the
equation of motion gives dE/dt = -(damping) theta'^2 <= 0 (c dd + c_rot): the dampers only
dissipate. So at every later time
t' >= t, V(theta(t')) <= E(t') <= E(t), and since theta is continuous it stays in the
connected component R(t) of {theta : V(theta) <= E(t)} that contains theta(t); its tip
speed tau |theta'| = tau sqrt(2 (E - V) / M) is at most G(t) = max over R(t) of
tau sqrt(2 (E(t) - V) / M). Let [theta_min, theta_max] be the range visited so far
(theta_min > theta_closed while not closed). If V(theta_min) > E(t) and
V(theta_max) > E(t), R(t) lies strictly inside (theta_min, theta_max): the lid can never
reach theta_closed, theta_min and theta_max never change, nor do the spring-length
extremes (l over [theta_min, theta_max]); if also G(t) <= the peak recorded so far
(bounded rigorously from the ranges of the cubic pieces), the peak tip speed is final.
Then every SPEC metric is what integrating to t_max would give, and the kernel stops.

A fixed-step method's energy is not exactly non-increasing (a step may gain a little), so
the rule uses E + delta with the margin delta = 2 (steps left to t_max) g + 1e-12 E_scale,
g the largest energy gain of one step seen so far in this stroke (the method's own error,
measured where the dampers do not mask it, e.g. at the turning points) and E_scale the size
of the energy's terms (its rounding). It assumes that no later step gains more than twice
the worst step so far -- the motion only decays -- and the tests check on every exited row
of a design grid, for each method, that the rest of the stroke never rises above E + delta.
(``energy_tol``, 5 % of the energy the stroke releases, would be far too coarse a margin:
a lid held open in a shallow well would never be stopped.) An undamped design
(c = c_rot = 0) keeps its energy, so the rule is not applied to it at all: its metrics over
[0, t_max] depend on the method's drift, and it runs to t_max. Likewise a lid that
creeps monotonically towards an equilibrium never turns back, so theta_min (and a spring
extreme) keeps moving until t_max and the stroke is integrated to the end. A step that
returns its start state bit for bit (at rest at a fixed point of the step map) skips the
remaining full steps, which would all return that state. The same bound with
tau = 1 (|theta'| <= sqrt(2 (E - V) / M) <= the largest theta' so far) keeps
``theta_dot_max`` final too, and E < V(theta_max) <= max E keeps ``energy_rise``: only
``steps`` and ``stop_time`` show that a stroke stopped early.

Why a stroke stays open is recorded in ``stop_reason`` (1: trapped behind a barrier, a
maximum of V between the lid and the rim, ``stop_theta`` = its top; 2: held open, the
potential rises from the lid's well all the way to the rim, ``stop_theta`` = the stable
equilibrium at the bottom of the well, V'(theta) = 0), also for a stroke that ran to t_max
when the energy then decides it; ``stop_time`` is when integration stopped (the closing
time, the early exit, t_max or a failure). :func:`not_closed_reasons` turns them into text.

The kernel is built by ``pip install`` as the extension ``softclose._kernel``; in a source
checkout without it (or with one older than ``_kernel.c``), it is compiled once with the
system C compiler into a cache folder. Calls go through ctypes, which releases the GIL, so
batches run on all cores in threads. On a CPU with AVX2 the strokes of a thread advance as
SIMD vectors (the same numbers bit for bit as the lane-by-lane code, which the environment
variable ``SC_SCALAR=1`` selects).
"""

from __future__ import annotations

import ctypes
import math
import os
import threading
from functools import cached_property
from pathlib import Path

import numpy as np

from . import elements
from .dynamics import COEFFS, EXTRA_COEFFS
from .errors import ConfigError, NumericalError
from .integrators import Method

#: output columns of the kernel, in order
OUT_FIELDS = ("status", "closing_time", "impact_theta_dot", "impact_tip_speed",
              "peak_tip_speed", "min_spring_length", "max_spring_length", "steps",
              "energy_rise", "theta_min", "theta_dot_max", "theta_max",
              "stop_reason", "stop_theta", "stop_time")
STATUS = {0: "closed", 1: "not closed", 2: "unstable", 3: "left the tabulated range",
          4: "non-finite", 5: "implicit solve failed"}
#: ``stop_reason`` codes: why a stroke does not close (0: it closed, failed, or is undecided)
STOP_REASONS = {0: "", 1: "energy below the barrier", 2: "held open"}
#: the design-row columns, in order: the parameter vector (SI), then energy_tol and the
#: optional lid_mass
DESIGN_COLUMNS = tuple(q.name.removesuffix("_deg") for q in elements.PARAMS) + (
    "energy_tol", "lid_mass")
#: the SI factor of each parameter column (an angle given in degrees: pi/180)
_SI = np.array([q.si for q in elements.PARAMS])
#: version of the exported C signatures; a built extension reporting another is not used
KERNEL_ABI = 3
#: element columns per row of the extra table (the kernel's NX: its columns, then zeros)
NX = 4
#: every layout constant this module shares with the kernel (``sc_layout()`` must equal it)
LAYOUT = (f"abi={KERNEL_ABI};cc={','.join(COEFFS)};mass={','.join(COEFFS[:4])};"
          f"xcc={','.join(EXTRA_COEFFS + ('-',) * (NX - len(EXTRA_COEFFS)))};"
          f"row={','.join(DESIGN_COLUMNS)};out={','.join(OUT_FIELDS)};nrng=18")

_lib = None
_lock = threading.Lock()
_SRC = Path(__file__).with_name("_kernel.c")
_COL = {name: i for i, name in enumerate(OUT_FIELDS)}


def _compile_fallback() -> Path:
    import hashlib  # (what only a source checkout needs is imported here, not at start-up)
    src = _SRC.read_bytes()
    tag = hashlib.sha256(src).hexdigest()[:16]
    cache = Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache")) / "softclose"
    lib = cache / f"_kernel_{tag}.so"
    if lib.exists():
        return lib
    import subprocess
    import sysconfig
    import tempfile
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


def _built_extension() -> Path | None:
    """The extension built by pip install, if it is current (same ABI, not older than the
    source next to it: an edited ``_kernel.c`` in a checkout is compiled afresh)."""
    try:
        from . import _kernel  # noqa: F401  (built by pip install)
    except ImportError:
        return None
    path = Path(_kernel.__file__)
    if _SRC.exists() and path.stat().st_mtime < _SRC.stat().st_mtime:
        return None
    try:
        lib = ctypes.CDLL(str(path))
        if lib.sc_abi() != KERNEL_ABI:
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
        path = _built_extension() or _compile_fallback()
        lib = ctypes.CDLL(str(path))
        dp, lp = ctypes.POINTER(ctypes.c_double), ctypes.POINTER(ctypes.c_long)
        d, l = ctypes.c_double, ctypes.c_long
        lib.sc_strokes.argtypes = [dp, dp, dp, dp, dp, dp, d, d, d, d, l, l, dp, l, dp]
        lib.sc_strokes.restype = None
        lib.sc_stroke_traj.argtypes = [dp, dp, dp, dp, dp, dp, d, d, d, d, l, dp, l, dp, dp, l,
                                       lp]
        lib.sc_stroke_traj.restype = None
        lib.sc_step.argtypes = [dp, dp, dp, dp, dp, dp, d, dp, dp]
        lib.sc_step.restype = ctypes.c_int
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
    what = next((f"{k}: the kernel has {got.get(k)!r}, softclose/native.py {v!r}"
                 for k, v in ours.items() if got.get(k) != v), "the output width")
    raise NumericalError(f"the stroke kernel does not match softclose/native.py ({what}); "
                         "reinstall softclose (pip install .)")


def kernel_rows(P: np.ndarray) -> np.ndarray:
    """Rows of the parameter vector in the kernel's units (SI: an angle in degrees becomes
    radians); the columns already in SI are passed through untouched."""
    P = np.array(P, float)
    scale = _SI != 1.0
    if scale.any():
        P[..., scale] = P[..., scale] * _SI[scale]
    return P


def _ptr(a: np.ndarray | None):
    if a is None:
        return ctypes.POINTER(ctypes.c_double)()
    return a.ctypes.data_as(ctypes.POINTER(ctypes.c_double))


def _kernel_layout(cc: np.ndarray) -> np.ndarray:
    """(ncell, NC, 4) pieces -> the kernel's power-major (ncell, 4, NC), 64-byte aligned."""
    t = cc.transpose(0, 2, 1)
    buf = np.empty(t.size + 8)
    off = (-buf.ctypes.data % 64) // 8
    out = buf[off:off + t.size].reshape(t.shape)
    out[...] = t
    return out


def _cubic_ranges(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Ranges over s in [0, 1] of the cubics q0 + q1 s + q2 s^2 + q3 s^3 (rows of q),
    from the ends and the real roots of the derivative, widened for rounding."""
    def at(s):
        return q[:, 0] + s * (q[:, 1] + s * (q[:, 2] + s * q[:, 3]))
    vals = [at(np.zeros(len(q))), at(np.ones(len(q)))]
    A, B, C = 3 * q[:, 3], 2 * q[:, 2], q[:, 1]
    with np.errstate(all="ignore"):
        D = B * B - 4 * A * C
        sq = np.sqrt(np.where(D >= 0, D, np.nan))
        lin = np.abs(A) < 1e-300
        roots = [np.where(lin, -C / B, (-B + sq) / (2 * A)),
                 np.where(lin, np.nan, (-B - sq) / (2 * A))]
        for r in roots:
            ok = (r > 0) & (r < 1)
            v = at(np.where(ok, r, 0.0))
            vals.append(np.where(ok, v, vals[0]))
    V = np.array(vals)
    lo, hi = V.min(axis=0), V.max(axis=0)
    pad = 1e-13 * (np.abs(lo) + np.abs(hi)) + 1e-300
    return lo - pad, hi + pad


def _cell_ranges(cc: np.ndarray) -> np.ndarray:
    """Per cell (the kernel's NRNG columns): ranges of tau, M, Vg, l, dVg, dl over the whole
    cell, then Vg, l, tau, M at its middle (for the early exit's tip-speed bound), then a
    flag: may the spring length have an extremum inside the cell."""
    M, Vg, dVg, l, dl, tau = (COEFFS.index(n) for n in ("M", "Vg", "dVg", "l", "dl", "tau"))
    out = np.empty((len(cc), 18))
    for col, j in zip(range(0, 12, 2), (tau, M, Vg, l, dVg, dl)):
        out[:, col], out[:, col + 1] = _cubic_ranges(cc[:, j])
    for col, j in zip(range(12, 16), (Vg, l, tau, M)):
        q = cc[:, j]
        out[:, col] = q[:, 0] + 0.5 * (q[:, 1] + 0.5 * (q[:, 2] + 0.5 * q[:, 3]))
    # may l' vanish in the cell? (roots of q1 + 2 q2 s + 3 q3 s^2 near [0, 1]; else the
    # kernel's spring-length extremes skip the cell)
    q = cc[:, l]
    A, B, C = 3 * q[:, 3], 2 * q[:, 2], q[:, 1]
    with np.errstate(all="ignore"):
        D = B * B - 4 * A * C
        sq = np.sqrt(np.where(D >= 0, D, np.nan))
        lin = np.abs(A) < 1e-300
        r1 = np.where(lin, np.where(B != 0, -C / B, np.nan), (-B + sq) / (2 * A))
        r2 = np.where(lin, np.nan, (-B - sq) / (2 * A))
        near = lambda r: (r >= -1e-9) & (r <= 1 + 1e-9)  # noqa: E731
        out[:, 16] = (near(r1) | near(r2)).astype(float)
    out[:, 17] = 0.0
    return out


def _pieces(model, nodes: np.ndarray, h: float, fn=None) -> np.ndarray:
    """Cubic Hermite pieces (ncell, NC, 4) in the local variable s in [0, 1] of the
    coefficients (or of ``fn``'s: theta -> (values, theta-derivatives))."""
    fn = fn or model.coeffs
    v, dv = (np.asarray(a) for a in fn.map(len(nodes))(nodes))  # (NC, n+1) each
    f0, f1, d0, d1 = v[:, :-1], v[:, 1:], dv[:, :-1] * h, dv[:, 1:] * h
    cc = np.stack([f0, d0, 3 * (f1 - f0) - 2 * d0 - d1, 2 * (f0 - f1) + d0 + d1], axis=-1)
    return np.ascontiguousarray(cc.transpose(1, 0, 2)), v


class CoefficientTable:
    """Cubic Hermite table of the geometric coefficients over ``model.theta_range``.

    ``lid_mass`` is the mass it was built at; :attr:`mass_derivative` (built on first use)
    holds d/d(mass.lid) of M, dM, Vg, dVg on the same cells.
    """

    #: interpolation error aimed for; cells are refined (x4) up to MAX_CELLS to reach it
    TARGET_REL_ERROR = 1e-10
    MAX_CELLS = 1 << 15

    def __init__(self, model, cell_deg: float = 0.1):
        self.model = model
        self.lid_mass = float(model.mass.lid)
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
        self.cc, v = _pieces(model, nodes, h)                  # (ncell, NC, 4)
        self.meta = np.array([n, lo, h, self.lid_mass], float)
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

    def state(self) -> dict:
        """The arrays a table is restored from (:meth:`restore`; the disk cache keeps them)."""
        return {"cc": self.cc, "meta": self.meta, "error": np.array([self.max_rel_error])}

    @classmethod
    def restore(cls, model, state: dict) -> "CoefficientTable":
        """The table of ``model`` from :meth:`state`'s arrays, without evaluating anything."""
        t = cls.__new__(cls)
        t.model, t.lid_mass = model, float(model.mass.lid)
        t.cc = np.ascontiguousarray(state["cc"], float)
        t.meta = np.array(state["meta"], float)
        n, t.lo, t.h, _ = (float(v) for v in t.meta)
        t.ncell, t.hi = int(n), model.theta_range[1]
        t.max_rel_error = float(state["error"][0])
        if t.cc.shape[0] != t.ncell or t.meta[3] != t.lid_mass:
            raise ValueError("the table does not match its model")
        return t

    def _kernel_arrays(self) -> tuple[np.ndarray, np.ndarray]:
        """The kernel's views of ``cc`` (derived again whenever ``cc`` is replaced)."""
        if getattr(self, "_kernel_src", None) is not self.cc:
            self._kernel = (_kernel_layout(self.cc), _cell_ranges(self.cc))
            self._kernel_src = self.cc
        return self._kernel

    @property
    def cc_kernel(self) -> np.ndarray:
        """``cc`` in the kernel's power-major layout (ncell, 4, NC), 64-byte aligned."""
        return self._kernel_arrays()[0]

    @property
    def cell_ranges(self) -> np.ndarray:
        """Per-cell ranges the kernel's early exit and spring extremes use (ncell, 18)."""
        return self._kernel_arrays()[1]

    @cached_property
    def mass_derivative(self) -> np.ndarray:
        """d/d(mass.lid) of the pieces of M, dM, Vg, dVg: array (ncell, 4, 4) laid out as
        ``cc`` (cell, coefficient, power).

        The coefficients are affine in the lid's mass, so the difference quotient of the
        tables at m0 and 2 m0 (same cells, same inertia rule: derived I = m L^2/12 unless
        ``mass.inertia_lid`` is configured) is exact up to rounding.
        """
        from .model import LidModel
        cfg, m0 = self.model.cfg, self.lid_mass
        other = LidModel(cfg.replace(mass={"lid": 2.0 * m0}))
        nodes = np.linspace(self.lo, self.hi, self.ncell + 1)
        cc2, _ = _pieces(other, nodes, self.h)
        return np.ascontiguousarray((cc2[:, :4] - self.cc[:, :4]) / m0)

    @cached_property
    def mass_derivative_kernel(self) -> np.ndarray:
        """:attr:`mass_derivative` in the kernel's layout, zero for the other coefficients."""
        d = np.zeros_like(self.cc)
        d[:, :4] = self.mass_derivative
        return _kernel_layout(d)

    def evaluate(self, theta, lid_mass=None) -> np.ndarray:
        """Interpolated coefficients at angles ``theta`` (shape (len, NC)), for the lid mass
        ``lid_mass`` (scalar or one per angle; None or NaN: the table's own mass)."""
        th = np.atleast_1d(np.asarray(theta, float))
        i, s = self._cell(th)
        q = self.cc[i]
        c = q[..., 0] + s * (q[..., 1] + s * (q[..., 2] + s * q[..., 3]))
        dm = self.mass_offsets(lid_mass, th.shape)
        if dm is not None:
            c = c.copy()
            c[:, :4] += dm[:, None] * self._mass_slope(i, s)
        return c

    def _cell(self, th: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Cells of the angles ``th`` and their local variables s in [0, 1] (a column)."""
        x = np.clip((th - self.lo) / self.h, 0, self.ncell)
        i = np.minimum(x.astype(int), self.ncell - 1)
        return i, (x - i)[:, None]

    def mass_offsets(self, lid_mass, shape) -> np.ndarray | None:
        """``lid_mass`` (scalar or per row; None or NaN: the table's own) less the table's
        mass, broadcast to ``shape``; None when every row is at the table's mass."""
        if lid_mass is None:
            return None
        dm = np.broadcast_to(np.asarray(lid_mass, float), shape) - self.lid_mass
        dm = np.where(np.isfinite(dm), dm, 0.0)
        return dm if np.any(dm != 0) else None

    @cached_property
    def extra(self) -> np.ndarray:
        """The element columns of the extra table (:data:`softclose.dynamics.EXTRA_COEFFS`,
        those of the elements added since the seed) as cubic pieces on the same cells,
        (ncell, len(EXTRA_COEFFS), 4): built on first use, when a stroke has such an element
        (their interpolation error is measured like the table's, ``max_rel_error_extra``)."""
        nodes = np.linspace(self.lo, self.hi, self.ncell + 1)
        xc, v = _pieces(self.model, nodes, self.h, self.model.xcoeffs)
        mid = 0.5 * (nodes[:-1] + nodes[1:])
        exact = np.asarray(self.model.xcoeffs.map(self.ncell)(mid)[0])
        interp = (xc[:, :, 0] + 0.5 * xc[:, :, 1] + 0.25 * xc[:, :, 2] + 0.125 * xc[:, :, 3]).T
        scale = np.maximum(np.abs(v).max(axis=1, keepdims=True), 1e-300)
        self.max_rel_error_extra = float((np.abs(interp - exact) / scale).max())
        if not np.all(np.isfinite(xc)):
            raise NumericalError("an element's tabulated coordinate is not finite on the "
                                 "stroke range; the geometry is at or near a toggle position")
        return xc

    @cached_property
    def extra_kernel(self) -> np.ndarray:
        """:attr:`extra` in the kernel's layout (ncell, 4, NX), zero-padded to NX columns."""
        x = np.zeros((self.ncell, NX, 4))
        x[:, :len(EXTRA_COEFFS)] = self.extra
        return _kernel_layout(x)

    def rows(self, theta, n: int, lid_mass=None) -> np.ndarray:
        """:meth:`evaluate` for ``n`` rows at ``theta`` (scalar or one per row). At one angle
        the cell is looked up once and its row broadcast -- the same arithmetic per row as
        evaluating each row, so the same numbers -- instead of gathering n copies."""
        th = np.asarray(theta, float)
        if th.ndim:
            return self.evaluate(np.broadcast_to(th, (n,)), lid_mass)
        c = np.broadcast_to(self.evaluate(th[None]), (n, self.cc.shape[1]))
        dm = self.mass_offsets(lid_mass, (n,))
        if dm is None:
            return c
        c = c.copy()
        c[:, :4] += dm[:, None] * self.mass_slope(float(th))
        return c

    def rows_extra(self, theta, n: int) -> np.ndarray:
        """The element columns of the extra table at ``theta`` (scalar or one per row), n rows."""
        th = np.broadcast_to(np.atleast_1d(np.asarray(theta, float)), (n,))
        i, s = self._cell(th)
        q = self.extra[i]
        return q[..., 0] + s * (q[..., 1] + s * (q[..., 2] + s * q[..., 3]))

    def _mass_slope(self, i: np.ndarray, s: np.ndarray) -> np.ndarray:
        r = self.mass_derivative[i]
        return r[..., 0] + s * (r[..., 1] + s * (r[..., 2] + s * r[..., 3]))

    def mass_slope(self, theta: float) -> np.ndarray:
        """d(M, dM, Vg, dVg)/d(lid mass) at one angle (shape (4,)), as :meth:`evaluate`
        uses it."""
        return self._mass_slope(*self._cell(np.array([theta], float)))[0]


_NP = len(elements.PARAMS)


def _extra(designs: np.ndarray, table: CoefficientTable) -> np.ndarray | None:
    """The extra table in the kernel's layout if any row has an element of it, else None."""
    return table.extra_kernel if elements.needs_extra(designs[:, :_NP]) else None


def _lid_masses(designs: np.ndarray, table: CoefficientTable) -> np.ndarray | None:
    """Validate the optional lid-mass column; the derivative table if any row needs it."""
    if designs.shape[1] == _NP + 1:
        return None
    if designs.shape[1] != _NP + 2:
        raise ConfigError(f"design rows: expected {_NP + 1} or {_NP + 2} columns "
                          f"({', '.join(DESIGN_COLUMNS)}), got {designs.shape[1]}")
    m = designs[:, _NP + 1]
    given = ~np.isnan(m)
    if np.any(given & ~(np.isfinite(m) & (m > 0))):
        bad = m[given & ~(np.isfinite(m) & (m > 0))][0]
        raise ConfigError(f"lid_mass: must be a positive number of kg, got {bad}")
    if np.any(given & (m != table.lid_mass)):
        return table.mass_derivative_kernel
    return None


def run_strokes(table: CoefficientTable, method: Method, step: float, t_max: float,
                theta0: float, theta_closed: float, designs: np.ndarray,
                threads: int | None = None, early_exit: bool = True) -> np.ndarray:
    """Metrics of strokes for the design rows ``designs`` (see the module doc: the kernel's
    rows, SI, with or without the lid-mass column). ``early_exit=False`` integrates every
    open stroke to ``t_max``.

    Returns an array (n, len(OUT_FIELDS)). Work is split across threads.
    """
    lib = load()
    designs = np.ascontiguousarray(np.atleast_2d(designs), float)
    dcc = _lid_masses(designs, table)
    xcc = _extra(designs, table)
    cc, ranges = table.cc_kernel, table.cell_ranges      # held here while C reads them
    n, ncol = designs.shape
    out = np.empty((n, len(OUT_FIELDS)))
    tab = method.packed()
    cpus = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    threads = threads or min(cpus or 1, 8)
    threads = max(1, min(threads, n // 64 or 1))

    def work(a, b):
        lib.sc_strokes(_ptr(table.meta), _ptr(cc), _ptr(dcc), _ptr(xcc), _ptr(ranges),
                       _ptr(tab), step, t_max, theta0, theta_closed, b - a, ncol,
                       _ptr(designs[a:b]), int(early_exit), _ptr(out[a:b]))

    if threads == 1:
        work(0, n)
    else:
        # more chunks than threads: strokes differ in length (a slammed lid takes 150 steps,
        # a creeping one runs to t_max), so equal halves would leave one core idle; each
        # chunk a quarter of a thread's share of what is left (at least 64 rows), so the
        # last ones are short and the threads finish together
        bounds = [0]
        while bounds[-1] < n:
            left = n - bounds[-1]
            bounds.append(bounds[-1] + min(left, max(64, left // (4 * threads))))
        from concurrent.futures import ThreadPoolExecutor
        with ThreadPoolExecutor(threads) as ex:
            list(ex.map(lambda ab: work(*ab), zip(bounds[:-1], bounds[1:])))
    return out


def run_stroke_trajectory(table, method, step, t_max, theta0, theta_closed, design,
                          early_exit: bool = False):
    """One stroke with its trajectory: (metrics row, array of (t, theta, theta')).

    By default an open stroke is integrated to ``t_max`` (a figure shows all of it); the
    metrics are the same either way.
    """
    lib = load()
    design = np.ascontiguousarray(np.atleast_1d(design), float)
    dcc = _lid_masses(design[None, :], table)
    xcc = _extra(design[None, :], table)
    cc, ranges = table.cc_kernel, table.cell_ranges
    cap = int(math.ceil(t_max / step)) + 3
    traj = np.empty((cap, 3))
    out = np.empty(len(OUT_FIELDS))
    nt = ctypes.c_long(0)
    tab = method.packed()
    lib.sc_stroke_traj(_ptr(table.meta), _ptr(cc), _ptr(dcc), _ptr(xcc), _ptr(ranges),
                       _ptr(tab), step, t_max, theta0, theta_closed, len(design), _ptr(design),
                       int(early_exit), _ptr(out), _ptr(traj), cap, ctypes.byref(nt))
    return out, traj[:nt.value].copy()


def kernel_step(table, method, p, h, x0, lid_mass=None) -> np.ndarray:
    """One step of the kernel (for tests); ``p`` the parameter vector (config units),
    ``lid_mass`` None for the table's own."""
    lib = load()
    x1 = np.empty(2)
    mass = np.nan if lid_mass is None else float(lid_mass)
    from .problem import as_params
    d = np.ascontiguousarray(np.r_[kernel_rows(as_params(p)), 0.0, mass], float)
    dcc = _lid_masses(d[None, :], table)
    xcc = _extra(d[None, :], table)
    cc, tab, x0 = table.cc_kernel, method.packed(), np.ascontiguousarray(x0, float)
    st = lib.sc_step(_ptr(table.meta), _ptr(cc), _ptr(dcc), _ptr(xcc), _ptr(tab), _ptr(d), h,
                     _ptr(x0), _ptr(x1))
    if st:
        raise NumericalError(f"kernel step failed: {STATUS.get(st, st)}")
    return x1


def not_closed_reasons(out) -> np.ndarray:
    """Why each stroke did not close, as text ("" for a closed or failed stroke).

    ``out``: kernel rows (n, len(OUT_FIELDS)) or one row, or a mapping with the columns
    ``status``, ``stop_reason``, ``stop_theta`` (e.g. ``Simulator.run_batch``'s result).
    """
    if hasattr(out, "keys"):
        status, reason, theta = (np.atleast_1d(np.asarray(out[k], float))
                                 for k in ("status", "stop_reason", "stop_theta"))
    else:
        a = np.atleast_2d(np.asarray(out, float))
        status, reason, theta = (a[:, _COL[k]] for k in ("status", "stop_reason", "stop_theta"))
    text = np.full(status.shape, "", dtype=object)
    open_ = status == 1
    for code, head in ((1, "cannot reach the rim: energy below the barrier at theta = "),
                       (2, "held open at theta = ")):
        m = np.nonzero(open_ & (reason == code))[0]
        if len(m):   # each distinct angle formatted once (many rows share their well)
            t = theta[m]
            deg, at = np.unique(np.where(np.isfinite(t), np.degrees(t), 0.0),
                                return_inverse=True)
            words = np.array([f"{head}{d:.1f} deg" for d in deg.tolist()], dtype=object)
            text[m] = words[np.asarray(at).ravel()]
    text[open_ & (reason == 0)] = ("still moving towards the rim at t_max "
                                   "(too slow to close in time)")
    return text
