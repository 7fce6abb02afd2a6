"""Planar multibody machinery in absolute coordinates (Nikravesh style), and the driven four-bar.

Each body i has q_i = (x_i, y_i, phi_i): the position r_i of its reference point and its angle.
A point with body-fixed offset s' sits at r_i + A(phi_i) s'.  Constraints used here:

- revolute joint between body i (offset s_i') and body j (offset s_j') or the ground (point C):
  Phi = r_i + A_i s_i' - r_j - A_j s_j' = 0,
  Phi_q = [I, B_i s_i', -I, -B_j s_j'],  gamma = A_i s_i' phi_i'^2 - A_j s_j' phi_j'^2;
- absolute angle driver on body k: Phi = phi_k - phi0 - omega t,  nu = omega,  gamma = 0.

with A(phi) the rotation matrix and B(phi) = dA/dphi.  Kinematics: Newton on Phi(q, t) = 0,
Phi_q q' = nu, Phi_q q'' = gamma.  Dynamics: M q'' + Phi_q^T lambda = Q, Phi_q q'' = gamma.

The driven four-bar of seed 002: three bodies (crank, coupler, rocker) with their midpoints and
angles as coordinates, ground pivots (0, 0) and (20, 0), L1 = 10, L2 = 26, L3 = 18, phi1 = omega t.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

GROUND = -1


def rotate(phi: float) -> np.ndarray:
    """A(phi): planar rotation matrix."""
    c, s = np.cos(phi), np.sin(phi)
    return np.array([[c, -s], [s, c]])


def rotate_derivative(phi: float) -> np.ndarray:
    """B(phi) = dA/dphi."""
    c, s = np.cos(phi), np.sin(phi)
    return np.array([[-s, -c], [c, -s]])


@dataclass(frozen=True)
class Revolute:
    """Pin between body i at offset s_i and body j at offset s_j (j = GROUND: s_j is the ground point)."""

    i: int
    s_i: tuple[float, float]
    j: int
    s_j: tuple[float, float]


@dataclass(frozen=True)
class AngleDriver:
    """phi_k = phi0 + omega t."""

    k: int
    phi0: float
    omega: float


@dataclass
class PlanarSystem:
    """Bodies, joints and drivers; coordinates q = (x1, y1, phi1, x2, ...)."""

    n_bodies: int
    joints: list[Revolute] = field(default_factory=list)
    drivers: list[AngleDriver] = field(default_factory=list)

    @property
    def n_coordinates(self) -> int:
        return 3 * self.n_bodies

    @property
    def n_constraints(self) -> int:
        return 2 * len(self.joints) + len(self.drivers)


def locate_point(q: np.ndarray, body: int, s: np.ndarray) -> np.ndarray:
    """Global position r + A s' of a body point (body = GROUND: s itself)."""
    s = np.asarray(s, dtype=float)
    if body == GROUND:
        return s
    r = q[3 * body:3 * body + 2]
    return r + rotate(q[3 * body + 2]) @ s


def velocity_of_point(q: np.ndarray, qd: np.ndarray, body: int, s: np.ndarray) -> np.ndarray:
    """r' + B s' phi'."""
    if body == GROUND:
        return np.zeros(2)
    return qd[3 * body:3 * body + 2] + rotate_derivative(q[3 * body + 2]) @ np.asarray(s, float) * qd[3 * body + 2]


def _joint_terms(q, joints):
    """Yield (row, i, s_i, j, s_j) for each revolute."""
    for n, jt in enumerate(joints):
        yield 2 * n, jt.i, np.asarray(jt.s_i, float), jt.j, np.asarray(jt.s_j, float)


def evaluate_constraints(system: PlanarSystem, q: np.ndarray, t: float = 0.0) -> np.ndarray:
    """Phi(q, t)."""
    Phi = np.zeros(system.n_constraints)
    for row, i, s_i, j, s_j in _joint_terms(q, system.joints):
        Phi[row:row + 2] = locate_point(q, i, s_i) - locate_point(q, j, s_j)
    m0 = 2 * len(system.joints)
    for n, d in enumerate(system.drivers):
        Phi[m0 + n] = q[3 * d.k + 2] - d.phi0 - d.omega * t
    return Phi


