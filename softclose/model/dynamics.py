"""Equation of motion of the lid in CasADi (SPEC §2-3), summed over the machine elements.

Reduced (Lagrange) form, one coordinate theta. With every body point a function of
theta through the closure, the kinetic energy is ``T = 1/2 M(theta) theta'^2`` with

    M = m1 |dG1/dtheta|^2 + I1 + m2 |dG2/dtheta|^2 + I2 phi_theta^2
        + m3 |dG3/dtheta|^2 + I3 gamma_theta^2,

and every element e of :data:`softclose.model.elements.ELEMENTS` acts through its coordinate
q_e(theta) (:mod:`softclose.model.elements.base`), so the equation of motion is
``M theta'' + 1/2 M' theta'^2 = Q`` with

    Q = -sum T_e(q_e) q_e'  -  (sum B_e q_e'^2) theta'       (q' = dq/dtheta)

-- gravity's T q' is dVg/dtheta, the spring's k (l - l0) dl/dtheta, the dashpot's B q'^2 is
c (e_OC . dC/dtheta)^2, the rotary damper's c_rot. Everything in it is a function of theta
alone except the velocity terms, so the geometry enters through *coefficients* of theta: M,
M', the tip's |dT/dtheta| and each element's tabulated columns (its q, q' or q'^2); the fast
integrators tabulate those, the NLP and the reference use the expressions directly.

Newton-Euler form: the nine equations of the three bodies (seed eqs. 7.4.3-7.4.5) with every
element's loads on the bodies it acts on, in the eight pin-reaction components and theta''.
They are affine in those unknowns and are solved as a 9x9 linear system.
"""

from __future__ import annotations

import casadi as ca

from . import elements
from .elements import DAMPERS, ELEMENTS, FRICTIONS, SPRINGS
from .elements.coordinates import Length, moment_about, PivotAngle, PIVOTS, Pose
from .kinematics import (acceleration_loop, closure, cross, is_hinge, perp, points,
                         velocity_loop)

#: the coefficients of theta that are not an element's: the generalised mass, its slope, and
#: the tip's lever tau = |dT/dtheta| (|v_T| = tau |theta'|)
INERTIA = ("M", "dM")
TIP = ("tau",)
#: the kernel's fixed table: the inertia, the seed's elements' columns, the tip
COEFFS = INERTIA + tuple(c for e in ELEMENTS if e.table == "base" for c, _ in e.columns) + TIP
#: the coordinate table: the columns of the elements whose coordinate is an angle at a pivot
#: (the torsion spring, the rotary damper), tabulated when a stroke needs it
COORDINATE_COEFFS = tuple(c for e in ELEMENTS if e.table == "coordinates" for c, _ in e.columns)
#: the parameter vector p, in order (design keys without the section)
PARAMS = elements.PARAM_NAMES


class Coord:
    """An element's coordinate at theta: q, q' = dq/dtheta and q'^2 (each may be given
    alone: the coefficient table holds only what the kernel reads, e.g. the dashpot's q'^2).
    A coordinate that is the lid's own angle has q' = 1."""

    __slots__ = ("q", "dq", "_dq2")

    def __init__(self, q=None, dq=None, dq2=None):
        self.q, self.dq, self._dq2 = q, dq, dq2

    @property
    def dq2(self):
        return self.dq ** 2 if self._dq2 is None else self._dq2


def pose(theta, geo, mass, sigma) -> Pose:
    phi, gamma, _ = closure(theta, geo, sigma)
    return Pose(theta, phi, gamma, points(theta, phi, gamma, geo), geo, mass)


def coordinates(theta, lid, sigma, ps: Pose | None = None) -> dict:
    """Each element's coordinate at theta on ``lid`` (:class:`softclose.model.resolved.Lid`):
    {name: :class:`Coord`} (CasADi expressions)."""
    ps = ps or pose(theta, lid.geometry, lid.mass, sigma)
    out = {}
    for e in ELEMENTS:
        q = e.coordinate(lid).value(ps)
        out[e.name] = Coord(q, ca.jacobian(q, theta))
    return out


