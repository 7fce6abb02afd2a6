"""Four-bar kinematics of the lid in CasADi symbolics (SPEC §1).

Loop closure ``A + R(theta) AC - B - l3 e(gamma) = 0`` with ``A = l2 e(phi)``. For a
given coupler angle theta put ``w = R(theta) AC - B``; then ``|l2 e(phi) + w| = l3``
gives ``w . e(phi) = K`` with ``K = (l3^2 - l2^2 - |w|^2) / (2 l2)``, so

    phi = atan2(w_y, w_x) + sigma * acos(u),    u = K / |w|,

where sigma = +1 or -1 names the assembly (branch). ``|u| < 1`` is the condition for
the loop to close; ``|u| -> 1`` is a toggle position, where the two branches meet and
d phi / d theta is unbounded.

Which branch a configuration is on (:func:`crank_cross`, :func:`branch_of`). Since
``C - B = A + w``,

    D = A x (C - B) = A x w = l2 |w| sin(arg w - phi) = -sigma l2 |w| sqrt(1 - u^2),

because ``phi - arg w = sigma acos(u)`` with ``acos(u)`` in (0, pi) when ``|u| < 1``. Also
``D = l2 l3 sin(gamma - phi)``. So ``sign D = -sigma``: on the branch sigma = -1 crank BC
points counter-clockwise of crank OA (0 < gamma - phi < pi), on sigma = +1 clockwise.
Geometrically: hang a copy of crank BC from A (shift it by A - C); its pivot moves to
``P = B - R(theta) AC = -w``, and the two assemblies put A on the two sides of the line
from O to P (mirror images); ``D = P x A`` > 0 when A lies to the left of it.

Why the sign is invariant along a branch: a branch is a configuration that moves
continuously with theta, so D(theta) is continuous, and by the identity above it is zero
only where ``sqrt(1 - u^2) = 0``, i.e. ``|u| = 1`` (|w| > 0 wherever u is finite). By the
intermediate value theorem D keeps its sign on every theta interval without a toggle. D
is also, up to sign, the determinant of the velocity loop (:func:`velocity_loop`), which is
why phi' and gamma' are unbounded exactly there. The closed form with a fixed sigma is
therefore one branch followed continuously until a toggle; the 2 pi jump of ``atan2``
where w crosses the negative x axis changes the representation of phi, not the
configuration (sin(gamma - phi) does not jump).

The velocity and acceleration loops (the first and second time derivatives of the
closure, seed eqs. 7.4.2 and its derivative) are linear 2x2 systems in
(phi', gamma') and (phi'', gamma'').
"""

from __future__ import annotations

import math

import casadi as ca


def e(a):
    """Unit vector at angle a."""
    return ca.vertcat(ca.cos(a), ca.sin(a))


def perp(v):
    """z x v for a planar vector v."""
    return ca.vertcat(-v[1], v[0])


def rot(theta, r_local):
    """R(theta) r_local."""
    c, s = ca.cos(theta), ca.sin(theta)
    return ca.vertcat(c * r_local[0] - s * r_local[1], s * r_local[0] + c * r_local[1])


def cross(a, b):
    """z-component of a x b."""
    return a[0] * b[1] - a[1] * b[0]


def is_hinge(geo) -> bool:
    """A single-pivot lid (SPEC §15): A is the ground hinge H, theta the only coordinate."""
    return getattr(geo, "mechanism", "four_bar") == "hinge"


def closure(theta, geo, sigma):
    """Closed-form loop closure on branch ``sigma``: returns ``(phi, gamma, u)``.

    ``u`` is the acos argument: the loop closes for ``|u| < 1``. A hinge lid has no loop: its
    crank angles are constants (the cranks are massless and unused) and u = 0 everywhere.
    """
    if is_hinge(geo):
        zero = 0 * theta
        return zero + math.radians(geo.assembly[1]), zero + math.radians(geo.assembly[2]), zero
    l2, l3 = geo.crank_oa, geo.crank_bc
    w = rot(theta, geo.lid_c) - ca.DM(geo.pivot_b)
    w2 = ca.dot(w, w)
    u = (l3 ** 2 - l2 ** 2 - w2) / (2 * l2 * ca.sqrt(w2))
    phi = ca.atan2(w[1], w[0]) + sigma * ca.acos(u)
    c_minus_b = l2 * e(phi) + w
    gamma = ca.atan2(c_minus_b[1], c_minus_b[0])
    return phi, gamma, u


