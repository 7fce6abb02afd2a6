"""Springs: the spring on a length (of a kind, with a preload), a torsion spring at a pivot.

Both are affine laws on their coordinate q, ``T = a + b q``: the torsion spring's
``T = k (q - q0)``, valid everywhere; the spring's ``T = s F0 + k (l - l0)``, valid on its
side of its free length (:class:`Spring`).
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

    def coordinate(self, cfg):
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

    def range_messages(self, P, cfg, rows, short, edge, worst, excess):
        """:meth:`range_message` of many rows at once: the same text, each row's formatted
        by the template of its case (which limit, over the whole stroke or on which side of
        the edge) with %-formatting, which rounds as the f-strings of :meth:`_message` do."""
        s = np.asarray(P["spring_kind"], float)[rows]
        short = np.asarray(short, bool)
        edge, worst = np.degrees(np.asarray(edge, float)), np.degrees(np.asarray(worst, float))
        l0 = (np.asarray(P["spring_rest_length"], float)[rows] * 1e3).tolist()
        x = (np.asarray(excess, float) * 1e3).tolist()
        case = np.where((s > 0) & short, 0, np.where((s < 0) & ~short, 1,
                                                     np.where(short, 2, 3)))
        whole = np.isnan(edge)
        with np.errstate(invalid="ignore"):
            below = worst < edge
        d = cfg.design
        heads = ("the extension spring (it only pulls) would be shorter than its free "
                 "length %.2f mm",
                 "the compression spring (it only pushes) would be longer than its free "
                 "length %.2f mm",
                 "the spring would be shorter than its minimum length (design.spring_min_length"
                 " = " + (f"{d.spring_min_length * 1e3:.2f}" if d.spring_min_length is not None
                          else "None") + " mm)",
                 "the spring would be longer than its maximum length (design.spring_max_length"
                 " = " + (f"{d.spring_max_length * 1e3:.2f}" if d.spring_max_length is not None
                          else "None") + " mm)")
        out = [""] * len(case)
        e, w = edge.tolist(), worst.tolist()
        key = case * 3 + np.where(whole, 0, np.where(below, 1, 2))
        for g in np.unique(key).tolist():
            c, span = divmod(g, 3)
            head = heads[c] if c < 2 else heads[c].replace("%", "%%")
            tail = ("over the whole stroke" if span == 0 else
                    ("below" if span == 1 else "above") + " theta = %.1f deg")
            t = f"{head} {tail}, by up to %.2f mm (at theta = %.1f deg)"
            idx = np.flatnonzero(key == g).tolist()
            if c < 2 and span:
                args = [(l0[i], e[i], x[i], w[i]) for i in idx]
            elif c < 2:
                args = [(l0[i], x[i], w[i]) for i in idx]
            elif span:
                args = [(e[i], x[i], w[i]) for i in idx]
            else:
                args = [(x[i], w[i]) for i in idx]
            for i, a in zip(idx, args):
                out[i] = t % a
        return out

    def range_message(self, P, cfg, i, short, where, excess):
        s, l0 = float(P["spring_kind"][i]), float(P["spring_rest_length"][i])
        edge, worst = (None if a is None else math.degrees(a) for a in where)
        return self._message(s, l0, short, cfg.design, edge, worst, excess)

    @staticmethod
    def _message(s, l0, short, d, edge, worst, excess):
        """The text of :meth:`range_message` (``edge``, ``worst`` in degrees)."""
        if s > 0 and short:
            what = (f"the extension spring (it only pulls) would be shorter than its free "
                    f"length {l0 * 1e3:.2f} mm")
        elif s < 0 and not short:
            what = (f"the compression spring (it only pushes) would be longer than its free "
                    f"length {l0 * 1e3:.2f} mm")
        elif short:
            what = (f"the spring would be shorter than its minimum length "
                    f"(design.spring_min_length = {d.spring_min_length * 1e3:.2f} mm)")
        else:
            what = (f"the spring would be longer than its maximum length "
                    f"(design.spring_max_length = {d.spring_max_length * 1e3:.2f} mm)")
        span = ("over the whole stroke" if edge is None else
                f"{'below' if worst < edge else 'above'} theta = {edge:.1f} deg")
        return f"{what} {span}, by up to {excess * 1e3:.2f} mm (at theta = {worst:.1f} deg)"

    def valid(self, P, cfg=None):
        """(lo, hi) of l, per design: an extension spring from l0 up to its maximum length, a
        compression spring from its solid length up to l0, the linear one within its limits."""
        s, l0 = P["spring_kind"], P["spring_rest_length"]
        d = cfg.design if cfg is not None else None
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
            "A (lid on OA, theta - phi), C (lid on BC, theta - gamma)"),
    )
    params = (Param("torsion_k"), Param("torsion_free_angle_deg", math.pi / 180))
    columns = (("psi", "q"), ("dpsi", "dq"))
    table = "extra"

    def coordinate(self, cfg):
        return PivotAngle(cfg.design.torsion_pivot)

    def structure(self, cfg):
        return (cfg.design.torsion_pivot,)

    acting_params = ("torsion_k",)
