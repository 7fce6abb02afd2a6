"""The paper-bin lid (SPEC §1-§2) as three bodies in absolute coordinates: an independent check.

Coordinates q = (x_G1, y_G1, theta, x_2, y_2, phi, x_3, y_3, gamma): the lid's centre of mass
and angle, and the midpoints and angles of cranks OA and BC.  Eight constraints (pins O, A, B, C),
one degree of freedom.  The augmented equations

    M q'' + Phi_q^T lambda = Q,     Phi_q q'' = gamma_c

are solved for q'' (and the multipliers), from which theta'' = q''[2].  Q holds gravity on all
three bodies, the spring E-D, the dashpot C-O, the rotary damper on the lid, a torsion spring
at one of the pins (a moment on the two bodies' relative angle, read off q), friction on the
lid's rotation, and the end damper: a moment -c_e theta' on the lid while its angle q[2] is
below the engagement angle theta_e (acting on theta' itself, read off q'; one-way like the
other dampers).  Nothing here is shared with the reduced model in softclose.model.lid or the
element registry.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .driven_fourbar import (GROUND, AngleDriver, PlanarSystem, Revolute, add_moment,
                             add_point_force, assemble_mass_matrix, locate_point, solve_dynamics,
                             solve_positions, solve_velocities, velocity_of_point)


@dataclass(frozen=True)
class LidParameters:
    """SI geometry, masses and force elements; lid offsets measured from A in the lid frame."""

    l2: float
    l3: float
    B: tuple[float, float]
    AC: tuple[float, float]
    AE: tuple[float, float]
    AG: tuple[float, float]
    AT: tuple[float, float]
    D: tuple[float, float]
    assembly: tuple[float, float, float]     # theta, phi, gamma in radians
    m1: float
    m2: float
    m3: float
    J1: float
    J2: float
    J3: float
    g: float
    k: float = 0.0
    l0: float = 0.05
    c: float = 0.0
    c_rot: float = 0.0
    F: float = 0.0                   # the spring's signed preload: +F0 pulls, -F0 pushes
    rot_pivot: str = "lid"           # where the rotary damper acts: lid, O, B, A or C
    one_way: bool = False            # the dampers resist only closing (theta' < 0)
    kt: float = 0.0                  # torsion spring rate (N m/rad)
    psi0: float = 0.0                # its free angle (rad)
    pivot: str = "O"                 # O, B, A or C
    Tf: float = 0.0                  # Coulomb friction moment on the lid's rotation (N m)
    c_end: float = 0.0               # end damper on the lid's rotation (N m s/rad) ...
    theta_end: float = 0.08726646259971647   # ... acting while theta < theta_end (rad; 5 deg)


#: a pin's bodies: (body a, body b) with psi = angle(a) - angle(b); -1 = ground
_PINS = {"O": (1, -1), "B": (2, -1), "A": (0, 1), "C": (0, 2), "lid": (0, -1)}

def read_parameters(cfg) -> LidParameters:
    """Build the parameters from a Config-like object (attribute access; assembly in degrees)."""
    G, m, d = cfg.geometry, cfg.mass, cfg.design
    return LidParameters(
        l2=G.crank_oa, l3=G.crank_bc, B=tuple(G.pivot_b), AC=tuple(G.lid_c), AE=tuple(G.lid_e),
        AG=tuple(G.lid_g), AT=tuple(G.lid_tip), D=tuple(G.spring_anchor),
        assembly=tuple(np.radians(G.assembly)),
        m1=m.lid, m2=m.crank_oa, m3=m.crank_bc, J1=m.inertia_lid, J2=m.inertia_oa,
        J3=m.inertia_bc, g=m.gravity,
        k=d.spring_k, l0=d.spring_rest_length, c=d.damper_c, c_rot=d.rotary_damper_c,
        F={"extension": 1.0, "compression": -1.0}.get(d.spring_kind, 0.0) * d.spring_preload,
        rot_pivot=d.rotary_damper_pivot, one_way=d.damper_one_way,
        kt=d.torsion_k, psi0=np.radians(d.torsion_free_angle_deg), pivot=d.torsion_pivot,
        Tf=cfg.friction.torque, c_end=d.end_damper_c,
        theta_end=np.radians(d.end_damper_angle_deg))


def default_parameters(**design) -> LidParameters:
    """The SPEC §1/§6 defaults, typed in independently of softclose.config."""
    L, l2, l3 = 0.500, 0.045, 0.080
    m1, m2, m3 = 0.5, 0.05, 0.05
    p = dict(l2=l2, l3=l3, B=(0.060, 0.015), AC=(0.012, 0.013), AE=(0.004, 0.014),
             AG=(L / 2, 0.015), AT=(L, 0.0), D=(-0.060, 0.020),
             assembly=tuple(np.radians([18.0, 108.6655, 146.8855])),
             m1=m1, m2=m2, m3=m3, J1=m1 * L ** 2 / 12, J2=m2 * l2 ** 2 / 12, J3=m3 * l3 ** 2 / 12,
             g=9.81)
    p.update(design)
    return LidParameters(**p)


def _lid_offset(p: LidParameters, point) -> np.ndarray:
    """Lid-frame offset of a point from the lid's reference point G1."""
    return np.asarray(point, float) - np.asarray(p.AG, float)


