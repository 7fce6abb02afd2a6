"""SPEC §15: single-pivot (hinge) lids."""

import pytest

import softclose
from softclose.config import from_dict
from softclose.errors import ConfigError


def test_hinge_keys_and_defaults():
    cfg = from_dict({"geometry": {"mechanism": "hinge"}})
    assert cfg.geometry.mechanism == "hinge"
    assert tuple(cfg.geometry.hinge) == (0.0, 0.0)
    assert from_dict({}).geometry.mechanism == "four_bar"


@pytest.mark.parametrize("section,key,value", [
    ("geometry", "crank_oa", 0.05), ("geometry", "pivot_b", [0.1, 0.0]),
    ("geometry", "assembly", [18.0, 100.0, 140.0]), ("mass", "inertia_bc", 1e-4)])
def test_hinge_refuses_crank_keys(section, key, value):
    raw = {"geometry": {"mechanism": "hinge"}}
    raw.setdefault(section, {})[key] = value
    with pytest.raises(ConfigError) as exc:
        from_dict(raw)
    msg = str(exc.value)
    assert "\n" not in msg and msg.startswith(f"{section}.{key}:")


@pytest.mark.parametrize("spread", ["geometry.crank_bc", "geometry.pivot_b[1]",
                                    "mass.inertia_oa"])
def test_hinge_refuses_a_spread_of_a_crank_key(spread):
    raw = {"geometry": {"mechanism": "hinge"}, "tolerance": {spread: 1e-3, "mass.lid": 0.01}}
    with pytest.raises(ConfigError) as exc:
        from_dict(raw)
    msg = str(exc.value)
    assert "\n" not in msg and msg.startswith(f"tolerance.{spread}:") and "hinge" in msg
    del raw["tolerance"][spread]
    assert from_dict(raw).tolerance        # the lid's own spreads stay


@pytest.mark.parametrize("raw,key", [({"mechanism": "flap"}, "geometry.mechanism"),
                                     ({"mechanism": "hinge", "hinge": [0.0]}, "geometry.hinge"),
                                     ({"mechanism": "hinge", "hinge": [99.0, 0.0]},
                                      "geometry.hinge")])
def test_hinge_bad_values_name_the_key(raw, key):
    with pytest.raises(ConfigError) as exc:
        from_dict({"geometry": raw})
    assert key in str(exc.value) and "\n" not in str(exc.value)


# -- the hinge model against textbook mechanics ----------------------------------------------

import math

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from softclose.model.lid import LidModel
from softclose.model import dynamics as dyn
from softclose.simulation.reference import Reference
from softclose import simulate

#: a chest lid: 2 kg, 0.6 m deep, hinged at (0.1, 0.3), its centre of mass off the lid's line
CHEST = {"geometry": {"mechanism": "hinge", "hinge": [0.1, 0.3], "lid_length": 0.6,
                      "lid_g": [0.3, 0.02], "lid_tip": [0.6, 0.0]},
         "mass": {"lid": 2.0, "inertia_lid": 0.06},
         "stroke": {"theta0_deg": 40.0, "t_max": 2.0},
         "design": {"spring_k": 0.0, "damper_c": 0.0}}
M_LID, I_G, G_X, G_Y, H_Y, GRAV = 2.0, 0.06, 0.3, 0.02, 0.3, 9.81


def _cfg(extra=None, **sections):
    raw = {k: dict(v) for k, v in CHEST.items()}
    for k, v in (extra or {}).items():
        raw.setdefault(k, {}).update(v)
    return from_dict(raw)


