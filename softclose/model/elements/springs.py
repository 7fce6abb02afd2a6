"""Springs: the spring on a length (of a kind, with a preload), a torsion spring at a pivot.

Both are affine laws on their coordinate q, ``T = a + b q``: the torsion spring's
``T = k (q - q0)``, valid everywhere; the spring's ``T = s F0 + k (l - l0)``, valid on its
side of its free length (:class:`Spring`).
"""

from __future__ import annotations

import math

import numpy as np

from ...config.keys import Key
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


#: the spring's kinds, and the sign s of the preload each gives: T = s F0 + k (l - l0)
KINDS = {"linear": 0.0, "extension": 1.0, "compression": -1.0}


class Spring(Element):
    """The spring between E on the lid and the anchor D, of a kind that can be bought.

    ``T = s F0 + k (l - l0)``, ``V = 1/2 k (l - l0)^2 + s F0 l`` with s = +1 for an extension
    spring (pulls; F0 its initial tension; valid while l >= l0, its closed-coil free length,
    and up to ``spring_max_length``), s = -1 for a compression spring or gas strut (pushes; F0
    its preload, a strut's force at full extension with k its progression; valid while
    l <= l0, its free length, and down to ``spring_min_length``, its solid length), s = 0 for
    the seed's linear element (a double-acting cartridge: pulls and pushes, no preload, within
    the optional limits). A stroke that takes it outside its valid range is an invalid
    design: the law beyond the free length (a slack spring, a preload's jump) is never used
    for a reported number.
    """

    name = "spring"
    seed = True
    doc = ("spring between E on the lid and the anchor D: an extension spring (pulls), a "
           "compression spring or gas strut (pushes), or the seed's linear cartridge")
    keys = (
        Key("design", "spring_k", "nonneg", 0.0, "N/m", "spring rate k (>= 0)",
            lo=0.0, hi=1e7, spread=0.10),
        Key("design", "spring_rest_length", "pos", 0.05, "m",
            "spring free length l0 (> 0): an extension spring's closed-coil length, a "
            "compression spring's or strut's extended length", lo=1e-4, hi=10.0),
        Key("design", "spring_kind", "str:" + ",".join(KINDS), "linear", "",
            "`extension` (pulls, valid while l >= l0), `compression` (pushes, valid while "
            "l <= l0: a coil spring or gas strut) or `linear` (pulls and pushes: the seed's "
            "idealised element)"),
        Key("design", "spring_preload", "nonneg", 0.0, "N",
            "F0 (>= 0): an extension spring's initial tension, a compression spring's or gas "
            "strut's preload (a strut's force at full extension); not used by `linear`",
            lo=0.0, hi=1e5),
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
              Param("spring_kind", codes=KINDS), Param("spring_preload"))
    acting_params = ("spring_k", "spring_preload")
    columns = (("l", "q"), ("dl", "dq"))

    def coordinate(self, lid):
        return Length("E", "lid_e", "spring_anchor")

    def preload(self, P):
        """s F0: the signed preload (+ pulls, - pushes)."""
        return P["spring_kind"] * P["spring_preload"]

    def potential(self, q, P):
        return 0.5 * P["spring_k"] * (q - P["spring_rest_length"]) ** 2 + self.preload(P) * q

    def tension(self, q, P):
        return self.preload(P) + P["spring_k"] * (q - P["spring_rest_length"])

    def affine(self, P):
        return (self.preload(P) - P["spring_k"] * P["spring_rest_length"], P["spring_k"])

    extremes = ("min_spring_length", "max_spring_length")

    def range_messages(self, P, mounting, rows, short, edge, worst, excess):
        """:meth:`range_message` of many rows at once: the rows of each case (:meth:`_case`)
        formatted by its one template (:meth:`_template`), the parameters read once."""
        s = np.asarray(P["spring_kind"], float)[rows]
        short = np.asarray(short, bool)
        edge, worst = np.degrees(np.asarray(edge, float)), np.degrees(np.asarray(worst, float))
        case = np.where((s > 0) & short, 0, np.where((s < 0) & ~short, 1,
                                                     np.where(short, 2, 3)))
        with np.errstate(invalid="ignore"):
            span = np.where(np.isnan(edge), 0, np.where(worst < edge, 1, 2))
        l0 = (np.asarray(P["spring_rest_length"], float)[rows] * 1e3).tolist()
        x, e, w = (np.asarray(excess, float) * 1e3).tolist(), edge.tolist(), worst.tolist()
        out = [""] * len(case)
        key = case * 3 + span
        for g in np.unique(key).tolist():
            c, sp = divmod(g, 3)
            t = self._template(c, sp, mounting)
            idx = np.flatnonzero(key == g).tolist()
            cols = ([l0] if c < 2 else []) + ([e] if sp else []) + [x, w]
            for i, a in zip(idx, zip(*([col[i] for i in idx] for col in cols))):
                out[i] = t % a
        return out

    def range_message(self, P, mounting, i, short, where, excess):
        s, l0 = float(P["spring_kind"][i]), float(P["spring_rest_length"][i])
        edge, worst = (None if a is None else math.degrees(a) for a in where)
        return self._message(s, l0, short, mounting, edge, worst, excess)

    @staticmethod
    def _case(s, short) -> int:
        """Which limit a spring of kind ``s`` passes (``short``: below its range): 0 an
        extension spring's free length, 1 a compression spring's, 2 the minimum length,
        3 the maximum length."""
        return 0 if s > 0 and short else 1 if s < 0 and not short else 2 if short else 3

    @staticmethod
    def _template(case: int, span: int, d) -> str:
        """The %-template of a range message: ``case`` (:meth:`_case`), ``span`` 0 over the
        whole stroke, 1 below the edge, 2 above it. Its fields, in order: the free length
        (mm; cases 0 and 1), the edge (deg; span 1 and 2), the excess (mm), the worst angle
        (deg)."""
        if case == 0:
            what = "the extension spring (it only pulls) would be shorter than its free " \
                   "length %.2f mm"
        elif case == 1:
            what = "the compression spring (it only pushes) would be longer than its free " \
                   "length %.2f mm"
        elif case == 2:
            what = (f"the spring would be shorter than its minimum length "
                    f"(design.spring_min_length = {d.spring_min_length * 1e3:.2f} mm)")
        else:
            what = (f"the spring would be longer than its maximum length "
                    f"(design.spring_max_length = {d.spring_max_length * 1e3:.2f} mm)")
        where = ("over the whole stroke" if span == 0 else
                 f"{'below' if span == 1 else 'above'} theta = %.1f deg")
        return f"{what.replace('%', '%%') if case >= 2 else what} {where}, " \
               "by up to %.2f mm (at theta = %.1f deg)"

    @classmethod
    def _message(cls, s, l0, short, d, edge, worst, excess):
        """The text of :meth:`range_message` (``edge``, ``worst`` in degrees; ``edge`` None:
        beyond the range over the whole stroke)."""
        case = cls._case(s, short)
        span = 0 if edge is None else 1 if worst < edge else 2
        args = ((l0 * 1e3,) if case < 2 else ()) + ((edge,) if span else ()) + \
            (excess * 1e3, worst)
        return cls._template(case, span, d) % args

    def valid(self, P, mounting=None):
        """(lo, hi) of l, per design: an extension spring from l0 up to its maximum length, a
        compression spring from its solid length up to l0, the linear one within its limits."""
        s, l0 = P["spring_kind"], P["spring_rest_length"]
        d = mounting
        lmin = d.spring_min_length if d is not None and d.spring_min_length else -math.inf
        lmax = d.spring_max_length if d is not None and d.spring_max_length else math.inf
        return np.where(s > 0, l0, lmin), np.where(s < 0, l0, lmax)


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
    table = "extra"

    def coordinate(self, lid):
        return PivotAngle(lid.mounting.torsion_pivot)

    def structure(self, mounting):
        return (mounting.torsion_pivot,)

    acting_params = ("torsion_k",)
