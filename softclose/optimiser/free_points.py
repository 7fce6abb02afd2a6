"""Attachment points as design variables: the spring's and the dashpot's ends, carried
symbolically by the NLP (``optimise.free`` with ``geometry.spring_anchor[i]``,
``geometry.lid_e[i]``, ``geometry.dashpot_anchor[i]``, ``geometry.dashpot_lid[i]``).

The points enter the equation of motion only through the lengths of the spring and the
dashpot and their derivatives along the closure. A lid point P (lid frame p, from A) is at

    P(theta) = A(theta) + R(theta) p,      dP/dtheta = A'(theta) + z x R(theta) p,

the lid's own angle being theta, so the whole closure enters through the crank pin
A(theta) and its slope A'(theta), fitted once per geometry as Chebyshev series
("pose:Ax", "pose:Ay", "pose:dAx", "pose:dAy", with 1/M as "pose:invM":
:class:`softclose.optimiser.interval.ChebyshevFit`). With a ground point G,

    l = |P - G|,    l l' = (P - G) . P',    (dashpot) q'^2 = ((P - G) . P')^2 / l^2,

so the spring's term of theta'' is ``-(a l'/l ... )``: ``-(a_s l' + b_s l l')/M`` (its law
T = a_s + b_s l) and the dashpot's ``-c q'^2 theta'/M``: expressions of the free points,
whose derivatives Ipopt gets exactly. The 8 numbers (D, E, the dashpot's anchor F and lid
point H; :data:`SLOTS`) are a vector ``g`` of the interval function; the fixed ones are the
model's values.

Validity of the spring's kind (SPEC §9) over the whole stroke is a constraint here, not a
bound on l0 (the lengths move with the points): l at the nodes of an angle grid of
[theta_closed, theta0] and the maxima / minima of its cubic Hermite interpolant in every
interval (error O(h^4)); every result is verified by the adaptive reference at the
optimum's points (a config with the points set: :func:`placed_config`).
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from ..config.free import PLACEMENT_KEYS, config_value
from .hermite import hermite_max
from .parameters import holding_moment
from ..problem import PARAM_COLUMNS
from ..model import elements
from ..model.dynamics import pose
from ..model.elements.springs import strut_stroke

#: the vector g of attachment points, in order: D (spring anchor, world), E (spring's lid
#: point), F (dashpot anchor, world), H (dashpot's lid point)
SLOTS = PLACEMENT_KEYS
#: the series of the closure the placed NLP fits beside the elements'
POSE_SERIES = ("pose:Ax", "pose:Ay", "pose:dAx", "pose:dAy", "pose:invM")
#: intervals of the angle grid over which the spring's length is bounded
LENGTH_INTERVALS = 32


def placement_layout(cfg) -> tuple:
    """The free attachment-point components: (key, slot in g, scale) each, the scale the
    larger magnitude of the bounds."""
    return tuple((k, SLOTS.index(k), max(abs(lo), abs(hi)) or 1.0)
                 for k, lo, hi in (cfg.optimise.free or ()) if k in SLOTS)


def slot_values(cfg) -> np.ndarray:
    """g of ``cfg`` (or of a model's lid, :class:`softclose.model.resolved.Lid`): the 8
    components of D, E, F, H."""
    return np.array([config_value(cfg, k) for k in SLOTS])


def placed_config(cfg, values: dict):
    """``cfg`` with the attachment points ``values`` ({key or name without section: m})."""
    return cfg.update({(k if k.startswith("geometry.") else f"geometry.{k}"): float(v)
                       for k, v in values.items()
                       if (k if k.startswith("geometry.") else f"geometry.{k}") in SLOTS})


def pose_functions(theta, cfg, sigma, M):
    """The closure's functions the placed NLP fits: A_x, A_y, A'_x, A'_y and 1/M."""
    A = pose(theta, cfg.geometry, cfg.mass, sigma).points["A"]
    dA = ca.jacobian(A, theta)
    return [A[0], A[1], dA[0], dA[1], 1.0 / M]


def point(A, dA, theta, p):
    """(P, dP/dtheta) of a lid point p (lid frame) at the lid angle theta."""
    c, s = ca.cos(theta), ca.sin(theta)
    r = ca.vertcat(c * p[0] - s * p[1], s * p[0] + c * p[1])
    return A + r, dA + ca.vertcat(-r[1], r[0])


def lengths(fit, theta, B, g):
    """At theta (its Chebyshev basis B) and the points g: the spring's l, l l' (= (E-D).E'),
    the dashpot's q'^2 and 1/M (CasADi expressions)."""
    sx = [ca.dot(fit.series(n), B) for n in POSE_SERIES]
    A, dA, invM = ca.vertcat(sx[0], sx[1]), ca.vertcat(sx[2], sx[3]), sx[4]
    E, dE = point(A, dA, theta, g[2:4])
    r = E - g[0:2]
    l = ca.norm_2(r)
    H, dH = point(A, dA, theta, g[6:8])
    rH = H - g[4:6]
    return l, ca.dot(r, dE), ca.dot(rH, dH) ** 2 / ca.sumsqr(rH), invM


def length_function(fit):
    """``spring_length(theta, g, L) -> (l, dl/dtheta)`` on the fitted closure (``fit``:
    symbolic series, :class:`softclose.optimiser.parameters.SymbolicSeries`; L their numbers)."""
    th, g = ca.SX.sym("theta"), ca.SX.sym("g", len(SLOTS))
    l, ldl, _, _ = lengths(fit, th, fit.basis(th), g)
    return ca.Function("spring_length", [th, g, fit.sym], [l, ldl / l])


def length_bounds(fit, theta0, thc, g, L):
    """The spring's length over the stroke: (nodes of an angle grid, the Hermite maxima,
    the Hermite minima in every interval) -- every value within the bounds bounds the length
    over the whole stroke (to O(h^4))."""
    n = LENGTH_INTERVALS
    u = ca.DM(np.linspace(0.0, 1.0, n + 1)).T
    th = thc + (theta0 - thc) * u
    Ln, dL = length_function(fit).map(n + 1)(th, ca.repmat(g, 1, n + 1),
                                             ca.repmat(L, 1, n + 1))
    h = (theta0 - thc) / n
    va, vb, ma, mb = Ln[:n], Ln[1:], dL[:n] * h, dL[1:] * h
    return (Ln.T, hermite_max(va.T, ma.T, vb.T, mb.T),
            -hermite_max(-va.T, -ma.T, -vb.T, -mb.T))


def spring_moment(fit, theta, g, a, b, L, gas=None):
    """The spring's moment T l' at theta (T = a + b l; with ``gas`` = (G, beta, l0) a gas
    strut's T = G / (1 + beta (l - l0))): its part of the holding moment."""
    th, gs = ca.SX.sym("theta"), ca.SX.sym("g", len(SLOTS))
    l, ldl, _, _ = lengths(fit, th, fit.basis(th), gs)
    if gas is not None:
        law = ca.SX.sym("gas", 3)
        fn = ca.Function("spring_moment", [th, gs, law, fit.sym],
                         [law[0] / (1 + law[1] * (l - law[2])) * ldl / l])
        return fn(theta, g, ca.vertcat(*gas), L)
    ab = ca.SX.sym("ab", 2)
    fn = ca.Function("spring_moment", [th, gs, ab, fit.sym],
                     [ab[0] * ldl / l + ab[1] * ldl])
    return fn(theta, g, ca.vertcat(a, b), L)


def strut_law(nlp, design):
    """(G, beta, l0) of a gas strut's NLP (``nlp.spring == "gas"``), else None."""
    if getattr(nlp, "spring", "coil") != "gas":
        return None
    P = elements.params(design, "gas")
    G, beta = elements.BY_NAME["spring"].gas(P)
    return G, beta, P["spring_rest_length"]


def placed_constraints(nlp, design, g, theta0, thc, closed, L, c) -> dict:
    """The constraint groups of a placed NLP beside the shooting ones: the holding moment
    (every element's at theta_closed -- ``closed``: their coordinates there
    (:func:`softclose.optimiser.parameters.holding_moment`) --, the spring's at the points g), the
    release downwards, the spring's length over the stroke against its kind
    (``spring_long``: l0 - l >= 0 for a compression spring or gas strut; ``spring_short``:
    l - l0 >= 0 for an extension spring, l - (l0 - s) >= 0 for a gas strut of stroke s) and
    its limits (``spring_length``). ``L``: the series' numbers,
    ``c`` the combined coefficients (:func:`softclose.optimiser.interval.combine_function`)."""
    mask = np.ones(design.numel())
    for k in ("design.spring_k", "design.spring_preload"):
        mask[PARAM_COLUMNS[k]] = 0.0
    a, b = elements.BY_NAME["spring"].affine(elements.params(design))
    gas = strut_law(nlp, design)
    hold = holding_moment(closed, elements.params(design * ca.DM(mask), nlp.spring)) + \
        spring_moment(nlp.series, thc, g, a, b, L, gas)
    Ln, Lmax, Lmin = length_bounds(nlp.series, theta0, thc, g, L)
    l0 = design[PARAM_COLUMNS["design.spring_rest_length"]]
    # a gas strut's shortest length is its compressed one, l0 - s (a coil spring's short
    # side is its free length: an extension spring's)
    short = l0 - strut_stroke(elements.params(design, "gas")) if gas is not None else l0
    out = {"holding_moment": hold,
           "release_downwards": nlp.f(ca.vertcat(theta0, 0), c)[1],
           "spring_long": l0 - ca.vertcat(ca.vec(Ln), ca.vec(Lmax)),
           "spring_short": ca.vertcat(ca.vec(Ln), ca.vec(Lmin)) - short,
           "spring_length": ca.vertcat(ca.vec(Ln), ca.vec(Lmax), ca.vec(Lmin))}
    return out


def placed_bounds(cfg, lo: dict, hi: dict) -> None:
    """The bounds of :func:`placed_constraints`' groups for ``cfg``'s spring kind and
    limits (into ``lo``, ``hi``)."""
    d = cfg.design
    inf = np.inf
    lo["spring_long"] = 0.0 if d.spring_kind in ("compression", "gas_strut") else -inf
    lo["spring_short"] = 0.0 if d.spring_kind in ("extension", "gas_strut") else -inf
    hi["spring_long"] = hi["spring_short"] = inf
    lo["spring_length"] = d.spring_min_length if d.spring_min_length else -inf
    hi["spring_length"] = d.spring_max_length if d.spring_max_length else inf
    lo["keep_out"], hi["keep_out"] = 0.0, inf


__all__ = ["placed_constraints", "placed_bounds", "SLOTS", "POSE_SERIES", "LENGTH_INTERVALS", "placement_layout", "slot_values",
           "placed_config", "pose_functions", "point", "lengths", "length_function",
           "length_bounds", "spring_moment"]
