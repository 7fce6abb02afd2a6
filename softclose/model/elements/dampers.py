"""Dampers: a dashpot on a length, a rotary damper at a pivot (or on the lid's rotation), an
end damper that engages near the rim.

Both are viscous: the force along q is ``-B q-dot`` with B = c, so their generalised force on
theta is ``-c q'^2 theta'`` and they only dissipate (power ``-c q'^2 theta'^2``). With
``design.damper_one_way`` they resist only closing (theta' < 0), as most soft-close parts do:
a monotone closing stroke is the same either way, a stroke that turns back is not.
"""

from __future__ import annotations

import math

from ..keys import Key
from .base import Element, Param
from .coordinates import PIVOTS, Length, PivotAngle


class Dashpot(Element):
    name = "dashpot"
    seed = True
    doc = ("dashpot between a lid point H (default pin C) and a ground anchor (default the "
           "pivot O)")
    keys = (Key("design", "damper_c", "nonneg", 0.0, "N s/m", "dashpot coefficient c (>= 0)",
                lo=0.0, hi=1e7, spread=0.20),
            Key("design", "damper_one_way", "bool", False, "",
                "the dashpot and the rotary damper resist only closing (theta' < 0), as most "
                "soft-close parts do"),
            Key("geometry", "dashpot_anchor", "vec2", (0.0, 0.0), "m",
                "dashpot anchor on the ground (world; default the pivot O)", lo=-10.0,
                hi=10.0),
            Key("geometry", "dashpot_lid", "vec2", None, "m",
                "dashpot point on the lid, lid frame, from A", lo=-10.0, hi=10.0,
                derived="`lid_c` (pin C)", derive=lambda v: v["geometry"]["lid_c"]))
    params = (Param("damper_c"), Param("damper_one_way", codes={False: 0.0, True: 1.0}))
    acting_params = ("damper_c",)
    columns = (("dd", "dq2"),)

    def coordinate(self, lid):
        g = lid.geometry
        if tuple(g.dashpot_lid) == tuple(g.lid_c) and tuple(g.dashpot_anchor) == (0.0, 0.0):
            return Length("C", None, None, (0.0, 0.0))     # the seed's: C to O
        return Length("H", "dashpot_lid", "dashpot_anchor")

    def viscous(self, P):
        return P["damper_c"]


class RotaryDamper(Element):
    """A rotary damper at a pivot: a moment -c_rot psi' on the relative rotation of the two
    bodies the pin joins; at ``"lid"`` (the default) the seed's moment on the lid's own
    rotation, a modelling aid with no machine element behind it. Its q'^2 lies in the
    table of element columns (1 at the lid, which needs no column)."""

    name = "rotary"
    seed = True
    doc = "rotary damper at a pivot (O, B, A, C) or on the lid's own rotation (the seed's)"
    keys = (Key("design", "rotary_damper_c", "nonneg", 0.0, "N m s/rad",
                "rotary damper coefficient c_rot (>= 0)", lo=0.0, hi=1e5),
            Key("design", "rotary_damper_pivot", "str:" + ",".join(PIVOTS), "lid", "",
                "where the rotary damper acts: `lid` (the lid's own rotation theta: the seed's "
                "modelling aid) or a real damper at pivot O (phi), B (gamma), A (theta - phi), "
                "C (theta - gamma), or H (a hinge lid's hinge: theta)"))
    params = (Param("rotary_damper_c"),)
    columns = (("dpr2", "dq2"),)
    table = "coordinates"

    def coordinate(self, lid):
        return PivotAngle(lid.mounting.rotary_damper_pivot)

    def structure(self, mounting):
        return (mounting.rotary_damper_pivot,)

    def unit_rate(self, mounting) -> bool:
        return mounting.rotary_damper_pivot == "lid"

    def viscous(self, P):
        return P["rotary_damper_c"]


class EndDamper(Element):
    """The soft-close part proper: a plunger (or a rotary damper with a free travel) that the
    lid meets near the rim. It acts on the lid's own rotation, a moment ``-c_e theta'``, only
    while the lid is below its engagement angle theta_e (``design.end_damper_angle_deg``):
    the lid falls freely to theta_e and lands slowly. The switch is a discontinuity of the
    equation of motion in theta, never smoothed: the integrators locate the crossing of
    theta_e as an event (the reference and the fixed-step kernel to their own accuracy) and
    the NLP puts a phase boundary there (two-phase multiple shooting). With
    ``design.damper_one_way`` it resists only closing, as the other dampers."""

    name = "end_damper"
    doc = ("end damper: a moment -c_e theta' on the lid's rotation while theta is below the "
           "engagement angle (the soft-close plunger that engages near the rim)")
    keys = (Key("design", "end_damper_c", "nonneg", 0.0, "N m s/rad",
                "end damper coefficient c_e (>= 0): a moment -c_e theta' on the lid while "
                "theta < end_damper_angle_deg", lo=0.0, hi=1e5, spread=0.20),
            Key("design", "end_damper_angle_deg", "real", 5.0, "deg",
                "engagement angle theta_e of the end damper: it acts below it (the lid meets "
                "the plunger there); at or above `stroke.theta0_deg` it acts from the "
                "release, at or below `stroke.theta_closed_deg` never", lo=-360.0, hi=360.0))
    params = (Param("end_damper_c"), Param("end_damper_angle_deg", math.pi / 180))
    acting_params = ("end_damper_c",)
    columns = ()
    #: the parameter (in P) of the angle below which the element acts (module docstring)
    engagement = "end_damper_angle_deg"

    def coordinate(self, lid):
        return PivotAngle("lid")

    def unit_rate(self, mounting) -> bool:
        return True

    def viscous(self, P):
        return P["end_damper_c"]
