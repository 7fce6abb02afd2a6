"""Gravity: the weights of the three bodies. Coordinate: their potential itself (V = q)."""

from __future__ import annotations

import numpy as np

from ..keys import Key
from .base import Element
from .coordinates import Weights


class Gravity(Element):
    name = "gravity"
    seed = True
    doc = "weights of the lid and the cranks at their centres of mass"
    keys = (Key("mass", "gravity", "nonneg", 9.81, "m/s^2", "g (>= 0)", lo=0.0, hi=100.0),)
    columns = (("Vg", "q"), ("dVg", "dq"))

    def coordinate(self, lid):
        return Weights()

    def potential(self, q, P):
        return q

    def tension(self, q, P):
        return 1.0

    def affine(self, P):
        return (1.0, 0.0)

    def acts(self, values):
        return np.True_
