"""Closing strokes (SPEC §4): the fast fixed-step path against the adaptive reference and
the published SPEC §8 numbers; strokes that never close; stiff dampers; the error estimate;
metric-only runs; `softclose simulate --json` and `--out`.

Tolerances (the brief): |d closing_time| <= 1e-7 s, |d impact_theta_dot| <= 1e-6 rad/s,
relative 1e-6 on the tip speeds. Observed at the default step 1e-3 s: ~1e-11 s, ~1e-9 rad/s,
~1e-10 relative -- the remaining difference is mostly the reference's own error at its
default tolerance 1e-12 (see test_integrators for the fast path against a 1e-14 reference).
"""

from __future__ import annotations

import csv
import json
import math

import numpy as np
import pytest

from softclose import cli
from softclose.model.lid import LidModel
from softclose.simulation.reference import Reference
from softclose.problem import METRIC_KEYS
from softclose.simulation.simulator import Simulator
from softclose.problem import as_params

TOL = {"closing_time": 1e-7, "impact_theta_dot": 1e-6}
REL_TIP = 1e-6
SPEC8 = {"closing_time": 0.1491478, "impact_theta_dot": -4.155764, "impact_tip_speed": 2.150045}


def assert_agree(r, R, l_tol=1e-9):
    """A StrokeResult against a Reference.simulate dict, to the brief's tolerances."""
    assert r.ok, r.message
    assert r.closed == R.closed
    if R.closed:
        assert abs(r.closing_time - R.closing_time) <= TOL["closing_time"]
        assert abs(r.impact_theta_dot - R.impact_theta_dot) <= TOL["impact_theta_dot"]
        assert r.impact_tip_speed == pytest.approx(R.impact_tip_speed, rel=REL_TIP)
    else:
        assert r.closing_time is None and r.impact_theta_dot is None
    assert r.peak_tip_speed == pytest.approx(R.peak_tip_speed, rel=REL_TIP)
    assert abs(r.min_spring_length - R.min_spring_length) <= l_tol
    assert abs(r.max_spring_length - R.max_spring_length) <= l_tol
    assert r.holding_moment == pytest.approx(R.holding_moment, rel=1e-12, abs=1e-14)


def test_spec8_stroke_published_and_reference(sim, ref):
    r = sim.run()
    R = ref.simulate()
    for key, v in SPEC8.items():   # the published values are rounded within these tolerances
        tol = REL_TIP * abs(v) if key == "impact_tip_speed" else TOL[key]
        assert abs(getattr(r, key) - v) <= tol, key
        assert abs(getattr(R, key) - v) <= tol, key
    assert_agree(r, R)
    assert r.peak_tip_speed == pytest.approx(r.impact_tip_speed, rel=1e-12)  # still accelerating


#: (k, l0, c, c_rot). Default spring length runs 0.0527 (closed) .. 0.0584 m (theta0):
#: l0 < l pulls the lid shut, l0 > l pushes it open (compression spring / gas strut).
DESIGNS = [
    pytest.param((500.0, 0.03, 100.0, 0.0), id="tension+dashpot"),
    pytest.param((5000.0, 0.02, 0.0, 0.0), id="strong-tension"),
    pytest.param((800.0, 0.08, 30.0, 0.0), id="compression+dashpot"),
    pytest.param((2000.0, 0.08, 50.0, 0.0), id="compression-slow"),
    pytest.param((800.0, 0.12, 20.0, 0.002), id="compression+both-dampers"),
    pytest.param((300.0, 0.04, 3000.0, 0.0), id="heavy-dashpot"),
    pytest.param((1000.0, 0.07, 0.0, 0.01), id="compression+rotary"),
    pytest.param((0.0, 0.05, 0.0, 0.02), id="rotary-only"),
]


def _both(sim, ref, p):
    """(the fixed-step stroke, the reference's) of p, agreeing (:func:`assert_agree`)."""
    r, R = sim.run(np.array(p)), ref.simulate(np.array(p))
    assert_agree(r, R)
    return r, R


@pytest.mark.parametrize("p", DESIGNS)
def test_designs_agree_with_reference(sim, ref, p):
    p = np.array(p)
    r, R = _both(sim, ref, p)
    assert R.closed
    if p[1] > 0.0585:   # compression spring over the whole stroke: the spring pushes
        assert r.holding_moment < ref.model.holding_moment(np.r_[0.0, p[1:]])


