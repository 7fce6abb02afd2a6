"""The NLP's parameters: their order (:data:`NLP_PARAMS`) and the lid's numbers in them (an
NLP is built from its structure, a lid fills it).

An NLP's CasADi graph holds no number of the lid. What the equation of motion and the
constraints read of the mechanism -- the Chebyshev series of the geometric functions
(:class:`~softclose.optimiser.interval.ChebyshevFit`), the elements' coordinates at the
closed angle (the holding moment), the scales of the free variables, the fixed attachment
points, the opening effort's geometry on its angle grid, the self-close angle and the geometry
on its grid -- enters as one parameter vector
``L``, laid out by :class:`LidLayout`. So one NLP serves every lid, mass scenario and start
of the same structure (its elements, free variables, discretisation, scenario count), and a
compiled NLP is keyed by that structure alone.

The series are padded with zero coefficients to a degree of :data:`DEGREES` (the smallest
that holds the fit): the padded terms add exact zeros, so the series' values are those of
the fit's own degree.
"""

from __future__ import annotations

from types import SimpleNamespace

import casadi as ca
import numpy as np

from ..errors import ConfigError
from ..model import elements
from ..model.dynamics import COEFFS, friction, slope
from ..problem import DESIGN_KEYS, PARAM_KEYS
from .hermite import hermite_max

#: the parameters of p that are not design variables: NLP parameters
FIXED_PARAMS = PARAM_KEYS[len(DESIGN_KEYS):]
#: the nominal NLP's parameters, in order (then the time grid: the fractions of T of the N
#: intervals, then the lid vector of :class:`LidLayout`)
NLP_PARAMS = ("theta0", "theta_closed", "weight_impact", "weight_peak_tip", "weight_time",
              *FIXED_PARAMS, "J_ref")
J_INDEX = NLP_PARAMS.index("J_ref")

#: the degrees a series is padded to (part of an NLP's structure)
DEGREES = (16, 24, 32, 48, 64)
#: the elements whose coordinates at the closed angle give the holding moment
HOLDING = tuple(e.name for e in elements.SPRINGS)


def padded_degree(degree: int) -> int:
    """The smallest of :data:`DEGREES` at or above a fit's ``degree``."""
    for d in DEGREES:
        if d >= degree:
            return d
    raise ValueError(f"a Chebyshev fit of degree {degree} exceeds {DEGREES[-1]}")


def chebyshev_basis(u, degree: int):
    """Chebyshev polynomials T_0..T_degree at u in [-1, 1] (a CasADi column), by their
    three-term recurrence."""
    T = [1, u]
    for _ in range(2, degree + 1):
        T.append(2 * u * T[-1] - T[-2])
    return ca.vertcat(*T)


class SymbolicSeries:
    """The geometric functions' Chebyshev series as symbols (SX): the same interface as
    :class:`~softclose.optimiser.interval.ChebyshevFit` (``names``, ``elements``,
    ``degree``, :meth:`series`, :meth:`basis`), the coefficients and the interval [lo, hi]
    read from the vector :attr:`sym` (row-major coefficients, then lo and hi)."""

    def __init__(self, names, elements_, degree: int, sym=None):
        self.names, self.elements, self.degree = tuple(names), tuple(elements_), int(degree)
        self.size = len(self.names) * (self.degree + 1) + 2
        self.sym = ca.SX.sym("series", self.size) if sym is None else sym
        self.lo, self.hi = self.sym[-2], self.sym[-1]

    @property
    def pose(self) -> bool:
        return "pose:Ax" in self.names

    def over(self, vector) -> "SymbolicSeries":
        """The same series read from another vector (an SX expression of its layout)."""
        return SymbolicSeries(self.names, self.elements, self.degree, vector)

    def series(self, name: str):
        n = self.degree + 1
        i = self.names.index(name)
        return self.sym[i * n:(i + 1) * n]

    def basis(self, theta):
        """Chebyshev polynomials T_0..T_n at theta (an SX column)."""
        return chebyshev_basis((2 * theta - (self.lo + self.hi)) / (self.hi - self.lo),
                               self.degree)

    def values(self, fit) -> np.ndarray:
        """:attr:`sym`'s numbers for a fit of the same series."""
        if tuple(fit.names) != self.names or fit.degree > self.degree:
            raise ValueError("the fit's series are not this NLP's")
        C = np.zeros((len(self.names), self.degree + 1))
        C[:, :fit.coef.shape[1]] = fit.coef
        return np.r_[C.ravel(), fit.lo, fit.hi]


