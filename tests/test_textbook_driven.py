"""Driven four-bar (seed 002) in absolute coordinates: constraints, velocities, accelerations, dynamics."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from softclose.validation.textbook.driven_fourbar import (GROUND, DrivenFourBar, PlanarSystem, Revolute,
                                               add_point_force, assemble_driven_fourbar,
                                               assemble_mass_matrix, build_driven_fourbar,
                                               evaluate_constraints, evaluate_jacobian, locate_joints,
                                               solve_dynamics, solve_positions, solve_velocities,
                                               track_motion)

P = DrivenFourBar()
SYSTEM = build_driven_fourbar(P)
TIMES = np.linspace(0.0, 10.0, 41)


@pytest.fixture(scope="module")
def motion():
    q0 = assemble_driven_fourbar(P, upper=True)
    return track_motion(SYSTEM, q0, TIMES)


def test_assembly_and_link_lengths(motion):
    Q = motion[0]
    for q in Q:
        J = locate_joints(q, P)
        lengths = np.linalg.norm(np.diff(J, axis=0), axis=1)
        assert np.allclose(lengths, [P.L1, P.L2, P.L3], atol=1e-12)
    assert locate_joints(Q[0], P)[2, 1] > 0          # p3 above the ground line at t = 0
    assert np.all([locate_joints(q, P)[2, 1] > 0 for q in Q])   # crank-rocker: the branch is kept


def test_constraint_residuals(motion):
    Q = motion[0]
    res = max(np.max(np.abs(evaluate_constraints(SYSTEM, q, t))) for q, t in zip(Q, TIMES))
    assert res <= 1e-12
    assert np.allclose(Q[:, 2], P.omega * TIMES, atol=1e-12)


def test_velocities_match_finite_differences(motion):
    Q, QD, _ = motion
    h = 1e-5
    for q, qd, t in zip(Q[::4], QD[::4], TIMES[::4]):
        qp = solve_positions(SYSTEM, q, t + h)
        qm = solve_positions(SYSTEM, q, t - h)
        fd = (qp - qm) / (2 * h)
        assert np.allclose(qd, fd, rtol=1e-7, atol=1e-7 * np.max(np.abs(qd)))


def test_accelerations_match_finite_differences(motion):
    Q, QD, QDD = motion
    h = 1e-4
    for q, qdd, t in zip(Q[::4], QDD[::4], TIMES[::4]):
        qp = solve_positions(SYSTEM, q, t + h)
        qm = solve_positions(SYSTEM, q, t - h)
        fd_v = (solve_velocities(SYSTEM, qp) - solve_velocities(SYSTEM, qm)) / (2 * h)
        fd_p = (qp - 2 * q + qm) / h ** 2
        scale = np.max(np.abs(qdd))
        assert np.allclose(qdd, fd_v, atol=1e-6 * scale)
        assert np.allclose(qdd, fd_p, atol=1e-4 * scale)


def test_jacobian_matches_finite_differences(motion):
    q = motion[0][7]
    J = evaluate_jacobian(SYSTEM, q)
    h = 1e-7
    fd = np.column_stack([(evaluate_constraints(SYSTEM, q + h * e) - evaluate_constraints(SYSTEM, q - h * e)) / (2 * h)
                          for e in np.eye(9)])
    assert np.allclose(J, fd, atol=1e-7)


def test_dynamics_of_a_pinned_rod_matches_the_pendulum_equation():
    """One rod pinned at its end: (J + m l^2/4) phi'' = -m g (l/2) cos phi; lambda = pin reaction."""
    m, l, g = 2.0, 0.8, 9.81
    J = m * l ** 2 / 12
    rod = PlanarSystem(1, [Revolute(0, (-l / 2, 0.0), GROUND, (0.0, 0.0))])
    rng = np.random.default_rng(3)
    for _ in range(5):
        phi, phid = rng.uniform(-np.pi, np.pi), rng.uniform(-3, 3)
        q = np.array([l / 2 * np.cos(phi), l / 2 * np.sin(phi), phi])
        qd = np.array([-l / 2 * np.sin(phi) * phid, l / 2 * np.cos(phi) * phid, phid])
        Q = np.zeros(3)
        add_point_force(Q, q, 0, (0.0, 0.0), np.array([0.0, -m * g]))
        qdd, lam = solve_dynamics(rod, q, qd, assemble_mass_matrix([m], [J]), Q)
        expected = -m * g * l / 2 * np.cos(phi) / (J + m * l ** 2 / 4)
        assert qdd[2] == pytest.approx(expected, rel=1e-12)
        # Newton for the centre of mass: m a = gravity + reaction, reaction = -lambda
        assert np.allclose(m * qdd[:2], np.array([0.0, -m * g]) - lam, atol=1e-10)


def test_study_prints_the_requested_times():
    root = Path(__file__).resolve().parents[1]
    out = subprocess.run([sys.executable, str(root / "studies" / "driven_fourbar.py"), "--json", "--fast",
                          "--no-plots", "--times", "0,2.5,10"], capture_output=True, text=True, check=True)
    data = json.loads(out.stdout)
    assert data["t"] == [0.0, 2.5, 10.0]
    assert np.shape(data["q"]) == np.shape(data["qd"]) == np.shape(data["qdd"]) == (3, 9)
    assert data["max_constraint_residual"] <= 1e-12
    assert data["q"][2][2] == pytest.approx(15.0)
