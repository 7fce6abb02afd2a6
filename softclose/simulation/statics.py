"""Statics over the coefficient table: the one dV/dtheta, applied to rows of designs.

:func:`softclose.model.dynamics.slope` states dV/dtheta once, as a sum over the machine elements;
this module evaluates it (and V, and the damping) from the tabulated columns of a
:class:`~softclose.simulation.kernel.table.CoefficientTable` for many designs at once: the holding moment at
the rim, the energy a stroke releases, theta'' at rest (the release check, the equilibria and
the linearisation of the stability check). The CasADi model's ``dV`` is the same sum on exact
expressions.

Every function takes ``points``: the rows' own attachment points in the kernel's convention
(:func:`softclose.simulation.kernel.binding.point_rows`: the spring's four columns, or the dashpot's, NaN for
the table's own), whose lengths come from the rows' own pieces as the kernel reads them
(:func:`softclose.simulation.kernel.binding.point_lengths`: the same numbers as a table built at
those points, to the rounding of the node values); the scans over a stroke (the opening
effort, where a spring leaves its range) read them from the pose pieces on their grid
(:func:`softclose.simulation.kernel.binding.point_grid`, within ~1e-10 relative of those).
"""

from __future__ import annotations

import numpy as np

from ..errors import ConfigError

from ..model import elements
from ..model.dynamics import COEFFS, COORDINATE_COEFFS, coordinates_of_columns, damping, potential, slope
from ..problem import as_params
from ..numerics.roots import illinois
from .kernel.binding import leaves, point_grid, point_lengths, point_opening


#: the kernel's point columns of each element that may have its own (spring: D, E;
#: dashpot: F, H), and the table columns they replace
POINT_BLOCKS = {"spring": (slice(0, 4), ("l", "dl")), "dashpot": (slice(4, 8), ("dd",))}


def with_points(table, theta, points, cols: dict) -> dict:
    """``cols`` (columns at ``theta`` for rows) with the spring's l, dl and the dashpot's dd
    of the rows that have their own points (``points``, the kernel's convention, or None)."""
    if points is None:
        return cols
    pts = np.atleast_2d(np.asarray(points, float))
    pc = point_lengths(table, theta, pts)
    out = dict(cols)
    for blk, names in POINT_BLOCKS.values():
        has = ~np.isnan(pts[:, blk.start])
        if has.any():
            has = has.reshape((-1,) + (1,) * (pc[names[0]].ndim - 1))
            for name in names:
                out[name] = np.where(has, pc[name], cols[name])
    return out


def columns(table, theta, n: int, lid_mass=None, coordinates: bool = False, points=None) -> dict:
    """The named columns at ``theta`` (scalar or one per row) for ``n`` rows at ``lid_mass``,
    with the element columns of the coordinate table when ``coordinates``, and the rows'
    own points' lengths (``points``)."""
    c = table.rows(theta, n, lid_mass)
    out = {name: c[:, j] for j, name in enumerate(COEFFS)}
    if coordinates:
        x = table.rows_coordinates(theta, n)
        out.update({name: x[:, j] for j, name in enumerate(COORDINATE_COEFFS)})
    return with_points(table, theta, points, out)


def _at(table, theta, P, lid_mass, points=None):
    P = as_params(np.atleast_2d(np.asarray(P, float)))
    mounting = table.model.mounting
    cols = columns(table, theta, len(P), lid_mass, elements.needs_coordinates(P, mounting), points)
    return cols, coordinates_of_columns(cols, mounting, theta), elements.params(P)


def potential_energy(table, theta, P, lid_mass=None, points=None) -> np.ndarray:
    """V (J) at ``theta`` (scalar or one per row) for rows of P, at ``lid_mass`` (scalar, one
    per row, or None: the table's mass)."""
    _, co, Pn = _at(table, theta, P, lid_mass, points)
    return potential(co, Pn)


def slopes(table, theta, P, lid_mass=None, points=None) -> np.ndarray:
    """dV/dtheta (N m) at ``theta`` for rows of P; at theta_closed, > 0 presses the lid shut."""
    _, co, Pn = _at(table, theta, P, lid_mass, points)
    return slope(co, Pn)


def holding_moments(table, theta_closed: float, P, lid_mass=None, points=None) -> np.ndarray:
    """dV/dtheta at ``theta_closed`` (N m, > 0 presses the lid shut) for rows of P."""
    return slopes(table, float(theta_closed), P, lid_mass, points)


