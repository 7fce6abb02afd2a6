"""The lid's numbers as NLP parameters: an NLP is built from its structure, a lid fills it.

An NLP's CasADi graph holds no number of the lid. What the equation of motion and the
constraints read of the mechanism -- the Chebyshev series of the geometric functions
(:class:`~softclose.optimiser.interval.ChebyshevFit`), the elements' coordinates at the
closed angle (the holding moment), the scales of the free variables, the fixed attachment
points, the opening effort's geometry on its angle grid -- enters as one parameter vector
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

from ..model import elements
from ..model.dynamics import COEFFS, friction, slope
from .hermite import hermite_max

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
    grid: q, q', q'' of every conservative and friction element, tau and tau')."""

    def __init__(self, series: SymbolicSeries, n_scales: int, points: bool,
                 opening_angles: int = 0):
        self.series = series
        self.opening_elements = tuple(e.name for e in elements.SPRINGS + elements.FRICTIONS)
        self.opening_angles = int(opening_angles)
        self.sizes = {"series": series.size, "closed": 2 * len(HOLDING),
                      "scales": int(n_scales), "points": 8 if points else 0,
                      "opening": self.opening_angles * (3 * len(self.opening_elements) + 2)}
        self.size = sum(self.sizes.values())

    def split(self, L) -> dict:
        """{part: slice of L} (numbers or MX)."""
        out, i = {}, 0
        for k, n in self.sizes.items():
            out[k] = L[i:i + n]
            i += n
        return out

    # -- numbers of one lid ----------------------------------------------------------------
    def values(self, model, fit, scales=(), points=None, opening_grid=None) -> np.ndarray:
        """L of ``model`` (its ``fit``), the free variables' ``scales``, the attachment
        ``points`` and the opening grid's angles."""
        parts = [self.series.values(fit), closed_values(model),
                 np.asarray(scales, float).ravel()]
        if self.sizes["points"]:
            parts.append(np.asarray(points, float).ravel())
        if self.opening_angles:
            parts.append(opening_values(model, opening_grid, self.opening_elements))
        L = np.concatenate(parts)
        assert L.size == self.size
        return L


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


def opening_effort(values, P, names):
    """(F, dF/dtheta) of the opening effort at one angle from its ``values`` (q, q', q''
    per element, tau, tau'): (dV/dtheta + friction) / tau, differentiated exactly (the
    angle enters through a local coordinate t at t = 0)."""
    t = ca.MX.sym("t")
    coords = {}
    for i, name in enumerate(names):
        q, dq, ddq = values[3 * i], values[3 * i + 1], values[3 * i + 2]
        coords[name] = SimpleNamespace(q=q + dq * t + 0.5 * ddq * t * t, dq=dq + ddq * t)
    k = 3 * len(names)
    tau = values[k] + values[k + 1] * t
    fr = friction(coords, P)
    s = slope(coords, P)
    F = (s if fr is None else s + fr) / tau
    dF = ca.jacobian(F, t)
    F0, dF0 = ca.substitute([F, dF], [t], [ca.MX(0.0)])
    return F0, dF0


def opening_angles(model, n: int) -> np.ndarray:
    """The n + 1 angles of the opening effort's grid on [theta_closed, theta0]."""
    st = model.stroke
    return st.theta_closed + (st.theta0 - st.theta_closed) * np.linspace(0.0, 1.0, n + 1)




#: intervals of the angle grid over which the opening effort is bounded (when
#: optimise.opening_force_max is set): the nodes and the cubic Hermite maxima between them
OPENING_INTERVALS = 32


def opening_bound(layout, values, theta0, thc, design, spring: str = "coil"):
    """The opening effort at the nodes of a grid of [theta_closed, theta0] and the maxima of
    its cubic Hermite interpolant in every interval (error O(h^4)): every value <= the bound
    bounds the largest effort over the stroke. ``values``: the lid vector's opening part
    (the geometry at the grid's angles, :func:`softclose.optimiser.lid.opening_values`);
    ``spring``: the NLP's spring law ("coil" or "gas")."""
    n = OPENING_INTERVALS
    names = layout.opening_elements
    k = 3 * len(names) + 2
    P = elements.params(design, spring)
    F, dF = [], []
    for i in range(n + 1):
        f, df = opening_effort(values[i * k:(i + 1) * k], P, names)
        F.append(f)
        dF.append(df)
    F, dF = ca.vertcat(*F).T, ca.vertcat(*dF).T
    h = (theta0 - thc) / n
    va, vb, ma, mb = F[:n], F[1:], dF[:n] * h, dF[1:] * h
    return ca.vertcat(F.T, hermite_max(va.T, ma.T, vb.T, mb.T))


__all__ = ["DEGREES", "HOLDING", "padded_degree", "SymbolicSeries", "LidLayout",
           "closed_values", "holding_moment", "opening_values", "opening_effort",
           "opening_angles", "OPENING_INTERVALS", "opening_bound"]