def coordinates_of_columns(columns: dict, mounting, theta=None) -> dict:
    """Each element's :class:`Coord` with ``mounting`` (where the elements sit) from tabulated
    columns (``columns[name]``: numbers or arrays): what the element declares it
    tabulates (its q, q' or q'^2); an element on the lid's own angle has q' = 1 (and q =
    ``theta``, the angle of the columns, when given). An element whose columns are not
    in ``columns`` (the coordinate table, not read) is left out."""
    out = {}
    for e in ELEMENTS:
        if not e.columns or e.unit_rate(mounting):
            out[e.name] = Coord(theta, 1.0, 1.0)
        elif all(col in columns for col, _ in e.columns):
            out[e.name] = Coord(**{what: columns[col] for col, what in e.columns})
    return out


def coefficients(theta, lid, sigma) -> dict:
    """The coefficients of theta as CasADi expressions: M (kg m^2), dM = M', tau = |dT/dtheta|
    (m), every element's columns (:data:`COEFFS`, :data:`COORDINATE_COEFFS`: gravity's Vg (J) and
    dVg (N m), the spring's l (m) and dl, the dashpot's dd = (e_OC . dC/dtheta)^2 (m^2), and
    those of the coordinate table), and ``"coords"``: {element: :class:`Coord`}."""
    geo, mass = lid.geometry, lid.mass
    ps = pose(theta, geo, mass, sigma)
    p = ps.points
    jac = {k: ca.jacobian(p[k], theta) for k in ("G1", "G2", "G3", "T")}
    phi_t, gamma_t = ca.jacobian(ps.phi, theta), ca.jacobian(ps.gamma, theta)
    M = (mass.lid * ca.sumsqr(jac["G1"]) + mass.inertia_lid
         + mass.crank_oa * ca.sumsqr(jac["G2"]) + mass.inertia_oa * phi_t ** 2
         + mass.crank_bc * ca.sumsqr(jac["G3"]) + mass.inertia_bc * gamma_t ** 2)
    out = {"M": M, "dM": ca.jacobian(M, theta), "tau": ca.norm_2(jac["T"])}
    coords = coordinates(theta, lid, sigma, ps)
    for e in ELEMENTS:
        for col, what in e.columns:
            out[col] = getattr(coords[e.name], what)
    out["coords"] = coords
    return out


def _sum(terms):
    total = None
    for t in terms:
        total = t if total is None else total + t
    return total


def slope(coords, P):
    """dV/dtheta = sum T_e(q_e) q_e' over the conservative elements (N m): the one
    statement of the holding moment, the release check and the equilibria
    (:mod:`softclose.simulation.statics` applies it to the coefficient table). Elements missing from
    ``coords`` (columns not read) are left out."""
    return _sum(e.tension(coords[e.name].q, P) * coords[e.name].dq for e in SPRINGS
                if e.name in coords)


def damping(coords, P, engaged=None):
    """sum B_e q_e'^2 over the dampers: the generalised damping on theta (N m s/rad).

    A damper that acts only below its engagement angle (the end damper,
    :attr:`~softclose.model.elements.base.Element.engagement`) counts where it is engaged:
    ``engaged`` gives that as {element name: 1 or 0} -- an integrator's state between the
    events at which the lid crosses the angle --, or, when it is None, the element's own
    coordinate (the lid's angle) decides (a discontinuous function of theta: the exact
    equation, which an integrator must not step across without locating the crossing)."""
    return _sum(e.viscous(P) * coords[e.name].dq2 * _engaged(e, coords[e.name], P, engaged)
                for e in DAMPERS if e.name in coords)


def _engaged(e, coord, P, engaged):
    """1 where damper e acts (always, unless it has an engagement angle), else 0."""
    if e.engagement is None:
        return 1.0
    if engaged is not None:
        return engaged[e.name]
    if coord.q is None:
        raise ValueError(f"the {e.name}'s engagement needs the lid's angle (theta)")
    return e.engaged(coord.q, P)


