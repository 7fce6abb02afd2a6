"""Statics over the coefficient table: the one dV/dtheta, applied to rows of designs.

:func:`softclose.dynamics.slope` states dV/dtheta once, as a sum over the machine elements;
this module evaluates it (and V, and the damping) from the tabulated columns of a
:class:`~softclose.table.CoefficientTable` for many designs at once: the holding moment at
the rim, the energy a stroke releases, theta'' at rest (the release check, the equilibria and
the linearisation of the stability check). The CasADi model's ``dV`` is the same sum on exact
expressions.
"""

from __future__ import annotations

import numpy as np

from . import elements
from .dynamics import COEFFS, EXTRA_COEFFS, coordinates_of_columns, damping, potential, slope
from .problem import as_params


def columns(table, theta, n: int, lid_mass=None, extra: bool = False) -> dict:
    """The named columns at ``theta`` (scalar or one per row) for ``n`` rows at ``lid_mass``,
    with the element columns of the extra table when ``extra``."""
    c = table.rows(theta, n, lid_mass)
    out = {name: c[:, j] for j, name in enumerate(COEFFS)}
    if extra:
        x = table.rows_extra(theta, n)
        out.update({name: x[:, j] for j, name in enumerate(EXTRA_COEFFS)})
    return out


def _at(table, theta, P, lid_mass):
    P = as_params(np.atleast_2d(np.asarray(P, float)))
    cfg = table.model.cfg
    cols = columns(table, theta, len(P), lid_mass, elements.needs_extra(P, cfg))
    return cols, coordinates_of_columns(cols, cfg), elements.params(P)


def potential_energy(table, theta, P, lid_mass=None) -> np.ndarray:
    """V (J) at ``theta`` (scalar or one per row) for rows of P, at ``lid_mass`` (scalar, one
    per row, or None: the table's mass)."""
    _, co, Pn = _at(table, theta, P, lid_mass)
    return potential(co, Pn)


def slopes(table, theta, P, lid_mass=None) -> np.ndarray:
    """dV/dtheta (N m) at ``theta`` for rows of P; at theta_closed, > 0 presses the lid shut."""
    _, co, Pn = _at(table, theta, P, lid_mass)
    return slope(co, Pn)


def holding_moments(table, theta_closed: float, P, lid_mass=None) -> np.ndarray:
    """dV/dtheta at ``theta_closed`` (N m, > 0 presses the lid shut) for rows of P."""
    return slopes(table, float(theta_closed), P, lid_mass)


def rest_theta_ddot(table, theta, P, lid_mass=None) -> np.ndarray:
    """theta'' at rest, -V'(theta) / M, at ``theta`` (one per row, or a scalar) for rows of P:
    > 0 pushes the lid open."""
    cols, co, Pn = _at(table, theta, P, lid_mass)
    return -slope(co, Pn) / cols["M"]


def rest_jacobian(table, theta, p, lid_mass=None) -> tuple[np.ndarray, np.ndarray]:
    """The linearised (theta, theta') Jacobian entries at rest at the angles ``theta`` for
    one design p: d theta''/d theta (central difference of -V'/M) and d theta''/d theta'
    (-damping / M)."""
    theta = np.asarray(theta, float)
    P = np.tile(np.asarray(p, float), (len(theta), 1))
    eps = 1e-6
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        a = (rest_theta_ddot(table, theta + eps, P, lid_mass)
             - rest_theta_ddot(table, theta - eps, P, lid_mass)) / (2 * eps)
        cols, co, Pn = _at(table, theta, P, lid_mass)
        return a, -damping(co, Pn) / cols["M"]


def out_of_range(coordinate, cfg, P, metrics: dict) -> tuple[np.ndarray, np.ndarray]:
    """Which strokes take an element outside its valid range (a spring past its free length:
    an extension spring shorter, a compression spring longer; or past its length limits).

    ``metrics`` holds per row the extremes of each ranged element's coordinate over the
    stroke (the spring's ``min_spring_length``, ``max_spring_length``) and the angles it
    visited (``theta_min``, ``theta_max``); ``coordinate(element, thetas)`` gives an element's
    coordinate at angles (from the table: :func:`table_coordinate`; the reference uses the
    exact model). Returns (by how far beyond, m or rad; why, one line per row: "" for a valid
    stroke), the reason naming the element, where along the stroke it leaves the range and by
    how much.
    """
    P = as_params(np.atleast_2d(np.asarray(P, float)))
    n = len(P)
    excess, text = np.zeros(n), np.full(n, "", dtype=object)
    Pn = elements.params(P)
    for e in elements.ELEMENTS:
        if not e.extremes:
            continue
        lo, hi = (np.broadcast_to(np.asarray(v, float), (n,)) for v in e.valid(Pn, cfg))
        qmin, qmax = (np.atleast_1d(np.asarray(metrics[k], float)) for k in e.extremes)
        scale = 1e-9 * np.maximum(np.abs(qmax), 1.0)       # rounding of the extremes
        with np.errstate(invalid="ignore"):
            below, above = lo - qmin, qmax - hi
            bad = np.flatnonzero((below > scale) | (above > scale))
        for i in bad:
            th = (float(np.atleast_1d(metrics["theta_min"])[i]),
                  float(np.atleast_1d(metrics["theta_max"])[i]))
            short = below[i] > above[i]
            beyond = max(below[i], above[i])
            excess[i] = max(excess[i], beyond)
            where = _leaves(lambda t: coordinate(e, t), th, lo[i] if short else hi[i], short)
            text[i] = text[i] or e.range_message(Pn, cfg, i, short, where, beyond)
    return excess, text


