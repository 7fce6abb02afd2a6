"""The stroke kernel's early exit: a design that cannot close stops as soon as nothing can
change any more, with exactly the metrics of the stroke integrated to t_max.

Checks: on a grid of designs, every metric column of the kernel with early exit equals the
run without it bit for bit (for every method); the energy margin the rule rests on holds on
the rest of every exited stroke; closed/not closed agrees with the adaptive reference,
also just beside the closing boundary; the reasons (a held-open lid at its equilibrium,
V'(theta) = 0 with V'' > 0; a barrier top, V'(theta) = 0 with V'' < 0) are checked with the
model's own dV; the scalar and the SIMD paths of the kernel agree bit for bit.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from softclose.simulation.kernel import binding
from softclose.simulation.reference import Reference
from softclose.problem import as_params
from softclose.simulation.simulator import Simulator

from kernel_checks import energy_rise_ratio, scalar_strokes

#: the columns that must not depend on the early exit: the SPEC 4 metrics, the visited
#: range, the largest theta' (the rebound flag), the energy rise, why it stays open
FINAL = ("status", "closing_time", "impact_theta_dot", "impact_tip_speed", "peak_tip_speed",
         "min_spring_length", "max_spring_length", "theta_min", "theta_max", "theta_dot_max",
         "energy_rise", "stop_reason")
COL = {name: i for i, name in enumerate(binding.OUT_FIELDS)}


def designs_of(sim, P):
    return np.column_stack([binding.kernel_rows(P), sim.energy_tol(P)])


def strokes(sim, D, early=True):
    st = sim.stroke
    return binding.run_strokes(sim.table, sim.method, sim.step, st.t_max, st.theta0,
                              st.theta_closed, D, early_exit=early)


def grid_designs():
    """spring_k 500..9500 x spring_rest_length 0.05..0.09 x damper_c 100..4000 (288)."""
    k, l0, c = np.linspace(500, 9500, 8), np.linspace(0.05, 0.09, 6), np.linspace(100, 4000, 6)
    K, L, C = np.meshgrid(k, l0, c, indexing="ij")
    return as_params(np.column_stack([K.ravel(), L.ravel(), C.ravel(), np.zeros(K.size)]))


def exited(out, t_max):
    return (out[:, COL["status"]] == 1) & (out[:, COL["stop_time"]] < t_max * (1 - 1e-12))


@pytest.fixture(scope="module")
def grid(sim):
    P = grid_designs()
    D = designs_of(sim, P)
    return P, D, strokes(sim, D, True), strokes(sim, D, False)


def test_grid_metrics_identical_with_and_without_early_exit(sim, grid):
    P, D, on, off = grid
    t_max = sim.stroke.t_max
    for key in FINAL:
        assert np.array_equal(on[:, COL[key]], off[:, COL[key]], equal_nan=True), key
    # the physics names the same equilibrium at the exit as at t_max (to rounding)
    ex = exited(on, t_max)
    assert np.allclose(on[:, COL["stop_theta"]], off[:, COL["stop_theta"]], rtol=0, atol=1e-12,
                       equal_nan=True)
    # without early exit every open stroke runs to t_max; with it, most stop well before
    is_open = off[:, COL["status"]] == 1
    assert np.all(off[is_open, COL["stop_time"]] == pytest.approx(t_max, rel=1e-12))
    assert 40 < is_open.sum() < len(P) - 40           # the grid has both kinds
    assert ex.sum() >= 0.6 * is_open.sum()
    assert np.median(on[ex, COL["steps"]]) < 0.2 * np.median(off[ex, COL["steps"]])
    # closed strokes are not touched at all
    closed = off[:, COL["status"]] == 0
    assert np.array_equal(on[closed], off[closed], equal_nan=True)
    # every exited stroke says why it stays open
    assert np.all(np.isin(on[ex, COL["stop_reason"]], (1, 2)))


@pytest.mark.parametrize("integrator,step", [("euler_cromer", 5e-4), ("gauss4", 2e-3),
                                             ("radau5", 4e-3)])
def test_other_methods_identical_with_and_without_early_exit(cfg, model, integrator, step):
    sim = Simulator.from_config(cfg, model, integrator=integrator, step=step)
    P = grid_designs()[::3]
    D = designs_of(sim, P)
    on, off = strokes(sim, D, True), strokes(sim, D, False)
    for key in FINAL:
        assert np.array_equal(on[:, COL[key]], off[:, COL[key]], equal_nan=True), key
    assert exited(on, cfg.stroke.t_max).sum() > 20


def energies(sim, p, traj):
    """Mechanical energy at the nodes of a trajectory, from the table (as the kernel)."""
    c = sim.table.evaluate(traj[:, 1])
    dl0 = c[:, 4] - p[1]
    return 0.5 * c[:, 0] * traj[:, 2] * traj[:, 2] + c[:, 2] + 0.5 * p[0] * dl0 * dl0


@pytest.mark.parametrize("integrator,step", [("rk4", 2e-3), ("euler_cromer", 5e-4)])
def test_energy_margin_holds_after_every_exit(cfg, model, integrator, step):
    """The rule assumes the rest of the stroke never gains more than the margin
    2 (steps left) g + 1e-12 E_scale over the energy at the exit (g: the largest gain of one
    step before it). Checked on the full stroke of every exited row."""
    sim = Simulator.from_config(cfg, model, integrator=integrator, step=step)
    st = cfg.stroke
    P = grid_designs()[::2]
    D = designs_of(sim, P)
    on = strokes(sim, D, True)
    rows = np.nonzero(exited(on, st.t_max))[0]
    assert len(rows) > 30
    worst = 0.0
    for i in rows:
        _, tr = binding.run_stroke_trajectory(sim.table, sim.method, step, st.t_max, st.theta0,
                                             st.theta_closed, D[i], early_exit=False)
        E = energies(sim, P[i], tr)
        n = int(on[i, COL["steps"]])                  # the exit node
        assert tr[n, 0] == pytest.approx(on[i, COL["stop_time"]], abs=1e-12)
        c0 = sim.table.evaluate([st.theta0])[0]
        scale = abs(c0[2]) + 0.5 * P[i, 0] * (c0[4] - P[i, 1]) ** 2 + abs(E[0])
        worst = max(worst, energy_rise_ratio(E, tr[:, 0], n, st.t_max, step, scale, i))
    assert worst < 0.9   # (0 for rk4: its energy never rises again; ~0.3 for euler_cromer)


def boundary(sim, p, j, lo, hi):
    """The value of column j of p where the kernel's closed flag switches (bisection)."""
    def closed(x):
        q = p.copy()
        q[j] = x
        return bool(sim.run_batch(q[None, :])["closed"][0])
    c_lo = closed(lo)
    assert closed(hi) != c_lo
    for _ in range(50):
        mid = 0.5 * (lo + hi)
        if closed(mid) == c_lo:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