def friction(coords, P):
    """sum C_e |q_e'| over the dry-friction elements: the friction moment on theta while the
    lid moves (N m); None without one."""
    return _sum(e.coulomb(P) * _abs(coords[e.name].dq) for e in FRICTIONS if e.name in coords)


def _abs(x):
    return x if isinstance(x, float) and x >= 0 else (ca.fabs(x) if hasattr(x, "is_symbolic")
                                                      else abs(x))


def direction(theta_d):
    """sign(theta'): the way the lid moves (numbers, arrays or CasADi alike)."""
    return ca.sign(theta_d) if hasattr(theta_d, "is_symbolic") else \
        (float(theta_d > 0) - float(theta_d < 0) if isinstance(theta_d, float)
         else (theta_d > 0) * 1.0 - (theta_d < 0) * 1.0)


def potential(coords, P):
    """V = sum V_e(q_e) over the conservative elements (J)."""
    return _sum(e.potential(coords[e.name].q, P) for e in SPRINGS if e.name in coords)


def theta_ddot(cf, theta_d, p, moving=None, engaged=None):
    """theta'' from the coefficients ``cf`` (dict), theta' and the parameter vector p.

    Dry friction opposes the motion: ``moving`` is the way the lid moves (+1 up, -1 down;
    default sign(theta'), which at rest applies none: the stick is the integrator's event).
    ``engaged``: {name: 1 or 0} of the dampers with an engagement angle (:func:`damping`;
    default: by the lid's angle).
    """
    P = elements.params(p)
    Q = -slope(cf["coords"], P) - damping(cf["coords"], P, engaged) \
        * elements.one_way(P, theta_d) * theta_d
    fr = friction(cf["coords"], P)
    if fr is not None:
        Q = Q - fr * (direction(theta_d) if moving is None else moving)
    return (Q - 0.5 * cf["dM"] * theta_d ** 2) / cf["M"]


def energy(cf, theta_d, p):
    """Mechanical energy: kinetic + every element's potential (J)."""
    return 0.5 * cf["M"] * theta_d ** 2 + potential(cf["coords"], elements.params(p))


def damper_power(cf, theta_d, p):
    """Power of the dampers and of dry friction on the linkage (W, <= 0)."""
    P = elements.params(p)
    power = -damping(cf["coords"], P) * elements.one_way(P, theta_d) * theta_d ** 2
    fr = friction(cf["coords"], P)
    return power if fr is None else power - fr * _abs(theta_d)


