"""The compiled stroke kernel (``_kernel.c``): loading it, its rows, its calls.

The kernel reads the geometry from a :class:`~softclose.simulation.kernel.table.CoefficientTable` (no closure
is solved per step) and integrates strokes of the design rows below.

Design rows
-----------
:func:`run_strokes` integrates one stroke per row of a float array (:data:`DESIGN_COLUMNS`)::

    the parameter vector p (:data:`softclose.model.elements.PARAMS`: k (N/m), l0 (m), c (N s/m),
    c_rot (N m s/rad), then the elements' added since), energy_tol (J)[, lid_mass (kg)
    [, the attachment points (m): spring_anchor_x, _y, lid_e_x, _y, dashpot_anchor_x, _y,
    dashpot_lid_x, _y]]

The kernel takes p in SI (an angle given in degrees in radians: :func:`kernel_rows`
converts); its laws are the registry's (:mod:`softclose.model.elements`), stated once in the
element section of ``_kernel.c``. The end damper (``end_damper_c``, ``end_damper_angle``)
acts while the lid is below its angle: the kernel carries the engagement as a state of the
stroke, locates each crossing of the angle as an event (a last step of solved length, like
the closing: to the method's order) and reports the first engagement moving down as
``engage_time`` / ``engage_theta_dot`` (0 and 0 when released below the angle, NaN when it
never engages; an angle at or below ``theta_closed`` never acts).

``energy_tol`` is the energy rise that flags the stroke unstable (and the margin of the
early exit, below). ``lid_mass`` is the lid's mass for that row; NaN, or a missing column,
means the table's own mass (``table.lid_mass``). The coefficients M, dM, Vg, dVg are affine
in the lid's mass (M = m |dG1/dtheta|^2 + I_lid + cranks, Vg = g (m y_G1 + cranks), with
I_lid = m L^2 / 12 when it is derived, or fixed when ``mass.inertia_lid`` is configured), so
a row's coefficients are ``c(m0) + (m - m0) dc/dm`` with dc/dm from
:attr:`~softclose.simulation.kernel.table.CoefficientTable.mass_derivative`: 10^5 Monte Carlo samples of ``mass.lid`` need no
model rebuild. A row at the table's mass never reads that table (bit-identical results).

The point columns (:data:`POINT_COLUMNS`; after ``lid_mass``, which must then be present,
NaN for the table's) give a row its own attachment points: the spring's anchor D (world) and
lid point E (lid frame, from pin A), the dashpot's anchor F and lid point H. The spring's
four, or the dashpot's, are NaN for the table's own points (:func:`point_rows` turns a row's
points into this form: a partly given set is completed from the table's lid, and a set
equal to the table's own becomes NaN, so such a row gives the same bits as without the
columns). Every lid point is P = A(theta) + R(theta) p, so from the table's pose pieces
(:attr:`~softclose.simulation.kernel.table.CoefficientTable.pose`: the crank pin A, its slope, cos, sin, exact
at the nodes) each stroke builds its own cubic pieces of the spring's l, dl/dtheta and the
dashpot's (dl_d/dtheta)^2 on the cells it visits, from the node values and slopes, as a table
built at those points builds its own: a sample over placements needs no model per value, and
agrees with a model at those points to the rounding of the node values (0 to 4e-13 relative
measured). The early exit stays exact for such rows (the ranges of its own pieces; the
spring-length extremes searched on them: the kernel's section PER-ROW ATTACHMENT POINTS).
A stroke at a row's points that takes the spring below 2 mm is reported as invalid
(:data:`softclose.simulation.simulator.MIN_POINT_LENGTH`).

A spring of a kind (extension: valid while l >= l0; compression: l <= l0) outside that range
at every angle from ``theta_closed`` to ``theta0`` makes the design invalid whatever its
stroke does: the kernel does not integrate it, as the adaptive reference does not (0 steps,
stop_time 0; its visited range is [theta_closed, theta0], the spring's extremes are those
over it, and the statics then give the reference's reason, "over the whole stroke"). It is
decided with a margin of 1e-6 max(|l|, 1) m, so that every such row is invalid there too; a
row nearer its free length is integrated and judged after its stroke, as before.

Early exit
----------
A stroke that can no longer close nor change any metric is stopped before ``t_max``; why
that is exact, and what it assumes, is stated once in the documentation's page on the stroke
kernel (docs/kernel.md).

Why a stroke stays open is recorded in ``stop_reason`` (1: trapped behind a barrier, a
maximum of V between the lid and the rim, ``stop_theta`` = its top; 2: held open, the
potential rises from the lid's well all the way to the rim, ``stop_theta`` = the stable
equilibrium at the bottom of the well, V'(theta) = 0; 3: held by friction, the lid came to
rest where |V'| does not exceed the friction moment, ``stop_theta`` = that angle, located to
the method's order), also for a stroke that ran to t_max when the energy then decides it; ``stop_time`` is when integration stopped (the closing
time, the early exit, t_max or a failure). :func:`not_closed_reasons` turns them into text.

The kernel is built by ``pip install`` as the extension ``softclose.simulation.kernel._kernel``; in a source
checkout without it (or with one older than ``_kernel.c``), it is compiled once with the
system C compiler into the cache folder of :mod:`softclose.buildcache` (``SOFTCLOSE_CACHE``;
for this process only when there is none that can be written). Calls go through ctypes, which releases the GIL, so
batches run on all cores in threads. On a CPU with AVX2 the strokes of a thread advance as
SIMD vectors (the same numbers bit for bit as the lane-by-lane code, which the environment
variable ``SC_SCALAR=1`` selects).
"""