class LidLayout:
    """The parts of the lid vector ``L`` of one NLP structure, in order: ``series`` (the
    padded Chebyshev series), ``closed`` (q and q' of the conservative elements at
    theta_closed), ``scales`` (of the free variables and points), ``points`` (the 8
    attachment-point components, with free points), ``opening`` (per angle of the opening
    grid: q, q', q'' of every conservative and friction element, tau and tau'),
    ``self_close`` (the same per angle of the self-close grid on [theta_closed, theta_sc],
    then theta_sc: ``optimise.self_close_min_deg`` in radians, a parameter)."""

    def __init__(self, series: SymbolicSeries, n_scales: int, points: bool,
                 opening_angles: int = 0, self_close_angles: int = 0):
        self.series = series
        self.opening_elements = tuple(e.name for e in elements.SPRINGS + elements.FRICTIONS)
        self.opening_angles = int(opening_angles)
        self.self_close_angles = int(self_close_angles)
        per = 3 * len(self.opening_elements) + 2
        self.sizes = {"series": series.size, "closed": 2 * len(HOLDING),
                      "scales": int(n_scales), "points": 8 if points else 0,
                      "opening": self.opening_angles * per,
                      "self_close": self.self_close_angles * per + (
                          1 if self.self_close_angles else 0)}
        self.size = sum(self.sizes.values())

    def split(self, L) -> dict:
        """{part: slice of L} (numbers or MX)."""
        out, i = {}, 0
        for k, n in self.sizes.items():
            out[k] = L[i:i + n]
            i += n
        return out

    # -- numbers of one lid ----------------------------------------------------------------
    def values(self, model, fit, scales=(), points=None, opening_grid=None,
               self_close_deg: float | None = None) -> np.ndarray:
        """L of ``model`` (its ``fit``), the free variables' ``scales``, the attachment
        ``points``, the opening grid's angles and the self-close angle (deg,
        ``optimise.self_close_min_deg``): without it (None) L without its last part, the
        self-close part (:meth:`self_close_values`), which a problem appends."""
        parts = [self.series.values(fit), closed_values(model),
                 np.asarray(scales, float).ravel()]
        if self.sizes["points"]:
            parts.append(np.asarray(points, float).ravel())
        if self.opening_angles:
            parts.append(opening_values(model, opening_grid, self.opening_elements))
        if self.self_close_angles and self_close_deg is not None:
            parts.append(self.self_close_values(model, self_close_deg))
        L = np.concatenate(parts)
        assert L.size == self.size - (self.sizes["self_close"] if self_close_deg is None
                                      else 0)
        return L

    def self_close_values(self, model, self_close_deg: float) -> np.ndarray:
        """The self-close part of L: the geometry on the grid of [theta_closed, theta_sc]
        (:func:`self_close_angles`), then theta_sc (rad). An angle where the linkage does not
        assemble is a ConfigError (one above the open angle: :func:`check_self_close`)."""
        deg = float(self_close_deg)
        grid = self_close_angles(model, deg, self.self_close_angles - 1)
        v = np.r_[opening_values(model, grid, self.opening_elements), grid[-1]]
        if not np.isfinite(v).all():
            raise ConfigError(f"optimise.self_close_min_deg: the linkage does not assemble "
                              f"between stroke.theta_closed_deg and {deg:g} deg")
        return v


def closed_values(model) -> np.ndarray:
    """(q, q') of each conservative element at theta_closed."""
    th = model.stroke.theta_closed
    out = []
    for name in HOLDING:
        q, dq = model.coordinate_fns[name](th)
        out += [float(q), float(dq)]
    return np.array(out)