def rest_theta_ddot(table, theta, P, lid_mass=None, points=None) -> np.ndarray:
    """theta'' at rest, -V'(theta) / M, at ``theta`` (one per row, or a scalar) for rows of P:
    > 0 pushes the lid open."""
    cols, co, Pn = _at(table, theta, P, lid_mass, points)
    return -slope(co, Pn) / cols["M"]


def rest_jacobian(table, theta, p, lid_mass=None, points=None) -> tuple[np.ndarray, np.ndarray]:
    """The linearised (theta, theta') Jacobian entries at rest at the angles ``theta`` for
    one design p (with its own ``points``, one row of the kernel's convention, or None):
    d theta''/d theta (central difference of -V'/M) and d theta''/d theta' (-damping / M)."""
    theta = np.asarray(theta, float)
    P = np.tile(np.asarray(p, float), (len(theta), 1))
    pts = None if points is None else \
        np.tile(np.asarray(points, float).reshape(1, -1), (len(theta), 1))
    eps = 1e-6
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        a = (rest_theta_ddot(table, theta + eps, P, lid_mass, pts)
             - rest_theta_ddot(table, theta - eps, P, lid_mass, pts)) / (2 * eps)
        cols, co, Pn = _at(table, theta, P, lid_mass, pts)
        return a, -damping(co, Pn) / cols["M"]


