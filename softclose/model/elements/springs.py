"""Springs: the spring on a length (of a kind, with a preload; or a gas strut), a torsion
spring at a pivot.

The coil springs are affine laws on their coordinate q, ``T = a + b q``: the torsion spring's
``T = k (q - q0)``, valid everywhere; the spring's ``T = s F0 + k (l - l0)``, valid on its
side of its free length (:class:`Spring`). A gas strut is the spring of kind ``gas_strut``:
its force follows the gas law over its stroke (:func:`gas_tension`), not an affine one.
"""

from __future__ import annotations

import math

import numpy as np

from ..keys import Key
from .base import Element, Param
from .coordinates import PIVOTS, Length, PivotAngle


class _Linear(Element):
    """``T = k (q - q0)`` with k = P[rate], q0 = P[free]."""

    rate = free = ""

    def potential(self, q, P):
        return 0.5 * P[self.rate] * (q - P[self.free]) ** 2

    def tension(self, q, P):
        return P[self.rate] * (q - P[self.free])

    def affine(self, P):
        return (-P[self.rate] * P[self.free], P[self.rate])


#: the spring's kinds and the number p holds for each: for the coil springs the sign s of
#: the preload, T = s F0 + k (l - l0); -2 a gas strut (:func:`gas_tension`)
KINDS = {"linear": 0.0, "extension": 1.0, "compression": -1.0, "gas_strut": -2.0}
#: the number of a gas strut in p
GAS = KINDS["gas_strut"]
#: a strut's stroke when none is given, a fraction of its extended length (SPEC §12)
STROKE_FRACTION = 0.4


def _symbolic(*xs) -> bool:
    return any(hasattr(x, "is_symbolic") for x in xs)


def _where(c, a, b):
    """``a`` where ``c`` else ``b`` (numbers, arrays or CasADi expressions alike)."""
    if c is True or c is False:
        return a if c else b
    if _symbolic(c, a, b):
        import casadi as ca
        return ca.if_else(c, a, b)
    out = np.where(c, a, b)
    return float(out) if out.ndim == 0 else out


def strut_rate(P):
    """beta = (1 - 1/K) / s of a gas strut (1/m): its force is F1 / (1 - beta x) at x = L_ext
    - l into its stroke s (K its progression; s its stroke, 0.4 L_ext when none is given)."""
    L, s, K = P["spring_rest_length"], P["strut_stroke"], P["strut_progression"]
    stroke = _where(s > 0, s, STROKE_FRACTION * L)
    return (1 - 1 / K) / stroke


def strut_stroke(P):
    """The strut's stroke s (m): ``design.strut_stroke``, or 0.4 L_ext when none is given."""
    s = P["strut_stroke"]
    return _where(s > 0, s, STROKE_FRACTION * P["spring_rest_length"])


def gas_tension(u, G, beta):
    """A gas strut's tension along its length at u = l - L_ext (<= 0 within its stroke):
    ``T = G / (1 + beta u)``, G = -F1 (it pushes): the isothermal gas law, F1 at full
    extension, K F1 at full compression (beta = (1 - 1/K)/s)."""
    return G / (1 + beta * u)


def gas_potential(u, G, beta):
    """Its potential, ``V = (G / beta) ln(1 + beta u)`` (V(0) = 0; G u when beta = 0), written
    ``G u psi(beta u)`` with psi(z) = ln(1 + z)/z, psi(0) = 1, so that a constant-force strut
    (K = 1) is no special case."""
    z = beta * u
    if _symbolic(u, G, beta):
        import casadi as ca
        psi = ca.if_else(ca.fabs(z) < 1e-8, 1 - z / 2, ca.log1p(z) / ca.if_else(z == 0, 1, z))
        return G * u * psi
    z = np.asarray(z, float)
    with np.errstate(divide="ignore", invalid="ignore"):
        psi = np.where(np.abs(z) < 1e-8, 1 - z / 2, np.log1p(z) / np.where(z == 0, 1, z))
    out = G * u * psi
    return float(out) if np.ndim(out) == 0 else out


