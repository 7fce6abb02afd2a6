"""Springs one can buy: extension (pulls, initial tension), compression or gas strut (pushes,
preload), against independent formulations, and their valid ranges.

The law T = s F0 + k (l - l0) (s = +1 extension, -1 compression, 0 the seed's linear element)
is checked against the three-body absolute-coordinate model and Newton-Euler, its potential
against an independent closure, the energy balance in the model and along kernel strokes, and
kernel strokes against the adaptive reference. A stroke that takes a spring past its free
length (or its length limits) is an invalid design: simulate says where and by how much (exit
2 on the command line), a sweep row says it, and the reference agrees.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import softclose
from conftest import (assert_formulations_agree, assert_potential, energy_rate, np_closure,
                      uniform_states)
from softclose.cli import main
from softclose.config import default_config
from softclose.model.lid import LidModel
from softclose.problem import PARAM_KEYS, TARGETS, resolve
from softclose.simulation.reference import Reference
from softclose.simulation.simulator import Simulator
from softclose.simulation.stroke import StrokeStatus
from softclose.validation.textbook.lid_absolute import read_parameters

#: a compression spring (gas strut) that stays shorter than its free length over the stroke
#: (l runs 52.3..58.4 mm on the default geometry), and an extension spring that stays longer
#: than its (here shorter) free length
COMPRESSION = {"spring_kind": "compression", "spring_preload": 25.0, "spring_k": 1500.0,
               "spring_rest_length": 0.065, "damper_c": 1500.0}
EXTENSION = {"spring_kind": "extension", "spring_preload": 8.0, "spring_k": 900.0,
             "spring_rest_length": 0.045, "damper_c": 1500.0,
             "spring_anchor": None}


def cfg_of(design: dict):
    values = {f"design.{k}": v for k, v in design.items() if k != "spring_anchor"}
    return default_config().update(values)


@pytest.fixture(scope="module", params=["compression", "extension"])
def case(request):
    cfg = cfg_of(COMPRESSION if request.param == "compression" else EXTENSION)
    model = LidModel.from_config(cfg)
    return request.param, cfg, model


def test_three_formulations_agree_with_a_preload(case):
    _, cfg, model = case
    p = model.params()
    absolute = read_parameters(cfg)
    assert absolute.F == pytest.approx(
        (1.0 if cfg.design.spring_kind == "extension" else -1.0) * cfg.design.spring_preload)
    assert_formulations_agree(model, absolute, p, uniform_states(model, 10, 7, (-5, 3)))


def test_potential_and_holding_moment_against_an_independent_closure(case):
    """V = Vg + 1/2 k (l - l0)^2 + s F0 l from a numpy closure; dV/dtheta by differences
    equals the model's and the table's slope, and the holding moment."""
    kind, cfg, model = case
    geo, m, d = cfg.geometry, cfg.mass, cfg.design
    s = 1.0 if kind == "extension" else -1.0
    near = math.radians(geo.assembly[1])

    def V(th):
        phi, gamma = np_closure(th, geo, near)
        A = geo.crank_oa * np.array([math.cos(phi), math.sin(phi)])
        R = np.array([[math.cos(th), -math.sin(th)], [math.sin(th), math.cos(th)]])
        G1, E = A + R @ np.array(geo.lid_g), A + R @ np.array(geo.lid_e)
        G3 = np.array(geo.pivot_b) + 0.5 * geo.crank_bc * np.array([math.cos(gamma),
                                                                     math.sin(gamma)])
        l = float(np.hypot(*(np.array(geo.spring_anchor) - E)))
        return (m.gravity * (m.lid * G1[1] + m.crank_oa * 0.5 * A[1] + m.crank_bc * G3[1])
                + 0.5 * d.spring_k * (l - d.spring_rest_length) ** 2 + s * d.spring_preload * l)

    p = assert_potential(cfg, model, V, (0.0, 0.15, 0.3))
    assert model.holding_moment(p) == pytest.approx(float(model.dV(0.0, p)))


def test_energy_balance_and_the_reference(case):
    _, cfg, model = case
    rate = energy_rate(model)
    p = model.params()
    for th, thd in ((0.05, -1.0), (0.2, -3.0), (0.3, 1.0)):
        dEdt, P = (float(v) for v in rate([th, thd], p))
        assert dEdt == pytest.approx(P, rel=1e-9, abs=1e-12)
    sim = Simulator.from_config(cfg, model=model)
    r, rr = sim.run(p), Reference(model).simulate(p)
    assert r.status is StrokeStatus.CLOSED and rr.status is StrokeStatus.CLOSED
    assert abs(r.closing_time - rr.closing_time) < TARGETS["closing_time"]
    assert abs(r.impact_theta_dot - rr.impact_theta_dot) < TARGETS["impact_theta_dot"]
    assert r.peak_tip_speed == pytest.approx(rr.peak_tip_speed, rel=1e-6)
    # the preload changes the stroke (the test can fail)
    q = p.copy()
    q[PARAM_KEYS.index("spring_preload")] = 0.0
    assert abs(sim.run(q).closing_time - r.closing_time) > 1e-4


def _crossing(cfg, bound):
    """theta (rad) where the spring length l(theta) = bound, by bisection on an independent
    numpy closure (l rises with theta on the default geometry)."""
    geo = cfg.geometry
    near = math.radians(geo.assembly[1])

    def l(th):
        phi, _ = np_closure(th, geo, near)
        A = geo.crank_oa * np.array([math.cos(phi), math.sin(phi)])
        R = np.array([[math.cos(th), -math.sin(th)], [math.sin(th), math.cos(th)]])
        return float(np.hypot(*(np.array(geo.spring_anchor) - A - R @ np.array(geo.lid_e))))
    a, b = 0.0, math.radians(18.0)
    assert (l(a) - bound) * (l(b) - bound) < 0
    for _ in range(60):
        mid = 0.5 * (a + b)
        a, b = (mid, b) if (l(mid) - bound) * (l(a) - bound) > 0 else (a, mid)
    return 0.5 * (a + b)


def test_a_compression_spring_past_its_free_length_is_an_invalid_design():
    """l runs 52.3..58.4 mm: a compression spring of free length 56 mm would have to pull
    above the angle where l = 56 mm. The simulator, the reference and a sweep all say so,
    with the angle (to the 0.05 deg of the report's grid) and the excess (58.43 - 56 mm)."""
    cfg = cfg_of({**COMPRESSION, "spring_rest_length": 0.056})
    r = softclose.simulate(cfg)
    assert r.status is StrokeStatus.OUT_OF_RANGE and not r.ok and r.closing_time is None
    edge = math.degrees(_crossing(cfg, 0.056))
    assert f"above theta = {edge:.1f} deg" in r.message or \
        abs(float(r.message.split("above theta = ")[1].split(" deg")[0]) - edge) <= 0.06
    excess = (r.max_spring_length - 0.056) * 1e3
    assert f"by up to {excess:.2f} mm" in r.message
    assert "compression spring (it only pushes) would be longer than its free length" in \
        r.message
    rr = Reference(LidModel.from_config(cfg)).simulate()
    assert rr.status is StrokeStatus.OUT_OF_RANGE
    assert rr.max_spring_length == pytest.approx(r.max_spring_length, abs=1e-9)
    res = softclose.sweep(cfg, {"design.spring_rest_length": [0.056, 0.0585, 0.065]})
    frame = res.to_frame()
    assert list(frame["status"])[:2] == ["invalid", "closed"]
    assert frame["reason"][0].startswith("the compression spring")
    assert not frame["feasible"][0]


def test_an_extension_spring_shorter_than_its_free_length_and_length_limits():
    cfg = cfg_of({**EXTENSION, "spring_rest_length": 0.055})
    r = softclose.simulate(cfg)
    assert r.status is StrokeStatus.OUT_OF_RANGE
    assert "extension spring (it only pulls) would be shorter than its free length 55.00 mm" \
        in r.message
    edge = math.degrees(_crossing(cfg, 0.055))
    got = float(r.message.split("below theta = ")[1].split(" deg")[0])
    assert abs(got - edge) <= 0.06
    # a valid extension spring with a maximum length it exceeds
    ok = cfg_of(EXTENSION)
    assert softclose.simulate(ok).ok
    r2 = softclose.simulate(ok.set("design.spring_max_length", 0.057))
    assert r2.status is StrokeStatus.OUT_OF_RANGE and "maximum length" in r2.message
    # and a linear cartridge within limits is unaffected by them
    lin = cfg_of({**COMPRESSION, "spring_kind": "linear", "spring_preload": 0.0})
    assert softclose.simulate(lin.set("design.spring_min_length", 0.05)).ok


def test_the_command_line_refuses_an_invalid_design_with_one_line(capsys):
    code = main(["simulate", "--set", 'design.spring_kind="extension"',
                 "--set", "design.spring_k=1000", "--set", "design.spring_rest_length=0.07"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2
    assert len(err) == 1 and "extension spring (it only pulls)" in err[0]


def test_a_preloaded_strut_holds_the_lid_open_at_its_equilibrium():
    """The early exit with a preload in the potential: a strong strut pushes the lid up to
    where gravity and the strut balance; the reason names that angle, where the model's dV
    vanishes (not the table's)."""
    cfg = cfg_of({"spring_kind": "compression", "spring_preload": 60.0, "spring_k": 500.0,
                  "spring_rest_length": 0.07, "damper_c": 300.0})
    sim = Simulator.from_config(cfg)
    p = sim.model.params()
    r = sim.run_batch(p[None, :])
    assert r["status"][0] == 1 and r["stop_reason"][0] == 2
    th = r["stop_theta"][0]
    assert abs(float(sim.model.dV(th, p))) < 1e-8
    assert float(sim.model.dV(th - 1e-4, p)) < 0 < float(sim.model.dV(th + 1e-4, p))
    assert r["stop_time"][0] < cfg.stroke.t_max


def test_a_shared_model_is_checked_against_the_judged_configs_limits():
    """The caches key models by their structure, not by the spring's length limits: a model
    built for a config without limits judges another config's stroke against that config's
    limits when given it (the reference, and the optimiser's verification), as the
    fixed-step simulator does."""
    from softclose.optimiser.verify import verify
    from softclose.problem import params_of
    base = default_config().update({"design.spring_kind": "linear", "design.spring_k": 1914.7,
                                    "design.spring_rest_length": 0.07926,
                                    "design.damper_c": 2087.75})
    limited = base.set("design.spring_max_length", 0.057)
    shared = Reference(LidModel.from_config(base))
    p = params_of(base)
    assert shared.simulate(p).status == StrokeStatus.CLOSED
    ref = shared.simulate(p, resolve(limited))
    fixed = softclose.simulate(limited)
    assert ref.status == fixed.status == StrokeStatus.OUT_OF_RANGE
    assert "maximum length (design.spring_max_length = 57.00 mm)" in ref.reason
    assert ref.reason.split(" above theta")[0] == fixed.reason.split(" above theta")[0]
    design = {"spring_k": 1914.709, "spring_rest_length": 0.07925707, "damper_c": 2087.754}
    assert verify(base, design).ok       # the checker's model is now cached without limits
    v = verify(limited, design)
    assert not v.ok and "valid_range is violated" in v.message and "57.00 mm" in v.message
