"""The end damper (issue 23, item 2): a moment -c_e theta' on the lid's rotation while the lid
is below the engagement angle theta_e, never a smoothed step.

The fixed-step kernel carries the engagement as a state of the lane and locates every crossing
of theta_e as an event (a last step of solved length, like the closing and the friction rest).
Checked here: the kernel against the adaptive reference (each crossing an event of CVODES) on
designs with theta_e inside the stroke, above theta0 (engaged from the release), on theta0,
below the rim (never), with a dashpot, one-way, friction, a spring that holds the lid in a
well it keeps crossing theta_e in; the convergence order of every method on the closing time,
the impact and peak speeds and the engagement time (an unlocated switch, shown beside it,
converges at order 1); the energy balance with the dissipation only below theta_e; Newton-
Euler and the absolute-coordinate formulation against the reduced equation; the statics
(holding moment, opening effort) untouched; the scalar and SIMD paths bit for bit; the early
exit on a grid of end-damper rows; rows whose damper never acts identical to rows without
one; sweeps and samples over its keys equal to single strokes; the command line.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import softclose
from softclose.simulation.kernel import binding
from softclose.config import default_config
from softclose.numerics.integrators import get_method
from softclose.model.lid import LidModel
from softclose.problem import METRIC_KEYS, TARGETS, as_params
from softclose.simulation.reference import Reference
from softclose.simulation.simulator import Simulator
from softclose.validation.textbook.lid_absolute import compute_theta_ddot, read_parameters

from kernel_checks import energy_rise_ratio, scalar_strokes

COL = {name: i for i, name in enumerate(binding.OUT_FIELDS)}
SPRING = {"design.spring_k": 800.0, "design.spring_rest_length": 0.08}
#: a spring that holds the lid open in a well near 11.7 deg (test_friction's WELL)
WELL = {"design.spring_k": 3000.0, "design.spring_rest_length": 0.0792571}


def cfg_of(**sets):
    return default_config().update({(k if "." in k else f"design.{k}"): v
                                    for k, v in sets.items()})


def end(c, angle, **more):
    return {"design.end_damper_c": c, "design.end_damper_angle_deg": angle, **more}


#: name -> config keys; every one against the reference
DESIGNS = {
    "inside": {**SPRING, **end(0.8, 10.0)},
    "with a dashpot": {**SPRING, **end(0.4, 12.0), "design.damper_c": 30.0},
    "no spring": end(0.3, 5.0),
    "above theta0": {**SPRING, **end(0.3, 25.0)},
    "on theta0": {**SPRING, **end(0.3, 18.0)},
    "below the rim": {**SPRING, **end(0.8, -1.0)},
    "friction": {**SPRING, **end(0.8, 10.0), "friction.torque": 0.05},
    "one-way": {**SPRING, **end(0.8, 10.0), "design.damper_one_way": True},
    # not closing: the lid swings about its well, in and out of the damper
    "well": {**WELL, **end(0.05, 12.0)},
    "well, one-way": {**WELL, **end(0.05, 12.0), "design.damper_one_way": True},
    "well, friction": {**WELL, **end(0.05, 12.0), "friction.torque": 0.05},
    # released engaged, pushed open past theta_e (released there), held open above it
    "pushed open past it": {"design.spring_k": 3000.0, "design.spring_rest_length": 0.1,
                            **end(0.02, 19.0), "design.damper_one_way": True,
                            "stroke.t_max": 1.0},
}


@pytest.fixture(scope="module")
def cases():
    out = {}
    for name, sets in DESIGNS.items():
        cfg = default_config().update(sets)
        model = LidModel.from_config(cfg)
        out[name] = (cfg, Simulator.from_config(cfg, model=model).run(), Reference(model).simulate())
    return out


@pytest.mark.parametrize("name", list(DESIGNS))
def test_kernel_matches_the_reference(cases, name):
    cfg, r, rr = cases[name]
    assert r.status == rr.status
    assert rr.reason is None or r.reason == rr.reason   # (the reference names only a stick)
    for k in ("closing_time", "engage_time"):
        a, b = getattr(r, k), getattr(rr, k)
        assert (a is None) == (b is None), k
        if a is not None:
            assert abs(a - b) < TARGETS["closing_time"], (k, a, b)
    for k in ("impact_theta_dot", "engage_theta_dot"):
        a, b = getattr(r, k), getattr(rr, k)
        assert (a is None) == (b is None), k
        if a is not None:
            assert abs(a - b) < TARGETS["impact_theta_dot"], (k, a, b)
    assert r.peak_tip_speed == pytest.approx(rr.peak_tip_speed, rel=1e-6)
    assert r.theta_min == pytest.approx(rr.theta_min, abs=1e-9)
    assert r.theta_max == pytest.approx(rr.theta_max, abs=1e-9)
    for k in ("min_spring_length", "max_spring_length"):
        assert getattr(r, k) == pytest.approx(getattr(rr, k), abs=1e-9)
    theta_e = math.radians(cfg.design.end_damper_angle_deg)
    if theta_e >= cfg.stroke.theta0:                  # engaged from the release, at rest
        assert r.engage_time == 0.0 and r.engage_theta_dot == 0.0
    elif theta_e <= cfg.stroke.theta_closed:          # never acts
        assert r.engage_time is None
    else:                                             # met on the way down
        assert r.engage_time > 0 and r.engage_theta_dot < 0
    # the accuracy estimate covers the engagement where there is one
    if r.engage_time is not None:
        assert r.accuracy["engage_time"] < TARGETS["closing_time"]
        assert abs(r.engage_time - rr.engage_time) <= 10 * r.accuracy["engage_time"] + 1e-10


def test_the_damper_changes_the_stroke(cases):
    """The designs differ from the same lid without the damper (the tests can fail), and the
    released-engaged lid is the one whose damper acts from theta0 on."""
    _, r, _ = cases["inside"]
    free = Simulator.from_config(cfg_of(**SPRING)).run()
    assert r.closing_time > free.closing_time + 0.03
    assert abs(r.impact_theta_dot) < 0.5 * abs(free.impact_theta_dot)
    # below theta_e the peak is the engagement's: the lid falls freely to it, then slows
    assert r.peak_tip_speed == pytest.approx(
        abs(r.engage_theta_dot) * float(LidModel.from_config(cfg_of(**SPRING)).coeffs(
            math.radians(10.0))[0][7]), rel=1e-9)
    _, above, _ = cases["above theta0"]
    _, on, _ = cases["on theta0"]
    assert above.closing_time == on.closing_time     # engaged at once, either way
    _, below, _ = cases["below the rim"]
    assert below.closing_time == free.closing_time


def test_never_acting_damper_leaves_the_rows_unchanged(sim):
    """A row whose end damper never acts -- its angle at or below the rim, or above the rim
    but never reached -- gives the numbers of the row without it, bit for bit (the energy
    rule too: it applies from the first engagement), its engagement columns NaN."""
    st = sim.stroke
    rng = np.random.default_rng(4)
    n = 300
    P = np.tile(sim.model.params(), (n, 1))
    P[:, 0], P[:, 1] = rng.uniform(0, 9500, n), rng.uniform(0.04, 0.1, n)
    P[:, 2] = rng.uniform(0, 4000, n) * (rng.random(n) < 0.6)
    D = np.column_stack([binding.kernel_rows(as_params(P)), sim.energy_tol(P)])
    run = lambda X: binding.run_strokes(sim.table, sim.method, sim.step, st.t_max,  # noqa: E731
                                       st.theta0, st.theta_closed, X)
    plain = run(D)
    jc, ja = binding.DESIGN_COLUMNS.index("end_damper_c"), \
        binding.DESIGN_COLUMNS.index("end_damper_angle")
    for angle in (st.theta_closed, st.theta_closed - 0.05):
        E = D.copy()
        E[:, jc], E[:, ja] = 1.5, angle
        out = run(E)
        assert np.array_equal(out[:, :COL["engage_time"]], plain[:, :COL["engage_time"]],
                              equal_nan=True)
        assert np.all(np.isnan(out[:, COL["engage_time"]:]))
    # above the rim, below the lowest angle an open stroke reaches
    is_open = plain[:, COL["status"]] == 1
    assert is_open.sum() > 20
    E = D[is_open].copy()
    E[:, jc], E[:, ja] = 1.5, 0.5 * (plain[is_open, COL["theta_min"]] + st.theta_closed)
    out = run(E)
    assert np.array_equal(out[:, :COL["engage_time"]], plain[is_open, :COL["engage_time"]],
                          equal_nan=True)
    assert np.all(np.isnan(out[:, COL["engage_time"]:]))
    # rows without an end damper beside rows with one (lanes of a vector shared): unchanged
    mixed = D.copy()
    mixed[1::2, jc], mixed[1::2, ja] = 0.8, math.radians(9.0)
    out = run(mixed)
    assert np.array_equal(out[::2], plain[::2], equal_nan=True)
    assert not np.array_equal(out[1::2, :COL["engage_time"]], plain[1::2, :COL["engage_time"]],
                              equal_nan=True)
    assert np.all(np.isnan(plain[:, COL["engage_time"]:]))


# -- convergence order ----------------------------------------------------------------------
#: free fall to 10 deg, then the end damper alone: closing 0.218 s, engaged at 0.113 s
ORDER_SETS = {**SPRING, **end(0.8, 10.0)}
ORDER_STEPS = {"rk4": [0.016, 0.008, 0.004, 0.002],
               "euler_cromer": [0.008, 0.004, 0.002, 0.001],
               "gauss4": [0.016, 0.008, 0.004, 0.002],
               "radau5": [0.04, 0.02, 0.01, 0.005]}
ORDER_KEYS = ("closing_time", "impact_theta_dot", "peak_tip_speed", "engage_time")
#: below this an error is the tight reference's own: not fitted (CVODES at 1e-14 against
#: 1e-13: 6e-14 s on the engagement, 3e-13 s on the closing, 4e-12 and 8e-12 on the speeds)
FLOOR = {"closing_time": 2e-12, "engage_time": 2e-12, "impact_theta_dot": 4e-11,
         "peak_tip_speed": 4e-11}


@pytest.fixture(scope="module")
def order_case():
    cfg = default_config().update(ORDER_SETS)
    model = LidModel.from_config(cfg)
    return cfg, model, Reference(model, tol=1e-14).simulate()


def _slope(steps, errs, floor=FLOOR["closing_time"]):
    keep = np.asarray(errs) > floor
    assert keep.sum() >= 3, errs
    return float(np.polyfit(np.log(np.asarray(steps)[keep]), np.log(np.asarray(errs)[keep]),
                            1)[0])


@pytest.mark.parametrize("name", list(ORDER_STEPS))
def test_every_method_keeps_its_order(order_case, name):
    """The error of each metric against CVODES at 1e-14 falls as h^order: the crossing of
    theta_e is located to the method's order (a smoothed or unlocated switch would make it
    order 1, as the control below shows). rk4, Euler-Cromer and the Gauss method within 0.3
    of their order on every metric (fitted 4.07 4.07 4.10 3.99, 1.02 0.96 0.99 0.99, 3.98
    3.98 4.02 4.01); Radau IIA within (order - 1.3, order + 2.5): on these steps some of its
    errors are not yet asymptotic (its peak tip speed falls as h^3.6, then h^4.0, then h^5.4:
    3.80 fitted; its engagement time as ~h^6), which a tighter bound would mistake for a
    loss."""
    cfg, model, truth = order_case
    p = model.params()
    order = get_method(name).order
    errs = {k: [] for k in ORDER_KEYS}
    for h in ORDER_STEPS[name]:
        b = Simulator.from_config(cfg, model, name, h).run_batch(p[None, :])
        assert b["status"][0] == 0
        for k in ORDER_KEYS:
            errs[k].append(abs(float(b[k][0]) - getattr(truth, k)))
    for k in ORDER_KEYS:
        s = _slope(ORDER_STEPS[name], errs[k], FLOOR[k])
        if name != "radau5":
            assert abs(s - order) <= 0.3, (k, errs[k], s)
        else:                       # (pre-asymptotic here: see the docstring)
            assert order - 1.3 < s < order + 2.5, (k, errs[k], s)


def _rk4_switched_at_nodes(model, p, h, theta_e, theta0, theta_closed):
    """The closing time by RK4 with the damper switched at the nodes only (the state of the
    node's angle for its whole step: the crossing not located), the closing located."""
    def f(y, eg):
        return np.asarray(model.ode_moving(y, p, -1.0, [eg])).ravel()

    def step(x, tau, eg):
        k1 = f(x, eg)
        k2 = f(x + 0.5 * tau * k1, eg)
        k3 = f(x + 0.5 * tau * k2, eg)
        k4 = f(x + tau * k3, eg)
        return x + tau / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    x, t = np.array([theta0, 0.0]), 0.0
    while t < 1.0:
        eg = 1.0 if x[0] < theta_e else 0.0
        x1 = step(x, h, eg)
        if x1[0] <= theta_closed:
            a, b = 0.0, h
            for _ in range(60):
                m = 0.5 * (a + b)
                a, b = (m, b) if step(x, m, eg)[0] > theta_closed else (a, m)
            return t + 0.5 * (a + b)
        x, t = x1, t + h
    raise AssertionError("did not close")


def test_an_unlocated_switch_converges_at_order_one(order_case):
    """The control: the same RK4 with the switch taken at the nodes is first order, so the
    order test above can fail."""
    cfg, model, truth = order_case
    p, st = model.params(), cfg.stroke
    theta_e = math.radians(cfg.design.end_damper_angle_deg)
    steps = [0.004, 0.002, 0.001, 0.0005]
    errs = [abs(_rk4_switched_at_nodes(model, p, h, theta_e, st.theta0, st.theta_closed)
                - truth.closing_time) for h in steps]
    assert 0.5 < _slope(steps, errs) < 1.6, errs
    # and the kernel at the coarsest of those steps is far better than the control at its finest
    k = Simulator.from_config(cfg, model, "rk4", steps[0]).run_batch(p[None, :])["closing_time"][0]
    assert abs(k - truth.closing_time) < 1e-3 * errs[-1]


# -- the physics: energy, the three formulations, the statics --------------------------------
@pytest.mark.parametrize("sets", [{**SPRING, **end(0.4, 12.0), "design.damper_c": 30.0},
                                  {**WELL, **end(0.05, 12.0), "design.damper_one_way": True}],
                         ids=["closing, with a dashpot", "in the well, one-way"])
def test_energy_balance(sets):
    """Kinetic + potential + dissipated = the initial energy along the kernel's trajectory,
    the end damper's power -c_e theta'^2 counted only below theta_e (and, one-way, only
    while the lid closes): trapezoids on the trajectory, whose nodes include each crossing.
    Counting it over the whole stroke breaks the balance (the test can fail)."""
    cfg = default_config().update({**sets, "stroke.t_max": 1.0})
    sim = Simulator.from_config(cfg, step=2.5e-4)
    tr = sim.run(trajectory=True).trajectory
    t, th, thd = tr["t"], tr["theta"], tr["theta_dot"]
    E = tr["energy"]
    c = np.asarray(sim.model.coeffs.map(len(th))(th)[0])
    dd = c[6]                                          # (dl_d/dtheta)^2
    theta_e = math.radians(cfg.design.end_damper_angle_deg)
    ow = cfg.design.damper_one_way
    mid = 0.5 * (th[1:] + th[:-1])

    def lost(engaged_everywhere=False):
        on = np.ones(len(mid)) if engaged_everywhere else (mid < theta_e) * 1.0
        Bl = cfg.design.damper_c * dd[:-1] + cfg.design.end_damper_c * on
        Br = cfg.design.damper_c * dd[1:] + cfg.design.end_damper_c * on
        if ow:
            Bl = Bl * (thd[:-1] <= 0)
            Br = Br * (thd[1:] <= 0)
        power = 0.5 * (Bl * thd[:-1] ** 2 + Br * thd[1:] ** 2)
        return np.r_[0.0, np.cumsum(power * np.diff(t))]
    scale = E[0] - E.min()                             # the energy the stroke releases
    assert scale > 3e-3
    assert len(np.flatnonzero(np.diff(mid < theta_e))) >= (1 if not ow else 3)   # crossings
    np.testing.assert_allclose(E + lost(), E[0], rtol=0, atol=2e-6 * scale)
    assert np.max(np.abs(E + lost(True) - E[0])) > 0.05 * scale


def test_three_formulations_agree():
    """theta'' of the reduced equation (the exact, discontinuous one: engaged by the angle),
    of Newton-Euler and of the three bodies in absolute coordinates agree above and below
    theta_e; below it they differ from the lid without the damper by -c_e theta' / M
    (one-way: only while closing)."""
    for ow in (False, True):
        cfg = cfg_of(**SPRING, **end(0.6, 8.0), damper_c=50.0, damper_one_way=ow,
                     **{"friction.torque": 0.02})
        model, ab = LidModel.from_config(cfg), read_parameters(cfg)
        assert ab.c_end == 0.6 and ab.theta_end == pytest.approx(math.radians(8.0))
        without = LidModel.from_config(cfg.set("design.end_damper_c", 0.0))
        p, p0 = model.params(), without.params()
        for th, thd in ((0.05, -1.5), (0.12, -3.0), (0.139, -0.7), (0.04, 2.0), (0.2, 1.0)):
            red = model.theta_ddot(th, thd, p)
            ne = float(np.asarray(model.newton_euler(th, thd, p)).ravel()[8])
            assert ne == pytest.approx(red, rel=1e-10, abs=1e-10)
            assert compute_theta_ddot(ab, th, thd) == pytest.approx(red, rel=1e-10, abs=1e-10)
            M = float(model.coeffs(th)[0][0])
            acts = th < math.radians(8.0) and not (ow and thd > 0)
            assert red - without.theta_ddot(th, thd, p0) == pytest.approx(
                -0.6 * thd / M if acts else 0.0, rel=1e-9, abs=1e-12)
            # softclose state reports the same (Newton-Euler, with the reactions)
            assert model.state(th, thd, p)["theta_ddot"] == pytest.approx(red, rel=1e-10)


def test_statics_are_those_of_the_lid_without_it():
    """The holding moment and the opening effort (a slow lift) do not see a damper."""
    a = Simulator.from_config(cfg_of(**SPRING)).run()
    b = Simulator.from_config(cfg_of(**SPRING, **end(2.0, 10.0))).run()
    c = Reference(LidModel.from_config(cfg_of(**SPRING, **end(2.0, 10.0)))).simulate()
    assert b.holding_moment == a.holding_moment == c.holding_moment
    assert b.opening_force == a.opening_force
    assert c.opening_force == pytest.approx(a.opening_force, rel=1e-9)


def test_kernel_step_takes_the_state_of_its_start(sim):
    """One kernel step engaged as its start angle says (for the tests' single steps)."""
    cfg = cfg_of(**SPRING, **end(0.8, 10.0))
    s = Simulator.from_config(cfg)
    p = s.model.params()
    p0 = s.model.params()
    p0[list(binding.DESIGN_COLUMNS).index("end_damper_c")] = 0.0
    for th, acts in ((math.radians(9.0), True), (math.radians(11.0), False)):
        x0 = np.array([th, -2.0])
        a = binding.kernel_step(s.table, s.method, p, 1e-3, x0)
        b = binding.kernel_step(s.table, s.method, p0, 1e-3, x0)
        assert bool(abs(a[1] - b[1]) > 1e-3) == acts


# -- the kernel's paths and its early exit ---------------------------------------------------
def grid_rows(sim):
    """End-damper rows: k x l0 x c_e x theta_e, without and with a dashpot (324)."""
    k, l0 = np.linspace(500, 9500, 6), np.array([0.05, 0.07, 0.09])
    ce, ang = np.array([0.02, 0.3, 2.0]), np.array([3.0, 10.0, 16.0])
    K, L, C, A = (g.ravel() for g in np.meshgrid(k, l0, ce, ang, indexing="ij"))
    P = np.tile(sim.model.params(), (2 * len(K), 1))
    cols = list(binding.DESIGN_COLUMNS)
    for half, dashpot in ((slice(0, len(K)), 0.0), (slice(len(K), None), 100.0)):
        P[half, 0], P[half, 1], P[half, 2] = K, L, dashpot
        P[half, cols.index("end_damper_c")] = C
        P[half, cols.index("end_damper_angle")] = A
    return as_params(P)


def strokes(sim, D, early=True):
    st = sim.stroke
    return binding.run_strokes(sim.table, sim.method, sim.step, st.t_max, st.theta0,
                              st.theta_closed, D, early_exit=early)


#: what the early exit must not change (test_early_exit's FINAL, and the engagement)
FINAL = ("status", "closing_time", "impact_theta_dot", "impact_tip_speed", "peak_tip_speed",
         "min_spring_length", "max_spring_length", "theta_min", "theta_max", "theta_dot_max",
         "energy_rise", "stop_reason", "engage_time", "engage_theta_dot")


@pytest.mark.parametrize("integrator,step", [("rk4", 2e-3), ("euler_cromer", 5e-4)])
def test_early_exit_on_end_damper_rows(cfg, model, integrator, step):
    """On a grid of end-damper rows every final column is the same with the early exit as
    without it, bit for bit; rows whose only damper is the end damper stop early once it
    has engaged; the energy margin the rule rests on holds on the rest of every exited
    stroke (integrated to t_max)."""
    sim = Simulator.from_config(cfg, model, integrator=integrator, step=step)
    st = cfg.stroke
    P = grid_rows(sim)
    D = np.column_stack([binding.kernel_rows(P), sim.energy_tol(P)])
    on, off = strokes(sim, D), strokes(sim, D, False)
    for key in FINAL:
        assert np.array_equal(on[:, COL[key]], off[:, COL[key]], equal_nan=True), key
    ex = (on[:, COL["status"]] == 1) & (on[:, COL["stop_time"]] < st.t_max * (1 - 1e-12))
    only_end = P[:, 2] == 0
    assert (ex & only_end).sum() >= 5 and (ex & ~only_end).sum() > 30
    assert np.all(np.isfinite(on[ex & only_end, COL["engage_time"]]))   # engaged first
    # an open lid that never reaches theta_e has no damper: it runs to t_max
    never = (on[:, COL["status"]] == 1) & only_end & np.isnan(on[:, COL["engage_time"]])
    assert never.sum() > 20
    assert np.all(on[never, COL["stop_time"]] == pytest.approx(st.t_max, rel=1e-12))
    rows = np.flatnonzero(ex)[:: 3 if integrator == "rk4" else 6]
    worst = 0.0
    for i in rows:
        _, tr = binding.run_stroke_trajectory(sim.table, sim.method, step, st.t_max, st.theta0,
                                             st.theta_closed, D[i], early_exit=False)
        c = sim.table.evaluate(tr[:, 1])
        E = 0.5 * c[:, 0] * tr[:, 2] ** 2 + c[:, 2] + 0.5 * P[i, 0] * (c[:, 4] - P[i, 1]) ** 2
        n = int(on[i, COL["steps"]])                      # the exit node
        assert tr[n, 0] == pytest.approx(on[i, COL["stop_time"]], abs=1e-12)
        c0 = sim.table.evaluate([st.theta0])[0]
        scale = abs(c0[2]) + 0.5 * P[i, 0] * (c0[4] - P[i, 1]) ** 2 + abs(E[0])
        worst = max(worst, energy_rise_ratio(E, tr[:, 0], n, st.t_max, step, scale, i))
    assert worst < 0.9


def test_scalar_and_simd_paths_agree_bit_for_bit(sim):
    """SC_SCALAR=1 (lane by lane) and the AVX2 lanes: the same numbers for end-damper rows
    (mixed with rows without one, one-way and friction rows among them)."""
    P = grid_rows(sim)
    rng = np.random.default_rng(2)
    cols = list(binding.DESIGN_COLUMNS)
    P[rng.random(len(P)) < 0.3, cols.index("end_damper_c")] = 0.0
    P[rng.random(len(P)) < 0.3, cols.index("damper_one_way")] = 1.0
    P[rng.random(len(P)) < 0.2, cols.index("friction_torque")] = 0.03
    D = np.column_stack([binding.kernel_rows(P), sim.energy_tol(P)])
    vec = strokes(sim, D)
    assert np.isfinite(vec[:, COL["engage_time"]]).sum() > 100
    assert np.array_equal(scalar_strokes(D), vec, equal_nan=True)
    assert np.array_equal(strokes(sim, D[:5]), vec[:5], equal_nan=True)   # lanes idle


def test_stiff_end_damper_is_unstable_not_stuck():
    """rk4 beyond its stability at a stiff end damper: the step from theta_e returns past it
    at once; the lane must not switch back and forth without time passing. It is reported
    unstable with the step that is stable, in well under a second."""
    import time
    cfg = cfg_of(**end(100.0, 5.0))
    t = time.perf_counter()
    r = Simulator.from_config(cfg).run()
    assert time.perf_counter() - t < 5.0
    assert r.status.text == "unstable" and "use simulate.step <=" in r.message
    assert "radau5" in r.message
    ok = Simulator.from_config(cfg.set("simulate.integrator", "radau5")).run()
    assert ok.ok and ok.engage_time == pytest.approx(
        Reference(LidModel.from_config(cfg)).simulate().engage_time, abs=1e-7)


# -- sweeps, the command line, the figure ----------------------------------------------------
def _agree(row, r):
    for key in METRIC_KEYS[1:]:
        v, w = getattr(r, key), row[key]
        if v is None:
            assert w is None or (isinstance(w, float) and math.isnan(w)), key
        else:
            assert abs(v - w) <= 1e-12 * max(1.0, abs(v)), (key, v, w)


def test_sweep_and_sample_rows_equal_single_strokes():
    """Both keys are columns of the kernel's rows: a grid and a sample over them give each
    design's numbers as softclose.simulation.simulator of that design does."""
    cfg = cfg_of(**SPRING)
    res = softclose.sweep(cfg, {"design.end_damper_c": [0.0, 0.3, 1.5],
                                "design.end_damper_angle_deg": [-1.0, 6.0, 12.0, 25.0]})
    f = res.to_frame()
    assert len(f) == 12
    closing = set()
    for _, row in f.iterrows():
        one = cfg.update({"design.end_damper_c": float(row["design.end_damper_c"]),
                          "design.end_damper_angle_deg":
                              float(row["design.end_damper_angle_deg"])})
        r = softclose.simulate(one)
        _agree({k: (None if isinstance(row[k], float) and math.isnan(row[k]) else row[k])
                for k in METRIC_KEYS}, r)
        closing.add(round(r.closing_time, 9))
    assert len(closing) == 7      # the keys change the strokes (c_e = 0 or theta_e below the
    #                               rim: one stroke; 2 x 3 others)
    s = softclose.sample(cfg, {"design.end_damper_c": (0.05, 2.0),
                               "design.end_damper_angle_deg": (2.0, 16.0)}, 8, seed=3)
    for _, row in s.to_frame().iterrows():
        one = cfg.update({k: float(row[k]) for k in ("design.end_damper_c",
                                                      "design.end_damper_angle_deg")})
        _agree({k: row[k] for k in METRIC_KEYS}, softclose.simulate(one))


def _cli(*argv):
    from softclose.cli import main
    import contextlib
    import io
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = main(list(argv))
    return rc, out.getvalue(), err.getvalue()


def test_simulate_command_reports_the_engagement(tmp_path):
    sets = ["--set", "design.spring_k=800", "--set", "design.spring_rest_length=0.08",
            "--set", "design.end_damper_c=0.8", "--set", "design.end_damper_angle_deg=10"]
    rc, out, _ = _cli("simulate", *sets, "--json")
    m = json.loads(out)
    assert rc == 0 and m["engage_time"] == pytest.approx(0.1127588, abs=1e-7)
    assert m["engage_theta_dot"] == pytest.approx(-2.424226, abs=1e-6)
    assert m["accuracy"]["engage_time"] < 1e-9 and "end_damper" not in m
    f = softclose.simulate(cfg_of(**SPRING, **end(0.8, 10.0))).to_frame()
    assert f["engage_time"][0] == m["engage_time"]
    assert "engage_time" not in softclose.simulate(cfg_of(**SPRING)).to_frame()
    rc, text, _ = _cli("simulate", *sets, "--out", str(tmp_path / "o"))
    assert rc == 0
    assert "engage_time         0.1127588 s  (± " in text
    assert "engage_theta_dot    -2.424226 rad/s  (± " in text
    # the trajectory has the event's node: theta_e at the engagement time
    import pandas as pd
    tr = pd.read_csv(tmp_path / "o" / "stroke_trajectory.csv", comment="#")
    i = int(np.argmin(np.abs(tr.iloc[:, 0] - m["engage_time"])))
    assert tr.iloc[i, 0] == pytest.approx(m["engage_time"], abs=1e-12)
    assert tr.iloc[i, 1] == pytest.approx(math.radians(10.0), abs=1e-12)
    # no end damper: nothing said
    rc, text, _ = _cli("simulate", "--set", "design.end_damper_angle_deg=10")
    assert rc == 0 and "engage" not in text and "end damper" not in text


@pytest.mark.parametrize("angle,words", [
    ("25", "end damper: acts from the release: end_damper_angle_deg = 25 is not below "
           "stroke.theta0_deg = 18"),
    ("18", "end damper: acts from the release: end_damper_angle_deg = 18 is not below "
           "stroke.theta0_deg = 18"),
    ("0", "end damper: never acts: end_damper_angle_deg = 0 is not above the rim "
          "(stroke.theta_closed_deg = 0)"),
    ("-40", "end damper: never acts: end_damper_angle_deg = -40 is not above the rim"),
])
def test_an_angle_outside_the_stroke_is_said_not_refused(angle, words):
    rc, text, err = _cli("simulate", "--set", "design.end_damper_c=0.3",
                         "--set", f"design.end_damper_angle_deg={angle}")
    assert rc == 0 and err == "" and words in text
    rc, out, _ = _cli("simulate", "--set", "design.end_damper_c=0.3",
                      "--set", f"design.end_damper_angle_deg={angle}", "--json")
    assert words.removeprefix("end damper: ") in json.loads(out)["end_damper"]


def test_an_open_lid_above_the_angle_is_said_never_engaged():
    rc, text, _ = _cli("simulate", "--set", "design.spring_k=3000",
                       "--set", "design.spring_rest_length=0.0792571",
                       "--set", "design.damper_c=200", "--set", "design.end_damper_c=0.3",
                       "--set", "design.end_damper_angle_deg=4")
    assert rc == 0 and "end damper: never engaged: the lid stays above " \
                       "end_damper_angle_deg = 4 (lowest angle " in text


@pytest.mark.parametrize("key,value,msg", [
    ("design.end_damper_c", "-0.5", "design.end_damper_c: must be non-negative, got -0.5"),
    ("design.end_damper_c", "1e6", "design.end_damper_c: 1e+06 N m s/rad is outside the "
                                   "admissible range 0..100000 N m s/rad"),
    ("design.end_damper_c", "nan", "design.end_damper_c: expected a finite number, got nan"),
    ("design.end_damper_angle_deg", "400", "design.end_damper_angle_deg: 400 deg is outside "
                                           "the admissible range -360..360 deg"),
    ("design.end_damper_angle_deg", '"low"', "design.end_damper_angle_deg: "),
])
def test_bad_values_are_refused_in_one_line(key, value, msg):
    rc, out, err = _cli("simulate", "--set", f"{key}={value}")
    lines = err.strip().splitlines()
    assert rc == 2 and len(lines) == 1 and lines[0].startswith(f"softclose: error: {msg}")


def test_time_history_figure_marks_the_engagement():
    from softclose.present.figures import plt
    from softclose.present.figures.stroke import plot_time_histories
    from test_figures_read import _clear
    for sets, text in (({**SPRING, **end(0.8, 10.0)}, "end damper on\n0.1128 s, -2.424 rad/s"),
                       ({**SPRING, **end(0.3, 25.0)}, "end damper engaged\nfrom the release"),
                       ({"design.spring_k": 1914.709, "design.spring_rest_length": 0.07925707,
                         "design.damper_c": 800.0, **end(0.4, 6.0)},
                        "end damper on\n0.2230 s, -1.154 rad/s")):
        res = Simulator.from_config(default_config().update(sets)).run(trajectory=True)
        fig = plot_time_histories(res)
        assert [a.get_text() for a in fig.labels][-1] == text and len(fig.labels) == 4
        _clear(fig, fig.labels)
        plt.close(fig)