@pytest.mark.slow
def test_closed_agrees_with_reference_incl_closing_boundary(cfg):
    """30 rows: random grid rows and pairs just beside the closing boundary (lids whose
    first swing barely misses the rim and stop early, and slow creepers at t_max); the
    kernel (with early exit) and CVODES agree on closed, and on the metrics of open rows."""
    cfg1 = cfg.replace(stroke={"t_max": 1.0})       # keeps the reference affordable
    sim = Simulator.from_config(cfg1)
    ref = Reference(sim.model)
    rows = []
    for l0, c, rel in ((0.075, 20.0, 1e-4), (0.075, 300.0, 1e-4), (0.09, 100.0, 1e-3),
                       (0.06, 800.0, 1e-3)):
        kb = boundary(sim, as_params([0.0, l0, c, 0.0]), 0, 500.0, 9500.0)
        rows += [[kb * (1 - rel), l0, c, 0.0], [kb * (1 + rel), l0, c, 0.0]]
    kb = boundary(sim, as_params([0.0, 0.07, 2000.0, 0.0]), 0, 500.0, 9500.0)   # creeper
    rows += [[kb * (1 - 2e-3), 0.07, 2000.0, 0.0], [kb * (1 + 2e-3), 0.07, 2000.0, 0.0]]
    rng = np.random.default_rng(14)
    G = grid_designs()
    rows += list(G[rng.choice(len(G), 20, replace=False), :4])
    R = as_params(np.array(rows))
    b = sim.run_batch(R)
    assert 8 < int(b["closed"].sum()) < 22
    ex = (b["status"] == 1) & (b["stop_time"] < 1.0 - 1e-9)
    assert ex[:8].sum() == 4                           # the open side of each swing pair exits
    for i, p in enumerate(R):
        r = ref.simulate(p)
        assert bool(b["closed"][i]) == r.closed, (i, p)
        if not r.closed and b["status"][i] == 1:
            assert b["peak_tip_speed"][i] == pytest.approx(r.peak_tip_speed, rel=1e-6)
            assert b["min_spring_length"][i] == pytest.approx(r.min_spring_length, abs=1e-9)
            assert b["max_spring_length"][i] == pytest.approx(r.max_spring_length, abs=1e-9)


