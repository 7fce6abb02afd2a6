"""Keep-out regions (``optimise.keep_out``): convex polygons in the ground frame that the
spring's line D-E and the dashpot's line F-H must not cross over the stroke.

A segment P0-P1 and a convex polygon V are disjoint exactly when one of the polygon's edge
normals or the segment's own normal separates them (the separating-axis theorem); the
*gap*

    gap = max( max_i [min(n_i . P0, n_i . P1) - c_i],        (edge i: n_i . x <= c_i inside)
               max(min_k m . (v_k - P0), -max_k m . (v_k - P0)) )   (m = the segment's normal)

is >= 0 exactly when they do not overlap (in m, the distance of the separating line's
clearance). The NLP asks gap >= 0 at the nodes of the stroke's angle grid
(:data:`softclose.optimiser.free_points.LENGTH_INTERVALS` intervals) for each line whose
points are free; :func:`clearance` checks every line afterwards on a dense grid of the exact
closure (2001 angles), which is what the result reports.
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
from ..model.lid import LidModel
from .free_points import LENGTH_INTERVALS, POSE_SERIES, point
from ..problem import resolve

#: angles of the exact check after the solve
CHECK_ANGLES = 2001
#: the lines: (name, ground point slots, lid point slots) in the points vector g
LINES = (("spring", slice(0, 2), slice(2, 4)), ("dashpot", slice(4, 6), slice(6, 8)))


def gap_function(poly) -> ca.Function:
    """``gap(P0, P1)`` of one convex polygon (module docstring): >= 0 when disjoint."""
    V = np.asarray(poly, float)
    n = len(V)
    area = sum(V[i, 0] * V[(i + 1) % n, 1] - V[(i + 1) % n, 0] * V[i, 1] for i in range(n))
    sgn = 1.0 if area > 0 else -1.0            # counter-clockwise: outward = (e_y, -e_x)
    P0, P1 = ca.SX.sym("P0", 2), ca.SX.sym("P1", 2)
    gaps = []
    for i in range(n):
        e = V[(i + 1) % n] - V[i]
        nrm = sgn * np.array([e[1], -e[0]]) / math.hypot(*e)
        c = float(nrm @ V[i])
        gaps.append(ca.fmin(ca.dot(ca.DM(nrm), P0), ca.dot(ca.DM(nrm), P1)) - c)
    d = P1 - P0
    m = ca.vertcat(-d[1], d[0]) / ca.sqrt(ca.sumsqr(d) + 1e-30)
    a = [ca.dot(m, ca.DM(v) - P0) for v in V]
    lo, hi = a[0], a[0]
    for x in a[1:]:
        lo, hi = ca.fmin(lo, x), ca.fmax(hi, x)
    gaps.append(ca.fmax(lo, -hi))
    out = gaps[0]
    for x in gaps[1:]:
        out = ca.fmax(out, x)
    return ca.Function("keep_out_gap", [P0, P1], [out])


def free_lines(place) -> tuple:
    """The lines with a free point (``place``: the NLP's placement layout)."""
    slots = {x[1] for x in place}
    return tuple(ln for ln in LINES
                 if slots & (set(range(8)[ln[1]]) | set(range(8)[ln[2]])))


def keep_out_constraints(fit, theta0, thc, g, polys, place=None, L=None):
    """gap >= 0 of every polygon and every line with a free point (all lines when
    ``place`` is None) at the nodes of the stroke's angle grid (CasADi expressions);
    ``fit`` symbolic series, ``L`` their numbers."""
    th, gs = ca.SX.sym("theta"), ca.SX.sym("g", 8)
    B = fit.basis(th)
    sx = [ca.dot(fit.series(n), B) for n in POSE_SERIES[:4]]
    A, dA = ca.vertcat(sx[0], sx[1]), ca.vertcat(sx[2], sx[3])
    lines = LINES if place is None else free_lines(place)
    ends = []
    for _, ground, lid in lines:
        ends += [gs[ground], point(A, dA, th, gs[lid])[0]]
    fn = ca.Function("lines", [th, gs, fit.sym], [ca.vertcat(*ends)])
    n = LENGTH_INTERVALS + 1
    u = ca.DM(np.linspace(0.0, 1.0, n)).T
    E = fn.map(n)(thc + (theta0 - thc) * u, ca.repmat(g, 1, n), ca.repmat(L, 1, n))
    out = []
    for poly in polys:
        gap = gap_function(poly).map(n)
        for j in range(len(lines)):
            out.append(ca.vec(gap(E[4 * j:4 * j + 2, :], E[4 * j + 2:4 * j + 4, :])))
    return ca.vertcat(*out) if out else ca.MX(0, 1)


def clearance(cfg, polys=None) -> dict:
    """The exact check: per line, the smallest gap over the stroke (m; < 0: it crosses a
    region) and the angle where (deg), on :data:`CHECK_ANGLES` angles of the exact closure."""
    polys = cfg.optimise.keep_out if polys is None else polys
    if not polys:
        return {}
    st, geo = cfg.stroke, cfg.geometry
    model = LidModel.cached(resolve(cfg))   # (the model's disk cache: no optimiser cache below)
    th = np.linspace(st.theta_closed, st.theta0, CHECK_ANGLES)
    A = np.asarray(model.kin.map(CHECK_ANGLES)(np.vstack([th, np.zeros_like(th)]))[5])
    c, s = np.cos(th), np.sin(th)

    def lid(p):
        return A + np.vstack([c * p[0] - s * p[1], s * p[0] + c * p[1]])

    ends = {"spring": (np.asarray(geo.spring_anchor, float), lid(geo.lid_e)),
            "dashpot": (np.asarray(geo.dashpot_anchor, float), lid(geo.dashpot_lid))}
    out = {}
    for name, (P0, P1) in ends.items():
        worst, at = math.inf, float(np.degrees(th[-1]))
        for poly in polys:
            gap = np.asarray(gap_function(poly).map(CHECK_ANGLES)(
                np.repeat(P0[:, None], CHECK_ANGLES, axis=1), P1)).ravel()
            gap = np.where(np.isfinite(gap), gap, -math.inf)   # (never: polygons are checked)
            i = int(np.argmin(gap))
            if gap[i] < worst:
                worst, at = float(gap[i]), float(np.degrees(th[i]))
        out[name] = {"clearance": worst, "theta_deg": at, "ok": worst >= -1e-9}
    return out


__all__ = ["CHECK_ANGLES", "LINES", "gap_function", "keep_out_constraints", "clearance",
           "free_lines"]
