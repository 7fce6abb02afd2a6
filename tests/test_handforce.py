"""The hand force and the zones of a lid (SPEC §13): against a hand computation from the
model's closure, the zones' edges against |dV/dtheta| = T_fr, and the energy balance."""

import math

import casadi as ca
import numpy as np
import pytest
from scipy.integrate import simpson

from softclose.config import ConfigError, from_dict
from softclose.model.lid import LidModel
from softclose.simulation import statics
from softclose.problem import params_of, resolve
from softclose.simulation.handforce import HandForce, hand_force


def _lid(cfg):
    return LidModel.from_config(cfg, cached=True), cfg


#: a torsion spring at A that nearly balances gravity: it closes by itself low down, rises
#: by itself high up, and with friction holds open between
BALANCED = {"design": {"torsion_k": 0.1, "torsion_free_angle_deg": 300, "torsion_pivot": "A"},
            "stroke": {"theta_open_deg": 80}}


def _hand_V(m, cfg, theta):
    """V (J) of gravity alone from the closure's points: m1 g y_G1 + m2 g y_mid(OA) +
    m3 g y_mid(BC), O at the origin."""
    k = m.kin(ca.vertcat(theta, 0.0))
    A, C, G1 = (np.asarray(k[i]).ravel() for i in (5, 6, 9))
    B = np.asarray(cfg.geometry.pivot_b, float)
    ms, g = cfg.mass, cfg.mass.gravity
    return g * (ms.lid * G1[1] + ms.crank_oa * A[1] / 2 + ms.crank_bc * (B[1] + C[1]) / 2)


def _hand_tau(m, theta, h=1e-6):
    T = lambda t: np.asarray(m.kin(ca.vertcat(t, 0.0))[8]).ravel()      # noqa: E731
    return float(np.linalg.norm((T(theta + h) - T(theta - h)) / (2 * h)))


def test_no_spring_against_a_hand_computation():
    m, cfg = _lid(from_dict({}))
    hf = hand_force(m, case=resolve(cfg))
    assert isinstance(hf, HandForce)
    for deg in (0.0, 4.5, 13.5, 18.0):          # (on the 2001-point grid)
        th, h = math.radians(deg), 1e-5
        dV = (_hand_V(m, cfg, th + h) - _hand_V(m, cfg, th - h)) / (2 * h)
        i = int(np.argmin(np.abs(np.asarray(hf.theta_deg) - deg)))
        assert hf.theta_deg[i] == pytest.approx(deg, abs=1e-9)
        assert hf.slope[i] == pytest.approx(dV, rel=1e-7)
        assert hf.f_open[i] == pytest.approx(dV / _hand_tau(m, th), rel=1e-6)
        assert hf.f_close[i] == hf.f_open[i]          # no friction
    # a lid without a spring closes by itself everywhere
    assert hf.self_close_deg == 18.0 and hf.self_rise_deg is None and hf.hold_open == ()
    assert hf.closing_force == 0.0
    # the §9 opening force, the same number
    assert hf.opening_force == statics.opening_force_exact(m, params_of(cfg))
    assert hf.opening_force == pytest.approx(2.5492138071830834, rel=1e-12)
    assert hf.metrics() == {"opening_force": hf.opening_force, "closing_force": 0.0,
                            "self_close_deg": 18.0, "self_rise_deg": None, "hold_open": []}
    with pytest.raises(Exception):
        hf.opening_force = 1.0                        # frozen
    fr = hf.to_frame()
    assert len(fr) == len(hf.theta_deg) and {"f_open", "f_close"} <= set(fr.columns)
    assert hf.to_json()["zones"] == [{"zone": "self_close", "lo_deg": 0.0, "hi_deg": 18.0}]


def test_zones_of_a_balanced_lid_and_their_edges():
    cfg = from_dict(dict(BALANCED, friction={"torque": 0.05}))
    m = LidModel.from_config(cfg, cached=True)
    p = params_of(cfg)
    hf = hand_force(m, case=resolve(cfg))
    assert [z for z, _, _ in hf.zones] == ["self_close", "hold_open", "self_rise"]
    assert hf.self_close_deg == pytest.approx(31.912041430086095, abs=1e-6)
    assert hf.self_rise_deg == pytest.approx(46.63944172617751, abs=1e-6)
    assert hf.hold_open == ((hf.self_close_deg, hf.self_rise_deg),)
    # the edges to root accuracy: dV/dtheta = +T_fr at the lower, -T_fr at the upper
    lo, hi = hf.hold_open[0]
    assert float(m.dV(math.radians(lo), p)) - 0.05 == pytest.approx(0.0, abs=1e-9)
    assert float(m.dV(math.radians(hi), p)) + 0.05 == pytest.approx(0.0, abs=1e-9)
    assert set(np.round(hf.friction, 12)) == {0.05}
    assert hf.closing_force == pytest.approx(1.0679116598226026, rel=1e-6)
    assert hf.opening_force > 0 and hf.closing_force > 0
    # without friction the hold-open band shrinks to one edge
    hf0 = hand_force(m, case=resolve(from_dict(BALANCED)))
    assert hf0.hold_open == () and hf0.self_close_deg == hf0.self_rise_deg
    assert hf0.self_close_deg == pytest.approx(40.453669153446036, abs=1e-6)
    assert float(m.dV(math.radians(hf0.self_close_deg), params_of(from_dict(BALANCED)))) \
        == pytest.approx(0.0, abs=1e-9)