def table_coordinate(table):
    """``coordinate(element, thetas)`` from the table's column of each element's q."""
    def q(element, th):
        col = COEFFS.index(next(c for c, what in element.columns if what == "q"))
        return table.evaluate(th)[:, col]
    return q


def _leaves(q_of, theta_range, bound: float, short: bool) -> tuple[float, float]:
    """(where the coordinate crosses ``bound`` -- the edge of the region beyond it nearest its
    worst point --, where it lies furthest beyond it), rad, over ``theta_range``."""
    th = np.linspace(theta_range[0], theta_range[1], 401)
    q = np.asarray(q_of(th), float).ravel()
    beyond = (bound - q) if short else (q - bound)
    worst = int(np.argmax(beyond))
    inside = np.flatnonzero(beyond <= 0)
    if not len(inside):                     # beyond over the whole stroke
        return None, float(th[worst])
    j = int(inside[np.argmin(np.abs(inside - worst))])
    k = j + 1 if j < worst else j - 1       # its neighbour towards the worst point
    return 0.5 * float(th[j] + th[k]), float(th[worst])


#: angles of the opening-force search over [theta_closed, theta0] (then a parabola at the
#: largest; the slope's ~1e-3 relative curvature over a cell leaves ~1e-9 relative error)
OPENING_GRID = 241
#: rows of designs evaluated at once
OPENING_CHUNK = 2048


def opening_forces(table, cfg, P, lid_mass=None) -> np.ndarray:
    """The opening effort of each design (N): the largest hand force at the tip, along its
    path, that lifts the lid slowly from theta_closed to theta0 against gravity, every spring
    and friction: max over theta of (dV/dtheta + T_f) / |dr_T/dtheta| (SPEC §9).

    The slope is affine in the parameters element by element (T_e = a_e + b_e q_e), so for
    many designs it is a small matrix product over a fixed grid of angles, refined by a
    parabola through the largest grid value and its neighbours.
    """
    P = as_params(np.atleast_2d(np.asarray(P, float)))
    if len(P) > OPENING_CHUNK:          # (rows in chunks: the angle grid times the rows)
        m = None if lid_mass is None else np.broadcast_to(np.asarray(lid_mass, float),
                                                          (len(P),))
        return np.concatenate([opening_forces(table, cfg, P[i:i + OPENING_CHUNK],
                                              None if m is None else m[i:i + OPENING_CHUNK])
                               for i in range(0, len(P), OPENING_CHUNK)])
    st = cfg.stroke
    th = np.linspace(st.theta_closed, st.theta0, OPENING_GRID)
    extra = elements.needs_extra(P, table.model.cfg)
    c = table.evaluate(th)
    cols = {name: c[:, j] for j, name in enumerate(COEFFS)}
    if extra:
        x = table.rows_extra(th, len(th))
        cols.update({name: x[:, j] for j, name in enumerate(EXTRA_COEFFS)})
    co = coordinates_of_columns(cols, table.model.cfg)
    Pn = elements.params(P)
    slope = np.zeros((len(P), len(th)))
    for e in elements.SPRINGS:
        if e.name not in co:
            continue
        q, dq = co[e.name].q, co[e.name].dq
        a, b = e.affine(Pn)
        slope += np.multiply.outer(np.broadcast_to(np.asarray(a, float), (len(P),)), dq)
        if not (np.ndim(b) == 0 and b == 0.0):
            slope += np.multiply.outer(np.asarray(b, float), q * dq)
    dm = table.mass_offsets(lid_mass, (len(P),))
    if dm is not None:               # gravity's slope at another lid mass: affine in it
        slope += np.multiply.outer(dm, table.mass_slope_at(th)[:, COEFFS.index("dVg")])
    slope += friction_torque(cfg)
    F = slope / cols["tau"]
    return _parabola_max(F, th)


def friction_torque(cfg) -> float:
    """The lumped friction torque on the lid's rotation (N m; 0 without friction)."""
    fr = getattr(cfg, "friction", None)
    return float(getattr(fr, "torque", 0.0) or 0.0)


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


def opening_force_exact(model, p) -> float:
    """The opening effort of one design from the exact model (the reference's): the largest
    (dV/dtheta + T_f) / |dr_T/dtheta| over a 2001-point grid of [theta_closed, theta0], then a
    golden-section search around the largest point."""
    import math
    st, cfg = model.cfg.stroke, model.cfg
    Tf = friction_torque(cfg)
    tau_row = COEFFS.index("tau")

    def F(th):
        th = np.atleast_1d(np.asarray(th, float))
        dV = np.asarray(model.dV.map(len(th))(th, np.repeat(np.asarray(p, float)[:, None],
                                                             len(th), 1))).ravel()
        tau = np.asarray(model.coeffs.map(len(th))(th)[0])[tau_row]
        return (dV + Tf) / tau
    th = np.linspace(st.theta_closed, st.theta0, 2001)
    v = F(th)
    i = int(np.argmax(v))
    lo, hi = th[max(i - 1, 0)], th[min(i + 1, len(th) - 1)]
    g = (math.sqrt(5) - 1) / 2
    best = float(v[i])
    for _ in range(60):
        a, b = hi - g * (hi - lo), lo + g * (hi - lo)
        fa, fb = F([a, b])
        best = max(best, float(fa), float(fb))
        if fa > fb:
            hi = b
        else:
            lo = a
    return best
