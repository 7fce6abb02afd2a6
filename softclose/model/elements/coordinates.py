"""Where an element acts: its coordinate q(theta) and the loads a force along q puts on the bodies.

The geometry of an element, apart from its law (:mod:`softclose.model.elements.base`):

- :class:`Length` -- the distance from a ground point G to a lid point P (lid frame, from
  A), ``q = |P - G|``; a tension T along it pulls P towards G: the force on the lid at P is
  ``-T u`` with ``u = (P - G) / q`` (q grows along u);
- :class:`PivotAngle` -- the relative rotation psi = angle(a) - angle(b) of the two bodies a
  pin joins (O: crank OA on the ground, phi; B: crank BC on the ground, gamma; A: the lid on
  crank OA, theta - phi; C: the lid on crank BC, theta - gamma; "lid": the lid on the ground,
  theta; H: a hinge lid's hinge, theta). A moment tau along psi turns body a by +tau and body b by -tau. Crank angles are
  taken within half a turn of the pivot's angle at ``geometry.assembly``, so psi is
  continuous over the stroke whatever the closed form's branch cut does;
- :class:`Weights` -- gravity's coordinate: the weights' potential
  ``g (m1 y_G1 + m2 y_G2 + m3 y_G3)`` itself (its law is V = q), with the weights on the
  three bodies as its loads.

Each coordinate evaluates on a :class:`Pose` (CasADi expressions of theta on the model's
branch) and gives its loads for Newton-Euler: ``(body, point name or None, force vector or
moment)``; bodies are "lid", "oa", "bc" (the ground takes no equation).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import casadi as ca

from ..kinematics import cross

#: the pins an element may act at, and the bodies each joins (a, b): psi = angle(a) - angle(b)
PIVOTS = {"lid": ("lid", "ground"), "O": ("oa", "ground"), "B": ("bc", "ground"),
          "A": ("lid", "oa"), "C": ("lid", "bc"), "H": ("lid", "ground")}
#: the pivots of a hinge lid (SPEC §15): H, the hinge (the lid on the ground, theta); "lid" the same
HINGE_PIVOTS = ("lid", "H")


class Pose(NamedTuple):
    """The linkage at theta: angles, named points (world), and the lid's geometry and mass."""

    theta: object
    phi: object
    gamma: object
    points: dict
    geo: object
    mass: object

    def angle(self, body: str):
        return {"lid": self.theta, "oa": self.phi, "bc": self.gamma, "ground": 0.0}[body]


class Length(NamedTuple):
    """``q = |P - G|``: P a lid point (``lid_key``: a ``geometry`` key in the lid frame from
    A), G a ground point (``ground_key``, or the fixed ``ground`` when no key)."""

    point: str                  # name of P among the pose's points (e.g. "E", "C")
    lid_key: str | None
    ground_key: str | None
    ground: tuple = (0.0, 0.0)

    def ground_point(self, geo):
        return ca.DM(getattr(geo, self.ground_key) if self.ground_key else self.ground)

    def value(self, pose: Pose):
        r = pose.points[self.point] - self.ground_point(pose.geo)
        return ca.norm_2(r)

    def loads(self, pose: Pose, force):
        """A force ``force`` along q (positive: it lengthens q) on the lid at P."""
        P = pose.points[self.point]
        r = P - self.ground_point(pose.geo)
        return [("lid", self.point, force * r / ca.norm_2(r))]


class PivotAngle(NamedTuple):
    """``q = psi``, the relative rotation at ``pivot`` (one of :data:`PIVOTS`)."""

    pivot: str

    def _raw(self, theta, phi, gamma):
        a, b = PIVOTS[self.pivot]
        ang = {"lid": theta, "oa": phi, "bc": gamma, "ground": 0.0}
        return ang[a] - ang[b]

    def value(self, pose: Pose):
        raw = self._raw(pose.theta, pose.phi, pose.gamma)
        if self.pivot in HINGE_PIVOTS:
            return raw
        ref = self._raw(*(math.radians(x) for x in pose.geo.assembly))
        d = raw - ref
        return ref + ca.atan2(ca.sin(d), ca.cos(d))

    def loads(self, pose: Pose, force):
        """A moment ``force`` along psi: +force on body a, -force on body b."""
        a, b = PIVOTS[self.pivot]
        return [(body, None, sgn * force) for body, sgn in ((a, 1.0), (b, -1.0))
                if body != "ground"]


class Weights(NamedTuple):
    """Gravity's coordinate: ``q = g (m1 y_G1 + m2 y_G2 + m3 y_G3)`` (J)."""

    def value(self, pose: Pose):
        m, p = pose.mass, pose.points
        return m.gravity * (m.lid * p["G1"][1] + m.crank_oa * p["G2"][1]
                            + m.crank_bc * p["G3"][1])

    def loads(self, pose: Pose, force):
        """The weights at the centres of mass (``force`` is gravity's T = 1: unused)."""
        m = pose.mass
        return [(body, centre, ca.vertcat(0, -mb * m.gravity))
                for body, centre, mb in (("lid", "G1", m.lid), ("oa", "G2", m.crank_oa),
                                         ("bc", "G3", m.crank_bc))]


def moment_about(point, centre, force):
    """z-moment of ``force`` applied at ``point`` about ``centre``."""
    return cross(point - centre, force)
