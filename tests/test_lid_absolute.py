"""The lid as three bodies in absolute coordinates against SPEC §8 and the reduced model."""

import numpy as np
import pytest

from softclose.validation.textbook.driven_fourbar import evaluate_constraints, evaluate_gamma, evaluate_jacobian
from softclose.validation.textbook.lid_absolute import (build_lid_system, compute_theta_ddot, default_parameters,
                                             read_parameters, solve_lid_accelerations)


def test_spec_reference_state_at_18_deg():
    q, qd, qdd, _ = solve_lid_accelerations(default_parameters(), np.radians(18.0), 0.0)
    assert np.degrees(q[5]) == pytest.approx(108.6655, abs=1e-4)
    assert np.degrees(q[8]) == pytest.approx(146.8855, abs=1e-4)
    assert qdd[2] == pytest.approx(-28.5296, abs=1e-4)


def test_constraints_hold_at_position_velocity_and_acceleration_level():
    p = default_parameters(k=400.0, l0=0.04, c=30.0, c_rot=0.02)
    system = build_lid_system(p)
    rng = np.random.default_rng(5)
    for _ in range(5):
        q, qd, qdd, _ = solve_lid_accelerations(p, rng.uniform(-0.2, 1.2), rng.uniform(-6, 6))
        assert np.max(np.abs(evaluate_constraints(system, q))) <= 1e-12
        assert np.max(np.abs(evaluate_jacobian(system, q) @ qd)) <= 1e-12
        # second derivative of Phi along the motion: Phi_q q'' - gamma == 0, checked by differencing Phi_q q'
        h = 1e-6
        assert np.allclose(evaluate_jacobian(system, q) @ qdd, evaluate_gamma(system, q, qd), atol=1e-10)
        dPhi = (evaluate_jacobian(system, q + h * qd) @ (qd + h * qdd)
                - evaluate_jacobian(system, q - h * qd) @ (qd - h * qdd)) / (2 * h)
        assert np.max(np.abs(dPhi)) <= 1e-6 * max(1.0, np.max(np.abs(qdd)))


def test_config_parameters_match_the_spec_defaults():
    config = pytest.importorskip("softclose.config")
    a, b = read_parameters(config.load_config()), default_parameters()
    for name in a.__dataclass_fields__:
        x, y = getattr(a, name), getattr(b, name)
        assert x == y if isinstance(x, str) else np.allclose(x, y, rtol=1e-12, atol=0), name


def test_agrees_with_reduced_model_at_random_states():
    config = pytest.importorskip("softclose.config")
    model = pytest.importorskip("softclose.model.lid")
    cfg = config.load_config(overrides=["design.spring_k=350", "design.spring_rest_length=0.045",
                                        "design.damper_c=40", "design.rotary_damper_c=0.03"])
    reduced = model.LidModel.from_config(cfg)
    p = read_parameters(cfg)
    assert p.k > 0 and p.c > 0 and p.c_rot > 0
    rng = np.random.default_rng(2024)
    for _ in range(20):
        theta, theta_dot = rng.uniform(np.radians(-10), np.radians(70)), rng.uniform(-8.0, 8.0)
        q, _, qdd, _ = solve_lid_accelerations(p, theta, theta_dot)
        phi, gamma = reduced.closure(theta)
        assert np.cos(q[5] - phi) == pytest.approx(1.0, abs=1e-12)
        assert np.cos(q[8] - gamma) == pytest.approx(1.0, abs=1e-12)
        expected = reduced.theta_ddot(theta, theta_dot)
        assert qdd[2] == pytest.approx(expected, rel=1e-10)
        assert compute_theta_ddot(p, theta, theta_dot) == qdd[2]
