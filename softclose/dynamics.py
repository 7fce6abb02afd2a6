"""Equation of motion of the lid in CasADi (SPEC §2-3).

Reduced (Lagrange) form, one coordinate theta. With every body point a function of
theta through the closure, the kinetic energy is ``T = 1/2 M(theta) theta'^2`` with

    M = m1 |dG1/dtheta|^2 + I1 + m2 |dG2/dtheta|^2 + I2 phi_theta^2
        + m3 |dG3/dtheta|^2 + I3 gamma_theta^2,

and the equation of motion is ``M theta'' + 1/2 M' theta'^2 = Q`` with

    Q = -dVg/dtheta - k (l - l0) dl/dtheta - (c (e_OC . dC/dtheta)^2 + c_rot) theta'.

Everything in it is a function of theta alone except the velocity terms, so the
geometry enters through eight *coefficients* of theta (``COEFFS``); the fast
integrators tabulate those, the NLP and the reference use the expressions directly.

Newton-Euler form: the nine equations of the three bodies (seed eqs. 7.4.3-7.4.5,
with the spring and dampers on the lid) in the eight pin-reaction components and
theta''. They are affine in those unknowns and are solved as a 9x9 linear system.
"""

from __future__ import annotations

import casadi as ca

from .kinematics import acceleration_loop, closure, cross, perp, points, rot, velocity_loop

#: geometric coefficients of theta, in the order the tabulated kernels use
COEFFS = ("M", "dM", "Vg", "dVg", "l", "dl", "dd", "tau")
#: design parameters p, in order
PARAMS = ("spring_k", "spring_rest_length", "damper_c", "rotary_damper_c")


def coefficients(theta, geo, mass, sigma):
    """The eight geometric coefficients as CasADi expressions of ``theta``.

    M (kg m^2), dM = M', Vg gravity potential (J), dVg = dVg/dtheta (N m), l spring length (m), dl = dl/dtheta,
    dd = (e_OC . dC/dtheta)^2 (m^2), tau = |dT/dtheta| (m) so that |v_T| = tau |theta'|.
    """
    phi, gamma, _ = closure(theta, geo, sigma)
    p = points(theta, phi, gamma, geo)
    jac = {k: ca.jacobian(p[k], theta) for k in ("G1", "G2", "G3", "C", "T", "E")}
    phi_t, gamma_t = ca.jacobian(phi, theta), ca.jacobian(gamma, theta)
    M = (mass.lid * ca.sumsqr(jac["G1"]) + mass.inertia_lid
         + mass.crank_oa * ca.sumsqr(jac["G2"]) + mass.inertia_oa * phi_t ** 2
         + mass.crank_bc * ca.sumsqr(jac["G3"]) + mass.inertia_bc * gamma_t ** 2)
    dM = ca.jacobian(M, theta)
    Vg = mass.gravity * (mass.lid * p["G1"][1] + mass.crank_oa * p["G2"][1]
                         + mass.crank_bc * p["G3"][1])
    dVg = ca.jacobian(Vg, theta)
    r_ED = ca.DM(geo.spring_anchor) - p["E"]
    l = ca.norm_2(r_ED)
    dl = ca.jacobian(l, theta)
    e_OC = p["C"] / ca.norm_2(p["C"])
    dd = ca.dot(e_OC, jac["C"]) ** 2
    tau = ca.norm_2(jac["T"])
    return {"M": M, "dM": dM, "dVg": dVg, "l": l, "dl": dl, "dd": dd, "tau": tau, "Vg": Vg}


def theta_ddot(cf, theta_d, p):
    """theta'' from the coefficients ``cf`` (dict), theta' and parameters p = (k, l0, c, c_rot)."""
    k, l0, c, c_rot = p[0], p[1], p[2], p[3]
    Q = -cf["dVg"] - k * (cf["l"] - l0) * cf["dl"] - (c * cf["dd"] + c_rot) * theta_d
    return (Q - 0.5 * cf["dM"] * theta_d ** 2) / cf["M"]


