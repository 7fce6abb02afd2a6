"""The fixed-step methods: tableau identities and order conditions, the CasADi step against
the C kernel's step, and the observed convergence order of each method's impact_theta_dot
against the adaptive reference (CVODES run at tolerance 1e-14 here, so that its own error,
~1e-12 in impact_theta_dot, is far below the errors fitted)."""

from __future__ import annotations


import numpy as np
import pytest

from softclose.simulation.kernel import binding
from softclose.numerics.integrators import METHODS, casadi_step, get_method
from softclose.simulation.reference import Reference
from softclose.numerics.integrators import amplification
from softclose.simulation.simulator import Simulator
from softclose.problem import as_params


def _tab(m):
    return np.asarray(m.A, float), np.asarray(m.b, float), np.asarray(m.c, float)


def order_conditions(A, b, c):
    """Butcher's conditions up to order 5: {order: [(value, exact), ...]}."""
    Ac, Ac2, Ac3 = A @ c, A @ c ** 2, A @ c ** 3
    AAc = A @ Ac
    return {
        1: [(b.sum(), 1.0)],
        2: [(b @ c, 1 / 2)],
        3: [(b @ c ** 2, 1 / 3), (b @ Ac, 1 / 6)],
        4: [(b @ c ** 3, 1 / 4), (b @ (c * Ac), 1 / 8), (b @ Ac2, 1 / 12), (b @ AAc, 1 / 24)],
        5: [(b @ c ** 4, 1 / 5), (b @ (c ** 2 * Ac), 1 / 10), (b @ (c * Ac2), 1 / 15),
            (b @ (c * AAc), 1 / 30), (b @ (Ac * Ac), 1 / 20), (b @ Ac3, 1 / 20),
            (b @ (A @ (c * Ac)), 1 / 40), (b @ (A @ Ac2), 1 / 60), (b @ (A @ AAc), 1 / 120)],
    }


@pytest.mark.parametrize("name,order", [("rk4", 4), ("gauss4", 4), ("radau5", 5),
                                        ("euler_cromer", 1)])
def test_tableau_identities_and_order(name, order):
    m = get_method(name)
    assert m.order == order
    A, b, c = _tab(m)
    np.testing.assert_allclose(A.sum(axis=1), c, atol=1e-15)      # row sums = c
    conds = order_conditions(A, b, c)
    for q in range(1, order + 1):
        for value, exact in conds[q]:
            assert value == pytest.approx(exact, abs=1e-14), (name, q)
    if order < 5 and m.kind != "symplectic_euler":
        # the stated order is the order: some condition of the next order fails
        assert max(abs(v - e) for v, e in conds[order + 1]) > 1e-6
    if m.kind == "explicit":
        assert np.all(np.triu(A) == 0)


def test_radau_and_gauss_structure():
    A, b, c = _tab(get_method("radau5"))
    np.testing.assert_allclose(A[-1], b, atol=1e-15)        # stiffly accurate
    assert c[-1] == 1.0
    # L-stable: R(z) -> 0 as z -> -inf; A-stable on the imaginary axis
    for z in (-1e8, -1e4):
        R = amplification(get_method("radau5"), np.array([[z, 0], [0, z]]))
        assert abs(R[0, 0]) < 1e-3
    A, b, c = _tab(get_method("gauss4"))
    M = np.outer(b, b) - b[:, None] * A - (b[:, None] * A).T  # symplectic: b_i a_ij + b_j a_ji = b_i b_j
    np.testing.assert_allclose(M, 0, atol=1e-15)


def test_rk4_real_stability_limit():
    m = get_method("rk4")
    z = -m.real_stability
    assert abs(1 + z + z ** 2 / 2 + z ** 3 / 6 + z ** 4 / 24) == pytest.approx(1.0, abs=1e-12)
    R = amplification(m, np.array([[z, 0.0], [0.0, z]]))
    assert abs(R[0, 0]) == pytest.approx(1.0, abs=1e-12)


@pytest.mark.parametrize("name", list(METHODS))
@pytest.mark.parametrize("h", [1e-3, 1e-2])
def test_casadi_step_matches_kernel_step(model, sim, name, h):
    m = get_method(name)
    F = casadi_step(m, model.ode)
    rng = np.random.default_rng(5)
    lo, hi = model.theta_range
    worst = 0.0
    for _ in range(8):
        x0 = np.array([rng.uniform(lo + 0.1, hi - 0.1), rng.uniform(-5, 0.5)])
        p = as_params([rng.uniform(0, 3000), rng.uniform(0.02, 0.12), rng.uniform(0, 300),
                       rng.uniform(0, 0.02)])
        x1_ca = np.asarray(F(x0, p, h)).ravel()
        x1_c = binding.kernel_step(sim.table, m, p, h, x0)
        # relative to the size of the step's increment (and of x)
        scale = np.abs(x1_ca - x0) + 1e-3 * np.abs(x0) + 1e-12
        worst = max(worst, float(np.max(np.abs(x1_ca - x1_c) / scale)))
    assert worst < 1e-8
    # absolute agreement at the table's ~1e-11 level
    assert np.max(np.abs(x1_ca - x1_c)) < 1e-10 * max(1.0, np.abs(x0).max())


# -- convergence orders ---------------------------------------------------------------------
#: spring + dashpot + rotary damper, closing in 0.173 s with |theta'| 3.38 rad/s at impact
ORDER_DESIGN = as_params([800.0, 0.08, 30.0, 0.005])
#: steps fitted per method: the errors there are 1e-10..1e-6, far above the 1e-14
#: reference's ~1e-12 and the table's ~1e-11
ORDER_STEPS = {
    "rk4": [0.016, 0.008, 0.004, 0.002],
    "euler_cromer": [0.008, 0.004, 0.002, 0.001],
    "gauss4": [0.016, 0.008, 0.004, 0.002],
    "radau5": [0.032, 0.016, 0.008],
}


@pytest.fixture(scope="module")
def tight_reference(model):
    return Reference(model, tol=1e-14).simulate(ORDER_DESIGN)


@pytest.mark.parametrize("name", list(ORDER_STEPS))
def test_convergence_order_of_impact_theta_dot(cfg, model, tight_reference, name):
    exact = tight_reference.impact_theta_dot
    steps = np.array(ORDER_STEPS[name])
    errs = []
    for h in steps:
        r = Simulator.from_config(cfg, model, name, h).run(ORDER_DESIGN, estimate_error=False)
        assert r.closed
        errs.append(abs(r.impact_theta_dot - exact))
    errs = np.array(errs)
    assert errs.min() > 5e-11        # far above the tight reference's ~1.5e-12 error
    slope = np.polyfit(np.log(steps), np.log(errs), 1)[0]
    order = get_method(name).order
    assert abs(slope - order) <= 0.3, f"{name}: errors {errs} -> slope {slope:.2f}"
