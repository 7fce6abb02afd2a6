"""The stroke kernel's per-design lid mass (design rows with a ``lid_mass`` column).

The coefficients are affine in the lid's mass, so one table and its mass derivative serve
every mass: strokes through the column must be those of a simulator built on a config at
that mass (derived inertia m L^2/12, or a configured fixed inertia), a row at the table's
own mass must be bit-identical to a row without the column, and bad masses are refused.
"""

from __future__ import annotations

import os

import numpy as np
import pytest

from softclose.simulation.kernel import binding
from softclose.simulation.kernel import library
from softclose.simulation import statics
from softclose.errors import ConfigError
from softclose.model.lid import LidModel
from softclose.simulation.simulator import Simulator
from softclose.problem import as_params

COL = {name: i for i, name in enumerate(binding.OUT_FIELDS)}


def designs(cfg, sim_at_mass, P, mass):
    """Kernel rows (the parameter vector, energy_tol, lid_mass); energy_tol as the simulator
    at that mass sets it (the unstable-stroke threshold depends on the mass too)."""
    return np.column_stack([binding.kernel_rows(P), sim_at_mass.energy_tol(P),
                            np.full(len(P), mass)])


def sample_designs(cfg, n=24, seed=8):
    rng = np.random.default_rng(seed)
    P = np.column_stack([rng.uniform(500, 4000, n), rng.uniform(0.05, 0.09, n),
                         rng.uniform(100, 3000, n), np.zeros(n)])
    P[0] = [cfg.design.spring_k, cfg.design.spring_rest_length, cfg.design.damper_c,
            cfg.design.rotary_damper_c]
    P[1] = [1914.7, 0.079257, 2087.75, 0.0]          # the default problem's optimum
    return as_params(P)


@pytest.mark.parametrize("inertia", [None, 0.02])
@pytest.mark.parametrize("mass", [0.45, 0.55])
def test_lid_mass_column_matches_a_model_at_that_mass(cfg, mass, inertia):
    base = cfg if inertia is None else cfg.replace(mass={"inertia_lid": inertia})
    sim = Simulator.from_config(base)
    other = Simulator.from_config(base.replace(mass={"lid": mass}))
    if inertia is not None:
        assert other.model.mass.inertia_lid == inertia      # fixed, not rescaled
    else:
        assert other.model.mass.inertia_lid == pytest.approx(mass * 0.5 ** 2 / 12, rel=1e-15)
    assert other.table.ncell == sim.table.ncell
    P = sample_designs(cfg)
    st = cfg.stroke
    out = binding.run_strokes(sim.table, sim.method, sim.step, st.t_max, st.theta0,
                             st.theta_closed, designs(cfg, other, P, mass))
    ref = other.run_batch(P)
    assert np.array_equal(out[:, COL["status"]], ref["status"])
    closed = ref["status"] == 0
    assert closed.sum() > 10
    for key in ("closing_time", "impact_theta_dot"):
        assert np.abs(out[closed, COL[key]] - ref[key][closed]).max() < 1e-10, key
    for key in ("peak_tip_speed", "min_spring_length", "max_spring_length"):
        ok = np.isin(ref["status"], (0, 1))
        assert np.abs(out[ok, COL[key]] - ref[key][ok]).max() < 1e-10, key
    # the holding moment from the table at theta_closed, at that mass
    hm = statics.holding_moments(sim.table, st.theta_closed, P, mass)
    assert np.abs(hm - ref["holding_moment"]).max() < 1e-10
    assert hm[0] == pytest.approx(other.model.holding_moment(P[0]), abs=1e-10)
    # and the mass changes the answer (the test can fail)
    assert np.abs(hm - sim.run_batch(P)["holding_moment"]).min() > 1e-3


def test_mass_derivative_is_exact(cfg, sim):
    """Coefficients at a third mass from the table and its derivative vs a model there."""
    m = 0.8
    th = np.linspace(sim.table.lo, sim.table.hi, 97)
    exact = np.asarray(LidModel.from_config(cfg.replace(mass={"lid": m})).coeffs.map(len(th))(th)[0]).T
    mine = sim.table.evaluate(th, lid_mass=m)
    base = sim.table.evaluate(th)
    scale = np.abs(exact).max(axis=0)
    assert np.all(np.abs(mine - exact) <= 1e-9 * scale)            # table error only
    assert np.all(np.abs(mine[:, 4:] - base[:, 4:]) == 0)           # l, dl, dd, tau: no mass
    assert np.all(np.abs(mine[:, :4] - base[:, :4]).max(axis=0) > 1e-3 * scale[:4])


def test_row_at_table_mass_is_bit_identical(cfg, sim):
    st = cfg.stroke
    P = sample_designs(cfg, 40, seed=3)
    D = np.column_stack([binding.kernel_rows(P), sim.energy_tol(P)])
    run = lambda X: binding.run_strokes(sim.table, sim.method, sim.step, st.t_max,  # noqa: E731
                                       st.theta0, st.theta_closed, X)
    plain = run(D)
    same = np.column_stack([D, np.full(len(P), cfg.mass.lid)])
    nan = np.column_stack([D, np.full(len(P), np.nan)])
    mixed = np.column_stack([D, np.where(np.arange(len(P)) % 3 == 0, 0.6, cfg.mass.lid)])
    assert np.array_equal(run(same), plain, equal_nan=True)
    assert np.array_equal(run(nan), plain, equal_nan=True)
    keep = np.arange(len(P)) % 3 != 0                 # lanes shared with other masses
    out = run(mixed)
    assert np.array_equal(out[keep], plain[keep], equal_nan=True)
    assert not np.array_equal(out[~keep], plain[~keep], equal_nan=True)


