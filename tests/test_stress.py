"""Numerical stress: every stressed stroke gives an answer that the adaptive reference
confirms, or a clear one-line report of why not. Never a NaN, a hang or a traceback.

The cases are ``softclose.validation.stress.stress_cases(fast=True)`` (damping 0 … 1e6 N s/m, springs up
to 1e6 N/m, steps far too large and very small, long undamped runs with their energy drift, a
toggle near or inside the stroke, a release angle at the edge of the assembly) plus random
valid configs (hypothesis). ``studies/stress_survey.py`` runs the full list and writes the
stress table of docs/performance.md.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

from softclose.validation import stress
from softclose.config import default_config
from softclose.errors import ConfigError
from softclose.model.lid import LidModel
from softclose.simulation.reference import Reference
from softclose.simulation.simulator import Simulator
from softclose.simulation.stroke import StrokeStatus

#: the numerical stress tests (marker ``stress``); the quick checks of the survey's verdicts
#: below are unmarked, so that the default run covers ``softclose.validation.stress`` too
stress_mark = pytest.mark.stress

CASES = stress.stress_cases(fast=True)
#: a stroke of this survey that takes longer than this counts as a hang
HANG_S = 30.0


def _check_row(case, row):
    assert row["outcome"] not in stress.FAILURES, f"{case.name}: {row['outcome']}: {row['message']}"
    assert row["time_s"] < HANG_S, f"{case.name} took {row['time_s']:.1f} s"
    if row["outcome"] in ("reported", "config error"):
        msg = row["message"]
        assert msg and "\n" not in msg and "Traceback" not in msg, msg
        assert "nan" not in msg.lower().split(), msg
    if case.expect == "answer":
        assert row["outcome"] == "confirmed", f"{case.name}: {row['outcome']}: {row['message']}"
    elif case.expect == "report":
        assert row["outcome"] == "reported", f"{case.name}: {row['outcome']}"
    elif case.expect == "config error":
        assert row["outcome"] == "config error", f"{case.name}: {row['outcome']}"
    if row.get("energy_drift") is not None:
        assert math.isfinite(row["energy_drift"])


@stress_mark
@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_stress_case(case):
    row = stress.run_stress_case(case, rerun=False)
    _check_row(case, row)


@stress_mark
def test_unstable_report_names_a_step_that_works():
    """c = 1e6 N s/m with rk4 at 1 ms: reported with the step it needs; at that step (with a
    safety factor 0.8) the stroke runs and agrees with radau5 at a small step."""
    cfg = default_config().replace(design={"damper_c": 1e6})
    model = LidModel.from_config(cfg)
    res = Simulator.from_config(cfg, model=model).run()
    assert res.status.text == "unstable" and not res.ok
    h = stress.recommended_step(res.message)
    assert h is not None and 1e-5 < h < 1e-3, res.message
    assert "radau5" in res.message
    ok = Simulator.from_config(cfg, model=model, step=0.8 * h).run()
    assert ok.ok, ok.message
    fine = Simulator.from_config(cfg, model=model, integrator="radau5", step=1e-4).run()
    assert ok.closed == fine.closed
    assert abs(ok.peak_tip_speed - fine.peak_tip_speed) <= 1e-6 * fine.peak_tip_speed


@stress_mark
@pytest.mark.parametrize("integ", ["rk4", "gauss4", "euler_cromer"])
def test_long_undamped_run_energy_drift(integ):
    """20 s of undamped oscillation (the spring holds the lid open): the energy drift is
    reported by the kernel and small, and the stroke is not flagged unstable."""
    cfg = default_config().replace(design={"spring_k": 2000.0, "spring_rest_length": 0.1},
                                   stroke={"t_max": 20.0}, simulate={"integrator": integ})
    sim = Simulator.from_config(cfg)
    p = sim.model.params()
    b = sim.run_batch(p[None, :], threads=1)
    E0 = float(sim.model.energy_fn([cfg.stroke.theta0, 0.0], p))
    drift = float(b["energy_rise"][0]) / abs(E0)
    assert b["status"][0] == 1  # not closed, ran to t_max
    assert math.isfinite(drift)
    assert drift < (1e-5 if integ == "euler_cromer" else 1e-10), drift


def test_steps_far_too_large_are_reported_not_nan():
    """rk4 at 0.2 s and 1 s on a 0.15 s stroke: a one-line report, never a NaN."""
    for h in (0.2, 1.0):
        cfg = default_config().replace(simulate={"step": h})
        res = Simulator.from_config(cfg).run()
        if res.ok:
            assert res.closing_time is not None and math.isfinite(res.closing_time)
        else:
            assert res.message and "\n" not in res.message
            assert "step" in res.message


# -- random valid configs -------------------------------------------------------------------
@settings(max_examples=12, deadline=None, derandomize=True, phases=[Phase.explicit,
          Phase.generate], suppress_health_check=[HealthCheck.too_slow])
@given(k=st.floats(0, 1e4), l0=st.floats(0.02, 0.12), c=st.floats(0, 5e3),
       crank_oa=st.floats(0.040, 0.050), crank_bc=st.floats(0.075, 0.088),
       theta0=st.floats(5.0, 30.0), lid=st.floats(0.2, 1.0),
       integ=st.sampled_from(["rk4", "gauss4", "radau5", "euler_cromer"]),
       step=st.sampled_from([2e-4, 5e-4, 1e-3, 2e-3]))
@stress_mark
def test_random_valid_configs(k, l0, c, crank_oa, crank_bc, theta0, lid, integ, step):
    geo = stress.geometry_with_assembly(crank_oa=crank_oa, crank_bc=crank_bc)
    overrides = {"geometry": geo, "mass": {"lid": lid},
                 "design": {"spring_k": k, "spring_rest_length": l0, "damper_c": c},
                 "stroke": {"theta0_deg": theta0, "t_max": 2.0},
                 "simulate": {"integrator": integ, "step": step}}
    case = stress.StressCase("random", "random", "", overrides, "any")
    _check_row(case, stress.run_stress_case(case, rerun=False))


# -- regressions: core bugs this survey found (all fixed) ------------------------------------
@stress_mark
def test_reference_peak_in_first_grid_intervals():
    """Regression (found by this survey, fixed in reference.py): d|v_T|/dt is NaN at rest, so a
    tip-speed peak in the first two grid intervals (c = 1e6 N s/m: at t = 2.3 ms) was not
    refined; the reference returned 0.0026377940 m/s, the converged value is 0.0026378194."""
    cfg = default_config().replace(design={"damper_c": 1e6})
    model = LidModel.from_config(cfg)
    r = Reference(model).simulate()
    fine = Simulator.from_config(cfg, model=model, integrator="radau5", step=1e-5).run(estimate_error=False)
    assert abs(r.peak_tip_speed - fine.peak_tip_speed) <= 1e-8 * fine.peak_tip_speed


@stress_mark
def test_near_toggle_result_is_accurate_or_flagged():
    geo = stress.geometry_with_assembly(crank_bc=0.0925)
    cfg = default_config().replace(geometry=geo, stroke={"theta_closed_deg": -2.4})
    model = LidModel.from_config(cfg)
    res = Simulator.from_config(cfg, model=model, step=1e-4).run()
    ref = Reference(model).simulate()
    if res.ok:
        assert abs(res.closing_time - ref.closing_time) <= 1e-7
        assert abs(res.impact_theta_dot - ref.impact_theta_dot) <= 1e-6
    else:
        assert "toggle" in res.message


def test_toggle_inside_stroke_is_a_config_error():
    geo = stress.geometry_with_assembly(crank_bc=0.0935)
    with pytest.raises(ConfigError, match="toggle"):
        LidModel.from_config(default_config().replace(geometry=geo))


@stress_mark
def test_no_nan_in_batch_of_extreme_designs():
    """A batch across the extremes: every row has a status; metrics finite or NaN only where
    the status says the stroke did not close."""
    cfg = default_config()
    sim = Simulator.from_config(cfg)
    P = np.array([[k, l0, c, 0.0] for k in (0.0, 1e3, 1e6) for l0 in (0.02, 0.12)
                  for c in (0.0, 1e3, 1e6)])
    b = sim.run_batch(P, threads=1)
    for i in range(len(P)):
        if b["status"][i] == 0:
            assert all(math.isfinite(b[k][i]) for k in ("closing_time", "impact_theta_dot",
                                                        "impact_tip_speed", "peak_tip_speed"))


@stress_mark
def test_recommended_step_for_rotary_damper_works():
    cfg = default_config().replace(design={"rotary_damper_c": 1e3})
    sim = Simulator.from_config(cfg)
    res = sim.run()
    assert res.status.text == "unstable"
    h = stress.recommended_step(res.message)
    assert h is not None
    again = Simulator.from_config(cfg, model=sim.model, step=h).run()
    assert again.ok, again.message


def test_confirm_uses_the_targets_and_the_estimate():
    """confirm(): a stroke equal to the reference passes; one moved by 2x the closing_time
    target fails, unless its own error estimate covers the move (4x the estimate)."""
    import dataclasses

    from softclose.problem import TARGETS
    cfg = default_config()
    model = LidModel.from_config(cfg)
    ref = Reference(model).simulate()
    same = dataclasses.replace(ref, method="rk4", accuracy=None)
    ok, err, allowed = stress.confirm(same, ref)
    assert ok and err["closing_time"] == 0.0
    moved = dataclasses.replace(same, closing_time=ref.closing_time + 2 * TARGETS["closing_time"])
    ok, err, allowed = stress.confirm(moved, ref)
    assert not ok
    assert err["closing_time"] == pytest.approx(2 * TARGETS["closing_time"], rel=1e-6)
    covered = dataclasses.replace(moved, accuracy={"closing_time": TARGETS["closing_time"]})
    assert stress.confirm(covered, ref)[0]
    # a relative target: peak_tip_speed moved by 2e-6 relative fails
    rel = dataclasses.replace(same, peak_tip_speed=ref.peak_tip_speed * (1 + 2e-6))
    ok, err, _ = stress.confirm(rel, ref)
    assert not ok and err["peak_tip_speed"] == pytest.approx(2e-6, rel=1e-6)
    # closed against not closed is never confirmed
    assert not stress.confirm(dataclasses.replace(same, closed=False), ref)[0]


@stress_mark
def test_reference_near_a_toggle_neither_grinds_nor_raises_a_traceback():
    """Regression (CI of 8f31760): the reference runs CVODES on through 16 grid nodes a call;
    near the rim such a run went on past it towards the toggle position, where the equation
    is NaN, and ground for 80 s shrinking its steps. It now stops within CHUNK_MAX_STEPS and
    the stroke goes on node by node; a single flow that fails is a NumericalError (exit code
    3 with its message), never a bare RuntimeError of CVODES."""
    import time
    from softclose.errors import NumericalError
    from softclose.simulation.reference import CHUNK_MAX_STEPS
    geo = stress.geometry_with_assembly(crank_bc=0.0925)
    cfg = default_config().replace(geometry=geo, stroke={"theta_closed_deg": -2.4})
    ref = Reference(LidModel.from_config(cfg))
    t0 = time.process_time()
    r = ref.simulate()
    assert time.process_time() - t0 < 10.0          # 80 s of CPU before the fix
    assert r.closed and abs(r.closing_time - 0.169856) < 1e-5
    assert CHUNK_MAX_STEPS >= 1000                  # a chunk of a stroke takes ~70-120
    with pytest.raises(NumericalError, match="reference integrator"):
        ref.flow(np.array([math.radians(-2.3), -3.0]), ref.model.params(), 0.5)


def test_reference_judges_a_spring_out_of_range_everywhere_without_integrating():
    """Regression (fuzz, CI of 8f31760): a lid point 14 m away makes the compression spring
    longer than its free length at every angle; such a lid oscillates wildly (every turn an
    event of the reference: 13 s a stroke). The design is invalid whatever the stroke does,
    and the reference says so at once, with the reason the kernel gives."""
    cfg = default_config().update({"mass.crank_bc": 1e-4, "geometry.lid_e": [-10.0, -10.0],
                                   "design.spring_kind": "compression", "design.spring_k": 2000.0,
                                   "design.spring_rest_length": 0.057,
                                   "design.damper_c": 3000.0})
    ref = Reference(LidModel.from_config(cfg)).simulate()
    fixed = Simulator.from_config(cfg).run(estimate_error=False)
    assert ref.status == fixed.status == StrokeStatus.OUT_OF_RANGE
    assert "over the whole stroke" in ref.reason
    assert ref.reason.split(", by up to")[0] == fixed.reason.split(", by up to")[0]