from __future__ import annotations

import ctypes
import math
import os

import numpy as np

from ...model import elements
from ...errors import ConfigError, NumericalError
from ...numerics.integrators import Method
from .layout import (DESIGN_COLUMNS, KERNEL_ABI, LAYOUT, NPT, OUT_FIELDS, POINT_COLUMNS,  # noqa: F401
                     SI)
from .library import load
from .table import POINT_NAMES, CoefficientTable
from ...problem import RANGES, as_params
from ..stroke import StrokeStatus

_COL = {name: i for i, name in enumerate(OUT_FIELDS)}


def kernel_rows(P: np.ndarray) -> np.ndarray:
    """Rows of the parameter vector in the kernel's units (SI: an angle in degrees becomes
    radians); the columns already in SI are passed through untouched."""
    P = np.array(P, float)
    scale = SI != 1.0
    if scale.any():
        P[..., scale] = P[..., scale] * SI[scale]
    return P


def cores() -> int:
    """The cores this process may use (its CPU affinity), at least 1."""
    n = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    return max(1, n or 1)


#: most kernel threads a batch uses by default
MAX_THREADS = 8


def kernel_threads(threads: int | None = None) -> int:
    """The kernel threads asked for, or by default one per core, at most MAX_THREADS."""
    return threads or min(cores(), MAX_THREADS)


def _ptr(a: np.ndarray | None):
    if a is None:
        return ctypes.POINTER(ctypes.c_double)()
    return a.ctypes.data_as(ctypes.POINTER(ctypes.c_double))


_NP = len(elements.PARAMS)


def _coordinates(designs: np.ndarray, table: CoefficientTable) -> np.ndarray | None:
    """The coordinate table in the kernel's layout if any row has an element of it, else None."""
    if elements.needs_coordinates(designs[:, :_NP], table.model.mounting):
        return table.coordinates_kernel
    return None


def _lid_masses(designs: np.ndarray, table: CoefficientTable) -> np.ndarray | None:
    """Validate the optional lid-mass column; the derivative table if any row needs it."""
    if designs.shape[1] == _NP + 1:
        return None
    if designs.shape[1] not in (_NP + 2, _NP + 2 + NPT):
        raise ConfigError(f"design rows: expected {_NP + 1}, {_NP + 2} or {_NP + 2 + NPT} "
                          f"columns ({', '.join(DESIGN_COLUMNS)}), got {designs.shape[1]}")
    m = designs[:, _NP + 1]
    given = ~np.isnan(m)
    if np.any(given & ~(np.isfinite(m) & (m > 0))):
        bad = m[given & ~(np.isfinite(m) & (m > 0))][0]
        raise ConfigError(f"lid_mass: must be a positive number of kg, got {bad}")
    if np.any(given & (m != table.lid_mass)):
        return table.mass_derivative_kernel
    return None