def test_compound_pendulum_coefficients():
    """A hinge lid without spring or damper: M = I_G + m |r_G|^2 constant, Vg = m g y_G."""
    model = LidModel.from_config(_cfg())
    i_h = I_G + M_LID * (G_X ** 2 + G_Y ** 2)
    for theta in np.radians([-5.0, 0.0, 17.0, 40.0, 65.0]):
        c, dc = (np.asarray(v).ravel() for v in model.coeffs(theta))
        cf = dict(zip(dyn.COEFFS, c))
        y_g = H_Y + math.sin(theta) * G_X + math.cos(theta) * G_Y
        assert cf["M"] == pytest.approx(i_h, rel=1e-14)
        assert cf["dM"] == pytest.approx(0.0, abs=1e-14)
        assert cf["Vg"] == pytest.approx(M_LID * GRAV * y_g, rel=1e-13)
        assert cf["dVg"] == pytest.approx(
            M_LID * GRAV * (G_X * math.cos(theta) - G_Y * math.sin(theta)), rel=1e-12)
        k = model.kin(np.array([theta, 1.0]))
        assert np.asarray(k[5]).ravel() == pytest.approx([0.1, 0.3], abs=1e-15)  # A = H
        tip = [0.1 + 0.6 * math.cos(theta), 0.3 + 0.6 * math.sin(theta)]
        assert np.asarray(k[8]).ravel() == pytest.approx(tip, abs=1e-14)


def _free_fall_time():
    i_h = I_G + M_LID * (G_X ** 2 + G_Y ** 2)

    def f(t, x):
        th = x[0]
        return [x[1], -M_LID * GRAV * (G_X * math.cos(th) - G_Y * math.sin(th)) / i_h]

    hit = lambda t, x: x[0]  # noqa: E731
    hit.terminal, hit.direction = True, -1
    sol = solve_ivp(f, (0, 2.0), [math.radians(40.0), 0.0], method="DOP853", rtol=1e-13,
                    atol=1e-13, events=hit)
    return float(sol.t_events[0][0]), float(sol.y_events[0][0][1])


def test_free_fall_closing_time_against_solve_ivp():
    t_ref, w_ref = _free_fall_time()
    cfg = _cfg()
    ref = Reference(LidModel.from_config(cfg)).simulate()
    assert ref.closing_time == pytest.approx(t_ref, abs=1e-6)
    assert ref.impact_theta_dot == pytest.approx(w_ref, rel=1e-6)
    # the kernel (rk4) agrees at the method's order: halving the step cuts the error ~16 x
    errs = [abs(simulate(cfg.replace(simulate={**cfg.simulate._asdict(), "step": h})
                         ).closing_time - t_ref) for h in (4e-3, 2e-3)]
    assert errs[1] < 1e-6 and errs[1] < errs[0] / 8


def test_rotary_damper_and_torsion_spring_at_h_linear_oscillator():
    """Without gravity a torsion spring and a rotary damper at H make the linear ODE
    I theta'' + c theta' + k (theta - theta_f) = 0: its closed form gives the closing time."""
    k, c, th_f = 2.0, 0.3, math.radians(-20.0)
    cfg = _cfg({"mass": {"gravity": 0.0},
                "design": {"torsion_k": k, "torsion_free_angle_deg": -20.0,
                           "rotary_damper_c": c, "rotary_damper_pivot": "H"}})
    assert cfg.design.torsion_pivot == "H"
    i_h = I_G + M_LID * (G_X ** 2 + G_Y ** 2)
    wn, zeta = math.sqrt(k / i_h), c / (2 * math.sqrt(k * i_h))
    wd, a0 = wn * math.sqrt(1 - zeta ** 2), math.radians(40.0) - th_f
    theta = lambda t: th_f + a0 * math.exp(-zeta * wn * t) * (  # noqa: E731
        math.cos(wd * t) + zeta * wn / wd * math.sin(wd * t))
    t_close = brentq(theta, 1e-6, math.pi / wd, xtol=1e-15)
    ref = Reference(LidModel.from_config(cfg)).simulate()
    assert ref.closing_time == pytest.approx(t_close, abs=1e-6)
    # the rotary damper on the lid's own rotation is the same damper for a hinge lid
    cfg_lid = _cfg({"mass": {"gravity": 0.0},
                    "design": {"torsion_k": k, "torsion_free_angle_deg": -20.0,
                               "rotary_damper_c": c, "rotary_damper_pivot": "lid"}})
    assert simulate(cfg_lid).closing_time == pytest.approx(simulate(cfg).closing_time,
                                                           abs=1e-12)