#: second geometry: spring length 0.0326 (closed) .. 0.0395 m (theta0)
DESIGNS2 = [
    pytest.param((0.0, 0.05, 0.0, 0.0), id="no-elements"),
    pytest.param((600.0, 0.03, 80.0, 0.0), id="tension+dashpot"),
    pytest.param((300.0, 0.06, 1500.0, 0.0), id="compression+heavy-dashpot"),
    pytest.param((700.0, 0.07, 30.0, 0.004), id="compression+both-dampers"),
]


@pytest.mark.parametrize("p", DESIGNS2)
def test_second_geometry_agrees_with_reference(sim2, ref2, p):
    _both(sim2, ref2, p)


@pytest.fixture(scope="module")
def short(cfg):
    """t_max = 1 s (the reference costs ~0.6 s per stroke second): model, sim, reference."""
    c = cfg.replace(stroke={"t_max": 1.0})
    m = LidModel.from_config(c)
    return c, m, Simulator.from_config(c, m), Reference(m)


@pytest.mark.parametrize("p", [
    pytest.param((1400.0, 0.11, 5.0, 0.0), id="held-open-damped"),
    pytest.param((2200.0, 0.09, 0.0, 0.0), id="held-open-undamped"),
])
def test_never_closes_peak_and_spring_extremes(short, p):
    c, m, s, R = short
    p = np.array(p)
    r, RR = s.run(p), R.simulate(p)
    assert not RR.closed and RR.theta_min > math.radians(5)   # turns back well above 0
    assert_agree(r, RR)
    assert r.min_spring_length < r.max_spring_length


def test_spring_extremes_of_a_lid_that_opens_first(short):
    c, m, s, R = short
    p = as_params([2600.0, 0.09, 0.0, 0.0])          # pushes at theta0: swings up to ~19.2 deg
    r = s.run(p, trajectory=True)
    assert r.ok and not r.closed
    tr = Simulator.from_config(c, m, "gauss4", 2.5e-4).run(p, trajectory=True).trajectory
    th_max = float(tr["theta"].max())
    assert th_max > c.stroke.theta0 + math.radians(1.0)
    E = np.asarray(m.kin([th_max, 0.0])[7]).ravel()
    l_top = float(np.hypot(*(np.asarray(m.geo.spring_anchor) - E)))
    assert r.max_spring_length >= l_top - 1e-9          # the spring is longest at the top
    assert R.simulate(p).max_spring_length >= l_top - 1e-9


def test_lid_pushed_open_beyond_the_table(short):
    c, m, s, R = short
    p = as_params([3000.0, 0.09, 0.0, 0.0])
    r = s.run(p)
    RR = R.simulate(p)
    assert not RR.closed and np.isfinite(RR.peak_tip_speed)
    if r.ok:
        assert_agree(r, RR)
    else:   # reported: following the advice must then work
        assert Simulator.from_config(c, m, "radau5", s.step / 10).run(p).ok, r.message


# -- stiff damping ------------------------------------------------------------------------
def _finite_or_none(res):
    for k in METRIC_KEYS:
        v = getattr(res, k)
        assert v is None or isinstance(v, bool) or math.isfinite(v), (k, v)


@pytest.fixture(scope="module")
def stiff_reference(ref):
    """Reference strokes of the stiff dampers (~2.5 s each), computed once."""
    cache = {}

    def get(c_damp):
        if c_damp not in cache:
            cache[c_damp] = ref.simulate(as_params([0.0, 0.05, c_damp, 0.0]))
        return cache[c_damp]
    return get


def _true_peak(ref, p, t_lo, t_hi, n=400):
    """max |v_T| over [t_lo, t_hi] from dense reference-flow samples + golden section."""
    x0 = np.array([ref.model.stroke.theta0, 0.0])
    speed = lambda t: float(ref._speed(ref.flow(x0, p, t), p)[0])  # noqa: E731
    ts = np.linspace(t_lo, t_hi, n)
    i = int(np.argmax([speed(t) for t in ts]))
    lo, hi = ts[max(i - 1, 0)], ts[min(i + 1, n - 1)]
    gr = (math.sqrt(5) - 1) / 2
    for _ in range(50):
        c, d = hi - gr * (hi - lo), lo + gr * (hi - lo)
        if speed(c) > speed(d):
            hi = d
        else:
            lo = c
    return speed(0.5 * (lo + hi))


