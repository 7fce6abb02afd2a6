"""The end of life (SPEC §17): ``[life]`` says what changes by the end of a lid's life; a
stroke in ``life.state = "end_of_life"`` sees a gas strut's force x (1 - loss), a coil
spring relaxed (the force it holds shut lost at every length, its rate unchanged), every
damper x (1 + change) and the friction x (1 + change). Each factor's stroke is the stroke of
the new lid with the changed part values written by hand in its config (a second
formulation): the same in the kernel, within 1e-9 s in the adaptive reference; the defaults
change nothing; the kernel's structure is the new lid's."""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import casadi as ca
import numpy as np
import pytest

from softclose import LidModel, Reference, Simulator
from softclose.config import default_config, load_config
from softclose.errors import ConfigError
from softclose.model.lid import model_key
from softclose.model.life import aged, at_end_of_life, shut_coordinates
from softclose.model.resolved import Life
from softclose.problem import params_of, resolve

ROOT = Path(__file__).resolve().parents[1]
#: a spring and every damper and friction, so every law is exercised
DESIGN = {"design.spring_k": 1500.0, "design.spring_rest_length": 0.07,
          "design.damper_c": 600.0, "design.rotary_damper_c": 0.02,
          "design.end_damper_c": 0.5, "design.end_damper_angle_deg": 6.0,
          "friction.torque": 0.02}
CHEST = ROOT / "examples" / "lids" / "chest_lid.toml"


def lid(**values):
    return default_config().update({**DESIGN, **values})


def old(cfg, **life):
    """``cfg`` at the end of life with the factors ``life``."""
    return cfg.update({"life.state": "end_of_life", **{f"life.{k}": v for k, v in life.items()}})


def spring_shut(cfg) -> float:
    """The spring's length at the shut angle, from the lid's pose (its point E on the lid and
    the anchor D), not from the element's coordinate."""
    model = LidModel.from_config(cfg)
    E = np.asarray(model.kin(ca.vertcat(cfg.stroke.theta_closed, 0.0))[7]).ravel()
    return float(np.hypot(*(np.asarray(cfg.geometry.spring_anchor) - E)))


def agree(aged_cfg, hand_cfg, t_tol=1e-9):
    """The aged stroke and the hand-written one: the kernel's the same (to rounding), the
    reference's within ``t_tol`` s, the kernel within its accuracy of the reference; both
    close, and the hand force and holding moment are the same."""
    a = Simulator.from_config(aged_cfg).run()
    b = Simulator.from_config(hand_cfg).run()
    assert a.closed and b.closed, (a.message, b.message)
    assert a.closing_time == pytest.approx(b.closing_time, rel=1e-12, abs=1e-13)
    assert a.impact_tip_speed == pytest.approx(b.impact_tip_speed, rel=1e-11)
    assert a.holding_moment == pytest.approx(b.holding_moment, rel=1e-11, abs=1e-13)
    ra = Reference.from_config(aged_cfg).simulate()
    rb = Reference.from_config(hand_cfg).simulate()
    assert abs(ra.closing_time - rb.closing_time) <= t_tol
    assert abs(ra.impact_theta_dot - rb.impact_theta_dot) <= 1e-8
    assert abs(a.closing_time - ra.closing_time) <= 10 * a.accuracy["closing_time"] + 1e-9
    A = Simulator.from_config(aged_cfg).run_batch(params_of(aged_cfg)[None, :])
    assert A["closing_time"][0] == a.closing_time
    return a, ra


def test_the_defaults_change_nothing():
    cfg = lid()
    assert resolve(cfg).life == Life() and not aged(resolve(cfg).life)
    same = old(cfg)          # end of life with nothing changed: the new lid
    assert not aged(resolve(same).life)
    assert Simulator.from_config(same).run().closing_time == \
        Simulator.from_config(cfg).run().closing_time
    p = params_of(cfg)
    assert at_end_of_life(p, Life(damper_change=-0.5), None) is p        # state new


def test_dampers_and_friction_change_by_their_factors():
    cfg = lid()
    a, _ = agree(old(cfg, damper_change=-0.15, friction_change=0.3),
                 cfg.update({"design.damper_c": 600.0 * 0.85,
                             "design.rotary_damper_c": 0.02 * 0.85,
                             "design.end_damper_c": 0.5 * 0.85,
                             "friction.torque": 0.02 * 1.3}))
    assert a.closing_time < Simulator.from_config(cfg).run().closing_time   # faded: faster


