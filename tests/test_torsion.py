"""The torsion spring at a pivot (an element added through the registry) against independent
formulations: Newton-Euler with the pin moments on the bodies, the three-body
absolute-coordinate model (its own angles), an energy balance in the CasADi model and along
the kernel's strokes, the adaptive reference, the potential from an independent closure, and
the held-open equilibrium.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import softclose
from conftest import (assert_formulations_agree, assert_potential, energy_rate, np_closure,
                      uniform_states)
from softclose.simulation.kernel import binding
from softclose.config import default_config
from softclose.numerics.integrators import casadi_step, get_method
from softclose.model.lid import LidModel
from softclose.problem import PARAM_KEYS, TARGETS, as_params
from softclose.simulation.reference import Reference
from softclose.simulation.simulator import Simulator
from softclose.validation.textbook.lid_absolute import read_parameters

#: a free angle per pivot near its angle over the default stroke (deg): a spring that acts
#: both ways over the stroke
FREE = {"O": 100.0, "B": 150.0, "A": -95.0, "C": -135.0}
PIVOTS = tuple(FREE)


def torsion_cfg(pivot, kt=0.5, free=None, **design):
    values = {"design.torsion_k": kt, "design.torsion_pivot": pivot,
              "design.torsion_free_angle_deg": FREE[pivot] if free is None else free}
    values.update({f"design.{k}": v for k, v in design.items()})
    return default_config().update(values)


@pytest.fixture(scope="module", params=PIVOTS)
def case(request):
    cfg = torsion_cfg(request.param, damper_c=300.0, spring_k=800.0, spring_rest_length=0.06)
    model = LidModel.from_config(cfg)
    return request.param, cfg, model


def _states(model, n, seed):
    return uniform_states(model, n, seed)


def test_reduced_newton_euler_and_absolute_coordinates_agree(case):
    pivot, cfg, model = case
    p = model.params()
    absolute = read_parameters(cfg)
    assert absolute.kt == 0.5 and absolute.pivot == pivot
    states = _states(model, 12, seed=3)
    red = assert_formulations_agree(model, absolute, p, states)
    th, thd = states[-1]
    # and the spring changes the answer (the test can fail)
    off = model.theta_ddot(th, thd, as_params(np.r_[p[:4], 0.0, 0.0]))
    assert abs(off - red) > 1e-3


def test_energy_rate_equals_damper_power_with_torsion(case):
    """dE/dt along the equation of motion (AD) is the dampers' power: the torsion spring's
    potential is the integral of its moment."""
    _, cfg, model = case
    rate = energy_rate(model)
    p = model.params()
    for th, thd in _states(model, 10, seed=4):
        dEdt, P = (float(v) for v in rate([th, thd], p))
        assert dEdt == pytest.approx(P, rel=1e-9, abs=1e-12)
    p_undamped = p.copy()
    p_undamped[PARAM_KEYS.index("damper_c")] = 0.0
    for th, thd in _states(model, 5, seed=5):
        dEdt, P = (float(v) for v in rate([th, thd], p_undamped))
        assert P == 0.0 and abs(dEdt) < 1e-10


def test_holding_moment_is_the_slope_of_an_independent_potential(case):
    """dV/dtheta (the model's and the table's statics) against a central difference of V from
    a plain-numpy closure: gravity, the spring, and 1/2 k_t (psi - psi_free)^2 with psi read
    off the crank angles."""
    pivot, cfg, model = case
    geo, m, d = cfg.geometry, cfg.mass, cfg.design
    near = {"phi": math.radians(geo.assembly[1])}

    def V(th):
        phi, gamma = np_closure(th, geo, near["phi"])
        A = geo.crank_oa * np.array([math.cos(phi), math.sin(phi)])
        R = np.array([[math.cos(th), -math.sin(th)], [math.sin(th), math.cos(th)]])
        G1, E = A + R @ np.array(geo.lid_g), A + R @ np.array(geo.lid_e)
        G3 = np.array(geo.pivot_b) + 0.5 * geo.crank_bc * np.array([math.cos(gamma),
                                                                     math.sin(gamma)])
        Vg = m.gravity * (m.lid * G1[1] + m.crank_oa * 0.5 * A[1] + m.crank_bc * G3[1])
        l = np.hypot(*(np.array(geo.spring_anchor) - E))
        psi = {"O": phi, "B": gamma, "A": th - phi, "C": th - gamma}[pivot]
        ref = math.radians({"O": geo.assembly[1], "B": geo.assembly[2],
                            "A": geo.assembly[0] - geo.assembly[1],
                            "C": geo.assembly[0] - geo.assembly[2]}[pivot])
        psi = ref + math.atan2(math.sin(psi - ref), math.cos(psi - ref))
        return (Vg + 0.5 * d.spring_k * (l - d.spring_rest_length) ** 2
                + 0.5 * d.torsion_k * (psi - math.radians(d.torsion_free_angle_deg)) ** 2)

    assert_potential(cfg, model, V, (0.0, 0.1, 0.3))


def test_kernel_strokes_match_the_adaptive_reference(case):
    _, cfg, model = case
    sim = Simulator.from_config(cfg, model=model)
    ref = Reference(model)
    stiffer = model.params()
    stiffer[PARAM_KEYS.index("torsion_k")] *= 3
    for p in (model.params(), stiffer):
        r, rr = sim.run(p), ref.simulate(p)
        assert r.ok
        assert r.closed == rr.closed
        if r.closed:
            assert abs(r.closing_time - rr.closing_time) < TARGETS["closing_time"]
            assert abs(r.impact_theta_dot - rr.impact_theta_dot) < TARGETS["impact_theta_dot"]
        assert r.peak_tip_speed == pytest.approx(rr.peak_tip_speed, rel=1e-6)
        assert r.holding_moment == pytest.approx(rr.holding_moment, rel=1e-12)
        assert r.accuracy["closing_time"] < TARGETS["closing_time"] if r.closed else True


def test_kernel_energy_balance_along_a_stroke(case):
    """Along the kernel's trajectory the energy (CasADi, exact) falls by the dampers' work
    (trapezoid of the power), and without dampers it stays (rk4 at 2 ms)."""
    _, cfg, model = case
    sim = Simulator.from_config(cfg, model=model)
    p = model.params()
    r = sim.run(p, trajectory=True)
    tr = r.trajectory
    X = np.vstack([tr["theta"], tr["theta_dot"]])
    E = np.asarray(model.energy_fn.map(X.shape[1])(X, np.repeat(p[:, None], X.shape[1], 1)))
    P = np.asarray(model.power_fn.map(X.shape[1])(X, np.repeat(p[:, None], X.shape[1], 1)))
    E, P = E.ravel(), P.ravel()
    work = np.concatenate([[0.0], np.cumsum(0.5 * (P[1:] + P[:-1]) * np.diff(tr["t"]))])
    drift = np.abs(E - E[0] - work).max()
    assert drift < 2e-4 * abs(E[0] - E[-1])            # trapezoid error of the work
    # undamped: the energy stays to the method's drift
    q = p.copy()
    q[PARAM_KEYS.index("damper_c")] = 0.0
    q[PARAM_KEYS.index("rotary_damper_c")] = 0.0
    r0 = sim.run(q, trajectory=True)
    X = np.vstack([r0.trajectory["theta"], r0.trajectory["theta_dot"]])
    E0 = np.asarray(model.energy_fn.map(X.shape[1])(X, np.repeat(q[:, None], X.shape[1], 1)))
    assert np.ptp(E0) < 1e-8 * np.abs(E0).max()


def test_kernel_step_matches_the_casadi_step(case):
    _, cfg, model = case
    sim = Simulator.from_config(cfg, model=model)
    p = model.params()
    for name in ("rk4", "gauss4"):
        m = get_method(name)
        F = casadi_step(m, model.ode)
        for th, thd in _states(model, 4, seed=6):
            a = np.asarray(F([th, thd], p, 2e-3)).ravel()
            b = binding.kernel_step(sim.table, m, p, 2e-3, np.array([th, thd]))
            assert np.allclose(a, b, rtol=1e-9, atol=1e-10)


def test_rows_with_and_without_the_torsion_spring_in_one_batch():
    """Lanes with and without the element share vector groups: each row's numbers are those
    of a batch of its own kind."""
    cfg = torsion_cfg("O", kt=0.0)
    sim = Simulator.from_config(cfg)
    rng = np.random.default_rng(2)
    n = 64
    P = as_params(np.column_stack([rng.uniform(500, 4000, n), rng.uniform(0.05, 0.09, n),
                                   rng.uniform(100, 3000, n), np.zeros(n)]))
    with_t = P.copy()
    with_t[::2, PARAM_KEYS.index("torsion_k")] = rng.uniform(0.1, 1.0, n // 2)
    with_t[::2, PARAM_KEYS.index("torsion_free_angle_deg")] = 100.0
    mixed = sim.run_batch(with_t)
    alone_t = sim.run_batch(with_t[::2])
    alone_0 = sim.run_batch(with_t[1::2])
    plain = sim.run_batch(P[1::2])
    for k in ("status", "closing_time", "peak_tip_speed", "steps", "stop_reason"):
        assert np.array_equal(mixed[k][::2], alone_t[k], equal_nan=True), k
        assert np.array_equal(mixed[k][1::2], alone_0[k], equal_nan=True), k
        assert np.array_equal(alone_0[k], plain[k], equal_nan=True), k
    assert not np.array_equal(mixed["closing_time"][::2], sim.run_batch(P[::2])["closing_time"])


def test_a_stiff_torsion_spring_holds_the_lid_open_at_its_equilibrium():
    """The kernel's early exit with the torsion spring's potential: the lid is held open at
    the stable equilibrium, where the model's dV vanishes (independent of the table)."""
    cfg = torsion_cfg("O", kt=30.0, free=114.0, damper_c=3000.0)   # phi = 114 deg at ~10 deg
    sim = Simulator.from_config(cfg)
    model = sim.model
    p = model.params()
    r = sim.run_batch(p[None, :])
    assert r["status"][0] == 1 and r["stop_reason"][0] == 2
    th = r["stop_theta"][0]
    assert r["stop_time"][0] < cfg.stroke.t_max
    assert abs(float(model.dV(th, p))) < 1e-8
    assert float(model.dV(th - 1e-4, p)) < 0 < float(model.dV(th + 1e-4, p))
    assert r["reason"][0] == f"held open at theta = {math.degrees(th):.1f} deg"


def test_public_api_sweep_over_the_torsion_rate_equals_single_strokes():
    cfg = torsion_cfg("B", kt=0.0, free=150.0, damper_c=300.0)
    res = softclose.sweep(cfg, {"design.torsion_k": [0.0, 0.3, 0.8]})
    frame = res.to_frame()
    for kt, row in zip((0.0, 0.3, 0.8), frame.itertuples()):
        one = softclose.simulate(cfg.set("design.torsion_k", kt))
        assert row.closing_time == one.closing_time
        assert row.holding_moment == pytest.approx(one.holding_moment, rel=1e-12)


def test_the_optimiser_designs_around_a_torsion_spring():
    """A torsion spring that helps hold the lid shut (free angle beyond the closed crank
    angle): the optimum is verified by the reference with the spring in the equation."""
    cfg = torsion_cfg("O", kt=0.3, free=125.0)
    res = softclose.optimise(cfg, starts=2)
    assert res.success, res.message
    base = softclose.optimise(default_config(), starts=2)
    assert res.design["spring_k"] != pytest.approx(base.design["spring_k"], rel=1e-3)
    assert res.metrics["holding_moment"] >= cfg.optimise.holding_moment_min - 1e-7