def crank_cross(phi, gamma, geo):
    """``D = A x (C - B) = l2 l3 sin(gamma - phi)`` (m^2): its sign is ``-sigma``.

    Zero exactly at a toggle (the cranks in line), so its sign names the branch of a
    configuration and does not change along it (module docstring).
    """
    return geo.crank_oa * geo.crank_bc * ca.sin(gamma - phi)


def branch_of(phi: float, gamma: float) -> int:
    """sigma of the assembly whose crank angles are phi, gamma (rad): ``-sign sin(gamma - phi)``.

    Only the side matters: the angles need not close the loop exactly. Cranks in line
    (sin = 0) name no branch; the caller decides what to do with that (returns 0).
    """
    s = math.sin(gamma - phi)
    return -1 if s > 0 else (1 if s < 0 else 0)


def points(theta, phi, gamma, geo):
    """World positions of the named points for a closed configuration."""
    A = ca.DM(geo.hinge) + 0 * theta if is_hinge(geo) else geo.crank_oa * e(phi)
    B = ca.DM(geo.pivot_b)
    h = getattr(geo, "dashpot_lid", None)
    extra = {} if h is None else {"H": A + rot(theta, h)}
    return {**extra,
        "A": A,
        "C": A + rot(theta, geo.lid_c),
        "E": A + rot(theta, geo.lid_e),
        "G1": A + rot(theta, geo.lid_g),
        "T": A + rot(theta, geo.lid_tip),
        "G2": 0.5 * A,
        "G3": B + 0.5 * geo.crank_bc * e(gamma),
        "B": B,
    }


def loop_residual(theta, phi, gamma, geo):
    """The loop-closure residual (two equations), zero on a closed configuration."""
    return geo.crank_oa * e(phi) + rot(theta, geo.lid_c) - ca.DM(geo.pivot_b) \
        - geo.crank_bc * e(gamma)


def velocity_loop(theta, phi, gamma, theta_d, geo):
    """(phi', gamma') from the velocity loop, linear in theta'.

    l2 phi' z x e(phi) - l3 gamma' z x e(gamma) = -theta' z x r_AC
    """
    if is_hinge(geo):
        return 0 * theta_d, 0 * theta_d
    r_AC = rot(theta, geo.lid_c)
    a1 = geo.crank_oa * perp(e(phi))
    a2 = -geo.crank_bc * perp(e(gamma))
    rhs = -theta_d * perp(r_AC)
    return _solve2(a1, a2, rhs)


def acceleration_loop(theta, phi, gamma, theta_d, phi_d, gamma_d, theta_dd, geo):
    """(phi'', gamma'') from the acceleration loop, affine in theta''.

    l2 phi'' z x e(phi) - l3 gamma'' z x e(gamma)
        = l2 phi'^2 e(phi) - theta'' z x r_AC + theta'^2 r_AC - l3 gamma'^2 e(gamma)
    """
    if is_hinge(geo):
        return 0 * theta_dd, 0 * theta_dd
    r_AC = rot(theta, geo.lid_c)
    a1 = geo.crank_oa * perp(e(phi))
    a2 = -geo.crank_bc * perp(e(gamma))
    rhs = (geo.crank_oa * phi_d ** 2 * e(phi) - theta_dd * perp(r_AC)
           + theta_d ** 2 * r_AC - geo.crank_bc * gamma_d ** 2 * e(gamma))
    return _solve2(a1, a2, rhs)


def _solve2(a1, a2, rhs):
    """Solve [a1 a2] [x1, x2]^T = rhs by Cramer's rule."""
    det = cross(a1, a2)
    return cross(rhs, a2) / det, cross(a1, rhs) / det