class Spring(Element):
    """The spring between E on the lid and the anchor D, of a kind that can be bought.

    ``T = s F0 + k (l - l0)``, ``V = 1/2 k (l - l0)^2 + s F0 l`` with s = +1 for an extension
    spring (pulls; F0 its initial tension; valid while l >= l0, its closed-coil free length,
    and up to ``spring_max_length``), s = -1 for a compression spring (pushes; F0 its
    preload; valid while l <= l0, its free length, and down to ``spring_min_length``, its
    solid length), s = 0 for the seed's linear element (a double-acting cartridge: pulls and
    pushes, no preload, within the optional limits).

    A gas strut (kind ``gas_strut``) pushes with the gas law over its stroke s: with x = l0 -
    l (l0 its extended length), ``F = F1 / (1 - (1 - 1/K) x / s)`` (F0 = F1 its force at full
    extension, K its progression, :func:`gas_tension`); its rate k is not used. Valid while
    l0 - s <= l <= l0 (and within the length limits).

    A stroke that takes a spring outside its valid range is an invalid design: the law
    beyond it (a slack spring, a preload's jump, a strut past its end stops) is never used
    for a reported number.
    """

    name = "spring"
    seed = True
    doc = ("spring between E on the lid and the anchor D: an extension spring (pulls), a "
           "compression spring (pushes), a gas strut (pushes with the gas law), or the "
           "seed's linear cartridge")
    keys = (
        Key("design", "spring_k", "nonneg", 0.0, "N/m", "spring rate k (>= 0)",
            lo=0.0, hi=1e7, spread=0.10),
        Key("design", "spring_rest_length", "pos", 0.05, "m",
            "spring free length l0 (> 0): an extension spring's closed-coil length, a "
            "compression spring's or strut's extended length", lo=1e-4, hi=10.0),
        Key("design", "spring_kind", "str:" + ",".join(KINDS), "linear", "",
            "`extension` (pulls, valid while l >= l0), `compression` (a coil spring that "
            "pushes, valid while l <= l0), `gas_strut` (pushes with the gas law over its "
            "stroke: l0 - s <= l <= l0) or `linear` (pulls and pushes: the seed's idealised "
            "element)"),
        Key("design", "spring_preload", "nonneg", 0.0, "N",
            "F0 (>= 0): an extension spring's initial tension, a compression spring's "
            "preload, a gas strut's force F1 at full extension (its datasheet's F1, at the "
            "reference temperature); not used by `linear`", lo=0.0, hi=1e5),
        Key("design", "strut_stroke", "pos", None, "m",
            "a gas strut's stroke s; none: 0.4 x its extended length (design.spring_rest_length)",
            lo=1e-4, hi=10.0),
        Key("design", "strut_progression", "pos", 1.3, "1",
            "a gas strut's progression K (>= 1): its force at full compression over F1",
            lo=1.0, hi=5.0),
        Key("design", "spring_min_length", "pos", None, "m",
            "shortest length the spring may take (a compression spring's solid length, a "
            "strut's compressed length); none: no limit", lo=1e-4, hi=10.0),
        Key("design", "spring_max_length", "pos", None, "m",
            "longest length the spring may take (an extension spring's maximum extension); "
            "none: no limit", lo=1e-4, hi=10.0),
        Key("geometry", "lid_e", "vec2", (0.004, 0.014), "m",
            "spring point E, lid frame, from A", lo=-10.0, hi=10.0),
        Key("geometry", "spring_anchor", "vec2", (-0.060, 0.020), "m",
            "spring anchor D (world)", lo=-10.0, hi=10.0),
    )
    params = (Param("spring_k"), Param("spring_rest_length"),
              Param("spring_kind", codes=KINDS), Param("spring_preload"),
              Param("strut_stroke", none=0.0), Param("strut_progression"))
    acting_params = ("spring_k", "spring_preload")
    columns = (("l", "q"), ("dl", "dq"))

    def coordinate(self, lid):
        return Length("E", "lid_e", "spring_anchor")

    def preload(self, P):
        """s F0: a coil spring's signed preload (+ pulls, - pushes)."""
        return P["spring_kind"] * P["spring_preload"]

    def gas(self, P):
        """(G, beta) of the gas law (:func:`gas_tension`): G = -F1 for a strut, 0 else."""
        return _where(self.is_gas(P), -P["spring_preload"], 0.0), strut_rate(P)

    def potential(self, q, P):
        coil = 0.5 * P["spring_k"] * (q - P["spring_rest_length"]) ** 2 + self.preload(P) * q
        if not self._any_gas(P):
            return coil
        G, beta = self.gas(P)
        return _where(self.is_gas(P), gas_potential(q - P["spring_rest_length"], G, beta),
                      coil)

    def tension(self, q, P):
        coil = self.preload(P) + P["spring_k"] * (q - P["spring_rest_length"])
        if not self._any_gas(P):
            return coil
        G, beta = self.gas(P)
        return _where(self.is_gas(P), gas_tension(q - P["spring_rest_length"], G, beta), coil)

    def affine(self, P):
        """(a, b) of a coil spring's T = a + b l (a gas strut's law is not affine: callers
        that need it use :meth:`tension`)."""
        return (self.preload(P) - P["spring_k"] * P["spring_rest_length"], P["spring_k"])

    @staticmethod
    def _any_gas(P):
        """Might a row be a gas strut (always, for a symbolic kind)?"""
        law = getattr(P, "spring", None)
        if law is not None:
            return law == "gas"
        kind = P["spring_kind"]
        return _symbolic(kind) or bool(np.any(np.asarray(kind) == GAS))

    @staticmethod
    def is_gas(P):
        """True (per row) where the spring is a gas strut."""
        law = getattr(P, "spring", None)
        if law is not None:
            return law == "gas"
        return P["spring_kind"] == GAS

    extremes = ("min_spring_length", "max_spring_length")

    def range_messages(self, P, mounting, rows, short, edge, worst, excess):
        """:meth:`range_message` of many rows at once: the rows of each case (:meth:`_case`)
        formatted by its one template (:meth:`_template`), the parameters read once."""
        s = np.asarray(P["spring_kind"], float)[rows]
        short = np.asarray(short, bool)
        edge, worst = np.degrees(np.asarray(edge, float)), np.degrees(np.asarray(worst, float))
        l0 = np.asarray(P["spring_rest_length"], float)[rows]
        end = l0 - np.asarray(strut_stroke(P), float)[rows] if self._any_gas(P) else l0
        lmin = mounting.spring_min_length if mounting is not None else None
        case = np.where((s > 0) & short, 0, np.where((s < 0) & ~short, 1,
                                                     np.where(short, 2, 3)))
        case = np.where(s == GAS, np.where(~short, 4, np.where(
            (end < lmin) if lmin else False, 2, 5)), case) if self._any_gas(P) else case
        with np.errstate(invalid="ignore"):
            span = np.where(np.isnan(edge), 0, np.where(worst < edge, 1, 2))
        length = (np.where(case == 5, end, l0) * 1e3).tolist()
        x, e, w = (np.asarray(excess, float) * 1e3).tolist(), edge.tolist(), worst.tolist()
        out = [""] * len(case)
        key = case * 3 + span
        for g in sorted(set(key.tolist())):   # (np.unique would import numpy.ma)
            c, sp = divmod(g, 3)
            t = self._template(c, sp, mounting)
            idx = np.flatnonzero(key == g).tolist()
            cols = ([length] if c in self._LENGTH_CASES else []) + ([e] if sp else []) + [x, w]
            for i, a in zip(idx, zip(*([col[i] for i in idx] for col in cols))):
                out[i] = t % a
        return out

    def range_message(self, P, mounting, i, short, where, excess):
        s, l0 = float(P["spring_kind"][i]), float(P["spring_rest_length"][i])
        end = l0 - float(np.asarray(strut_stroke(P), float)[i]) if s == GAS else None
        edge, worst = (None if a is None else math.degrees(a) for a in where)
        return self._message(s, l0, short, mounting, edge, worst, excess, end)

    @classmethod
    def _message(cls, s, l0, short, d, edge, worst, excess, end=None):
        """The text of :meth:`range_message`, one row at a time (``edge``, ``worst`` in
        degrees; ``edge`` None: beyond the range over the whole stroke; ``end``: a gas strut's
        compressed length): the statement :meth:`range_messages` formats many rows at once."""
        case = cls._case(s, short, end, d.spring_min_length if d is not None else None)
        span = 0 if edge is None else 1 if worst < edge else 2
        length = (end if case == 5 else l0) * 1e3
        args = ((length,) if case in cls._LENGTH_CASES else ()) + ((edge,) if span else ()) \
            + (excess * 1e3, worst)
        return cls._template(case, span, d) % args

    #: the cases whose message names a length of the spring itself
    _LENGTH_CASES = (0, 1, 4, 5)

    @staticmethod
    def _case(s, short, end=None, lmin=None) -> int:
        """Which limit a spring of kind ``s`` passes (``short``: below its range): 0 an
        extension spring's free length, 1 a compression spring's, 2 the minimum length,
        3 the maximum length, 4 a gas strut's extended length, 5 a gas strut's compressed
        end (``end`` = l0 - s, unless the minimum length ``lmin`` lies above it)."""
        if s == GAS:
            if not short:
                return 4
            return 2 if lmin and end is not None and lmin > end else 5
        return 0 if s > 0 and short else 1 if s < 0 and not short else 2 if short else 3

    @staticmethod
    def _template(case: int, span: int, d) -> str:
        """The %-template of a range message: ``case`` (:meth:`_case`), ``span`` 0 over the
        whole stroke, 1 below the edge, 2 above it. Its fields, in order: the spring's
        length (mm; :attr:`_LENGTH_CASES`), the edge (deg; span 1 and 2), the excess (mm),
        the worst angle (deg)."""
        if case == 0:
            what = "the extension spring (it only pulls) would be shorter than its free " \
                   "length %.2f mm"
        elif case == 1:
            what = "the compression spring (it only pushes) would be longer than its free " \
                   "length %.2f mm"
        elif case == 4:
            what = "the gas strut would be longer than its extended length %.2f mm"
        elif case == 5:
            what = ("the gas strut would be pushed in beyond its stroke (shorter than "
                    "%.2f mm: design.strut_stroke)")
        elif case == 2:
            what = (f"the spring would be shorter than its minimum length "
                    f"(design.spring_min_length = {d.spring_min_length * 1e3:.2f} mm)")
        else:
            what = (f"the spring would be longer than its maximum length "
                    f"(design.spring_max_length = {d.spring_max_length * 1e3:.2f} mm)")
        where = ("over the whole stroke" if span == 0 else
                 f"{'below' if span == 1 else 'above'} theta = %.1f deg")
        lit = case not in Spring._LENGTH_CASES
        return f"{what.replace('%', '%%') if lit else what} {where}, " \
               "by up to %.2f mm (at theta = %.1f deg)"

    def valid(self, P, mounting=None):
        """(lo, hi) of l, per design: an extension spring from l0 up to its maximum length, a
        compression spring from its solid length up to l0, a gas strut over its stroke
        (l0 - s up to l0), the linear one within its limits."""
        s, l0 = P["spring_kind"], P["spring_rest_length"]
        d = mounting
        lmin = d.spring_min_length if d is not None and d.spring_min_length else -math.inf
        lmax = d.spring_max_length if d is not None and d.spring_max_length else math.inf
        lo = np.where(s > 0, l0, lmin)
        if self._any_gas(P):
            lo = np.where(s == GAS, np.maximum(np.asarray(l0) - strut_stroke(P), lmin), lo)
        return lo, np.where(s < 0, l0, lmax)