# -- commands on a hinge lid -----------------------------------------------------------------

import json
import os
import subprocess
import sys
from pathlib import Path

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "lids" / "chest_lid.toml"


def _cli(*args):
    out = subprocess.run([sys.executable, "-m", "softclose", *args], capture_output=True,
                         text=True, env=os.environ.copy(), timeout=600)
    return out.returncode, out.stdout, out.stderr


def test_optimise_hinge_chest_lid_is_verified():
    rc, out, err = _cli("optimise", "--config", str(EXAMPLE), "--json")
    assert rc == 0, err
    res = json.loads(out)
    assert res["success"] and res["verification"]["ok"] and res["closed"]
    # a gas strut (the example's), its force F1 chosen with the opening force at its bound
    assert res["kind"] == "gas_strut"
    assert res["objective"] == pytest.approx(1.0194747, rel=1e-5)
    assert res["closing_time"] == pytest.approx(1.0, abs=1e-6)
    assert res["opening_force"] == pytest.approx(8.0, abs=1e-6)
    assert res["design"]["spring_preload"] == pytest.approx(77.0436, rel=1e-4)
    assert res["min_spring_length"] == pytest.approx(math.hypot(0.06, 0.07), rel=1e-9)
    # the strut spans exactly the stroke's lengths: extended at the open lid
    assert res["design"]["spring_rest_length"] == pytest.approx(res["max_spring_length"],
                                                                rel=1e-9)


def test_cli_refuses_crank_key_on_hinge_in_one_line():
    rc, out, err = _cli("simulate", "--config", str(EXAMPLE), "--set", "geometry.crank_bc=0.1")
    assert rc == 2 and len(err.strip().splitlines()) == 1 and "geometry.crank_bc" in err


def test_four_bar_default_unchanged():
    rc, out, err = _cli("optimise", "--json")
    assert rc == 0, err
    # to the last bits Ipopt's answer depends on the machine's floating point (BLAS, MUMPS)
    assert json.loads(out)["objective"] == pytest.approx(0.02289949029239926, rel=1e-13)


def test_newton_euler_hinge_reaction():
    """At rest at theta the hinge carries m (a_G + g y): a_G = theta'' z x R(theta) r_G."""
    model = LidModel.from_config(_cfg())
    theta = math.radians(30.0)
    s = model.state(theta, 0.0)
    i_h = I_G + M_LID * (G_X ** 2 + G_Y ** 2)
    tdd = -M_LID * GRAV * (G_X * math.cos(theta) - G_Y * math.sin(theta)) / i_h
    assert s["theta_ddot"] == pytest.approx(tdd, rel=1e-12)
    r = (G_X * math.cos(theta) - G_Y * math.sin(theta), G_X * math.sin(theta) + G_Y * math.cos(theta))
    R = [M_LID * tdd * -r[1], M_LID * tdd * r[0] + M_LID * GRAV]
    assert list(s["reactions"]) == ["H"]          # a hinge lid's one reaction: the hinge's
    assert s["reactions"]["H"] == pytest.approx(R, rel=1e-12)
    assert (s["phi"], s["gamma"], s["phi_dot"], s["gamma_dot"]) == (None, None, None, None)
    assert softclose.state(_cfg(), 30.0).to_json() == s


def test_hinge_config_file_round_trip(tmp_path):
    """A written hinge config (e.g. optimise --out's design.toml) loads back: no crank keys."""
    from softclose.config import load_config, to_toml
    cfg = _cfg({"design": {"torsion_k": 1.5}})
    path = tmp_path / "design.toml"
    path.write_text(to_toml(cfg))
    back = load_config(path)
    for section in ("geometry", "mass", "design", "stroke"):
        assert getattr(back, section) == getattr(cfg, section)