#: the placement keys of the point columns, in order (``geometry.spring_anchor[0]`` ...)
POINT_KEYS = tuple(f"geometry.{name}[{i}]" for name in POINT_NAMES for i in (0, 1))
_POINT_INDEX = {**{k: j for j, k in enumerate(POINT_KEYS)},
                **{k.removeprefix("geometry."): j for j, k in enumerate(POINT_KEYS)}}


def point_rows(table: CoefficientTable, points, n: int) -> np.ndarray | None:
    """A batch's own attachment points as the kernel's point columns (n, NPT), or None
    when no row has points other than the table's.

    ``points``: None; an array (n, 8) or (8,) in the order of :data:`POINT_KEYS` (m; NaN:
    the table's own component); or a mapping {placement key (``geometry.lid_e[0]`` or
    ``lid_e[0]``): a value or one per row}. A spring (or dashpot) whose points are partly
    given takes the others from the table's lid; one whose points are the table's own
    becomes NaN (it reads the table's columns: the same bits as without points). A given
    component must be a finite number within the key's range (ConfigError naming it)."""
    if points is None:
        return None
    if hasattr(points, "keys"):
        X = np.full((n, NPT), np.nan)
        for k, v in points.items():
            if k not in _POINT_INDEX:
                raise ConfigError(f"points: {k} is not an attachment point's component "
                                  f"(one of {', '.join(POINT_KEYS)})")
            X[:, _POINT_INDEX[k]] = np.broadcast_to(np.asarray(v, float), (n,))
    else:
        X = np.array(np.broadcast_to(np.asarray(points, float), (n, NPT)))
    for j, k in enumerate(POINT_KEYS):
        lo, hi, unit = RANGES[k.split("[")[0]]
        x = X[:, j]
        bad = ~np.isnan(x) & ~((x >= lo) & (x <= hi))
        if bad.any():
            raise ConfigError(f"{k}: must be a finite number of {unit} within [{lo:g}, {hi:g}], "
                              f"got {x[bad][0]}")
    own = table.own_points
    for g in (slice(0, 4), slice(4, 8)):
        blk = X[:, g]
        given = ~np.isnan(blk)
        blk = np.where(given, blk, own[g])
        blk[~given.any(axis=1) | (blk == own[g]).all(axis=1)] = np.nan
        X[:, g] = blk
    return X if not np.isnan(X).all() else None


def point_columns(table: CoefficientTable, theta, points) -> np.ndarray:
    """The spring's l, dl and the dashpot's dd of rows with their own points (``points``
    (n, NPT), the kernel's convention) at ``theta`` -- a scalar, one per row (n,), a grid per
    row (n, G) or a grid shared by the rows (1, G) -- from the rows' own pieces as the
    kernel's strokes read them: array (n, G, 3) (G = 1 for a scalar or (n,)), NaN where a
    row has the table's own (or outside the table). Rows split across threads."""
    lib = load()
    pts = np.ascontiguousarray(np.atleast_2d(np.asarray(points, float)))
    n = len(pts)
    th = np.asarray(theta, float)
    shared = th.ndim == 0 or (th.ndim == 2 and th.shape[0] == 1 and n != 1)
    th2 = np.ascontiguousarray(th.reshape(1, -1) if th.ndim == 0 else
                               (th.reshape(n, -1) if not shared else th))
    G = th2.shape[1]
    out = np.empty((n, G, 3))
    pcc, cc = table.pose_kernel, table.cc_kernel

    def work(a, b):
        lib.sc_point_columns(_ptr(table.meta), _ptr(cc), _ptr(pcc), b - a,
                             _ptr(pts[a:b]), G, _ptr(th2 if shared else th2[a:b]),
                             int(shared), _ptr(out[a:b]))
    if n * G < 20000:
        work(0, n)
    else:
        import threading
        half = n // 2
        t = threading.Thread(target=work, args=(half, n))
        t.start()
        work(0, half)
        t.join()
    return out