def evaluate_jacobian(system: PlanarSystem, q: np.ndarray) -> np.ndarray:
    """Phi_q."""
    Phi_q = np.zeros((system.n_constraints, system.n_coordinates))
    for row, i, s_i, j, s_j in _joint_terms(q, system.joints):
        for body, s, sign in ((i, s_i, 1.0), (j, s_j, -1.0)):
            if body == GROUND:
                continue
            c = 3 * body
            Phi_q[row:row + 2, c:c + 2] += sign * np.eye(2)
            Phi_q[row:row + 2, c + 2] += sign * rotate_derivative(q[c + 2]) @ s
    m0 = 2 * len(system.joints)
    for n, d in enumerate(system.drivers):
        Phi_q[m0 + n, 3 * d.k + 2] = 1.0
    return Phi_q


def evaluate_nu(system: PlanarSystem) -> np.ndarray:
    """nu = -Phi_t."""
    nu = np.zeros(system.n_constraints)
    m0 = 2 * len(system.joints)
    for n, d in enumerate(system.drivers):
        nu[m0 + n] = d.omega
    return nu


def evaluate_gamma(system: PlanarSystem, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
    """gamma = -(Phi_q q')_q q' - 2 Phi_qt q' - Phi_tt (the last two vanish here)."""
    gamma = np.zeros(system.n_constraints)
    for row, i, s_i, j, s_j in _joint_terms(q, system.joints):
        for body, s, sign in ((i, s_i, 1.0), (j, s_j, -1.0)):
            if body == GROUND:
                continue
            c = 3 * body
            gamma[row:row + 2] += sign * rotate(q[c + 2]) @ s * qd[c + 2] ** 2
    return gamma


def solve_positions(system: PlanarSystem, q_guess: np.ndarray, t: float = 0.0,
                    tol: float = 1e-13, max_iter: int = 50) -> np.ndarray:
    """Newton on Phi(q, t) = 0 (square system: joints + drivers = coordinates)."""
    q = np.array(q_guess, dtype=float)
    for _ in range(max_iter):
        Phi = evaluate_constraints(system, q, t)
        dq = np.linalg.solve(evaluate_jacobian(system, q), -Phi)
        q += dq
        if np.max(np.abs(dq)) <= tol * max(1.0, np.max(np.abs(q))):
            return q
    if np.max(np.abs(evaluate_constraints(system, q, t))) > 1e-9:
        raise RuntimeError(f"Newton did not converge at t = {t}")
    return q


def solve_velocities(system: PlanarSystem, q: np.ndarray) -> np.ndarray:
    """q' from Phi_q q' = nu."""
    return np.linalg.solve(evaluate_jacobian(system, q), evaluate_nu(system))


def solve_accelerations(system: PlanarSystem, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
    """q'' from Phi_q q'' = gamma."""
    return np.linalg.solve(evaluate_jacobian(system, q), evaluate_gamma(system, q, qd))


def track_motion(system: PlanarSystem, q0: np.ndarray, times, max_step: float = 0.02):
    """Positions, velocities, accelerations at sorted `times`, following the branch of q0 at t = 0.

    Newton is restarted from the previous solution on a sub-grid no coarser than max_step, so
    the assembly found at t = 0 is followed continuously.
    """
    times = np.asarray(times, dtype=float)
    if np.any(np.diff(times) < 0) or times[0] < 0:
        raise ValueError("times must be sorted and non-negative")
    q = solve_positions(system, q0, 0.0)
    t_now = 0.0
    Q, QD, QDD = [], [], []
    for t in times:
        n_sub = max(1, int(np.ceil((t - t_now) / max_step)))
        for tk in np.linspace(t_now, t, n_sub + 1)[1:]:
            q = solve_positions(system, q, tk)
        t_now = t
        qd = solve_velocities(system, q)
        Q.append(q.copy())
        QD.append(qd)
        QDD.append(solve_accelerations(system, q, qd))
    return np.array(Q), np.array(QD), np.array(QDD)


# --- dynamics -----------------------------------------------------------------------------------

def assemble_mass_matrix(masses, inertias) -> np.ndarray:
    """M = diag(m1, m1, J1, m2, ...), with the reference points at the centres of mass."""
    return np.diag(np.ravel([[m, m, J] for m, J in zip(masses, inertias)]))


def add_point_force(Q: np.ndarray, q: np.ndarray, body: int, s: np.ndarray, F: np.ndarray) -> None:
    """Q_i += [F, (B_i s')^T F]: a force F applied at body point s' (in place)."""
    c = 3 * body
    Q[c:c + 2] += F
    Q[c + 2] += (rotate_derivative(q[c + 2]) @ np.asarray(s, float)) @ F


def add_moment(Q: np.ndarray, body: int, n: float) -> None:
    """Q_phi_i += n (in place)."""
    Q[3 * body + 2] += n


def solve_dynamics(system: PlanarSystem, q: np.ndarray, qd: np.ndarray, M: np.ndarray,
                   Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """q'' and lambda from [[M, Phi_q^T], [Phi_q, 0]] [q''; lambda] = [Q; gamma]."""
    Phi_q = evaluate_jacobian(system, q)
    n, m = system.n_coordinates, system.n_constraints
    K = np.zeros((n + m, n + m))
    K[:n, :n] = M
    K[:n, n:] = Phi_q.T
    K[n:, :n] = Phi_q
    rhs = np.concatenate([Q, evaluate_gamma(system, q, qd)])
    sol = np.linalg.solve(K, rhs)
    return sol[:n], sol[n:]


# --- the seed-002 four-bar --------------------------------------------------------------------------

@dataclass(frozen=True)
class DrivenFourBar:
    """Crank L1 from ground (0, 0), coupler L2, rocker L3 to ground (G, 0); phi1 = omega t."""

    L1: float = 10.0
    L2: float = 26.0
    L3: float = 18.0
    G: float = 20.0
    omega: float = 1.5


def build_driven_fourbar(p: DrivenFourBar = DrivenFourBar()) -> PlanarSystem:
    """Three bodies, four revolutes (p1 ground-crank, p2, p3, p4 rocker-ground), one driver."""
    h1, h2, h3 = p.L1 / 2, p.L2 / 2, p.L3 / 2
    joints = [
        Revolute(0, (-h1, 0.0), GROUND, (0.0, 0.0)),
        Revolute(0, (h1, 0.0), 1, (-h2, 0.0)),
        Revolute(1, (h2, 0.0), 2, (-h3, 0.0)),
        Revolute(2, (h3, 0.0), GROUND, (p.G, 0.0)),
    ]
    return PlanarSystem(3, joints, [AngleDriver(0, 0.0, p.omega)])


def assemble_driven_fourbar(p: DrivenFourBar = DrivenFourBar(), upper: bool = True) -> np.ndarray:
    """q at t = 0 with the coupler-rocker joint p3 above (upper) or below the ground line."""
    p2 = np.array([p.L1, 0.0])                  # crank tip at phi1 = 0
    p4 = np.array([p.G, 0.0])
    d = np.linalg.norm(p4 - p2)
    a = (p.L2 ** 2 - p.L3 ** 2 + d ** 2) / (2 * d)
    h = np.sqrt(p.L2 ** 2 - a ** 2)
    e = (p4 - p2) / d
    p3 = p2 + a * e + (1 if upper else -1) * h * np.array([-e[1], e[0]])
    phi2 = np.arctan2(*(p3 - p2)[::-1])
    phi3 = np.arctan2(*(p4 - p3)[::-1])
    q = np.array([p.L1 / 2, 0.0, 0.0, *(p2 + p3) / 2, phi2, *(p3 + p4) / 2, phi3])
    return solve_positions(build_driven_fourbar(p), q, 0.0)


def locate_joints(q: np.ndarray, p: DrivenFourBar = DrivenFourBar()) -> np.ndarray:
    """Joint positions p1..p4 (4 x 2) for one q."""
    return np.array([[0.0, 0.0],
                     locate_point(q, 0, (p.L1 / 2, 0.0)),
                     locate_point(q, 1, (p.L2 / 2, 0.0)),
                     [p.G, 0.0]])