def newton_euler_system(theta, theta_d, p, lid, sigma):
    """The nine Newton-Euler equations as ``(A, b)`` with ``A z = b``.

    Unknowns z = (R_O, R_A, R_B, R_C, theta'') -- R_A, R_C act on the lid from the
    cranks, R_O, R_B on the cranks from the ground (SPEC §3). Rows: lid (Fx, Fy, Mz about
    G1), crank OA (Fx, Fy, Mz about G2), crank BC (Fx, Fy, Mz about G3). Every element puts
    its force along its coordinate, ``-(T(q) + B q-dot)`` with q-dot from the velocity loop,
    on the bodies it acts on (:mod:`softclose.model.elements.coordinates`).
    """
    geo, mass = lid.geometry, lid.mass
    z = ca.SX.sym("z", 9)
    R_O, R_A, R_B, R_C, tdd = z[0:2], z[2:4], z[4:6], z[6:8], z[8]
    ps = pose(theta, geo, mass, sigma)
    pts = ps.points
    phi_d, gamma_d = velocity_loop(theta, ps.phi, ps.gamma, theta_d, geo)
    phi_dd, gamma_dd = acceleration_loop(theta, ps.phi, ps.gamma, theta_d, phi_d, gamma_d, tdd,
                                         geo)

    def acc(r, omega, alpha):  # acceleration of a point at r from a fixed pivot / moving ref
        return alpha * perp(r) - omega ** 2 * r

    A, O, B, C = pts["A"], ca.DM.zeros(2), pts["B"], pts["C"]
    a_A = acc(A, phi_d, phi_dd)
    a_G1 = a_A + acc(pts["G1"] - A, theta_d, tdd)
    a_G2 = 0.5 * a_A
    a_G3 = acc(pts["G3"] - B, gamma_d, gamma_dd)
    omega = {"lid": theta_d, "oa": phi_d, "bc": gamma_d, "ground": 0.0}

    P = elements.params(p)
    forces = {"lid": [], "oa": [], "bc": []}    # (point name or None, force or moment)
    for e in ELEMENTS:
        coord = e.coordinate(lid)
        q = coord.value(ps)
        f = -e.tension(q, P)
        if e.viscous(P) is not None:
            f = f - e.viscous(P) * e.engaged(theta, P) * elements.one_way(P, theta_d) \
                * _rate(coord, ps, omega, A, phi_d, theta_d)
        if e.coulomb(P) is not None:
            f = f - e.coulomb(P) * direction(_rate(coord, ps, omega, A, phi_d, theta_d))
        for body, point, load in coord.loads(ps, f):
            forces[body].append((point, load))
    centre = {"lid": "G1", "oa": "G2", "bc": "G3"}

    def applied(body):     # (sum of forces, sum of moments about the body's centre)
        F, Mz = [], []
        for point, load in forces[body]:
            if point is None:
                Mz.append(load)
            else:
                F.append(load)
                if point != centre[body]:
                    Mz.append(moment_about(pts[point], pts[centre[body]], load))
        return F, Mz

    (F1, M1), (F2, M2), (F3, M3) = applied("lid"), applied("oa"), applied("bc")
    G1, G2, G3 = pts["G1"], pts["G2"], pts["G3"]
    if is_hinge(geo):      # the lid alone on its hinge: R_O = R_A the hinge's, no pin C
        return _solved(ca.vertcat(
            _sum([R_A + R_C] + F1) - mass.lid * a_G1,
            _sum([cross(A - G1, R_A) + cross(C - G1, R_C)] + M1) - mass.inertia_lid * tdd,
            R_O - R_A, R_B, R_C), z)
    res = ca.vertcat(
        _sum([R_A + R_C] + F1) - mass.lid * a_G1,
        _sum([cross(A - G1, R_A) + cross(C - G1, R_C)] + M1) - mass.inertia_lid * tdd,
        _sum([R_O - R_A] + F2) - mass.crank_oa * a_G2,
        _sum([cross(O - G2, R_O) + cross(A - G2, -R_A)] + M2) - mass.inertia_oa * phi_dd,
        _sum([R_B - R_C] + F3) - mass.crank_bc * a_G3,
        _sum([cross(B - G3, R_B) + cross(C - G3, -R_C)] + M3) - mass.inertia_bc * gamma_dd,
    )
    return _solved(res, z)


def _solved(res, z):
    """``(A, b)`` of the residuals ``res``, affine in z: ``A z = b``."""
    return ca.jacobian(res, z), -ca.substitute(res, z, ca.DM.zeros(z.numel()))


def _rate(coord, ps: Pose, omega: dict, A, phi_d, theta_d):
    """q-dot of a coordinate from the velocity loop (not from q'): the speed along a length
    (u . v_P), or the relative angular velocity at a pivot."""
    if isinstance(coord, Length):
        P = ps.points[coord.point]
        r = P - coord.ground_point(ps.geo)
        return ca.dot(r / ca.norm_2(r), velocity_of(ps.points, A, phi_d, theta_d, P))
    if isinstance(coord, PivotAngle):
        a, b = PIVOTS[coord.pivot]
        return omega[a] - omega[b]
    raise TypeError(f"no rate for the coordinate {coord!r}")


def velocity_of(pts, A, phi_d, theta_d, P):
    """Velocity of a lid point P: v_A + theta' z x (P - A), with v_A = phi' z x A."""
    return phi_d * perp(A) + theta_d * perp(P - A)


__all__ = ["COEFFS", "COORDINATE_COEFFS", "PARAMS", "Coord", "friction", "direction", "coefficients", "coordinates",
           "coordinates_of_columns", "theta_ddot",
           "energy", "damper_power", "slope", "damping", "potential", "newton_euler_system",
           "pose"]