def test_kernel_step_with_a_lid_mass(cfg, sim):
    """One kernel step at mass m equals the step of the table built at m."""
    m = 0.62
    other = Simulator.from_config(cfg.replace(mass={"lid": m}))
    p = as_params([1500.0, 0.07, 900.0, 0.002])
    x0 = np.array([0.2, -1.5])
    a = binding.kernel_step(sim.table, sim.method, p, 2e-3, x0, lid_mass=m)
    b = binding.kernel_step(other.table, other.method, p, 2e-3, x0)
    assert np.allclose(a, b, rtol=1e-13, atol=1e-15)
    assert not np.allclose(a, binding.kernel_step(sim.table, sim.method, p, 2e-3, x0),
                           rtol=1e-9, atol=0)


@pytest.mark.parametrize("bad", [0.0, -0.3, np.inf])
def test_bad_lid_mass_is_refused(cfg, sim, bad):
    st = cfg.stroke
    D = np.array([[1000.0, 0.07, 500.0, 0.0, 0.0, 0.0, 1e-3, bad]])
    with pytest.raises(ConfigError, match="lid_mass"):
        binding.run_strokes(sim.table, sim.method, sim.step, st.t_max, st.theta0,
                           st.theta_closed, D)


def test_design_rows_need_their_columns(cfg, sim):
    st = cfg.stroke
    n = len(binding.DESIGN_COLUMNS)          # (the last NPT: the optional point columns)
    with pytest.raises(ConfigError, match=f"expected {n - binding.NPT - 1}, {n - binding.NPT} "
                                          f"or {n} columns"):
        binding.run_strokes(sim.table, sim.method, sim.step, st.t_max, st.theta0,
                           st.theta_closed, np.ones((2, 4)))


def test_one_angle_looked_up_once_gives_each_row_s_own_numbers(cfg, sim):
    """statics at one angle broadcast that angle's coefficients
    (and lid-mass slope) instead of looking the angle up per row: bit for bit the numbers of
    the per-row evaluation, with and without lid masses (NaN: the table's own)."""
    tab = sim.table
    rng = np.random.default_rng(3)
    n = 500
    P = as_params(np.column_stack([rng.uniform(0, 1e4, n), rng.uniform(0.04, 0.1, n),
                                   rng.uniform(0, 5e3, n), np.zeros(n)]))
    m = rng.uniform(0.3, 0.9, n)
    m[::7] = np.nan
    m[::11] = tab.lid_mass
    for th in (cfg.stroke.theta0, cfg.stroke.theta_closed, 0.3):
        for lm in (None, m, 0.7):
            c = tab.evaluate(np.full(n, th), lm)     # per row
            V = c[:, 2] + 0.5 * P[:, 0] * (c[:, 4] - P[:, 1]) ** 2
            H = c[:, 3] + P[:, 0] * (c[:, 4] - P[:, 1]) * c[:, 5]
            assert np.array_equal(statics.potential_energy(tab, th, P, lm), V)
            assert np.array_equal(statics.holding_moments(tab, th, P, lm), H)


def test_the_kernel_s_layout_is_checked_at_load():
    """Every layout constant shared with the C side (columns, rows, outputs, range columns)
    is compared when the kernel is loaded: a mismatch is a one-line error naming it."""
    lib = binding.load()
    library.check_layout(lib)                                  # the built kernel agrees

    class Other:                                              # a kernel of another layout
        def __init__(self, layout):
            self.sc_layout = lambda: layout.encode()
            self.sc_nout = lambda: len(binding.OUT_FIELDS)
            self.sc_abi = lambda: binding.KERNEL_ABI

    wrong = binding.LAYOUT.replace("row=spring_k,", "row=k,")
    with pytest.raises(binding.NumericalError, match="row: the kernel has 'k,spring_rest"):
        library.check_layout(Other(wrong))
    with pytest.raises(binding.NumericalError, match="nrng"):
        library.check_layout(Other(binding.LAYOUT.replace("nrng=18", "nrng=17")))


def test_the_built_extension_is_known_by_its_sources_content_not_their_times(tmp_path,
                                                                            monkeypatch):
    """pip install's extension carries the tag of the source it was compiled from: it is used
    whatever the files' times (an installed package's are the wheel's), and not once the
    source beside it is another."""
    if library._built_extension() is None:
        pytest.skip("no extension built from this source (a checkout's kernel is compiled)")
    src = tmp_path / "_kernel.c"
    src.write_bytes(library.SOURCE.read_bytes())
    os.utime(src, ns=(0, 4102444800 * 10**9))                  # newer than any build
    monkeypatch.setattr(library, "SOURCE", src)
    assert library._built_extension() is not None
    src.write_bytes(src.read_bytes() + b"/* edited */\n")
    assert library._built_extension() is None
