"""Equation of motion (SPEC §2-3) on the default and the second geometry.

- theta'' at release (SPEC §8);
- the reduced (Lagrange) equation and the Newton-Euler system agree on theta'' at random
  states with spring, dashpot and rotary damper on;
- the reactions satisfy every body's force and moment balance, written here in numpy from
  model.kin positions with finite-difference accelerations (conftest.body_residuals);
- energy: d/dt (T + V) along model.ode, by CasADi AD, equals the damper power; the energy
  function itself equals the bodies' kinetic + potential energy computed here;
- the holding moment is dV/dtheta at theta_closed.
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pytest

from conftest import (body_motion, external_forces, body_residuals, np_energy,
                      random_states)
from softclose.problem import as_params

SPEC_THETA_DDOT = -28.5296   # rad/s^2, SPEC §8 (published to 1e-4)


def test_spec8_theta_ddot_at_release(model):
    tdd = model.theta_ddot(math.radians(18.0), 0.0, as_params(np.zeros(4)))
    assert abs(tdd - SPEC_THETA_DDOT) <= 1e-4
    # Newton-Euler gives the same number
    z = np.asarray(model.newton_euler(math.radians(18.0), 0.0, as_params(np.zeros(4)))).ravel()
    assert z[8] == pytest.approx(tdd, rel=1e-12)


def test_reduced_equation_agrees_with_newton_euler(geometry_case):
    cfg, model = geometry_case
    worst = 0.0
    for th, thd, p in random_states(model, 30, seed=11):
        tdd = model.theta_ddot(th, thd, p)
        z = np.asarray(model.newton_euler(th, thd, p)).ravel()
        worst = max(worst, abs(z[8] - tdd) / max(abs(tdd), 1e-12))
    assert worst < 1e-10


def test_reactions_satisfy_each_body_balance(geometry_case):
    """Nine residuals per state, all written here: forces (N) and moments (N m)."""
    cfg, model = geometry_case
    worst_f, worst_m = 0.0, 0.0
    for th, thd, p in random_states(model, 20, seed=12):
        z = np.asarray(model.newton_euler(th, thd, p)).ravel()
        f, mom, fs, ms = body_residuals(model, th, thd, p, z)
        worst_f = max(worst_f, np.abs(f).max() / fs)
        worst_m = max(worst_m, np.abs(mom).max() / ms)
    # finite-difference accelerations: round-off ~1e-10 of the scale
    assert worst_f < 1e-7
    assert worst_m < 1e-7


def test_reactions_detect_a_wrong_theta_ddot(model):
    """The residual check is sharp: a 1e-4 relative error in theta'' is seen."""
    th, thd, p = random_states(model, 1, seed=13)[0]
    z = np.asarray(model.newton_euler(th, thd, p)).ravel()
    z_bad = z.copy()
    z_bad[8] *= 1 + 1e-4
    f, mom, fs, ms = body_residuals(model, th, thd, p, z_bad)
    assert max(np.abs(f).max() / fs, np.abs(mom).max() / ms) > 1e-6


def test_reactions_at_rest_without_elements_are_statics_plus_inertia(model):
    """At release (theta' = 0, no spring/damper) the whole mechanism: sum of external forces
    = sum m_i a_Gi (the internal pins A, C cancel)."""
    th = math.radians(18.0)
    p = as_params(np.zeros(4))
    z = np.asarray(model.newton_euler(th, 0.0, p)).ravel()
    pos, vel, acc = body_motion(model, th, 0.0, z[8])
    m = model.mass
    ext = z[0:2] + z[4:6] + np.array([0, -(m.lid + m.crank_oa + m.crank_bc) * m.gravity])
    ma = m.lid * acc["G1"] + m.crank_oa * acc["G2"] + m.crank_bc * acc["G3"]
    np.testing.assert_allclose(ext, ma, atol=1e-8 * m.lid * m.gravity)


@pytest.fixture(scope="module")
def energy_rate():
    """Per model: (x, p) -> (dE/dt along the ODE by AD, damper power, scale)."""
    cache = {}

    def get(model):
        if id(model) not in cache:
            x, p = ca.SX.sym("x", 2), ca.SX.sym("p", len(as_params(np.zeros(4))))
            E = model.energy_fn(x, p)
            xdot = model.ode(x, p)
            dEdt = ca.jtimes(E, x, xdot)
            grad = ca.jacobian(E, x)
            scale = ca.fabs(grad[0] * xdot[0]) + ca.fabs(grad[1] * xdot[1])
            cache[id(model)] = ca.Function("rate", [x, p], [dEdt, model.power_fn(x, p), scale])
        return cache[id(model)]
    return get


def test_energy_rate_equals_damper_power(geometry_case, energy_rate):
    cfg, model = geometry_case
    f = energy_rate(model)
    worst = 0.0
    for th, thd, p in random_states(model, 40, seed=14):
        dEdt, P, scale = (float(v) for v in f([th, thd], p))
        assert P <= 0.0
        worst = max(worst, abs(dEdt - P) / max(abs(P), scale))
    assert worst < 1e-10


def test_energy_rate_without_damping_is_zero(geometry_case, energy_rate):
    cfg, model = geometry_case
    f = energy_rate(model)
    for th, thd, p in random_states(model, 10, seed=15):
        p = as_params([p[0], p[1], 0.0, 0.0])
        dEdt, P, scale = (float(v) for v in f([th, thd], p))
        assert P == 0.0
        assert abs(dEdt) < 1e-12 * scale


def test_damper_power_from_the_bodies(geometry_case):
    """power_fn against -c (e_OC . v_C)^2 - c_rot theta'^2 with v_C from finite differences."""
    cfg, model = geometry_case
    worst = 0.0
    for th, thd, p in random_states(model, 15, seed=16):
        pos, vel, _ = body_motion(model, th, thd, 0.0)
        F_s, F_d, M_rot = external_forces(model, pos, vel, thd, p)
        P_np = float(F_d @ vel["C"]) + M_rot * thd
        P = float(model.power_fn([th, thd], p))
        worst = max(worst, abs(P - P_np) / abs(P_np))
    assert worst < 1e-8


def test_energy_function_is_kinetic_plus_potential(geometry_case):
    cfg, model = geometry_case
    worst = 0.0
    for th, thd, p in random_states(model, 15, seed=17):
        E = float(model.energy_fn([th, thd], p))
        E_np = np_energy(model, th, thd, p)
        worst = max(worst, abs(E - E_np) / max(abs(E_np), 1e-3))
    assert worst < 1e-9


def test_holding_moment_is_dV_dtheta_at_closed(geometry_case):
    cfg, model = geometry_case
    thc = cfg.stroke.theta_closed
    for p in (as_params(np.zeros(4)), as_params([800.0, 0.08, 30.0, 0.0]), as_params([3000.0, 0.03, 0, 0])):
        h = 1e-4
        V = lambda th: np_energy(model, th, 0.0, p)  # noqa: E731
        dV = (V(thc - 2 * h) - 8 * V(thc - h) + 8 * V(thc + h) - V(thc + 2 * h)) / (12 * h)
        assert model.holding_moment(p) == pytest.approx(dV, rel=1e-7, abs=1e-9)
    if model.geo is cfg.geometry and cfg.geometry.crank_oa == 0.045:
        assert model.holding_moment(as_params(np.zeros(4))) > 0   # gravity alone presses the lid shut
