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
    cols = columns(table, theta, len(P), lid_mass, elements.needs_extra(P))
    return cols, coordinates_of_columns(cols), elements.params(P)


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