def out_of_range(coordinate, mounting, P, metrics: dict, explain: bool = True
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Which strokes take an element outside its valid range (a spring past its free length:
    an extension spring shorter, a compression spring longer; or past its length limits).

    ``metrics`` holds per row the extremes of each ranged element's coordinate over the
    stroke (the spring's ``min_spring_length``, ``max_spring_length``) and the angles it
    visited (``theta_min``, ``theta_max``); ``coordinate(element, thetas)`` gives an element's
    coordinate at angles (from the table: :func:`table_coordinate`; the reference uses the
    exact model). Returns (by how far beyond, m or rad; why, one line per row: "" for a valid
    stroke), the reason naming the element, where along the stroke it leaves the range and by
    how much (``explain=False``: only "leaves its valid range", which a screen of many
    designs that keeps no reason needs, at a fraction of the cost).
    """
    P = as_params(np.atleast_2d(np.asarray(P, float)))
    n = len(P)
    excess, text = np.zeros(n), np.full(n, "", dtype=object)
    Pn = elements.params(P)
    for e in elements.ELEMENTS:
        if not e.extremes:
            continue
        lo, hi = (np.broadcast_to(np.asarray(v, float), (n,)) for v in e.valid(Pn, mounting))
        qmin, qmax = (np.atleast_1d(np.asarray(metrics[k], float)) for k in e.extremes)
        scale = 1e-9 * np.maximum(np.abs(qmax), 1.0)       # rounding of the extremes
        with np.errstate(invalid="ignore"):
            below, above = lo - qmin, qmax - hi
            bad = np.flatnonzero((below > scale) | (above > scale))
        if not len(bad):
            continue
        short = below[bad] > above[bad]
        beyond = np.maximum(below[bad], above[bad])
        excess[bad] = np.maximum(excess[bad], beyond)
        if not explain:
            text[bad] = np.where(text[bad] == "", f"the {e.name} leaves its valid range",
                                 text[bad])
            continue
        th = np.column_stack([np.atleast_1d(np.asarray(metrics[k], float))[bad]
                              for k in ("theta_min", "theta_max")])
        rows_q = (lambda t, r: coordinate(e, t, bad[r])) if getattr(coordinate, "per_row",
                                                                    False) else \
            (lambda t, r: coordinate(e, t))
        edge, worst = _leaves(rows_q, th,
                              np.where(short, lo[bad], hi[bad]), short)
        words = e.range_messages(Pn, mounting, bad, short, edge, worst, beyond)
        free = text[bad] == ""                 # (the first element out of range says it)
        text[bad[free]] = np.array(words, dtype=object)[free]
    return excess, text


def table_coordinate(table, points=None):
    """``coordinate(element, thetas, rows)`` from the table's column of each element's q; for
    the rows (indices into ``points``, the kernel's convention) that have their own points,
    the spring's length from the table's pose pieces."""
    def q(element, th, rows=None):
        col = COEFFS.index(next(c for c, what in element.columns if what == "q"))
        blk = POINT_BLOCKS.get(element.name)
        if points is None or rows is None or blk is None or "l" not in blk[1]:
            return table.evaluate_column(th, col)
        pts = np.asarray(points, float)[rows]
        has = ~np.isnan(pts[:, blk[0].start])
        th = np.asarray(th, float)
        if not has.any():
            return table.evaluate_column(th, col)
        if has.all():
            return point_grid(table, th.reshape(len(pts), -1), pts, "l").reshape(th.shape)
        out = np.empty(th.shape)
        out[has] = point_grid(table, th[has].reshape(int(has.sum()), -1), pts[has],
                              "l").reshape(th[has].shape)
        if not has.all():
            out[~has] = table.evaluate_column(th[~has], col)
        return out
    q.per_row = True
    return q


class Aging:
    """``aged(P, points=None)``: rows P of new parts at the end of ``life``
    (:func:`softclose.model.life.at_end_of_life`) when its strokes are aged, P itself else; a
    coil spring relaxes at its shut length, each row's own with ``points`` (picklable)."""

    def __init__(self, life, model, table):
        from ..model.life import aged
        self.life = life if aged(life) else None
        self.model, self.table, self.shut = model, table, None

    def __call__(self, P, points=None):
        if self.life is None:
            return P
        from ..model.life import at_end_of_life, shut_coordinates
        if self.shut is None:
            self.shut = shut_coordinates(self.model)
        return at_end_of_life(P, self.life, shut_lengths(
            self.table, self.model.stroke.theta_closed, self.shut, points))


def shut_lengths(table, theta_closed: float, shut: dict, points=None) -> dict:
    """The springs' coordinates at the shut angle (``shut``: the model's, exact;
    :func:`softclose.model.life.shut_coordinates`), a row with its own attachment points
    (``points``, the kernel's convention) its own spring length (the table's pose pieces)."""
    if points is None:
        return shut
    X = np.asarray(points, float)
    has = ~np.isnan(X[:, 0])
    if not has.any():
        return shut
    n = len(X)
    q = table_coordinate(table, X)(elements.BY_NAME["spring"], np.full(n, theta_closed),
                                   np.arange(n))
    return {**shut, "spring": np.where(has, q, shut["spring"])}


#: angles per stroke where :func:`_leaves` looks for the edge of the invalid region (the
#: edge is interpolated between two of them, the worst point refined by a parabola)
LEAVE_GRID = 101


def _leaves(q_of, theta_ranges, bound, short, chunk: int = 4096):
    """Per row (``q_of(thetas, rows)``: the coordinate of those rows at their angles):
    (where the coordinate crosses ``bound`` -- the edge of the region beyond it
    nearest its worst point; NaN when it is beyond over the whole range --, where it lies
    furthest beyond it), rad, over the row's ``theta_ranges`` (m, 2), on a grid of
    LEAVE_GRID angles (rows in chunks: the coordinate is evaluated for a chunk at once; the
    search on the grid is the kernel's ``sc_leaves``: bit for bit the numpy arithmetic it
    replaced, which ``tests/test_invalid_skip.py`` keeps as its second formulation)."""
    theta_ranges = np.atleast_2d(np.asarray(theta_ranges, float))
    m, G = len(theta_ranges), LEAVE_GRID
    bound = np.broadcast_to(np.asarray(bound, float), (m,))
    short = np.broadcast_to(np.asarray(short, bool), (m,))
    edge, worst = np.full(m, np.nan), np.empty(m)
    u = np.linspace(0.0, 1.0, G)
    for a in range(0, m, chunk):
        r = slice(a, min(a + chunk, m))
        lo, hi = theta_ranges[r, :1], theta_ranges[r, 1:]
        th = lo + (hi - lo) * u                        # (rows, grid)
        th[:, -1] = hi[:, 0]
        q = np.asarray(q_of(th, np.arange(r.start, r.stop)), float).reshape(th.shape)
        edge[r], worst[r] = leaves(th, q, bound[r], short[r])
    return edge, worst


#: angles of the opening-force search over [theta_closed, theta0] (then a parabola at the
#: largest; the slope's ~1e-3 relative curvature over a cell leaves ~1e-9 relative error)
OPENING_GRID = 241
#: rows of designs evaluated at once
OPENING_CHUNK = 2048


def opening_forces(table, stroke, P, lid_mass=None, points=None) -> np.ndarray:
    """The opening effort of each design (N): the largest hand force at the tip, along its
    path, that lifts the lid slowly from theta_closed to theta0 against gravity, every spring
    and friction: max over theta of (dV/dtheta + T_f) / |dr_T/dtheta| (SPEC §9).

    The slope is affine in the parameters element by element (T_e = a_e + b_e q_e), so for
    many designs it is a small matrix product over a fixed grid of angles, refined by a
    parabola through the largest grid value and its neighbours; a row with its own points
    (``points``) adds its spring's term T(l) l' from its own l, l' on that grid.
    """
    P = as_params(np.atleast_2d(np.asarray(P, float)))
    if len(P) > OPENING_CHUNK:          # (rows in chunks: the angle grid times the rows)
        m = None if lid_mass is None else np.broadcast_to(np.asarray(lid_mass, float),
                                                          (len(P),))
        pts = None if points is None else np.asarray(points, float)
        return np.concatenate([opening_forces(table, stroke, P[i:i + OPENING_CHUNK],
                                              None if m is None else m[i:i + OPENING_CHUNK],
                                              None if pts is None else pts[i:i + OPENING_CHUNK])
                               for i in range(0, len(P), OPENING_CHUNK)])
    st = stroke
    th = np.linspace(st.theta_closed, st.theta0, OPENING_GRID)
    own = None                                 # the rows whose spring has its own points
    if points is not None:
        pts = np.asarray(points, float)
        has = ~np.isnan(pts[:, 0])
        own = np.flatnonzero(has) if has.any() else None
    if own is None:
        slope, tau = _opening_slopes(table, P, lid_mass, th)
        return _parabola_max(slope / tau, th)
    # rows with their own spring points: the other elements' slope once per distinct set of
    # parameters (and lid mass), the spring's term and the maximum in C (sc_point_opening)
    F = np.empty(len(P))
    m = None if lid_mass is None else np.broadcast_to(np.asarray(lid_mass, float), (len(P),))
    if m is not None:                          # (NaN: the table's own mass)
        m = np.where(np.isfinite(m), m, table.lid_mass)
    rest = np.flatnonzero(~has)
    if len(rest):
        F[rest] = opening_forces(table, stroke, P[rest], None if m is None else m[rest])
    key = P[own] if m is None else np.column_stack([P[own], m[own]])
    if (key == key[0]).all():                  # (a sweep over the points alone: one set)
        uniq, inv = key[:1], np.zeros(len(key), np.int64)
    else:
        uniq, inv = np.unique(key, axis=0, return_inverse=True)
    Pu = uniq[:, :P.shape[1]]
    base, tau = _opening_slopes(table, Pu, None if m is None else uniq[:, -1], th,
                                skip="spring")
    if elements.BY_NAME["spring"]._any_gas(elements.params(P[own])):
        raise ConfigError("a gas strut's opening effort with the spring's points varied "
                          "per design is not computed; vary the points of a coil spring, "
                          "or give the strut's points in [geometry]")
    a, b = elements.BY_NAME["spring"].affine(elements.params(P[own]))
    ab = np.column_stack([np.broadcast_to(np.asarray(v, float), (len(own),)) for v in (a, b)])
    F[own] = point_opening(table, th, pts[own], ab, base, np.asarray(inv).ravel(), tau)
    return F


def _opening_slopes(table, P, lid_mass, th, skip: str | None = None):
    """(dV/dtheta + friction of rows of P over the angles th, (len(P), len(th)); the tip's
    lever tau there), leaving out the element ``skip``."""
    coordinates = elements.needs_coordinates(P, table.model.mounting)
    c = table.evaluate(th)
    cols = {name: c[:, j] for j, name in enumerate(COEFFS)}
    if coordinates:
        x = table.rows_coordinates(th, len(th))
        cols.update({name: x[:, j] for j, name in enumerate(COORDINATE_COEFFS)})
    co = coordinates_of_columns(cols, table.model.mounting)
    Pn = elements.params(P)
    slope = np.zeros((len(P), len(th)))
    for e in elements.SPRINGS:
        if e.name not in co or e.name == skip:
            continue
        q, dq = co[e.name].q, co[e.name].dq
        if e.name == "spring" and e._any_gas(Pn):     # the gas law is not affine in q
            slope += e.tension(np.asarray(q)[None, :], _ColumnParams(Pn)) * dq
            continue
        a, b = e.affine(Pn)
        a = np.broadcast_to(np.asarray(a, float), (len(P),))
        slope += np.multiply.outer(a, dq)
        if not (np.ndim(b) == 0 and b == 0.0):
            slope += np.multiply.outer(np.asarray(b, float), q * dq)
    dm = table.mass_offsets(lid_mass, (len(P),))
    if dm is not None:               # gravity's slope at another lid mass: affine in it
        slope += np.multiply.outer(dm, table.mass_slope_at(th)[:, COEFFS.index("dVg")])
    for e in elements.FRICTIONS:     # T_fr = sum C |q'| (the lid's angle: q' = 1)
        if e.name in co:
            f = np.broadcast_to(np.asarray(e.coulomb(Pn), float), (len(P),))
            slope += f[:, None] * np.abs(np.atleast_1d(np.asarray(co[e.name].dq, float)))
    return slope, cols["tau"]


class _ColumnParams:
    """Rows' named parameters as columns (n, 1), to broadcast against angles (1, m)."""

    def __init__(self, Pn):
        self._P = Pn

    def __getitem__(self, name):
        return np.asarray(self._P[name], float)[:, None]


def _parabola_max(F: np.ndarray, th: np.ndarray) -> np.ndarray:
    """Per row, the largest value of F over the grid th, refined by the parabola through it
    and its neighbours (an end stays an end)."""
    j = np.argmax(F, axis=1)
    rows = np.arange(len(F))
    best = F[rows, j]
    inner = (j > 0) & (j < len(th) - 1)
    if inner.any():
        r, k = rows[inner], j[inner]
        y0, y1, y2 = F[r, k - 1], F[r, k], F[r, k + 1]
        den = y0 - 2 * y1 + y2
        with np.errstate(invalid="ignore", divide="ignore"):
            peak = np.where(den < 0, y1 - (y2 - y0) ** 2 / (8 * den), y1)
        best[inner] = np.maximum(best[inner], peak)
    return best


def opening_force_exact(model, p, grid=None) -> float:
    """The opening effort of one design from the exact model (the reference's): the largest
    (dV/dtheta + T_f) / |dr_T/dtheta| (``model.opening``) over a 2001-point grid of
    [theta_closed, theta0], then the root of its theta-derivative between the neighbours of
    the largest point (Illinois false position; an end stays an end). ``grid``: (angles,
    F, dF) of ``model.opening`` at ``p`` evaluated already by the caller, used when the
    angles are this grid's."""
    st = model.stroke
    p = np.asarray(p, float)
    last = model.__dict__.get("_opening_last")     # the optimiser's claims, then the
    if last is not None and last[0] == p.tobytes():  # reference's: the same design twice
        return last[1]
    th = np.linspace(st.theta_closed, st.theta0, OPENING_EXACT_GRID)
    if grid is not None and np.array_equal(grid[0], th):
        F, dF = grid[1], grid[2]
    else:          # the model's hand function: F and dF as ``opening`` has them, ~1/3 the work
        fn = model.__dict__.get("_opening_grid")
        if fn is None:                # (mapping a Function builds one: once per model)
            fn = model.__dict__["_opening_grid"] = model.hand.map(OPENING_EXACT_GRID)
        F, dF = (np.asarray(a).ravel()
                 for a in fn(th, np.repeat(p[:, None], len(th), 1))[1:3])
    i = int(np.argmax(F))
    best = float(F[i])
    if 0 < i < len(th) - 1 and dF[i - 1] > 0 > dF[i + 1]:
        def dF_at(x):           # every force met on the way counts towards the largest
            nonlocal best
            Fx, dFx = (float(v) for v in model.hand(x, p)[1:3])
            best = max(best, Fx)
            return dFx
        illinois(dF_at, th[i - 1], th[i + 1], dF[i - 1], dF[i + 1],
                 lambda a, b, x, r: r == 0 or b - a < 1e-15, 60)
    model.__dict__["_opening_last"] = (p.tobytes(), best)
    return best


#: angles of :func:`opening_force_exact`'s grid
OPENING_EXACT_GRID = 2001