def holding_moment(closed, P):
    """dV/dtheta at theta_closed (N m) from the ``closed`` part of L and the element
    parameters P (:func:`softclose.model.dynamics.slope` on the coordinates' values)."""
    coords = {name: SimpleNamespace(q=closed[2 * i], dq=closed[2 * i + 1])
              for i, name in enumerate(HOLDING)}
    return slope(coords, P)


def opening_values(model, angles, names) -> np.ndarray:
    """Per angle: (q, q', q'') of each element in ``names``, then tau and tau'."""
    th = ca.SX.sym("theta")
    outs = []
    for name in names:
        q, dq = model.coordinate_fns[name](th)
        outs += [q, dq, ca.jacobian(dq, th)]
    c, dc = model.coeffs(th)
    i = COEFFS.index("tau")
    outs += [c[i], dc[i]]
    fn = ca.Function("opening_geometry", [th], [ca.vertcat(*outs)])
    V = np.asarray(fn.map(len(angles))(np.asarray(angles, float)))
    return V.T.ravel()


def _at_angle(values, P, names, quantity):
    """(Q, dQ/dtheta) at one angle of ``quantity(dV/dtheta, friction moment or None, tau)``
    from the angle's ``values`` (q, q', q'' per element, tau, tau'), differentiated exactly
    (the angle enters through a local coordinate t at t = 0)."""
    t = ca.MX.sym("t")
    coords = {}
    for i, name in enumerate(names):
        q, dq, ddq = values[3 * i], values[3 * i + 1], values[3 * i + 2]
        coords[name] = SimpleNamespace(q=q + dq * t + 0.5 * ddq * t * t, dq=dq + ddq * t)
    k = 3 * len(names)
    tau = values[k] + values[k + 1] * t
    Q = quantity(slope(coords, P), friction(coords, P), tau)
    dQ = ca.jacobian(Q, t)
    Q0, dQ0 = ca.substitute([Q, dQ], [t], [ca.MX(0.0)])
    return Q0, dQ0


def opening_effort(values, P, names):
    """(F, dF/dtheta) of the opening effort at one angle from its ``values`` (q, q', q''
    per element, tau, tau'): (dV/dtheta + friction) / tau."""
    return _at_angle(values, P, names,
                     lambda s, fr, tau: (s if fr is None else s + fr) / tau)


def self_close_moment(values, P, names):
    """(m, dm/dtheta) of the self-closing moment at one angle from its ``values``: dV/dtheta
    - T_fr (N m; > 0: a lid released there at rest starts to close, SPEC §13)."""
    return _at_angle(values, P, names, lambda s, fr, tau: s if fr is None else s - fr)


def opening_angles(model, n: int) -> np.ndarray:
    """The n + 1 angles of the opening effort's grid on [theta_closed, theta0]."""
    st = model.stroke
    return st.theta_closed + (st.theta0 - st.theta_closed) * np.linspace(0.0, 1.0, n + 1)




#: intervals of the angle grid over which the opening effort is bounded (when
#: optimise.opening_force_max is set): the nodes and the cubic Hermite maxima between them
OPENING_INTERVALS = 32


def _on_grid(quantity, values, P, names, n: int):
    """(values (1, n + 1), their slopes (1, n + 1), the entries per angle) of ``quantity``
    (:func:`opening_effort` or :func:`self_close_moment`) at the n + 1 angles of a grid
    whose geometry ``values`` holds, angle after angle."""
    k = 3 * len(names) + 2
    F, dF = [], []
    for i in range(n + 1):
        f, df = quantity(values[i * k:(i + 1) * k], P, names)
        F.append(f)
        dF.append(df)
    return ca.vertcat(*F).T, ca.vertcat(*dF).T, k


def opening_bound(layout, values, theta0, thc, design, spring: str = "coil"):
    """The opening effort at the nodes of a grid of [theta_closed, theta0] and the maxima of
    its cubic Hermite interpolant in every interval (error O(h^4)): every value <= the bound
    bounds the largest effort over the stroke. ``values``: the lid vector's opening part
    (the geometry at the grid's angles, :func:`softclose.optimiser.parameters.opening_values`);
    ``spring``: the NLP's spring law ("coil" or "gas")."""
    n = OPENING_INTERVALS
    F, dF, _ = _on_grid(opening_effort, values, elements.params(design, spring),
                        layout.opening_elements, n)
    h = (theta0 - thc) / n
    va, vb, ma, mb = F[:n], F[1:], dF[:n] * h, dF[1:] * h
    return ca.vertcat(F.T, hermite_max(va.T, ma.T, vb.T, mb.T))