@pytest.mark.parametrize("kind, l0, preload, r", [
    ("compression", 0.075, 3.0, 0.03),       # the loss comes off the preload
    ("compression", 0.075, 0.2, 0.05),       # beyond the preload: the free length moves
    ("extension", 0.05, 2.0, 0.03),
    ("linear", 0.07, 0.0, 0.03),
])
def test_a_relaxed_coil_spring_loses_its_shut_force_at_every_length(kind, l0, preload, r):
    cfg = lid(**{"design.spring_kind": kind, "design.spring_rest_length": l0,
                 "design.spring_preload": preload})
    k, ls = 1500.0, spring_shut(cfg)
    s = {"linear": 0.0, "extension": 1.0, "compression": -1.0}[kind]
    held = s * preload + k * (ls - l0)          # the tension it holds shut
    loss = r * held
    if kind == "linear":
        hand = {"design.spring_rest_length": l0 + loss / k}
    else:
        off = min(s * loss, preload)              # off the preload first, then the length
        hand = {"design.spring_preload": preload - off,
                "design.spring_rest_length": l0 + (loss - s * off) / k}
    new_force = lambda l, pre, length: s * pre + k * (l - length)  # noqa: E731
    # the force at the shut length lost r of itself, the rate unchanged
    assert new_force(ls, hand.get("design.spring_preload", preload),
                     hand["design.spring_rest_length"]) == pytest.approx((1 - r) * held,
                                                                         rel=1e-12)
    agree(old(cfg, spring_relaxation=r), cfg.update(hand))


def test_a_relaxed_torsion_spring_loses_its_shut_moment():
    cfg = lid(**{"design.torsion_k": 0.05, "design.torsion_free_angle_deg": 90.0})
    model = LidModel.from_config(cfg)
    q_shut = shut_coordinates(model)["torsion"]
    phi = model.closure(cfg.stroke.theta_closed)[0]      # pivot O: psi = phi
    assert math.remainder(q_shut - phi, 2 * math.pi) == pytest.approx(0.0, abs=1e-12)
    r = 0.04       # (psi measured as geometry.assembly gives the cranks)
    free = math.radians(90.0) + r * (q_shut - math.radians(90.0))
    ls = spring_shut(cfg)                 # (the spring on E relaxes with it)
    agree(old(cfg, spring_relaxation=r),
          cfg.update({"design.torsion_free_angle_deg": math.degrees(free),
                      "design.spring_rest_length": 0.07 + r * (ls - 0.07)}))


def test_a_gas_struts_force_curve_loses_its_loss_on_a_hinge_lid():
    cfg = load_config(CHEST)
    F1 = cfg.design.spring_preload
    a, _ = agree(old(cfg, strut_force_loss=0.10, spring_relaxation=0.03),
                 cfg.update({"design.spring_preload": F1 * 0.9}))
    # a weaker strut: the lid falls faster
    assert a.closing_time < Simulator.from_config(cfg).run().closing_time
    both = old(cfg, strut_force_loss=0.10, damper_change=-0.15, friction_change=-0.2)
    agree(both, cfg.update({"design.spring_preload": F1 * 0.9,
                            "design.damper_c": cfg.design.damper_c * 0.85,
                            "design.strut_friction": cfg.design.strut_friction * 0.8}))


def test_end_of_life_and_temperature_commute():
    """The temperature scales a coil spring's rate and preload alike; a relaxed spring's
    free length does not move with it: aged, then moved to T, is moved, then aged."""
    cfg = lid(**{"design.spring_kind": "compression", "design.spring_rest_length": 0.075,
                 "design.spring_preload": 3.0, "design.damper_temperature_coeff": -0.005})
    cold = cfg.update({"operating.temperature_c": -10.0})
    aged_cold = old(cold, spring_relaxation=0.03, damper_change=-0.1)
    case = resolve(aged_cold)
    from softclose.model.temperature import at_temperature, parameter_factors
    shut = shut_coordinates(LidModel.from_config(cfg))
    f = parameter_factors(case.temperatures)
    one = at_temperature(at_end_of_life(case.p, case.life, shut), f)
    # the other order: the temperature first, then the loss of the (cold) shut force
    T = at_temperature(case.p, f)
    two = at_end_of_life(T, case.life, shut)
    assert np.allclose(one, two, rtol=1e-13, atol=1e-15)