def point_lengths(table: CoefficientTable, theta, points) -> dict:
    """The spring's l, dl and the dashpot's dd of rows with their own attachment points at
    ``theta`` (one per row, or a grid per row: shape (n,) or (n, G); or a scalar), from the
    rows' own pieces as the kernel reads them (:func:`point_columns`: the pieces a table
    built at the row's points holds).

    A grid shared by the rows is given as shape (1, G) (the pose is evaluated once).
    ``points`` (n, 8) in the kernel's convention (:func:`point_rows`): the spring's four
    columns, or the dashpot's, NaN where the row has the table's own. Returns {"l", "dl",
    "dd"}: arrays of theta's broadcast shape (n, ...), NaN where the row has the table's own
    (the caller keeps the table's column there)."""
    pts = np.atleast_2d(np.asarray(points, float))
    n = len(pts)
    th = np.asarray(theta, float)
    shape = (n,) if th.ndim <= 1 else (n, th.shape[1])
    c = point_columns(table, th, pts)
    return {name: c[..., j].reshape(shape) for j, name in enumerate(("l", "dl", "dd"))}


def point_grid(table: CoefficientTable, theta, points, what: str = "all",
               ab=None) -> np.ndarray:
    """:func:`point_columns` on a grid of angles -- (G,) shared by the rows, or (n, G) one
    per row -- from the pose pieces interpolated there rather than the rows' own pieces
    (to the tables' interpolation error, ~1e-10 relative, of them; no piece is built, so a
    grid over a whole stroke costs a few ns an angle): for the statics that scan a stroke
    (the opening effort, where a spring leaves its valid range). Array (n, G, 3); with
    ``what="l"`` the spring's length alone (n, G); with ``what="slope"`` its term of the
    slope dV/dtheta, (a + b l) l' with ``ab`` (n, 2) the rows' affine law T = a + b l."""
    lib = load()
    pts = np.ascontiguousarray(np.atleast_2d(np.asarray(points, float)))
    n = len(pts)
    th = np.ascontiguousarray(np.asarray(theta, float))
    per_row = th.ndim == 2
    G = th.shape[-1]
    mode = {"all": 0, "l": 1, "slope": 2}[what]
    out = np.empty((n, G, 3) if mode == 0 else (n, G))
    ab = None if ab is None else np.ascontiguousarray(ab, float)
    pcc = table.pose_kernel
    lib.sc_point_grid(_ptr(table.meta), _ptr(pcc), n, _ptr(pts), G, _ptr(th), int(per_row),
                      mode, _ptr(ab), _ptr(out))
    return out


def point_opening(table: CoefficientTable, theta, points, ab, base, idx, tau) -> np.ndarray:
    """The opening effort of rows with their own spring points (:func:`point_grid`'s lengths
    on the grid ``theta`` (G,)): per row, the largest (base[idx] + (a + b l) l') / tau,
    refined by the parabola through it and its neighbours (``ab`` (n, 2): the spring's affine
    law of each row; ``base`` (u, G): the slope of the other elements and friction of the
    rows' parameter sets, ``idx`` (n,) which; ``tau`` (G,): the tip's lever)."""
    lib = load()
    pts = np.ascontiguousarray(np.atleast_2d(np.asarray(points, float)))
    n = len(pts)
    th = np.ascontiguousarray(theta, float)
    ab = np.ascontiguousarray(ab, float)
    base = np.ascontiguousarray(base, float)
    idx = np.ascontiguousarray(idx, np.int64)
    tau = np.ascontiguousarray(tau, float)
    out = np.empty(n)
    lib.sc_point_opening(_ptr(table.meta), _ptr(table.pose_kernel), n, _ptr(pts), _ptr(ab),
                         len(th), _ptr(th), _ptr(base),
                         idx.ctypes.data_as(ctypes.POINTER(ctypes.c_long)), _ptr(tau),
                         _ptr(out))
    return out


