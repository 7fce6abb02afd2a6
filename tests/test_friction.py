"""Dry (Coulomb) friction on the lid's rotation: stick and slip with known answers.

Without a damper, the energy lost between two rests is the friction moment times the angle
travelled, so the rests of a stroke follow from the potential alone: from a rest at a, the
lid moves the way -V'(a) drives it if |V'(a)| > T_f and stops at the first b with
V(a) - V(b) = T_f |a - b|; it sticks at the first rest where |V'| <= T_f. The kernel (its
rests located to the method's order) and the reference (rests as events) must find that
sequence; the trajectory's energy must fall by T_f times the path; the three formulations of
the equation of motion must agree on the friction moment; the optimiser, whose strokes are
monotone, must see it as a constant moment and be verified by the reference.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from softclose.config import default_config
from softclose.model.lid import LidModel
from softclose.simulation.reference import Reference
from softclose.simulation.simulator import Simulator
from softclose.validation.textbook.lid_absolute import compute_theta_ddot, read_parameters

#: a spring that holds the lid open in a well near 11 deg (no damper: friction alone)
WELL = dict(spring_k=3000.0, spring_rest_length=0.0792571, damper_c=0.0)


def cfg_of(Tf, **design):
    cfg = default_config().update({f"design.{k}": v for k, v in (design or WELL).items()})
    return cfg.set("friction.torque", Tf)


def potential(model, p):
    return lambda th: float(model.energy_fn([th, 0.0], p))


def rests(model, p, Tf, theta0, n_max=200):
    """The rests of a stroke from the energy alone (no damper): a list of angles, the last
    the one where the lid sticks."""
    V = potential(model, p)
    dV = lambda th: float(model.dV(th, p))  # noqa: E731
    lo, hi = model.stroke.theta_closed, theta0
    out, a = [], theta0
    for _ in range(n_max):
        if abs(dV(a)) <= Tf:
            return out + [a]
        s = -1.0 if dV(a) > 0 else 1.0                    # the way -V' drives it
        g = lambda b: V(a) - V(b) - Tf * abs(a - b)         # noqa: E731  (> 0 while moving)
        step, b = 1e-4, a
        while g(b + s * step) > 0:                          # walk to the sign change
            b += s * step
            assert lo - 0.2 < b < hi + 0.2, "the lid left the well"
        x0, x1 = b, b + s * step
        for _ in range(100):                                # then bisect
            xm = 0.5 * (x0 + x1)
            x0, x1 = (xm, x1) if g(xm) > 0 else (x0, xm)
        out.append(a)
        a = 0.5 * (x0 + x1)
    raise AssertionError("no stick within n_max rests")


@pytest.mark.parametrize("Tf", [0.05, 0.1, 0.26])
def test_rests_and_stick_follow_the_energy(Tf):
    cfg = cfg_of(Tf)
    model = LidModel.from_config(cfg)
    p = model.params()
    seq = rests(model, p, Tf, cfg.stroke.theta0)
    assert len(seq) >= 2                                   # it moved, then stuck
    ref = Reference(model).simulate(p)
    kern = Simulator.from_config(cfg, model=model).run(p)
    for r, tol in ((ref, 1e-8), (kern, 1e-7)):
        assert not r.closed and r.reason.startswith("held by friction at theta = ")
        assert r.stop_theta == pytest.approx(seq[-1], abs=tol)
        assert r.theta_min == pytest.approx(min(seq), abs=tol)
        assert r.theta_max == pytest.approx(cfg.stroke.theta0, abs=1e-12)
    assert f"{math.degrees(seq[-1]):.1f} deg" in ref.reason and ref.reason == kern.reason
    # the lid sticks where |V'| <= T_f, and the previous rest was not such a place
    assert abs(float(model.dV(seq[-1], p))) <= Tf < abs(float(model.dV(seq[-2], p)))


def test_released_lid_sticks_exactly_when_the_driving_moment_is_small():
    cfg = cfg_of(0.0, spring_k=400.0, spring_rest_length=0.0792571, damper_c=0.0)
    model = LidModel.from_config(cfg)
    p0 = model.params()
    dV0 = float(model.dV(cfg.stroke.theta0, p0))
    for f, moves in ((1 - 1e-9, True), (1 + 1e-9, False)):
        c = cfg.set("friction.torque", f * dV0)
        m = LidModel.from_config(c)
        for r in (Simulator.from_config(c, model=m).run(), Reference(m).simulate()):
            assert (r.theta_min < c.stroke.theta0) is moves     # it fell, however slowly
            if not moves:
                assert r.stop_theta == c.stroke.theta0 and r.peak_tip_speed == 0.0
                assert r.reason == "held by friction at theta = 18.0 deg"


def test_sliding_stroke_matches_the_reference_and_is_slower():
    """A closing stroke with friction: kernel and reference agree; friction slows it."""
    design = dict(spring_k=1914.70922, spring_rest_length=0.0792570742, damper_c=2087.7541)
    free = Simulator.from_config(cfg_of(0.0, **design)).run()
    cfg = cfg_of(0.05, **design)
    model = LidModel.from_config(cfg)
    r, rr = Simulator.from_config(cfg, model=model).run(), Reference(model).simulate()
    assert r.closed and rr.closed and r.closing_time > free.closing_time + 0.01
    assert r.closing_time == pytest.approx(rr.closing_time, abs=1e-6)
    assert r.impact_theta_dot == pytest.approx(rr.impact_theta_dot, rel=1e-6)
    assert r.peak_tip_speed == pytest.approx(rr.peak_tip_speed, rel=1e-6)


def test_energy_falls_by_friction_times_the_path():
    Tf = 0.05
    cfg = cfg_of(Tf)
    r = Simulator.from_config(cfg).run(trajectory=True)
    tr = r.trajectory
    path = np.concatenate([[0.0], np.cumsum(np.abs(np.diff(tr["theta"])))])
    lost = tr["energy"][0] - tr["energy"]
    assert path[-1] > 0.25                              # three swings (0.30 rad)
    np.testing.assert_allclose(lost, Tf * path, atol=1e-8 * abs(tr["energy"][0]) + 1e-9)


@pytest.mark.parametrize("method,order", [("euler_cromer", 1), ("rk4", 4), ("gauss4", 4),
                                          ("radau5", 5)])
def test_rest_is_located_to_the_method_order(method, order):
    """The stuck angle's error against the energy answer falls at least as h^order (RK4's
    falls faster here, ~h^5.6 over these steps; the Gauss method's is a clean h^4)."""
    Tf = 0.05
    cfg = cfg_of(Tf).set("simulate.integrator", method)
    model = LidModel.from_config(cfg)
    exact = rests(model, model.params(), Tf, cfg.stroke.theta0)[-1]
    hs = np.array([4e-2, 2e-2, 1e-2, 5e-3]) if order > 1 else np.geomspace(4e-2, 2.5e-3, 5)
    err = [abs(Simulator.from_config(cfg.set("simulate.step", h), model=model).run(estimate_error=False)
               .stop_theta - exact) for h in hs]
    slope = np.polyfit(np.log(hs), np.log(err), 1)[0]
    assert order - 0.3 < slope < order + 2.0, (err, slope)
    if method == "gauss4":
        assert slope == pytest.approx(4.0, abs=0.1)