def test_the_kernel_and_the_model_are_the_new_lids():
    """Aging moves parameter values only: the same model (its cache key), table and kernel
    rows of the same width -- the kernel's work per stroke is the new lid's."""
    from softclose.simulation.kernel import binding
    cfg = lid()
    eol = old(cfg, spring_relaxation=0.03, damper_change=-0.15, friction_change=0.1)
    assert model_key(resolve(eol)) == model_key(resolve(cfg))
    s_new, s_old = Simulator.from_config(cfg), Simulator.from_config(eol)
    P = np.tile(params_of(cfg), (4, 1))
    Pold = at_end_of_life(P, resolve(eol).life, shut_coordinates(s_new.model))
    assert binding.kernel_rows(Pold).shape == binding.kernel_rows(P).shape
    a = s_old.run_batch(P)
    b = s_new.run_batch(Pold)
    assert np.array_equal(a["closing_time"], b["closing_time"])
    # a row with its own attachment points relaxes at its own shut length
    pts = {"geometry.spring_anchor[0]": [-0.060, -0.058]}
    got = s_old.run_batch(P[:2], points=pts)["closing_time"]
    moved = Simulator.from_config(old(cfg.update({"geometry.spring_anchor[0]": -0.058}),
                                      spring_relaxation=0.03, damper_change=-0.15,
                                      friction_change=0.1)).run().closing_time
    assert got[0] == a["closing_time"][0]
    assert got[1] == pytest.approx(moved, abs=1e-9)


def test_the_state_command_sees_the_old_parts():
    import softclose
    cfg = lid(**{"design.spring_kind": "compression", "design.spring_rest_length": 0.075,
                 "design.spring_preload": 3.0})
    eol = old(cfg, spring_relaxation=0.05, damper_change=-0.2)
    a = softclose.state(eol, 10.0, -1.0).to_json()
    hand = resolve(eol)
    p = at_end_of_life(hand.p, hand.life, shut_coordinates(LidModel.from_config(cfg)))
    b = LidModel.from_config(cfg).state(math.radians(10.0), -1.0, p)
    assert a["theta_ddot"] == pytest.approx(b["theta_ddot"], rel=1e-12)
    assert a["theta_ddot"] != softclose.state(cfg, 10.0, -1.0).to_json()["theta_ddot"]


@pytest.mark.parametrize("key, value, says", [
    ("life.strut_force_loss", 1.0, "admissible range"),
    ("life.strut_force_loss", -0.1, "negative"),
    ("life.spring_relaxation", 1.5, ""), ("life.damper_change", -1.0, "admissible range"),
    ("life.friction_change", -2.0, ""), ("life.state", "old", "new, end_of_life"),
    ("life.state", 1, ""), ("life.nonsense", 0.1, "")])
def test_bad_life_values_are_refused_in_one_line(key, value, says):
    with pytest.raises(ConfigError, match=rf"^{re_key(key)}") as e:
        default_config().update({key: value})
    assert says in str(e.value) and "\n" not in str(e.value)


def re_key(key):
    return key.replace(".", r"\.") if "nonsense" not in key else r".*life"


def test_the_optimiser_designs_the_new_parts():
    from softclose.optimiser import optimise
    with pytest.raises(ConfigError, match=r"^life\.state: the optimiser designs with the new"):
        optimise(old(lid(), damper_change=-0.15))
    r = subprocess.run([sys.executable, "-m", "softclose", "optimise", "--set",
                        "life.state=end_of_life", "--set", "life.damper_change=-0.1"],
                       capture_output=True, text=True, cwd=ROOT)
    assert r.returncode == 2 and r.stderr.count("\n") == 1 and "life.state" in r.stderr


def test_the_spring_made_to_order_is_checked_at_its_relaxed_free_length():
    """A compression spring relaxed by r loses r of its shut force k (L0 - l_shut): its free
    length is (1 - r) L0 + r l_shut, and softclose spring checks it there."""
    from softclose.optimiser.spring_order import spring_duty
    cfg = lid(**{"design.spring_kind": "compression", "design.spring_rest_length": 0.075,
                 "design.spring_preload": 0.0})
    new, ls = spring_duty(cfg), spring_shut(cfg)
    r = 0.03
    aged_duty = spring_duty(old(cfg, spring_relaxation=r))
    assert new.free_length == pytest.approx(0.075, rel=1e-12)
    assert aged_duty.free_length == pytest.approx((1 - r) * 0.075 + r * ls, rel=1e-12)
    assert aged_duty.rate == new.rate and aged_duty.shortest_length == new.shortest_length
    # with a preload the free length L0 + F0/k shortens by the loss over the rate
    pre = cfg.update({"design.spring_preload": 3.0})
    free = 0.075 + 3.0 / 1500.0
    assert spring_duty(old(pre, spring_relaxation=r)).free_length == pytest.approx(
        free - r * (free - ls), rel=1e-12)