def test_undamped_designs_run_to_t_max(sim):
    """Without dampers the energy rule has nothing to go by: the stroke runs to t_max (its
    extremes and peak over [0, t_max] depend on the method's drift)."""
    P = grid_designs()[::4].copy()
    P[:, 2] = 0.0
    out = strokes(sim, designs_of(sim, P))
    is_open = out[:, COL["status"]] == 1
    assert is_open.sum() > 10
    assert np.all(out[is_open, COL["stop_time"]] == pytest.approx(sim.stroke.t_max))


def test_held_open_at_the_equilibrium(sim, model):
    """A strong spring holds the lid open: the reason names the equilibrium, where V' = 0
    (the model's dV, not the table) and V'' > 0, and the lid comes to rest there."""
    st = sim.stroke
    p = as_params([6000.0, 0.07, 1000.0, 0.0])
    D = designs_of(sim, p[None, :])
    on = strokes(sim, D)[0]
    assert on[COL["status"]] == 1 and on[COL["stop_reason"]] == 2
    assert on[COL["stop_time"]] < 1.0
    th = on[COL["stop_theta"]]
    assert st.theta_closed < th < st.theta0
    grid = np.linspace(st.theta_closed, st.theta0, 19)
    scale = float(np.abs([model.dV(x, p) for x in grid]).max())
    assert abs(float(model.dV(th, p))) < 1e-8 * scale
    eps = 1e-4
    assert float(model.dV(th - eps, p)) < 0 < float(model.dV(th + eps, p))
    # where the lid settles when integrated to the end (no early exit)
    _, tr = binding.run_stroke_trajectory(sim.table, sim.method, sim.step, st.t_max, st.theta0,
                                         st.theta_closed, D[0], early_exit=False)
    assert tr[-1, 1] == pytest.approx(th, abs=1e-7)   # (still creeping in by ~1e-9)
    text = binding.not_closed_reasons(on)[0]
    assert text == f"held open at theta = {math.degrees(th):.1f} deg"


def test_barrier_between_the_lid_and_the_rim(cfg):
    """An over-centre spring (anchor where the spring is shortest mid-stroke, compressed)
    makes a hill of V between a well near theta0 and the rim: the lid falls into the well
    and stops behind the barrier; its top has V' = 0 and V'' < 0 (model's dV)."""
    cfg_b = cfg.replace(geometry={"spring_anchor": [-0.02, 0.06]})
    sim = Simulator.from_config(cfg_b)
    st = cfg_b.stroke
    l0 = float(sim.table.evaluate([st.theta0])[0, 4])  # at rest length at release
    for c in (0.0, 50.0):
        p = as_params([5e6, l0, c, 0.0])
        out = strokes(sim, designs_of(sim, p[None, :]))[0]
        assert out[COL["status"]] == 1 and out[COL["stop_reason"]] == 1
        th = out[COL["stop_theta"]]
        assert st.theta_closed < th < out[COL["theta_min"]]
        dV = lambda x: float(sim.model.dV(x, p))  # noqa: E731
        scale = max(abs(dV(x)) for x in np.linspace(st.theta_closed, st.theta0, 19))
        assert abs(dV(th)) < 1e-8 * scale
        assert dV(th - 1e-4) > 0 > dV(th + 1e-4)
        assert binding.not_closed_reasons(out)[0] == (
            f"cannot reach the rim: energy below the barrier at theta = {math.degrees(th):.1f} deg")
        assert (out[COL["stop_time"]] < 0.5) == (c > 0)   # damped: stops early


def test_not_closed_reasons_text():
    out = np.full((5, len(binding.OUT_FIELDS)), np.nan)
    out[:, COL["status"]] = [0, 1, 1, 1, 3]
    out[:, COL["stop_reason"]] = [0, 2, 1, 0, 0]
    out[:, COL["stop_theta"]] = [np.nan, math.radians(7.34), math.radians(12.06), np.nan, np.nan]
    text = binding.not_closed_reasons(out)
    assert list(text) == ["", "held open at theta = 7.3 deg",
                          "cannot reach the rim: energy below the barrier at theta = 12.1 deg",
                          "still moving towards the rim at t_max (too slow to close in time)", ""]
    cols = {k: out[:, COL[k]] for k in ("status", "stop_reason", "stop_theta")}
    assert list(binding.not_closed_reasons(cols)) == list(text)


def test_scalar_and_simd_paths_agree_bit_for_bit(sim, grid):
    """SC_SCALAR=1 forces the lane-by-lane code: the same numbers, bit for bit."""
    P, D, on, _ = grid
    assert np.array_equal(scalar_strokes(D[::2]), on[::2], equal_nan=True)
    one = strokes(sim, D[:7])                          # lanes partly idle, one thread
    assert np.array_equal(one, on[:7], equal_nan=True)