def check_self_close(cfg) -> None:
    """ConfigError when ``optimise.self_close_min_deg`` lies above ``stroke.theta_open_deg``:
    the hand force and its zones (SPEC §13), which the verification reads, end there."""
    deg, top = cfg.optimise.self_close_min_deg, cfg.stroke.theta_open_deg
    if deg is not None and deg > top:
        raise ConfigError(f"optimise.self_close_min_deg: {deg:g} deg is above the open angle "
                          f"stroke.theta_open_deg = {top:g} deg: lower it or open the lid further")


def self_close_angles(model, self_close_deg: float, n: int) -> np.ndarray:
    """The n + 1 angles (rad) of the self-close grid on [theta_closed, theta_sc], theta_sc
    = ``self_close_deg`` (at theta_closed or below it: every angle is theta_closed)."""
    thc = model.stroke.theta_closed
    hi = max(np.radians(float(self_close_deg)), thc)
    return thc + (hi - thc) * np.linspace(0.0, 1.0, n + 1)


#: intervals of the angle grid over which the self-closing moment is kept positive (when
#: optimise.self_close_min_deg is set): the nodes and the cubic Hermite minima between them
SELF_CLOSE_INTERVALS = 32
#: the least self-closing moment (N m) the NLP allows on [theta_closed, theta_sc]: "closes
#: by itself" is strict (dV/dtheta > T_fr), and the margin keeps the edge of the zone (a root
#: the verification locates) above theta_sc however closely Ipopt meets the bound
SELF_CLOSE_MARGIN = 1e-6


def self_close_bound(layout, values, thc, design, spring: str = "coil"):
    """The self-closing moment dV/dtheta - T_fr (N m) at the nodes of the grid of
    [theta_closed, theta_sc] and the minima of its cubic Hermite interpolant in every
    interval (error O(h^4)): every value >= :data:`SELF_CLOSE_MARGIN` keeps the lid closing by
    itself from every angle up to theta_sc. ``values``: the lid vector's self-close part
    (the geometry at the grid's angles, then theta_sc); ``spring``: the NLP's spring law
    ("coil" or "gas")."""
    n = layout.self_close_angles - 1
    m, dm, k = _on_grid(self_close_moment, values, elements.params(design, spring),
                        layout.opening_elements, n)
    theta_sc = values[(n + 1) * k]
    h = (ca.fmax(theta_sc, thc) - thc) / n
    va, vb, ma, mb = m[:n], m[1:], dm[:n] * h, dm[1:] * h
    return ca.vertcat(m.T, -hermite_max(-va.T, -ma.T, -vb.T, -mb.T))


def self_close_function(layout, spring: str = "coil") -> ca.Function:
    """(the self-close part of L, a parameter vector p, theta_closed) -> the values of
    :func:`self_close_bound` with the spring law ``spring``: the NLP's constraint evaluated
    apart from it (the active sets differentiate it in the angle); built once per layout."""
    fns = layout.__dict__.setdefault("_self_close_fns", {})
    if spring not in fns:
        v = ca.MX.sym("v", layout.sizes["self_close"])
        q, thc = ca.MX.sym("p", len(elements.PARAM_NAMES)), ca.MX.sym("thc")
        fns[spring] = ca.Function("self_close", [v, q, thc],
                                  [self_close_bound(layout, v, thc, q, spring)])
    return fns[spring]


__all__ = ["DEGREES", "HOLDING", "padded_degree", "SymbolicSeries", "LidLayout",
           "closed_values", "holding_moment", "opening_values", "opening_effort",
           "opening_angles", "OPENING_INTERVALS", "opening_bound", "self_close_moment", "check_self_close",
           "self_close_angles", "SELF_CLOSE_INTERVALS", "SELF_CLOSE_MARGIN",
           "self_close_bound", "self_close_function"]
