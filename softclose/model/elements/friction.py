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

from ..keys import Key
from .base import Element, Param
from .coordinates import Length, PivotAngle


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


class StrutFriction(Element):
    """Coulomb friction along the spring's length: a gas strut's seals (SPEC §12).

    A force F_R along the strut against its sliding, ``-F_R sign(l-dot)``; on the lid's
    coordinate the moment ``-F_R |dl/dtheta| sign(theta')``. With the lumped friction it makes
    the friction moment ``T_fr(theta) = T_f + F_R |dl/dtheta|``, which the stick at the release
    and at a turning point compares with the driving moment there (a datasheet's friction
    band F3 - F1 is 2 F_R)."""

    name = "strut_friction"
    doc = "Coulomb friction along the spring (a gas strut's seals), stick and slip"
    keys = (Key("design", "strut_friction", "nonneg", 0.0, "N",
                "F_R (>= 0): friction along the spring or gas strut, against its sliding (a "
                "datasheet's friction band F3 - F1 is 2 F_R)", lo=0.0, hi=1e4),)
    params = (Param("strut_friction"),)
    #: it reads the spring's own columns (its length and dl/dtheta), tabulated for the spring
    columns = (("l", "q"), ("dl", "dq"))
    table = "spring"

    def coordinate(self, lid):
        return Length("E", "lid_e", "spring_anchor")

    def coulomb(self, P):
        return P["strut_friction"]

    def acts(self, values):
        return np.asarray(values.get("strut_friction", 0.0)) != 0.0