class TorsionSpring(_Linear):
    name = "torsion"
    doc = ("torsion spring at a pivot: a moment -k_t (psi - psi_free) on the relative "
           "rotation psi of the two bodies it joins")
    rate, free = "torsion_k", "torsion_free_angle_deg"
    keys = (
        Key("design", "torsion_k", "nonneg", 0.0, "N m/rad", "torsion spring rate k_t (>= 0)",
            lo=0.0, hi=1e5),
        Key("design", "torsion_free_angle_deg", "real", 0.0, "deg",
            "torsion spring's free angle psi_free: the pivot's relative angle (measured as "
            "geometry.assembly gives the cranks) where it is unloaded", lo=-360.0, hi=360.0),
        Key("design", "torsion_pivot", "str:" + ",".join(p for p in PIVOTS if p != "lid"), "O",
            "", "pivot of the torsion spring: O (crank OA, psi = phi), B (crank BC, gamma), "
            "A (lid on OA, theta - phi), C (lid on BC, theta - gamma), H (a hinge lid's hinge, "
            "theta; the default of a hinge lid)"),
    )
    params = (Param("torsion_k"), Param("torsion_free_angle_deg", math.pi / 180))
    columns = (("psi", "q"), ("dpsi", "dq"))
    table = "coordinates"

    def coordinate(self, lid):
        return PivotAngle(lid.mounting.torsion_pivot)

    def structure(self, mounting):
        return (mounting.torsion_pivot,)

    acting_params = ("torsion_k",)
