"""Friction: lumped Coulomb friction on the lid's rotation, with stick and slip.

While the lid moves, a moment ``-T_f sign(theta')`` opposes it; at rest (released, or at a
turning point) it sticks unless the driving moment ``-dV/dtheta`` exceeds T_f, and then moves
the way that moment drives it. It is neither a spring nor a viscous damper: its law is the
constant force ``coulomb(P)`` along its coordinate against the motion, and the integrators
treat the sign and the stick as a state of the stroke: the reference locates every rest as
an event, the fixed-step kernel to its own order, and the optimiser, whose strokes are
monotone (theta' <= 0), sees the constant moment +T_f.
"""

from __future__ import annotations

import numpy as np

from ...config.keys import Key
from .base import Element, Param
from .coordinates import PivotAngle


class Friction(Element):
    name = "friction"
    doc = "lumped Coulomb friction on the lid's rotation (pins, a strut's seals), stick and slip"
    keys = (Key("friction", "torque", "nonneg", 0.0, "N m",
                "T_f (>= 0): the friction moment on the lid's rotation, against its motion; the "
                "lid sticks at rest unless the driving moment exceeds it", lo=0.0, hi=1e3),)
    params = (Param("friction_torque", config_key="friction.torque"),)
    columns = ()

    def coordinate(self, lid):
        return PivotAngle("lid")

    def unit_rate(self, mounting) -> bool:
        return True

    def coulomb(self, P):
        return P["friction_torque"]

    def acts(self, values):
        return np.asarray(values.get("friction_torque", 0.0)) != 0.0