@pytest.mark.parametrize("c_damp", [1e5, 1e6])
def test_stiff_damper_default_integrator(cfg, model, stiff_reference, c_damp):
    p = as_params([0.0, 0.05, c_damp, 0.0])
    s = Simulator.from_config(cfg, model)           # the default: rk4 at the default step
    r = s.run(p)
    _finite_or_none(r)
    RR = stiff_reference(c_damp)
    assert not RR.closed             # it creeps: t_max is too short to close
    if r.ok:   # handled: agrees within its own error estimate, and says when it is stiff
        assert r.closed == RR.closed
        err = abs(r.peak_tip_speed - RR.peak_tip_speed)
        assert err <= 3 * r.accuracy["peak_tip_speed"] + 1e-5 * RR.peak_tip_speed
        if r.accuracy["step_times_max_rate"] > 1.0:
            assert r.message and "stiff" in r.message and "radau5" in r.message
        else:
            assert r.peak_tip_speed == pytest.approx(RR.peak_tip_speed, rel=1e-4)
    else:      # reported with the step it needs; that step works
        assert r.status.text in ("unstable", "non-finite", "left the tabulated range")
        assert "simulate.step <=" in r.message and "radau5" in r.message
        h_ok = float(r.message.split("simulate.step <=")[1].split()[0])
        assert h_ok < s.step
        r2 = Simulator.from_config(cfg, model, step=h_ok).run(p)
        assert r2.ok
        assert r2.peak_tip_speed == pytest.approx(RR.peak_tip_speed, rel=1e-4)


@pytest.mark.parametrize("c_damp", [1e5, 1e6])
def test_stiff_damper_radau5(cfg, model, stiff_reference, c_damp):
    """radau5 at the default step: finite, not closed, and within its own error estimate of
    the reference (peak: the estimate is ~3e-5 relative at c = 1e6, where the peak sits in
    the first 3 ms); the spring extremes to 1e-9 m."""
    p = as_params([0.0, 0.05, c_damp, 0.0])
    r = Simulator.from_config(cfg, model, "radau5").run(p)
    RR = stiff_reference(c_damp)
    assert r.ok, r.message
    _finite_or_none(r)
    assert r.closed is False and RR.closed is False
    err = abs(r.peak_tip_speed - RR.peak_tip_speed)
    assert err <= max(3 * r.accuracy["peak_tip_speed"], REL_TIP * RR.peak_tip_speed)
    assert abs(r.min_spring_length - RR.min_spring_length) <= 1e-9
    assert abs(r.max_spring_length - RR.max_spring_length) <= 1e-9


def test_stiff_radau5_converges_to_the_true_peak(cfg, model, ref):
    """c = 1e6 at step 1e-4: the peak to 1e-6 of dense reference-flow samples."""
    p = as_params([0.0, 0.05, 1e6, 0.0])
    r = Simulator.from_config(cfg, model, "radau5", 1e-4).run(p)
    assert r.peak_tip_speed == pytest.approx(_true_peak(ref, p, 1e-3, 4e-3, 60), rel=1e-6)


def test_reference_peak_is_the_true_peak_when_it_comes_early(ref, stiff_reference):
    p = as_params([0.0, 0.05, 1e6, 0.0])
    true_peak = _true_peak(ref, p, 1e-3, 4e-3, 60)
    assert stiff_reference(1e6).peak_tip_speed == pytest.approx(true_peak, rel=1e-8)


def test_stiff_cli_reports_or_handles(capsys):
    rc = cli.main(["simulate", "--json", "--set", "design.damper_c=1e6"])
    out, err = capsys.readouterr()
    obj = json.loads(out)
    assert "NaN" not in out and "Infinity" not in out
    assert rc in (0, 3)
    if rc == 3:
        assert "simulate.step" in obj["error"]
    rc = cli.main(["simulate", "--json", "--set", "simulate.integrator=\"radau5\"",
                   "--set", "design.damper_c=1e6"])
    out, err = capsys.readouterr()
    assert rc == 0 and json.loads(out)["closed"] is False


# -- the error estimate, metric-only runs, batches --------------------------------------------
def test_error_estimate_bounds_the_actual_error(cfg, model):
    """At a coarse step the Richardson estimate is of the size of the true error."""
    p = as_params([800.0, 0.08, 30.0, 0.005])
    R = Reference(model, tol=1e-14).simulate(p)
    for name, h in (("rk4", 0.008), ("gauss4", 0.008), ("radau5", 0.016)):
        r = Simulator.from_config(cfg, model, name, h).run(p)
        for key in ("closing_time", "impact_theta_dot", "impact_tip_speed"):
            actual, est = abs(getattr(r, key) - getattr(R, key)), r.accuracy[key]
            assert actual <= 2.0 * est + 1e-11, (name, key, actual, est)
            assert est <= 10.0 * actual + 1e-11, (name, key, actual, est)