def _pose(designs: np.ndarray, table: CoefficientTable) -> np.ndarray | None:
    """The pose table in the kernel's layout if any row has its own points, else None."""
    if designs.shape[1] != _NP + 2 + NPT or np.isnan(designs[:, _NP + 2:]).all():
        return None
    return table.pose_kernel


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
    xcc = _coordinates(designs, table)
    pcc = _pose(designs, table)
    cc, ranges = table.cc_kernel, table.cell_ranges      # held here while C reads them
    n, ncol = designs.shape
    out = np.empty((n, len(OUT_FIELDS)))
    tab = method.packed()
    threads = kernel_threads(threads)
    threads = max(1, min(threads, n // 64 or 1))

    def work(a, b):
        lib.sc_strokes(_ptr(table.meta), _ptr(cc), _ptr(dcc), _ptr(xcc), _ptr(ranges),
                       _ptr(pcc), _ptr(tab), step, t_max, theta0, theta_closed, b - a, ncol,
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
        # (plain threads, this one among them: concurrent.futures costs ~5 ms to import,
        # a tenth of a command's own work; the C calls release the GIL)
        import threading
        chunks, lock = iter(list(zip(bounds[:-1], bounds[1:]))), threading.Lock()
        failed: list = []

        def worker():
            try:
                while not failed:
                    with lock:
                        ab = next(chunks, None)
                    if ab is None:
                        return
                    work(*ab)
            except BaseException as exc:     # noqa: BLE001  (raised below, in this thread)
                failed.append(exc)
        others = [threading.Thread(target=worker, daemon=True) for _ in range(threads - 1)]
        for t in others:
            t.start()
        worker()
        for t in others:
            t.join()
        if failed:
            raise failed[0]
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
    xcc = _coordinates(design[None, :], table)
    pcc = _pose(design[None, :], table)
    cc, ranges = table.cc_kernel, table.cell_ranges
    cap = int(math.ceil(t_max / step)) + 3
    traj = np.empty((cap, 3))
    out = np.empty(len(OUT_FIELDS))
    nt = ctypes.c_long(0)
    tab = method.packed()
    lib.sc_stroke_traj(_ptr(table.meta), _ptr(cc), _ptr(dcc), _ptr(xcc), _ptr(ranges),
                       _ptr(pcc), _ptr(tab), step, t_max, theta0, theta_closed, len(design),
                       _ptr(design),
                       int(early_exit), _ptr(out), _ptr(traj), cap, ctypes.byref(nt))
    return out, traj[:nt.value].copy()


def kernel_step(table, method, p, h, x0, lid_mass=None, points=None) -> np.ndarray:
    """One step of the kernel (for tests); ``p`` the parameter vector (config units),
    ``lid_mass`` None for the table's own, ``points`` as :func:`point_rows` takes them."""
    lib = load()
    x1 = np.empty(2)
    mass = np.nan if lid_mass is None else float(lid_mass)
    pts = point_rows(table, points, 1)
    pts = np.full(NPT, np.nan) if pts is None else pts[0]
    d = np.ascontiguousarray(np.r_[kernel_rows(as_params(p)), 0.0, mass, pts], float)
    dcc = _lid_masses(d[None, :], table)
    xcc = _coordinates(d[None, :], table)
    pcc = _pose(d[None, :], table)
    cc, tab, x0 = table.cc_kernel, method.packed(), np.ascontiguousarray(x0, float)
    st = lib.sc_step(_ptr(table.meta), _ptr(cc), _ptr(dcc), _ptr(xcc), _ptr(pcc), _ptr(tab),
                     _ptr(d), h, _ptr(x0), _ptr(x1))
    if st:
        what = StrokeStatus(st).text if 0 <= st < len(StrokeStatus) else st
        raise NumericalError(f"kernel step failed: {what}")
    return x1


def leaves(theta, q, bound, short) -> tuple[np.ndarray, np.ndarray]:
    """Per row of ``q`` (m, G), a coordinate on the row's angles ``theta`` (m, G): where it
    crosses ``bound`` (m,) -- the edge of the region beyond it (``short`` (m,): below it,
    else above) nearest its worst point, NaN when it is beyond on the whole grid -- and
    where it lies furthest beyond (refined by a parabola), rad: the arithmetic of
    :func:`softclose.simulation.statics._leaves` in C (``sc_leaves``), the same numbers."""
    lib = load()
    th = np.ascontiguousarray(theta, float)
    qq = np.ascontiguousarray(q, float)
    m, G = th.shape
    b = np.ascontiguousarray(np.broadcast_to(np.asarray(bound, float), (m,)))
    sh = np.ascontiguousarray(np.broadcast_to(np.asarray(short, float), (m,)))
    edge, worst = np.empty(m), np.empty(m)
    lib.sc_leaves(m, G, _ptr(th), _ptr(qq), _ptr(b), _ptr(sh), _ptr(edge), _ptr(worst))
    return edge, worst


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
    open_ = status == StrokeStatus.NOT_CLOSED
    for code, head in ((1, "cannot reach the rim: energy below the barrier at theta = "),
                       (2, "held open at theta = "), (3, "held by friction at theta = ")):
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