def energy(cf, theta_d, p):
    """Mechanical energy: kinetic + gravity + spring potential (J)."""
    return 0.5 * cf["M"] * theta_d ** 2 + cf["Vg"] + 0.5 * p[0] * (cf["l"] - p[1]) ** 2


def damper_power(cf, theta_d, p):
    """Power of the dashpot and rotary damper forces on the lid (W, <= 0)."""
    return -(p[2] * cf["dd"] + p[3]) * theta_d ** 2


def newton_euler_system(theta, theta_d, p, geo, mass, sigma):
    """The nine Newton-Euler equations as ``(A, b)`` with ``A z = b``.

    Unknowns z = (R_O, R_A, R_B, R_C, theta'') -- R_A, R_C act on the lid from the
    cranks, R_O, R_B on the cranks from the ground (SPEC §3). Rows: lid (Fx, Fy, Mz about
    G1), crank OA (Fx, Fy, Mz about G2), crank BC (Fx, Fy, Mz about G3).
    """
    z = ca.SX.sym("z", 9)
    R_O, R_A, R_B, R_C, tdd = z[0:2], z[2:4], z[4:6], z[6:8], z[8]
    phi, gamma, _ = closure(theta, geo, sigma)
    pts = points(theta, phi, gamma, geo)
    phi_d, gamma_d = velocity_loop(theta, phi, gamma, theta_d, geo)
    phi_dd, gamma_dd = acceleration_loop(theta, phi, gamma, theta_d, phi_d, gamma_d, tdd, geo)

    def acc(r, omega, alpha):  # acceleration of a point at r from a fixed pivot / moving ref
        return alpha * perp(r) - omega ** 2 * r

    A, O, B, C = pts["A"], ca.DM.zeros(2), pts["B"], pts["C"]
    a_A = acc(A, phi_d, phi_dd)
    a_G1 = a_A + acc(pts["G1"] - A, theta_d, tdd)
    a_G2 = 0.5 * a_A
    a_G3 = acc(pts["G3"] - B, gamma_d, gamma_dd)

    k, l0, c, c_rot = p[0], p[1], p[2], p[3]
    r_ED = ca.DM(geo.spring_anchor) - pts["E"]
    l = ca.norm_2(r_ED)
    F_s = k * (l - l0) * r_ED / l
    e_OC = C / ca.norm_2(C)
    v_C = velocity_of(pts, A, phi_d, theta_d, C)
    F_d = -c * ca.dot(e_OC, v_C) * e_OC
    g = mass.gravity
    W = lambda m: ca.vertcat(0, -m * g)  # noqa: E731

    G1, G2, G3 = pts["G1"], pts["G2"], pts["G3"]
    res = ca.vertcat(
        R_A + R_C + W(mass.lid) + F_s + F_d - mass.lid * a_G1,
        cross(A - G1, R_A) + cross(C - G1, R_C) + cross(pts["E"] - G1, F_s)
        + cross(C - G1, F_d) - c_rot * theta_d - mass.inertia_lid * tdd,
        R_O - R_A + W(mass.crank_oa) - mass.crank_oa * a_G2,
        cross(O - G2, R_O) + cross(A - G2, -R_A) - mass.inertia_oa * phi_dd,
        R_B - R_C + W(mass.crank_bc) - mass.crank_bc * a_G3,
        cross(B - G3, R_B) + cross(C - G3, -R_C) - mass.inertia_bc * gamma_dd,
    )
    A_mat = ca.jacobian(res, z)
    b = -ca.substitute(res, z, ca.DM.zeros(9))
    return A_mat, b


def velocity_of(pts, A, phi_d, theta_d, P):
    """Velocity of a lid point P: v_A + theta' z x (P - A), with v_A = phi' z x A."""
    return phi_d * perp(A) + theta_d * perp(P - A)


__all__ = ["COEFFS", "PARAMS", "coefficients", "theta_ddot", "energy", "damper_power",
           "newton_euler_system", "rot"]
