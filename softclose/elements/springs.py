"""Springs: a linear spring on a length, a torsion spring at a pivot.

Both are the same law on their coordinate q: ``V = 1/2 k (q - q0)^2``, ``T = k (q - q0)``
(affine: a = -k q0, b = k), valid everywhere.
"""

from __future__ import annotations

import math

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


class Spring(_Linear):
    name = "spring"
    doc = ("spring between E on the lid and the anchor D: pulls when longer than l0, "
           "pushes when shorter (the seed's idealised, double-acting element)")
    rate, free = "spring_k", "spring_rest_length"
    keys = (
        Key("design", "spring_k", "nonneg", 0.0, "N/m", "spring stiffness k (>= 0)",
            lo=0.0, hi=1e7, spread=0.10),
        Key("design", "spring_rest_length", "pos", 0.05, "m", "spring rest length l0 (> 0)",
            lo=1e-4, hi=10.0),
        Key("geometry", "lid_e", "vec2", (0.004, 0.014), "m",
            "spring point E, lid frame, from A", lo=-10.0, hi=10.0),
        Key("geometry", "spring_anchor", "vec2", (-0.060, 0.020), "m",
            "spring anchor D (world)", lo=-10.0, hi=10.0),
    )
    params = (Param("spring_k"), Param("spring_rest_length"))
    columns = (("l", "q"), ("dl", "dq"))

    def coordinate(self, cfg):
        return Length("E", "lid_e", "spring_anchor")


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
