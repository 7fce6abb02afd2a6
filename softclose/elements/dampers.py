"""Dampers: a dashpot on a length, a rotary damper on the lid's rotation.

Both are viscous: the force along q is ``-B q-dot`` with B = c, so their generalised force on
theta is ``-c q'^2 theta'`` and they only dissipate (power ``-c q'^2 theta'^2``).
"""

from __future__ import annotations

from ..keys import Key
from .base import Element, Param
from .coordinates import Length, PivotAngle


class Dashpot(Element):
    name = "dashpot"
    doc = "dashpot between pin C on the lid and the ground pivot O"
    keys = (Key("design", "damper_c", "nonneg", 0.0, "N s/m", "dashpot coefficient c (>= 0)",
                lo=0.0, hi=1e7, spread=0.20),)
    params = (Param("damper_c"),)
    columns = (("dd", "dq2"),)

    def coordinate(self, cfg):
        return Length("C", None, None, (0.0, 0.0))

    def viscous(self, P):
        return P["damper_c"]


class RotaryDamper(Element):
    name = "rotary"
    doc = "rotary damper on the lid's own rotation (a modelling aid of the seed)"
    keys = (Key("design", "rotary_damper_c", "nonneg", 0.0, "N m s/rad",
                "rotary damper coefficient c_rot (>= 0), on the lid's rotation theta",
                lo=0.0, hi=1e5),)
    params = (Param("rotary_damper_c"),)

    def coordinate(self, cfg):
        return PivotAngle("lid")

    def viscous(self, P):
        return P["rotary_damper_c"]