def test_state_on_a_hinge_gives_the_hinge_reaction_of_the_textbook(tmp_path, capsys):
    """``softclose state`` on a bare hinge lid at rest: theta'' from the moment about H,
    I_H theta'' = (r_G x m g), and the one reaction R_H = m (a_G - g); no crank angles."""
    from softclose.cli import main
    cfg = tmp_path / "hinge.toml"
    cfg.write_text('[geometry]\nmechanism = "hinge"\n')
    assert main(["state", "--config", str(cfg), "--theta-deg", "40", "--json"]) == 0
    s = json.loads(capsys.readouterr().out)
    c = from_dict({"geometry": {"mechanism": "hinge"}})
    m, ig, (gx, gy), g = c.mass.lid, c.mass.inertia_lid, c.geometry.lid_g, 9.81
    th = math.radians(40.0)
    r = np.array([gx * math.cos(th) - gy * math.sin(th), gx * math.sin(th) + gy * math.cos(th)])
    i_h = ig + m * (r @ r)
    tdd = m * (r[0] * -g) / i_h                  # (r x m g)_z with g = (0, -g)
    a_g = tdd * np.array([-r[1], r[0]])           # at rest: the tangential part only
    assert s["theta_ddot"] == pytest.approx(tdd, rel=1e-9)
    assert list(s["reactions"]) == ["H"] and s["phi"] is None and s["gamma"] is None
    np.testing.assert_allclose(s["reactions"]["H"], m * (a_g - np.array([0.0, -g])),
                               rtol=1e-9, atol=1e-12)


def test_the_parts_page_quotes_the_chest_lids_gas_strut():
    """docs/parts.md quotes the part line of the chest lid's optimum: it is the command's."""
    import softclose
    from softclose import load_config
    res = softclose.optimise(load_config(EXAMPLE))
    line = res.part.text().splitlines()[0]
    assert line.startswith("gas strut (pushes): extended length 132.72 mm")
    page = (Path(__file__).resolve().parents[1] / "docs" / "parts.md").read_text()
    assert f"  to buy: {line}\n" in page


def test_fit_recovers_the_toilet_seats_damper_from_a_recorded_stroke(tmp_path):
    """`softclose fit` on a hinge lid: a stroke of the toilet seat (its rotary damper 2.5 N m
    s/rad at the hinge) sampled at 50 Hz with 0.2 deg of noise gives the damper back within
    its 95 % interval."""
    import numpy as np
    from softclose import Simulator, load_config
    seat = EXAMPLE.parent / "toilet_seat.toml"
    r = Simulator.from_config(load_config(seat)).run(trajectory=True)
    t = np.arange(0.0, r.closing_time + 0.5, 0.02)
    th = np.degrees(np.interp(t, r.trajectory["t"], r.trajectory["theta"]))
    th[t > r.closing_time] = 0.0
    th += np.random.default_rng(1).normal(0.0, 0.2, len(t))
    data = tmp_path / "seat.csv"
    data.write_text("time_s,theta_deg\n" + "".join(f"{a:.4f},{b:.5f}\n" for a, b in zip(t, th)))
    rc, out, err = _cli("fit", str(data), "--config", str(seat), "--free",
                        "design.rotary_damper_c", "--json")
    assert rc == 0, err
    p = json.loads(out)["parameters"]["design.rotary_damper_c"]
    lo, hi = p["ci95"]
    assert lo <= 2.5 <= hi and hi - lo < 0.02


def test_pareto_defaults_follow_the_lids_closing_time_window():
    """The default closing times scale with optimise.closing_time_max and start above
    closing_time_min: the default lid's 0.3..3 s, the toilet seat's (5-8 s) 5.25..24 s."""
    from softclose import default_config, load_config
    from softclose.optimiser.pareto import PARETO_DEFAULT, default_closing_times
    assert default_closing_times(default_config()) == PARETO_DEFAULT
    assert default_closing_times(load_config(EXAMPLE.parent / "toilet_seat.toml")) == \
        "5.25:24:10:log"