def test_a_strong_spring_rises_by_itself():
    cfg = from_dict({"design": {"torsion_k": 0.5, "torsion_free_angle_deg": 90,
                                "torsion_pivot": "A"}, "stroke": {"theta_open_deg": 60}})
    hf = hand_force(LidModel.from_config(cfg, cached=True), case=resolve(cfg))
    assert hf.self_rise_deg == 0.0 and hf.self_close_deg is None and hf.hold_open == ()
    assert max(hf.f_close) < 0 and hf.closing_force == pytest.approx(-min(hf.f_close),
                                                                     rel=1e-6)


@pytest.mark.parametrize("conf", [{}, BALANCED])
def test_energy_balance(conf):
    cfg = from_dict(conf)
    m = LidModel.from_config(cfg, cached=True)
    p = params_of(cfg)
    hf = hand_force(m, case=resolve(cfg))
    th = np.radians(hf.theta_deg)
    work = simpson(np.asarray(hf.f_close) * np.asarray(hf.lever), x=th)
    V = lambda t: float(m.energy_fn(ca.vertcat(t, 0.0), p))        # noqa: E731
    assert work == pytest.approx(V(th[-1]) - V(th[0]), rel=1e-9, abs=1e-12)


@pytest.mark.parametrize("key,value", [("stroke.theta_open_deg", -5.0),
                                       ("stroke.theta_open_deg", "x"),
                                       ("optimise.self_close_min_deg", "x")])
def test_bad_input_names_the_key(key, value):
    sec, name = key.split(".")
    with pytest.raises(ConfigError) as e:
        from_dict({sec: {name: value}})
    assert key in str(e.value) and "\n" not in str(e.value)


#: the default optimum (softclose optimise --json at the defaults)
OPTIMUM = {"spring_k": 1914.709221447523, "spring_rest_length": 0.07925707423802691,
           "damper_c": 2087.7541030385964}


def test_self_close_min_deg_in_verification():
    from softclose.optimiser.verify import verify
    ok = verify(from_dict({"optimise": {"self_close_min_deg": 18.0}}), OPTIMUM)
    assert ok.constraints["self_close_min_deg"] == {"value": 18.0, "bound": 18.0,
                                                    "unit": "deg", "ok": True}
    assert ok.hand.metrics()["hold_open"] == [] and ok.constraints_ok
    bad = verify(from_dict({"optimise": {"self_close_min_deg": 50.0},
                            "stroke": {"theta_open_deg": 80}, "design": BALANCED["design"]}),
                 OPTIMUM)
    assert bad.constraints["self_close_min_deg"]["value"] is None
    assert not bad.constraints["self_close_min_deg"]["ok"] and not bad.ok
    assert bad.hand.self_rise_deg == 0.0


def test_simulate_json_and_figure(capsys, tmp_path):
    import json
    from softclose import cli
    out = tmp_path / "sim"
    rc = cli.main(["simulate", "--json", "--out", str(out), "--set", "design.torsion_k=0.1",
                   "--set", "design.torsion_free_angle_deg=300", "--set",
                   "design.torsion_pivot=A", "--set", "friction.torque=0.05", "--set",
                   "stroke.theta_open_deg=80"])
    obj = json.loads(capsys.readouterr().out)
    assert rc == 0
    assert obj["self_close_deg"] == pytest.approx(31.912041430086095, abs=1e-6)
    assert obj["self_rise_deg"] == pytest.approx(46.63944172617751, abs=1e-6)
    assert obj["hold_open"] == [[obj["self_close_deg"], obj["self_rise_deg"]]]
    assert obj["closing_force"] == pytest.approx(1.0679116598226026, rel=1e-6)
    png = out / "hand_force.png"
    assert str(png) in obj["files"] and png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_bad_key_on_the_command_line(capsys):
    from softclose import cli
    rc = cli.main(["simulate", "--set", "stroke.theta_open_deg=-5"])
    err = capsys.readouterr().err.strip()
    assert rc == 2 and "stroke.theta_open_deg" in err and len(err.splitlines()) == 1


def test_simulate_gives_the_hand_force_at_each_sign_off_temperature(capsys, tmp_path):
    """With several operating.temperatures_c, simulate's JSON ``temperatures`` holds the hand
    force's metrics at each: those of a stroke run at that temperature; --out draws them."""
    import json
    from softclose.cli import main
    sets = ['design.spring_kind="compression"', "design.spring_k=1914.709",
            "design.spring_rest_length=0.07925707", "friction.torque=0.03",
            "design.damper_temperature_coeff=-0.005"]
    args = [a for s in sets for a in ("--set", s)]
    assert main(["simulate", "--json", "--out", str(tmp_path), *args, "--set",
                 "operating.temperatures_c=[-20, 60]"]) == 0
    both = json.loads(capsys.readouterr().out)
    assert [t["temperature_c"] for t in both["temperatures"]] == [-20.0, 60.0]
    assert (tmp_path / "hand_force_temperatures.png").exists()
    for t in both["temperatures"]:
        assert main(["simulate", "--json", *args, "--set",
                     f"operating.temperature_c={t['temperature_c']}"]) == 0
        alone = json.loads(capsys.readouterr().out)
        for k in ("closing_force", "self_close_deg", "self_rise_deg", "hold_open"):
            assert t[k] == alone[k], k
    # the coil spring's rate moves with the temperature, and with it the lifting effort
    assert both["temperatures"][0]["opening_force"] != both["temperatures"][1]["opening_force"]
