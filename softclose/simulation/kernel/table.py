"""The coefficient table: the geometry of the equation of motion, tabulated once.

"Skip what a scene doesn't need": with the geometry fixed, the equation of motion
depends on theta only through coefficients (:data:`softclose.model.dynamics.COEFFS`: the inertia,
the seed's elements' columns, the tip's lever; and, when a stroke has an element at a
pivot, its columns :data:`softclose.model.dynamics.COORDINATE_COEFFS` in a second table, the
coordinate table), so
no closure is solved per step. :class:`CoefficientTable` evaluates them and their exact
theta-derivatives (CasADi AD) on a uniform grid once, as cubic Hermite pieces; the
interpolation error is measured at every cell midpoint and kept in ``max_rel_error``. The
C kernel (:mod:`softclose.simulation.kernel.binding`) reads the pieces in its own layout, with the per-cell
ranges its early exit uses; :mod:`softclose.simulation.statics` evaluates them for rows of designs.
"""

from __future__ import annotations

import math
from functools import cached_property

import numpy as np

from ...model import elements
from ...model.dynamics import COEFFS, pose
from ...errors import NumericalError
from ...model.lid import LidModel
from ...model.resolved import LidCase

#: element columns per row of the coordinate table (the kernel's NX: its columns, then zeros)
NX = 4
#: the pose table's columns (per-row attachment points: :meth:`CoefficientTable.pose`), and
#: its width in the kernel (NPOSE: those columns, then zeros)
POSE = ("Ax", "Ay", "dAx", "dAy", "cos", "sin")
NPOSE = 8
#: the attachment points a row may carry, in the kernel's order: the spring's anchor D
#: (world), its lid point E (lid frame, from A), the dashpot's anchor F (world), its lid
#: point H (lid frame) -- x, y each (:data:`softclose.config.free.PLACEMENT_KEYS`)
POINT_NAMES = ("spring_anchor", "lid_e", "dashpot_anchor", "dashpot_lid")


def _kernel_layout(cc: np.ndarray, width: int | None = None) -> np.ndarray:
    """(ncell, NC, 4) pieces -> the kernel's power-major (ncell, 4, NC), 64-byte aligned;
    with ``width``, the columns zero-padded to that many (the kernel's NX, NPOSE)."""
    if width is not None:
        padded = np.zeros((cc.shape[0], width, 4))
        padded[:, :cc.shape[1]] = cc
        cc = padded
    t = cc.transpose(0, 2, 1)
    buf = np.empty(t.size + 8)
    off = (-buf.ctypes.data % 64) // 8
    out = buf[off:off + t.size].reshape(t.shape)
    out[...] = t
    return out