def test_three_formulations_agree_on_the_friction_moment():
    cfg = cfg_of(0.3, spring_k=600.0, spring_rest_length=0.07, damper_c=100.0,
                 rotary_damper_c=0.02)
    model = LidModel.from_config(cfg)
    p, ab = model.params(), read_parameters(cfg)
    assert ab.Tf == 0.3
    without = LidModel.from_config(cfg.set("friction.torque", 0.0))
    for th, thd in ((0.05, -1.0), (0.2, -4.0), (0.25, 2.0)):
        red = model.theta_ddot(th, thd, p)
        ne = float(np.asarray(model.newton_euler(th, thd, p)).ravel()[8])
        assert ne == pytest.approx(red, rel=1e-10)
        assert compute_theta_ddot(ab, th, thd) == pytest.approx(red, rel=1e-10)
        # the moment -T_f sign(theta') divided by the reduced inertia M(theta)
        M = float(model.coeffs(th)[0][0])
        assert red - without.theta_ddot(th, thd, without.params()) == pytest.approx(-0.3 * np.sign(thd) / M,
                                                                     rel=1e-9)


def test_opening_force_adds_the_friction_moment():
    base = default_config()
    a = Simulator.from_config(base).run()
    b = Simulator.from_config(base.set("friction.torque", 0.2)).run()
    assert b.opening_force > a.opening_force
    # max_theta (V' + T_f)/tau: at least T_f / tau at the angle of a's maximum
    ref = Reference(LidModel.from_config(base.set("friction.torque", 0.2))).simulate()
    assert b.opening_force == pytest.approx(ref.opening_force, rel=1e-6)


@pytest.mark.slow
def test_optimiser_sees_friction_and_the_reference_verifies_it():
    from softclose.optimiser import optimise
    cfg = default_config().set("friction.torque", 0.1)
    res = optimise(cfg)
    assert res.success and res.verified
    free = optimise(default_config())
    assert res.objective != pytest.approx(free.objective, rel=1e-3)