def test_metric_only_runs_keep_no_trajectory(sim):
    r = sim.run(as_params([500.0, 0.03, 100.0, 0.0]))
    assert r.trajectory is None and r.ok
    r2 = sim.run(as_params([500.0, 0.03, 100.0, 0.0]), trajectory=True)
    tr = r2.trajectory
    assert tr is not None
    assert tr["t"][-1] == pytest.approx(r2.closing_time, abs=1e-15)
    assert tr["theta"][-1] == pytest.approx(0.0, abs=1e-12)
    assert tr["theta_dot"][-1] == pytest.approx(r2.impact_theta_dot, rel=1e-14)
    assert np.all(np.diff(tr["t"]) > 0)
    assert len(tr["t"]) == r2.steps + 1 or len(tr["t"]) == r2.steps
    assert r2.metrics() == r.metrics()


def test_trajectory_frame_is_the_time_histories():
    """simulate(cfg, trajectory=True).trajectory_frame(): one row per step, from the release
    (theta0, at rest) to the rim at the closing time; without a trajectory it says how to get
    one."""
    import softclose
    cfg = softclose.default_config()
    r = softclose.simulate(cfg, trajectory=True)
    f = r.trajectory_frame()
    assert list(f.columns) == ["t", "theta", "theta_dot", "theta_ddot", "phi", "gamma",
                               "tip_speed", "spring_length", "energy"]
    assert len(f) == r.steps + 1
    assert f["t"].iloc[0] == 0.0 and f["theta_dot"].iloc[0] == 0.0
    assert f["theta"].iloc[0] == pytest.approx(math.radians(cfg.stroke.theta0_deg), rel=1e-15)
    assert f["t"].iloc[-1] == pytest.approx(r.closing_time, abs=1e-15)
    assert f["theta_dot"].iloc[-1] == pytest.approx(r.impact_theta_dot, rel=1e-14)
    assert f["spring_length"].min() == pytest.approx(r.min_spring_length, abs=1e-9)
    with pytest.raises(ValueError, match="trajectory=True"):
        softclose.simulate(cfg).trajectory_frame()


def test_batch_equals_single_runs(sim):
    """run_batch (threads, lanes) gives the single-stroke numbers for every design."""
    rng = np.random.default_rng(21)
    n = 160
    P = np.column_stack([rng.uniform(0, 3000, n), rng.uniform(0.02, 0.12, n),
                         rng.uniform(0, 500, n), rng.uniform(0, 0.01, n)])
    b = sim.run_batch(P, threads=2)
    for i in range(0, n, 8):
        r = sim.run(P[i], estimate_error=False)
        assert bool(b["closed"][i]) == r.closed
        if not r.ok:
            continue
        for key in ("closing_time", "impact_theta_dot", "impact_tip_speed", "peak_tip_speed",
                    "min_spring_length", "max_spring_length", "holding_moment"):
            v = getattr(r, key)
            if v is None:
                assert not np.isfinite(b[key][i])
            else:
                assert b[key][i] == pytest.approx(v, rel=1e-12, abs=1e-15), key


# -- command line ---------------------------------------------------------------------------
def test_simulate_json_has_spec4_keys(capsys):
    rc = cli.main(["simulate", "--json"])
    out, err = capsys.readouterr()
    assert rc == 0
    obj = json.loads(out)
    assert set(METRIC_KEYS) <= set(obj)
    assert obj["closed"] is True
    assert abs(obj["closing_time"] - SPEC8["closing_time"]) <= 1e-7
    assert abs(obj["impact_theta_dot"] - SPEC8["impact_theta_dot"]) <= 1e-6


def test_simulate_json_not_closed_has_nulls(capsys):
    rc = cli.main(["simulate", "--json", "--set", "stroke.t_max=0.05"])
    obj = json.loads(capsys.readouterr().out)
    assert rc == 0 and obj["closed"] is False
    assert obj["closing_time"] is None and obj["impact_theta_dot"] is None
    assert obj["peak_tip_speed"] > 0


