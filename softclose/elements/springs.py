"""Springs: a linear spring on a length.

The law on its coordinate q: ``V = 1/2 k (q - q0)^2``, ``T = k (q - q0)`` (affine: a = -k q0,
b = k), valid everywhere.
"""

from __future__ import annotations

from ..keys import Key
from .base import Element, Param
from .coordinates import Length


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