def build_lid_system(p: LidParameters) -> PlanarSystem:
    """Bodies 0 lid, 1 crank OA, 2 crank BC; pins O, A, B, C."""
    joints = [
        Revolute(1, (-p.l2 / 2, 0.0), GROUND, (0.0, 0.0)),                 # O
        Revolute(1, (p.l2 / 2, 0.0), 0, tuple(_lid_offset(p, (0.0, 0.0)))),  # A
        Revolute(2, (-p.l3 / 2, 0.0), GROUND, tuple(p.B)),                  # B
        Revolute(2, (p.l3 / 2, 0.0), 0, tuple(_lid_offset(p, p.AC))),       # C
    ]
    return PlanarSystem(3, joints)


def _coordinates_from_angles(p: LidParameters, theta, phi, gamma) -> np.ndarray:
    """A consistent-looking q from the three angles (used as a Newton start)."""
    A = p.l2 * np.array([np.cos(phi), np.sin(phi)])
    R = np.array([[np.cos(theta), -np.sin(theta)], [np.sin(theta), np.cos(theta)]])
    G1 = A + R @ np.asarray(p.AG, float)
    m2 = A / 2
    m3 = np.asarray(p.B, float) + p.l3 / 2 * np.array([np.cos(gamma), np.sin(gamma)])
    return np.array([*G1, theta, *m2, phi, *m3, gamma])


def solve_configuration(p: LidParameters, theta: float, theta_dot: float = 0.0,
                        max_step: float = np.radians(2.0)):
    """q and q' for the lid at (theta, theta'), on the assembly branch continued from p.assembly."""
    base = build_lid_system(p)
    th0, ph0, ga0 = p.assembly
    q = _coordinates_from_angles(p, th0, ph0, ga0)
    n = max(1, int(np.ceil(abs(theta - th0) / max_step)))
    for th in np.linspace(th0, theta, n + 1):
        driven = PlanarSystem(3, base.joints, [AngleDriver(0, th, 0.0)])
        q = solve_positions(driven, q)
    driven = PlanarSystem(3, base.joints, [AngleDriver(0, theta, theta_dot)])
    return q, solve_velocities(driven, q)


def evaluate_applied_forces(p: LidParameters, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
    """Generalised forces Q: gravity, spring E-D, dashpot C-O, rotary damper, torsion spring,
    friction and the end damper on the lid's rotation (all but gravity on the lid or at a
    pin)."""
    Q = np.zeros(9)
    for body, m in enumerate((p.m1, p.m2, p.m3)):
        add_point_force(Q, q, body, (0.0, 0.0), np.array([0.0, -m * p.g]))
    s_E = _lid_offset(p, p.AE)
    E = locate_point(q, 0, s_E)
    ED = np.asarray(p.D, float) - E
    l = np.linalg.norm(ED)
    add_point_force(Q, q, 0, s_E, (p.F + p.k * (l - p.l0)) * ED / l)
    s_C = _lid_offset(p, p.AC)
    C = locate_point(q, 0, s_C)
    e_OC = C / np.linalg.norm(C)
    ld_dot = e_OC @ velocity_of_point(q, qd, 0, s_C)
    on = 0.0 if p.one_way and qd[2] > 0 else 1.0     # one-way dampers: only while closing
    add_point_force(Q, q, 0, s_C, -on * p.c * ld_dot * e_OC)
    a, b = _PINS[p.rot_pivot]                        # the rotary damper on its pin's bodies
    rate = (qd[3 * a + 2] if a >= 0 else 0.0) - (qd[3 * b + 2] if b >= 0 else 0.0)
    add_moment(Q, a, -on * p.c_rot * rate)
    if b >= 0:
        add_moment(Q, b, on * p.c_rot * rate)
    if p.kt:
        a, b = _PINS[p.pivot]
        angle = lambda i: q[3 * i + 2] if i >= 0 else 0.0  # noqa: E731
        ref = _pin_angle(p.assembly, a, b)
        d = angle(a) - angle(b) - ref
        psi = ref + np.arctan2(np.sin(d), np.cos(d))     # within half a turn of the assembly's
        moment = -p.kt * (psi - p.psi0)
        add_moment(Q, a, moment)
        if b >= 0:
            add_moment(Q, b, -moment)
    if p.Tf:                                         # dry friction against the lid's turning
        add_moment(Q, 0, -p.Tf * np.sign(qd[2]))
    if p.c_end and q[2] < p.theta_end:               # the end damper, below its angle
        add_moment(Q, 0, -on * p.c_end * qd[2])
    return Q


def _pin_angle(assembly, a: int, b: int) -> float:
    """The pin's relative angle at the assembly (theta, phi, gamma of bodies 0, 1, 2)."""
    return (assembly[a] if a >= 0 else 0.0) - (assembly[b] if b >= 0 else 0.0)


def solve_lid_accelerations(p: LidParameters, theta: float, theta_dot: float):
    """q, q', q'' and the eight multipliers at the state (theta, theta')."""
    q, qd = solve_configuration(p, theta, theta_dot)
    M = assemble_mass_matrix((p.m1, p.m2, p.m3), (p.J1, p.J2, p.J3))
    qdd, lam = solve_dynamics(build_lid_system(p), q, qd, M, evaluate_applied_forces(p, q, qd))
    return q, qd, qdd, lam


def compute_theta_ddot(p: LidParameters, theta: float, theta_dot: float) -> float:
    """theta'' from the augmented absolute-coordinate equations."""
    return float(solve_lid_accelerations(p, theta, theta_dot)[2][2])