def test_simulate_out_writes_csv_figures_gif(capsys, tmp_path):
    out = tmp_path / "sim"
    rc = cli.main(["simulate", "--set", "design.spring_k=500", "--set", "design.damper_c=100",
                   "--set", "design.spring_rest_length=0.03", "--out", str(out)])
    text = capsys.readouterr().out
    assert rc == 0 and "closing_time" in text
    for name in ("stroke_trajectory.csv", "stroke_time.png", "stroke_linkage.png",
                 "stroke_animation.gif"):
        f = out / name
        assert f.exists() and f.stat().st_size > 0, name
    assert (out / "stroke_time.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert (out / "stroke_animation.gif").read_bytes()[:4] == b"GIF8"
    with open(out / "stroke_trajectory.csv") as f:
        rows = list(csv.reader(f))
    assert rows[0] == ["t [s]", "theta [rad]", "theta [deg]", "theta_dot [rad/s]",
                       "theta_ddot [rad/s^2]", "phi [rad]", "gamma [rad]", "tip_speed [m/s]",
                       "spring_length [m]", "energy [J]"]
    data = np.array(rows[1:], float)
    assert data[0, 0] == 0.0 and data[0, 1] == pytest.approx(math.radians(18.0))
    assert np.allclose(data[:, 2], np.degrees(data[:, 1]), rtol=1e-10, atol=1e-10)
    assert abs(data[-1, 1]) < 1e-10                        # ends at the closing event
    assert np.all(np.diff(data[:, 0]) > 0)




def test_the_config_is_resolved_once_at_the_top(cfg):
    """``softclose.resolve`` gives immutable values (equal and hashed by value); the model,
    the simulator and the reference take them, each public class has a constructor from a
    config, and a config given below the features is refused in one line."""
    import softclose
    from softclose.problem import params_of, resolve
    case = resolve(cfg)
    assert case == resolve(cfg) and hash(case) == hash(resolve(cfg))
    assert case.p.tolist() == params_of(cfg).tolist()
    assert (case.stroke.theta0, case.stroke.theta_closed) == (cfg.stroke.theta0,
                                                              cfg.stroke.theta_closed)
    assert case.solver.step == cfg.simulate.step and case.lid.geometry is cfg.geometry
    with pytest.raises(AttributeError):
        case.stroke.t_max = 1.0
    for cls in (LidModel, Simulator):
        with pytest.raises(TypeError, match="resolve"):
            cls(cfg)
    model = LidModel(case)
    assert not hasattr(model, "cfg") and model.lid == case.lid
    assert Simulator.from_config(cfg).run().closing_time == \
        softclose.simulate(cfg).closing_time == Simulator(case).run().closing_time
    # the reference of a config runs at its temperature, as one given the resolved config
    cold = cfg.update({"operating.temperature_c": 0.0, "design.damper_c": 500.0,
                       "design.damper_temperature_coeff": -0.005})
    ref = Reference.from_config(cold)
    a = ref.simulate()
    b = Reference(LidModel.from_config(cold)).simulate(None, resolve(cold))
    warm = Reference(LidModel.from_config(cold)).simulate()      # at the reference temperature
    assert a.closing_time == b.closing_time > warm.closing_time


@pytest.mark.parametrize("inertia", [None, 0.02])
def test_a_resolved_lid_at_another_mass_is_the_configs(cfg, inertia):
    """What the coefficient table's lid-mass derivative builds (a model at twice the mass)
    is the lid a config with that mass resolves to, its inertia following the mass unless
    the config gives it."""
    from softclose.problem import resolve
    c = cfg if inertia is None else cfg.set("mass.inertia_lid", inertia)
    assert resolve(c).lid.with_lid_mass(1.3) == resolve(c.set("mass.lid", 1.3)).lid


def test_a_simulator_for_another_case_of_its_model(cfg, sim):
    """``for_case``: another spring limit, stroke time or temperature on the same model and
    table gives the bits of a simulator built for it; another model is refused."""
    from softclose.problem import resolve
    base = {"design.spring_k": 800.0, "stroke.t_max": 2.0, "operating.temperature_c": 5.0,
            "design.damper_temperature_coeff": -0.005, "design.damper_c": 300.0}
    for limit in (0.05, 0.09):          # the spring too long at 50 mm: an invalid design
        c = cfg.update({**base, "design.spring_max_length": limit})
        shared, fresh = sim.for_case(resolve(c)), Simulator.from_config(c)
        assert shared.table is sim.table and shared.case == fresh.case
        P = np.tile(resolve(c).p, (2, 1))
        a, b = shared.run_batch(P), fresh.run_batch(P)
        assert all(np.array_equal(a[k], b[k], equal_nan=True) for k in METRIC_KEYS if k in a)
        assert a["status"].tolist() == b["status"].tolist()
        assert list(a["reason"]) == list(b["reason"])
        assert bool(a["reason"][0]) == (limit == 0.05)
    with pytest.raises(ValueError):
        sim.for_case(resolve(cfg.set("mass.lid", 0.7)))
