"""The extension spring made to order (SPEC §14, EN 13906-2: the body), against hand
computations.

The worked check: EN 10270-1 SH, d = 1 mm, D = 8 mm, n = 20, free length L0 = 40 mm, initial
tension F0 = 4 N, pulled to 50 and 60 mm:
R = G d^4 / (8 D^3 n) = 81500 / (8 * 512 * 20) N/mm = 0.994873 N/mm; w = 8,
k = (w + 0.5)/(w - 0.75) = 8.5/7.25; F1 = 4 + 9.94873 N, F2 = 4 + 19.89746 N;
tau = 8 D F / (pi d^3) = 20.3718 MPa per N; tau_2 = 486.84 MPa <= 0.45 R_m = 0.45 * 2220 MPa;
the closed body (n + 1) d = 21 mm within 40 - 2 * 0.8 * 7 = 28.8 mm.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from softclose.coil_spring import CoilSpring, Duty, check, design
from softclose.coil_spring import extension as en13906_2
from softclose.errors import ConfigError

G, RHO = 81500e6, 7850.0
PER_N = 8 * 0.008 / (math.pi * 0.001 ** 3)           # tau per N of d = 1 mm, D = 8 mm (Pa)
K = 8.5 / 7.25


@pytest.fixture(scope="module")
def worked():
    spring = CoilSpring(wire_d=0.001, coil_d=0.008, active_coils=20)
    R = G * 0.001 ** 4 / (8 * 0.008 ** 3 * 20)
    duty = Duty(rate=R, free_length=0.040, longest_length=0.060, shortest_length=0.050,
                kind="extension", initial_tension=4.0, cycles=1e5)
    return check(spring, duty)


def test_worked_rate_forces_and_lengths(worked):
    r = worked
    assert r.kind == "extension"
    # R = G d^4/(8 D^3 n) = 81500/(8 * 512 * 20) N/mm
    assert r.rate == pytest.approx(81500 / 81920 * 1e3, rel=1e-13)
    assert round(r.rate, 2) == 994.87
    assert r.forces == {"F0": 4.0, "F1": pytest.approx(4 + 9.94873046875, rel=1e-12),
                        "F2": pytest.approx(4 + 19.8974609375, rel=1e-12)}
    j = r.spring_json()
    assert j["body_length"] == pytest.approx(0.021, abs=1e-15)       # (20 + 1) * 1 mm
    assert j["length_for_hooks"] == pytest.approx(0.019, abs=1e-15)
    assert r.check_named("body_length").limit == pytest.approx(0.040 - 2 * 0.8 * 0.007)
    assert j["solid_length"] is None and j["tolerance"] is None
    assert "not covered" in j["hooks"] and "EN 13906-2" in j["hooks"]
    # m = rho (pi d^2/4) pi D (n + 2): the body and a coil's wire in each hook
    assert r.mass == pytest.approx(RHO * math.pi * 1e-6 / 4 * math.pi * 0.008 * 22, rel=1e-12)
    assert r.mass == pytest.approx(3.40896e-3, rel=1e-5)
    # f_e = 3560 d/(n D^2) sqrt(G/rho) = 3560/(20 * 64) sqrt(81500/7.85) = 283.39 Hz
    assert r.natural_frequency == pytest.approx(3560 / 1280 * math.sqrt(81500 / 7.85),
                                                rel=1e-12)
    assert r.buckling == {"s_k": None, "s_2": None, "safe": True}


def test_worked_stresses(worked):
    r, st = worked, worked.stresses
    assert r.spring.stress_correction == pytest.approx(K, rel=1e-15)
    assert PER_N / 1e6 == pytest.approx(20.3718, abs=1e-4)
    F1, F2 = r.forces["F1"], r.forces["F2"]
    assert st["tau_2"] == pytest.approx(PER_N * F2, rel=1e-12)              # uncorrected
    assert st["tau_2"] / 1e6 == pytest.approx(486.84, abs=0.01)
    assert st["tau_2_allowed"] / 1e6 == pytest.approx(0.45 * 2220, rel=1e-12)  # R_m at 1 mm
    assert st["tau_k1"] == pytest.approx(K * PER_N * F1, rel=1e-12)
    assert st["tau_k2"] == pytest.approx(K * PER_N * F2, rel=1e-12)
    assert st["tau_kh"] == pytest.approx(K * PER_N * 19.8974609375 / 2, rel=1e-12)
    assert st["tau_kh"] / 1e6 == pytest.approx(237.62, abs=0.01)
    gm = r.spring.mat.goodman(0.001)
    assert st["tau_kh_allowed"] == pytest.approx(gm.permissible_stroke(st["tau_k1"], 1e5),
                                                 rel=1e-12)
    # initial tension: tau_0 = 81.49 MPa, at most 231/e^0.84 + 6.9 (4 - 5/6.5) = 122.02 MPa
    assert st["tau_0"] == pytest.approx(PER_N * 4.0, rel=1e-12)
    hi = 231 / math.exp(0.84) + 6.9 * (4 - 5 / 6.5)
    assert st["tau_0_allowed"] / 1e6 == pytest.approx(hi, rel=1e-12)
    assert round(hi, 2) == 122.02
    assert r.ok and r.life == 1e7
    assert [c.name for c in r.checks] == ["rate", "body_length", "initial_tension", "static",
                                          "fatigue", "temperature_min", "temperature_max"]


def _duty(**kw):
    R = G * 0.001 ** 4 / (8 * 0.008 ** 3 * 20)
    args = dict(rate=R, free_length=0.040, longest_length=0.060, shortest_length=0.050,
                kind="extension", initial_tension=4.0)
    args.update(kw)
    return Duty(**args)


def test_fails_exactly_static():
    """tau_2 = 0.45 R_m at F2 = 999 MPa / PER_N = 49.04 N: 1 % further it fails."""
    spring = CoilSpring(0.001, 0.008, 20)
    R = spring.rate
    s_lim = (0.45 * 2220e6 / PER_N - 4.0) / R
    ok = check(spring, _duty(longest_length=0.040 + 0.99 * s_lim))
    bad = check(spring, _duty(longest_length=0.040 + 1.01 * s_lim))
    assert "static" not in ok.failed and "static" in bad.failed
    assert bad.check_named("static").value / bad.check_named("static").limit == \
        pytest.approx((4 + 1.01 * s_lim * R) / (4 + s_lim * R), rel=1e-12)


def test_fails_body_and_initial_tension():
    spring = CoilSpring(0.001, 0.008, 20)
    # the body of 21 mm leaves 30 - 21 = 9 mm < 11.2 mm for the hooks
    r = check(spring, _duty(free_length=0.030))
    assert r.failed == ("body_length",)
    # 6.1 N of initial tension: tau_0 = 124.3 MPa above 122.02 MPa
    r = check(spring, _duty(initial_tension=6.1))
    assert r.failed == ("initial_tension",)
    assert r.check_named("initial_tension").value / 1e6 == pytest.approx(6.1 * 20.3718,
                                                                          rel=1e-5)


def test_temperature_scales_rate_and_initial_tension():
    """At -10 degC G is (1 + 2.5e-4 * 33) of its 23 degC value: the body's working stresses
    (F0 + R s) rise by that factor; the stress as wound does not."""
    spring = CoilSpring(0.001, 0.008, 20)
    r0 = check(spring, _duty())
    r = check(spring, _duty(temperatures_c=(-10.0, 23.0, 50.0)))
    f = 1 + 2.5e-4 * 33
    assert r.governing_temperature_c == -10.0
    assert r.stresses["tau_k2"] == pytest.approx(f * r0.stresses["tau_k2"], rel=1e-12)
    assert r.stresses["tau_2"] == pytest.approx(f * r0.stresses["tau_2"], rel=1e-12)
    assert r.stresses["tau_0"] == r0.stresses["tau_0"]
    assert r.temperatures[0]["F0"] == pytest.approx(4.0 * f, rel=1e-12)


@pytest.mark.parametrize("kwargs, message", [
    (dict(shortest_length=0.039), r"^duty\.shortest_length: 0\.039 m is shorter than the "
                                  r"extension spring's free length"),
    (dict(shortest_length=0.061), r"^duty\.shortest_length: 0\.061 m is longer than the "
                                  r"longest"),
    (dict(initial_tension=-1.0), r"^duty\.initial_tension: must be a number of newtons >= 0"),
    (dict(kind="torsion"), r"^duty\.kind: 'torsion' is not a coil spring made to order"),
])
def test_bad_extension_duty(kwargs, message):
    with pytest.raises(ConfigError, match=message):
        _duty(**kwargs)


def test_compression_duty_has_no_initial_tension():
    with pytest.raises(ConfigError, match=r"^duty\.initial_tension: only an extension"):
        Duty(rate=1000.0, free_length=0.06, longest_length=0.05, shortest_length=0.04,
             initial_tension=1.0)


def test_refused_extension_springs():
    with pytest.raises(ConfigError, match=r"^spring\.active_coils: n = 2\.5 is below "
                                          r"EN 13906-2's 3 active coils"):
        check(CoilSpring(0.001, 0.008, 2.5), _duty())
    with pytest.raises(ConfigError, match=r"^spring\.material: EN10270-1-SH-peened is "
                                          r"shot-peened wire"):
        check(CoilSpring(0.001, 0.008, 20, "EN10270-1-SH-peened"), _duty())
    with pytest.raises(ConfigError, match=r"^spring\.material: EN10270-1-SH-peened"):
        design(_duty(), "EN10270-1-SH-peened")


def test_design_meets_every_check_lightest_first():
    duty = _duty(rate=1000.0, free_length=0.045, longest_length=0.0584,
                 shortest_length=0.0523, initial_tension=2.0)
    res = design(duty, max_outer_d=0.012)
    assert res.success and res.best.ok and res.best.kind == "extension"
    masses = [c.mass for c in res.candidates]
    assert masses == sorted(masses) and res.best.mass == masses[0]
    for c in res.candidates:
        s = c.spring
        assert c.ok and s.active_coils >= 3 and s.active_coils % 0.25 == 0
        assert abs(c.rate / 1000.0 - 1) <= 0.125 / s.active_coils
        assert (s.active_coils + 1) * s.wire_d <= 0.045 - 1.6 * (s.coil_d - s.wire_d)
        assert s.outer_d <= 0.012 + 1e-12
    # the best again by check(): the same numbers
    again = check(res.best.spring, duty, max_outer_d=0.012)
    assert again.stresses == res.best.stresses and again.ok
    frame = res.to_frame()
    assert "body_length" in frame and "s_k" not in frame


# -- `softclose spring` on an extension spring -----------------------------------------------

EXTENSION = ['design.spring_kind="extension"', "design.spring_k=1000",
             "design.spring_rest_length=0.045", "design.spring_preload=2"]


def _sets(*overrides):
    return [a for o in (*EXTENSION, *overrides) for a in ("--set", o)]


def test_spring_command_designs_an_extension_spring(capsys, tmp_path):
    from softclose.cli import main
    from softclose.optimiser.spring_order import working_lengths
    from softclose.config import load_config
    rc = main(["spring", "--json", "--out", str(tmp_path), *_sets()])
    out = json.loads(capsys.readouterr().out)
    assert rc == 0 and out["mode"] == "design" and out["success"]
    s = out["spring"]
    assert s["kind"] == "extension" and s["initial_tension"] == 2.0
    assert set(s["stresses"]) == {"tau_0", "tau_0_allowed", "tau_k1", "tau_k2", "tau_kh",
                                  "tau_2", "tau_2_allowed", "tau_kh_allowed"}
    longest, shortest = working_lengths(load_config(None, EXTENSION))
    assert s["working_lengths"] == [shortest, longest]
    assert s["forces"]["F2"] == pytest.approx(2.0 + s["rate"] * (longest - 0.045), rel=1e-12)
    assert s["body_length"] == pytest.approx((s["active_coils"] + 1) * s["wire_d"])
    assert out["duty"]["kind"] == "extension"
    assert all(c["ok"] for c in out["checks"])
    assert (tmp_path / "spring.png").read_bytes().startswith(b"\x89PNG")
    main(["spring", *_sets()])
    text = capsys.readouterr().out
    assert text.startswith("extension spring designed: EN10270-1-SH")
    assert "hooks/loops not covered (hook stresses: EN 13906-2 §11" in text


def test_spring_command_checks_an_extension_spring(capsys):
    """d = 0.5 mm, D = 3.2 mm, n = 19.5: R = 81500 * 0.0625 / (8 * 32.768 * 19.5) N/mm."""
    from softclose.cli import main
    rc = main(["spring", "--json", *_sets("spring.wire_d=0.0005", "spring.coil_d=0.0032",
                                          "spring.active_coils=19.5")])
    res = json.loads(capsys.readouterr().out)
    assert rc == 0 and res["mode"] == "check" and res["ok"]
    assert res["spring"]["rate"] == pytest.approx(81500 * 0.0625 / (8 * 32.768 * 19.5) * 1e3,
                                                  rel=1e-12)
    # the same wire with 85 coils: its body, 86 * 0.5 = 43 mm, leaves less than
    # 2 * 0.8 * 2.7 = 4.32 mm of the 45 mm for the hooks (and the rate is 4.4 times too low)
    rc = main(["spring", *_sets("spring.wire_d=0.0005", "spring.coil_d=0.0032",
                                "spring.active_coils=85")])
    out, err = capsys.readouterr()
    assert rc == 3
    assert "; body_length: 43 mm, limit <= 40.68 mm" in err and "the spring fails rate" in err


def test_the_figure_of_an_extension_spring():
    from softclose.present.figures.spring import plot_spring, spring_curves
    spring = CoilSpring(0.001, 0.008, 20)
    c = check(spring, _duty())
    cv = spring_curves(c, n=2001)
    at = lambda k, x: float(np.interp(x, cv["length"], cv[k]))
    assert at("force", 0.050) == pytest.approx(c.forces["F1"], rel=1e-9)
    assert at("force", 0.060) == pytest.approx(c.forces["F2"], rel=1e-9)
    assert at("stress", 0.060) == pytest.approx(c.stresses["tau_2"], rel=1e-9)
    assert at("stress_corrected", 0.050) == pytest.approx(c.stresses["tau_k1"], rel=1e-9)
    assert cv["force"][0] == 4.0
    fig = plot_spring(c)
    assert len(fig.axes) == 2


def test_hook_and_body_helpers():
    assert en13906_2.body_length(20, 0.001) == pytest.approx(0.021)
    assert en13906_2.hook_room(0.008, 0.001) == pytest.approx(0.0112)
    lo, hi = en13906_2.initial_stress_range(8.0)
    assert (lo + hi) / 2e6 == pytest.approx(231 / math.exp(0.84), rel=1e-12)
    assert en13906_2.static_limit(2220e6) == pytest.approx(999e6)


def test_the_report_buys_the_extension_spring_of_softclose_spring():
    """The sign-off report's spring: the same design as `softclose spring`, its body checks,
    and the hooks named as not covered."""
    from types import SimpleNamespace

    from softclose.optimiser.spring_order import spring_order
    from softclose.config import load_config
    from softclose.signoff.parts import parts
    from softclose.signoff.text import spring_rows
    cfg = load_config(None, EXTENSION)
    p = parts(cfg, None, [23.0])["spring"]
    own = spring_order(cfg).best
    assert p["ok"] and p["mode"] == "designed"
    assert p["coil_spring"] == own.spring_json()
    assert [c["name"] for c in p["checks"]] == [c.name for c in own.checks]
    _, rows, checks, _ = spring_rows(SimpleNamespace(parts={"spring": p}))
    row = dict(rows)["free length / closed body"]
    assert row.startswith("45 mm / ") and "hooks/loops not covered" in row
    assert [c[0] for c in checks][:4] == ["rate", "body_length", "initial_tension", "static"]