def _finite(pieces: np.ndarray, what: str) -> np.ndarray:
    """``pieces``, or NumericalError (one line, naming ``what``) where one is not finite."""
    if not np.all(np.isfinite(pieces)):
        raise NumericalError(f"{what} is not finite on the stroke range; the geometry is at or "
                             "near a toggle position")
    return pieces


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
        self.meta = np.array([n, lo, h, self.lid_mass, *elements.kernel_meta(model.mounting)],
                             float)
        self.lo, self.hi, self.h, self.ncell = lo, hi, h, n
        # interpolation error at the cell midpoints, relative to each coefficient's scale
        mid = 0.5 * (nodes[:-1] + nodes[1:])
        exact = np.asarray(model.coeffs.map(n)(mid)[0])
        interp = (self.cc[:, :, 0] + 0.5 * self.cc[:, :, 1] + 0.25 * self.cc[:, :, 2]
                  + 0.125 * self.cc[:, :, 3]).T
        scale = np.maximum(np.abs(v).max(axis=1, keepdims=True), 1e-300)
        self.max_rel_error = float((np.abs(interp - exact) / scale).max())
        for j, name in enumerate(COEFFS):
            _finite(self.cc[:, j], f"the coefficient {name}")

    def state(self) -> dict:
        """The arrays a table is restored from (:meth:`restore`; the disk cache keeps them)."""
        return {"cc": self.cc, "meta": self.meta, "error": np.array([self.max_rel_error])}

    @classmethod
    def restore(cls, model, state: dict) -> "CoefficientTable":
        """The table of ``model`` from :meth:`state`'s arrays, without evaluating anything
        (the mass derivative and the element columns are derived again on first use)."""
        t = cls.__new__(cls)
        t.model, t.lid_mass = model, float(model.mass.lid)
        t.cc = np.ascontiguousarray(state["cc"], float)
        t.meta = np.array(state["meta"], float)
        n, t.lo, t.h, _ = (float(v) for v in t.meta[:4])
        t.ncell, t.hi = int(n), model.theta_range[1]
        t.max_rel_error = float(state["error"][0])
        expect = np.array([t.lid_mass, *elements.kernel_meta(model.mounting)], float)
        if t.cc.shape[0] != t.ncell or not np.array_equal(t.meta[3:], expect):
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
        m, m0 = self.model, self.lid_mass
        other = LidModel(LidCase(m.lid.with_lid_mass(2.0 * m0), m.stroke, m.design))
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

    def evaluate_column(self, theta, col: int) -> np.ndarray:
        """One interpolated coefficient (column ``col`` of :meth:`evaluate`) at angles
        ``theta`` (any shape), at the table's own mass."""
        th = np.asarray(theta, float)
        i, s = self._cell(th.ravel())
        q = self.cc[i, col]
        s = s[:, 0]
        return (q[:, 0] + s * (q[:, 1] + s * (q[:, 2] + s * q[:, 3]))).reshape(th.shape)

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
    def coordinates(self) -> np.ndarray:
        """The element columns of the coordinate table
        (:data:`softclose.model.dynamics.COORDINATE_COEFFS`, the torsion spring's and the
        rotary damper's at their pivots) as cubic pieces on the same cells,
        (ncell, len(COORDINATE_COEFFS), 4): built on first use, when a stroke has such an element
        (their interpolation error is measured like the table's, ``max_rel_error_coordinates``)."""
        nodes = np.linspace(self.lo, self.hi, self.ncell + 1)
        xc, v = _pieces(self.model, nodes, self.h, self.model.xcoeffs)
        mid = 0.5 * (nodes[:-1] + nodes[1:])
        exact = np.asarray(self.model.xcoeffs.map(self.ncell)(mid)[0])
        interp = (xc[:, :, 0] + 0.5 * xc[:, :, 1] + 0.25 * xc[:, :, 2] + 0.125 * xc[:, :, 3]).T
        scale = np.maximum(np.abs(v).max(axis=1, keepdims=True), 1e-300)
        self.max_rel_error_coordinates = float((np.abs(interp - exact) / scale).max())
        return _finite(xc, "an element's tabulated coordinate")

    @cached_property
    def coordinates_kernel(self) -> np.ndarray:
        """:attr:`coordinates` in the kernel's layout (ncell, 4, NX), zero-padded to NX columns."""
        return _kernel_layout(self.coordinates, NX)

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

    # -- per-row attachment points ----------------------------------------------------------
    @cached_property
    def pose(self) -> np.ndarray:
        """Cubic Hermite pieces (ncell, len(POSE), 4) of the crank pin A(theta), its slope
        A'(theta), cos theta and sin theta on the table's cells: every lid point is
        P = A + R(theta) p, so a row's own attachment points give their lengths from these
        (:func:`softclose.simulation.kernel.binding.point_lengths`; the kernel's ``pcc``). Built on first use,
        from the model's closure with exact derivatives, like the coefficients."""
        import casadi as ca
        m = self.model
        th = ca.SX.sym("theta")
        A = pose(th, m.geo, m.mass, m.sigma).points["A"]
        dA = ca.jacobian(A, th)
        vec = ca.vertcat(A, dA, ca.cos(th), ca.sin(th))
        fn = ca.Function("pose", [th], [vec, ca.jacobian(vec, th)])
        nodes = np.linspace(self.lo, self.hi, self.ncell + 1)
        pc, _ = _pieces(m, nodes, self.h, fn)
        return _finite(pc, "the crank pin's position")

    @cached_property
    def pose_kernel(self) -> np.ndarray:
        """:attr:`pose` in the kernel's layout (ncell, 4, NPOSE), zero-padded."""
        return _kernel_layout(self.pose, NPOSE)

    @cached_property
    def own_points(self) -> np.ndarray:
        """The lid's attachment points (8,), in the order of :data:`POINT_NAMES` (x, y
        each; the dashpot's lid point derived from ``lid_c`` when not given)."""
        g = self.model.geo
        return np.array([float(v) for name in POINT_NAMES for v in getattr(g, name)])

    def pose_at(self, theta) -> np.ndarray:
        """The pose columns (:data:`POSE`) at angles ``theta`` (any shape): (..., 6)."""
        th = np.asarray(theta, float)
        i, s = self._cell(th.ravel())
        q = self.pose[i]
        a = q[..., 0] + s * (q[..., 1] + s * (q[..., 2] + s * q[..., 3]))
        return a.reshape(th.shape + (len(POSE),))

    def rows_coordinates(self, theta, n: int) -> np.ndarray:
        """The element columns of the coordinate table at ``theta`` (scalar or one per row),
        n rows."""
        th = np.broadcast_to(np.atleast_1d(np.asarray(theta, float)), (n,))
        i, s = self._cell(th)
        q = self.coordinates[i]
        return q[..., 0] + s * (q[..., 1] + s * (q[..., 2] + s * q[..., 3]))

    def _mass_slope(self, i: np.ndarray, s: np.ndarray) -> np.ndarray:
        r = self.mass_derivative[i]
        return r[..., 0] + s * (r[..., 1] + s * (r[..., 2] + s * r[..., 3]))

    def mass_slope_at(self, theta) -> np.ndarray:
        """d(M, dM, Vg, dVg)/d(lid mass) at angles ``theta`` (shape (len, 4))."""
        return self._mass_slope(*self._cell(np.atleast_1d(np.asarray(theta, float))))

    def mass_slope(self, theta: float) -> np.ndarray:
        """d(M, dM, Vg, dVg)/d(lid mass) at one angle (shape (4,)), as :meth:`evaluate`
        uses it."""
        return self._mass_slope(*self._cell(np.array([theta], float)))[0]
