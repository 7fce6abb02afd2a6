"""Energy along fixed-step trajectories (energy from model.energy_fn at every step).

- No damping, a spring that holds the lid open (it oscillates between ~10.2 and 18 deg for
  t_max = 20 s without closing -- found with Simulator.run_batch, asserted below):
  RK4's energy drift grows linearly in time and shrinks with the step at (at least) 4th
  order; the symplectic Euler-Cromer and the symmetric, symplectic gauss4 keep it bounded.
- With damping, the energy never increases along a stroke (beyond round-off/truncation).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from softclose.model.lid import LidModel
from softclose.simulation.simulator import Simulator
from softclose.problem import as_params

HELD_OPEN = as_params([2200.0, 0.09, 0.0, 0.0])


@pytest.fixture(scope="module")
def long_run(cfg):
    c = cfg.replace(stroke={"t_max": 20.0})
    m = LidModel.from_config(c)
    cache = {}

    def get(method, h):
        if (method, h) not in cache:
            r = Simulator.from_config(c, m, method, h).run(HELD_OPEN, trajectory=True, estimate_error=False)
            assert r.ok and not r.closed, r.status
            tr = r.trajectory
            assert tr["t"][-1] == pytest.approx(20.0)
            dE = tr["energy"] - tr["energy"][0]
            n = len(dE) // 10
            cache[(method, h)] = dict(theta=tr["theta"], dE=dE,
                                      first=np.abs(dE[:n]).max(), last=np.abs(dE[-n:]).max(),
                                      max=np.abs(dE).max())
        return cache[(method, h)]
    return get


def test_design_oscillates_without_closing(cfg):
    c = cfg.replace(stroke={"t_max": 20.0})
    b = Simulator.from_config(c).run_batch(HELD_OPEN[None, :])
    assert b["status"][0] == 1                      # not closed, integrated to t_max
    assert math.radians(8) < b["theta_min"][0] < math.radians(14)


def _slope(hs, ys):
    return float(np.polyfit(np.log(hs), np.log(ys), 1)[0])


def test_rk4_energy_drift_is_secular_and_shrinks_at_order_4(long_run):
    hs = [0.016, 0.008, 0.004]
    runs = [long_run("rk4", h) for h in hs]
    drifts = [r["max"] for r in runs]
    slope = _slope(hs, drifts)
    # RK4 dissipates: |R(i y)|^2 = 1 - y^6/72 + ..., an energy loss per unit time ~ h^5,
    # so the energy error converges one order faster than the state (observed ~5)
    assert slope >= 4 - 0.3
    for r in runs:
        assert r["dE"][-1] < 0                      # it loses energy ...
        assert r["last"] > 5 * r["first"]           # ... steadily (linear growth in time)
    assert drifts[-1] < 1e-9                       # and is small at a moderate step


@pytest.mark.parametrize("method,h", [("euler_cromer", 0.002), ("euler_cromer", 0.001),
                                      ("gauss4", 0.008), ("gauss4", 0.004)])
def test_symplectic_energy_error_stays_bounded(long_run, method, h):
    r = long_run(method, h)
    # no secular drift: the error over the last 2 s is that of the first 2 s
    assert r["last"] <= 1.3 * r["first"] + 1e-13
    if method == "gauss4":
        assert r["max"] < 1e-10


def test_euler_cromer_energy_oscillation_is_first_order(long_run):
    a, b = long_run("euler_cromer", 0.002)["max"], long_run("euler_cromer", 0.001)["max"]
    assert abs(math.log2(a / b) - 1) < 0.2


@pytest.mark.parametrize("p", [
    (500.0, 0.03, 100.0, 0.0), (800.0, 0.08, 30.0, 0.0), (300.0, 0.04, 3000.0, 0.0),
    (0.0, 0.05, 0.0, 0.02), (1400.0, 0.11, 5.0, 0.0),
])
@pytest.mark.parametrize("method", ["rk4", "radau5"])
def test_damped_energy_never_increases(sim, cfg, model, p, method):
    s = sim if method == "rk4" else Simulator.from_config(cfg, model, method)
    r = s.run(np.array(p), trajectory=True, estimate_error=False)
    assert r.ok
    E = r.trajectory["energy"]
    scale = np.abs(E).max()
    rise = np.diff(E).max()
    assert rise <= 1e-11 * scale, rise
    assert E[-1] < E[0]
