"""The coil spring made to order (SPEC §14): EN 13906-1 checks, EN 10270 wire data, EN 15800
tolerances and the designer, against hand computations.

The worked design check is the field notes' (d = 2 mm, D = 16 mm, n = 8.5, EN 10270-1 SH,
L0 = 60 mm: R = 4.682 N/mm, w = 8, k = 1.1724, L_c = 21 mm); the wire data are springone's
material table (EN 10270-1 SH/DH, SH shot-peened)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from softclose.coil_spring import (MATERIALS, PREFERRED_WIRE_D, CoilSpring, Duty, check,
                                   design, material)
from softclose.coil_spring import standard as en13906
from softclose.coil_spring import tolerances as en15800
from softclose.errors import ConfigError

LOG2 = math.log10(2.0)


@pytest.fixture(scope="module")
def worked():
    return CoilSpring(wire_d=0.002, coil_d=0.016, active_coils=8.5)


# -- the field notes' worked check ---------------------------------------------------------

def test_worked_check(worked):
    s = worked
    assert s.material == "EN10270-1-SH"
    # R = 81500 * 16 / (8 * 4096 * 8.5) N/mm = 4.682 N/mm
    assert s.rate == pytest.approx(81500e6 * 0.002 ** 4 / (8 * 0.016 ** 3 * 8.5), rel=1e-14)
    assert s.rate == pytest.approx(4681.755514705882, rel=1e-12)
    assert round(s.rate / 1000, 3) == 4.682
    assert s.index == 8.0
    assert s.stress_correction == pytest.approx(8.5 / 7.25, rel=1e-15)
    assert round(s.stress_correction, 4) == 1.1724
    assert s.total_coils == 10.5
    assert s.solid_length == pytest.approx(0.021, abs=1e-15)          # 10.5 * 2 mm
    assert s.outer_d == pytest.approx(0.018) and s.inner_d == pytest.approx(0.014)


def test_worked_check_further_values(worked):
    s = worked
    # S_a = 1.5 n (0.0015 D^2/d + 0.1 d) = 12.75 * 0.392 mm = 4.998 mm
    assert s.min_gap_sum == pytest.approx(4.998e-3, rel=1e-12)
    assert s.min_working_length == pytest.approx(0.025998, rel=1e-12)
    # m = rho (pi d^2/4) pi D n_t = 7850 * pi * 1e-6 * pi * 0.016 * 10.5 kg = 13.016 g
    assert s.mass == pytest.approx(7850 * math.pi * 1e-6 * math.pi * 0.016 * 10.5, rel=1e-12)
    assert s.mass == pytest.approx(0.0130160, rel=1e-5)
    # f_e = 3560 d/(n D^2) sqrt(G/rho) = 3560 * 2/(8.5 * 256) * sqrt(81500/7.85) = 333.40 Hz
    assert s.natural_frequency == pytest.approx(3560 * 2 / (8.5 * 256) * math.sqrt(81500 / 7.85),
                                                rel=1e-12)
    assert s.natural_frequency == pytest.approx(333.3996, rel=1e-6)
    # closed, not ground: L_c = (n_t + 1.5) d = 24 mm
    assert CoilSpring(0.002, 0.016, 8.5, ends="closed").solid_length == pytest.approx(0.024)


def test_worked_check_against_a_duty(worked):
    duty = Duty(rate=worked.rate, free_length=0.060, longest_length=0.055,
                shortest_length=0.045, cycles=1e5, seating=0.5)
    r = check(worked, duty)
    assert r.ok and r.failed == ()
    F = r.forces
    assert F["F1"] == pytest.approx(worked.rate * 0.005) and F["F2"] == pytest.approx(
        worked.rate * 0.015)
    assert F["Fc"] == pytest.approx(worked.rate * 0.039)                # s_c = 60 - 21 mm
    per_n = 8 * 0.016 / (math.pi * 0.002 ** 3)                          # tau per N (Pa)
    k = 8.5 / 7.25
    st = r.stresses
    assert st["tau_c"] == pytest.approx(per_n * F["Fc"], rel=1e-12)     # 929.9 MPa
    assert st["tau_c"] / 1e6 == pytest.approx(929.915, abs=1e-3)
    assert st["tau_c_allowed"] / 1e6 == pytest.approx(0.56 * (2220 - 820 * LOG2), rel=1e-12)
    assert st["tau_k1"] == pytest.approx(k * per_n * F["F1"], rel=1e-12)
    assert st["tau_k2"] == pytest.approx(k * per_n * F["F2"], rel=1e-12)
    assert st["tau_kh"] == pytest.approx(st["tau_k2"] - st["tau_k1"], rel=1e-12)
    # nu = 0.5: (1 - G/E)/(0.5 + G/E) (pi D/(nu L0))^2 > 1, the spring cannot buckle
    assert r.buckling == {"s_k": None, "s_2": pytest.approx(0.015), "safe": True}
    assert r.life == 1e7
    # EN 15800 grade 2 at F1, F2; A_L0 = alpha_F k_F / R = 1.4204 mm
    assert r.tolerance.free_length == pytest.approx(1.420393761e-3, rel=1e-9)
    assert r.tolerance.force["F2"] == pytest.approx(6.67765591346 * 0.99584890427
                                                    + 1.5 * F["F2"] / 100, rel=1e-10)


# -- EN 10270 strength and fatigue data ----------------------------------------------------

def test_tensile_strength():
    sh, dh = material("EN10270-1-SH"), material("EN10270-1-DH")
    # R_m = min(R_max, A - B log10 d)
    assert sh.tensile_strength(0.002) / 1e6 == pytest.approx(2220 - 820 * LOG2, rel=1e-14)
    assert sh.tensile_strength(0.002) / 1e6 == pytest.approx(1973.1554, abs=1e-4)
    assert dh.tensile_strength(0.002) / 1e6 == pytest.approx(2218 - 817 * LOG2, rel=1e-14)
    assert sh.tensile_strength(0.001) == pytest.approx(2220e6)
    assert sh.tensile_strength(0.0003) / 1e6 == pytest.approx(2220 - 820 * math.log10(0.3))
    assert dh.tensile_strength(0.0001) == pytest.approx(2800e6)          # capped: 3035 > 2800
    assert material("EN10270-1-SH-peened").tensile_strength(0.002) == sh.tensile_strength(0.002)


def test_goodman_data_at_10e7():
    g = material("EN10270-1-SH").goodman(0.002)
    assert g.tau_kO7 / 1e6 == pytest.approx(506 - 175 * LOG2, rel=1e-14)      # 453.320
    assert g.tau_kO_max / 1e6 == pytest.approx(1118 - 410 * LOG2, rel=1e-14)  # 994.578
    assert g.tau_kU7 / 1e6 == pytest.approx(832 - 322 * LOG2, rel=1e-14)      # 735.068
    assert g.tau_kO7 / 1e6 == pytest.approx(453.3198, abs=1e-4)
    # tau_kH = tau_kO + (tau_kO,max - tau_kO) tau_k1/tau_kU - tau_k1 at tau_k1 = 100 MPa
    assert g.permissible_stroke(100e6, 1e7) / 1e6 == pytest.approx(426.9534417, rel=1e-9)
    # beyond tau_kU: the yield line, tau_kH = tau_kO,max - tau_k1
    assert g.permissible_stroke(800e6, 1e7) / 1e6 == pytest.approx(994.5777018 - 800, rel=1e-9)
    # more cycles than the data: the 10^7 line
    assert g.permissible_stroke(100e6, 1e9) == g.permissible_stroke(100e6, 1e7)
    p = material("EN10270-1-SH-peened").goodman(0.001)                  # log10 1 = 0
    assert (p.tau_kO7, p.tau_kO_max, p.tau_kU7) == (601e6, 1119e6, 698e6)
    u = material("EN10270-1-DH").goodman(0.001)
    assert (u.tau_kO7, u.tau_kO_max, u.tau_kU7) == (506e6, 1118e6, 832e6)


def test_goodman_below_10e7_basquin():
    g = material("EN10270-1-SH").goodman(0.002)
    tau_ut = (2220 - 820 * LOG2) / math.sqrt(3)
    tau_o3 = 0.95 * tau_ut                                              # 1082.25 MPa
    assert g.tau_kO3 / 1e6 == pytest.approx(tau_o3, rel=1e-12)
    b = math.log10((506 - 175 * LOG2) / tau_o3) / 4                      # -0.094480
    assert g.basquin_exponent == pytest.approx(b, rel=1e-12)
    assert g.upper_stress_at_zero(1e5) / 1e6 == pytest.approx(tau_o3 * 100 ** b, rel=1e-12)
    assert g.upper_stress_at_zero(1e5) / 1e6 == pytest.approx(700.4295, abs=1e-4)
    assert g.upper_stress_at_zero(1e3) / 1e6 == pytest.approx(tau_o3, rel=1e-12)
    # the line of 10^5 cycles aims at the 10^7 line's point on the diagonal, tau* = 1719.31
    assert g.tau_star / 1e6 == pytest.approx(1719.3144117, rel=1e-9)
    assert g.permissible_stroke(100e6, 1e5) / 1e6 == pytest.approx(659.6906560, rel=1e-9)
    # lives: under the 10^7 line 1e7; on the 10^5 line 1e5; over the 10^3 line 0
    assert g.life(100e6, 400e6) == 1e7
    assert g.life(100e6, g.permissible_stroke(100e6, 1e5)) == pytest.approx(1e5, rel=1e-9)
    assert g.life(0.0, 1100e6) == 0.0


def test_materials_on_offer():
    assert set(MATERIALS) == {"EN10270-1-SH", "EN10270-1-DH", "EN10270-1-SH-peened"}
    for m in MATERIALS.values():
        assert (m.E, m.G, m.rho, m.gamma_g) == (206000e6, 81500e6, 7850.0, 2.5e-4)
    assert PREFERRED_WIRE_D[0] == 0.0005 and PREFERRED_WIRE_D[-1] == 0.005
    assert len(PREFERRED_WIRE_D) == 22 and 0.00225 in PREFERRED_WIRE_D


# -- EN 15800 ------------------------------------------------------------------------------

def test_en15800_tolerances_by_hand():
    d, D, n = 2.0, 16.0, 8.5                                            # mm
    x = D / d / 10
    alpha = 65.92 * d ** 3.3 / D ** 1.6 * (-0.84 * x ** 3 + 3.781 * x ** 2 - 4.244 * x + 2.274)
    kf = 1 / (3 * n * n) + 8 / (5 * n) + 0.803
    assert alpha == pytest.approx(6.677655913, rel=1e-9)
    assert kf == pytest.approx(0.995848904, rel=1e-9)
    assert en15800.alpha_f(0.002, 0.016) == pytest.approx(alpha, rel=1e-13)
    assert en15800.k_f(8.5) == pytest.approx(kf, rel=1e-14)
    # A_F at F = 100 N: (alpha_F k_F + 1.5) Q
    for grade, q, af in ((1, 0.63, 5.134459884), (2, 1.0, 8.149936324), (3, 1.6, 13.03989812)):
        assert en15800.force_tolerance(0.002, 0.016, 8.5, 100.0, grade) == pytest.approx(
            (alpha * kf + 1.5) * q, rel=1e-12)
        assert en15800.force_tolerance(0.002, 0.016, 8.5, 100.0, grade) == pytest.approx(
            af, rel=1e-9)
    # A_L0 = alpha_F k_F Q / R: 1.4204 mm (grade 2), 2.2726 mm (grade 3)
    R = 81500 * 16 / (8 * 4096 * 8.5)                                   # N/mm
    assert en15800.free_length_tolerance(0.002, 0.016, 8.5, R * 1e3) == pytest.approx(
        alpha * kf / R * 1e-3, rel=1e-12)
    assert en15800.free_length_tolerance(0.002, 0.016, 8.5, R * 1e3, 3) == pytest.approx(
        2.272630018e-3, rel=1e-9)


# -- buckling ------------------------------------------------------------------------------

def test_buckling_deflection_by_hand():
    g_e = 81500 / 206000
    rad = 1 - (1 - g_e) / (0.5 + g_e) * (math.pi * 16 / 60) ** 2
    s_k = 60 * 0.5 / (1 - g_e) * (1 - math.sqrt(rad))                  # 13.624 mm
    assert en13906.buckling_deflection(0.060, 0.016, 81500e6, 206000e6, 1.0) == pytest.approx(
        s_k * 1e-3, rel=1e-12)
    assert s_k == pytest.approx(13.62402517, rel=1e-9)
    # one end free (nu = 2) buckles earlier; both clamped (nu = 0.5) not at all
    assert en13906.buckling_deflection(0.060, 0.016, 81500e6, 206000e6, 2.0) < s_k * 1e-3
    assert en13906.buckling_deflection(0.060, 0.016, 81500e6, 206000e6, 0.5) is None


# -- a spring that fails exactly one check -------------------------------------------------

def _judge(spring, **duty):
    return check(spring, Duty(rate=spring.rate, **duty))


def test_fails_exactly_buckling():
    # slender: L0/D = 10, nu = 1: s_K = 1.68 mm < s_2 = 8 mm; stresses low
    r = _judge(CoilSpring(0.001, 0.006, 40), free_length=0.060, longest_length=0.058,
               shortest_length=0.052)
    assert r.failed == ("buckling",)
    assert r.buckling["s_k"] == pytest.approx(1.6814363e-3, rel=1e-7)
    assert r.buckling["safe"] is False
    assert r.check_named("buckling").limit == r.buckling["s_k"]


def test_fails_exactly_static():
    # the worked spring at L0 = 80 mm: tau_c = 1406.8 MPa at L_c > 0.56 R_m = 1104.97 MPa
    r = _judge(CoilSpring(0.002, 0.016, 8.5), free_length=0.080, longest_length=0.078,
               shortest_length=0.072)
    assert r.failed == ("static",)
    c = r.check_named("static")
    assert c.value / 1e6 == pytest.approx(929.915416576 * 59 / 39, rel=1e-9)
    assert c.limit / 1e6 == pytest.approx(1104.967026, rel=1e-9)


def test_fails_exactly_fatigue():
    # the worked spring worked from 58 to 30 mm for 10^7 cycles, both ends clamped
    r = _judge(CoilSpring(0.002, 0.016, 8.5), free_length=0.060, longest_length=0.058,
               shortest_length=0.030, cycles=1e7, seating=0.5)
    assert r.failed == ("fatigue",)
    c = r.check_named("fatigue")
    tau_k1 = r.stresses["tau_k1"] / 1e6                                  # 55.9 MPa
    assert c.limit / 1e6 == pytest.approx(
        453.3197508 + (994.5777018 - 453.3197508) / 735.0683414 * tau_k1 - tau_k1, rel=1e-9)
    assert c.value / 1e6 == pytest.approx(782.7, abs=0.1)
    assert r.life == pytest.approx(21742.57, rel=1e-5)
    # the same spring for 2e4 cycles passes
    assert _judge(CoilSpring(0.002, 0.016, 8.5), free_length=0.060, longest_length=0.058,
                  shortest_length=0.030, cycles=2e4, seating=0.5).ok


def test_fails_space_and_gaps():
    s = CoilSpring(0.002, 0.016, 8.5)
    duty = Duty(rate=s.rate, free_length=0.060, longest_length=0.045, shortest_length=0.0255,
                seating=0.5, cycles=1e3)
    r = check(s, duty, max_outer_d=0.017, min_inner_d=0.015)
    assert set(r.failed) == {"outer_d", "inner_d", "min_working_length"}
    # a rate not the duty's
    r = check(s, Duty(rate=4000.0, free_length=0.060, longest_length=0.055,
                      shortest_length=0.045, seating=0.5))
    assert r.failed == ("rate",)
    assert r.rate_deviation == pytest.approx(s.rate / 4000 - 1)


def test_temperature_moves_the_rate_and_stresses(worked):
    hot = Duty(rate=worked.rate, free_length=0.06, longest_length=0.055,
               shortest_length=0.045, seating=0.5, temperatures_c=(23.0, 80.0))
    cold = Duty(rate=worked.rate, free_length=0.06, longest_length=0.055,
                shortest_length=0.045, seating=0.5, temperatures_c=(-20.0, 23.0))
    assert worked.rate_at(-20.0) == pytest.approx(worked.rate * (1 + 2.5e-4 * 43), rel=1e-14)
    rh, rc = check(worked, hot), check(worked, cold)
    assert rh.governing_temperature_c == 23.0 and rc.governing_temperature_c == -20.0
    assert rc.stresses["tau_k2"] == pytest.approx(rh.stresses["tau_k2"] * 1.01075, rel=1e-12)
    assert rc.forces == rh.forces                                       # at T_ref
    assert [t["temperature_c"] for t in rc.temperatures] == [-20.0, 23.0]
    too_cold = Duty(rate=worked.rate, free_length=0.06, longest_length=0.055,
                    shortest_length=0.045, seating=0.5, temperatures_c=(-50.0,))
    assert check(worked, too_cold).failed == ("temperature_min",)


# -- the designer --------------------------------------------------------------------------

@pytest.fixture(scope="module")
def lid_duty():
    return Duty(rate=1500.0, free_length=0.050, longest_length=0.045, shortest_length=0.030,
                cycles=1e5)


def test_design_meets_every_check(lid_duty):
    res = design(lid_duty, max_outer_d=0.020)
    assert res.success and res.best is not None and res.best.ok
    s = res.spring
    assert s.wire_d in PREFERRED_WIRE_D
    assert s.outer_d <= 0.020 + 1e-12
    assert 4 <= s.index <= 20 and s.active_coils >= 2
    # n is a quarter coil, the rounding of the exact n for the requested rate
    assert (s.active_coils * 4) == round(s.active_coils * 4)
    n_exact = 81500e6 * s.wire_d ** 4 / (8 * s.coil_d ** 3 * lid_duty.rate)
    assert abs(s.active_coils - n_exact) <= 0.125 + 1e-12
    assert res.best.rate == pytest.approx(
        81500e6 * s.wire_d ** 4 / (8 * s.coil_d ** 3 * s.active_coils), rel=1e-14)
    assert abs(res.best.rate / lid_duty.rate - 1) <= 0.125 / s.active_coils
    # D on the 0.1 mm grid; candidates all pass, lightest first, one per wire
    assert s.coil_d * 1e4 == pytest.approx(round(s.coil_d * 1e4), abs=1e-6)
    masses = [c.mass for c in res.candidates]
    assert masses == sorted(masses) and res.best is res.candidates[0]
    assert all(c.ok for c in res.candidates)
    assert len({c.spring.wire_d for c in res.candidates}) == len(res.candidates)
    # a neighbour on the grid is heavier or fails a check
    for dD in (-1e-4, 1e-4):
        D = round(s.coil_d + dD, 10)
        n = round(81500e6 * s.wire_d ** 4 / (8 * D ** 3 * lid_duty.rate) * 4) / 4
        if n >= 2 and 4 <= D / s.wire_d <= 20:
            nb = check(CoilSpring(s.wire_d, D, n), lid_duty, max_outer_d=0.020)
            assert not nb.ok or nb.mass >= res.best.mass
    json.dumps(res.to_json(), allow_nan=False)
    assert list(res.to_frame()["rank"]) == list(range(1, len(res.candidates) + 1))


def test_design_json_keys(lid_duty):
    out = design(lid_duty, max_outer_d=0.020).to_json()
    spec = {"material", "wire_d", "coil_d", "outer_d", "inner_d", "active_coils",
            "total_coils", "free_length", "solid_length", "min_working_length", "rate",
            "forces", "stresses", "life", "buckling", "natural_frequency", "mass",
            "tolerance"}
    assert spec <= set(out["spring"])
    assert set(out["spring"]["stresses"]) == {"tau_k1", "tau_k2", "tau_kh", "tau_c",
                                              "tau_c_allowed", "tau_kh_allowed"}
    assert set(out["spring"]["buckling"]) == {"s_k", "s_2", "safe"}
    assert set(out["spring"]["tolerance"]) == {"grade", "force", "free_length"}
    assert all({"name", "value", "limit", "ok"} <= set(c) for c in out["checks"])
    assert out["candidates"] and out["candidates"][0]["wire_d"] == out["spring"]["wire_d"]


def test_design_in_too_little_space(lid_duty):
    res = design(lid_duty, max_outer_d=0.005)
    assert not res.success and res.candidates == ()
    assert res.message.startswith("no spring of EN10270-1-SH meets every check")
    assert res.best is not None and not res.best.ok


def test_results_are_immutable(worked, lid_duty):
    r = check(worked, lid_duty)
    with pytest.raises(AttributeError):
        r.mass = 0.0
    with pytest.raises(AttributeError):
        worked.wire_d = 0.003


# -- bad input: one line naming the key ----------------------------------------------------

@pytest.mark.parametrize("kwargs, message", [
    (dict(wire_d=0.001, coil_d=0.025, active_coils=8),
     "spring.coil_d: the spring index w = D/d = 25 is outside EN 13906-1's 4 <= w <= 20 "
     "(d = 1 mm, D = 25 mm)"),
    (dict(wire_d=0.002, coil_d=0.006, active_coils=8),
     "spring.coil_d: the spring index w = D/d = 3 is outside EN 13906-1's 4 <= w <= 20 "
     "(d = 2 mm, D = 6 mm)"),
    (dict(wire_d=0.002, coil_d=0.016, active_coils=1.5),
     "spring.active_coils: n = 1.5 is below EN 13906-1's 2 active coils"),
    (dict(wire_d=-0.002, coil_d=0.016, active_coils=8),
     "spring.wire_d: the wire diameter d must be a positive number of metres, got -0.002"),
    (dict(wire_d=0.002, coil_d=0.016, active_coils=8, material="EN10270-3"),
     "spring.material: unknown material 'EN10270-3' (one of EN10270-1-SH, EN10270-1-DH, "
     "EN10270-1-SH-peened; other wires lack sourced strength and fatigue data)"),
    (dict(wire_d=0.002, coil_d=0.016, active_coils=8, ends="open"),
     "spring.ends: unknown end form 'open' (one of closed_ground, closed)"),
    (dict(wire_d=0.0002, coil_d=0.002, active_coils=8),
     "spring.wire_d: d = 0.2 mm is outside EN10270-1-SH's 0.28 < d <= 20 mm"),
])
def test_bad_spring(kwargs, message):
    with pytest.raises(ValueError) as e:
        CoilSpring(**kwargs)
    assert str(e.value) == message
    assert "\n" not in str(e.value) and isinstance(e.value, ConfigError)


@pytest.mark.parametrize("kwargs, key", [
    (dict(rate=-1.0), "duty.rate: "),
    (dict(free_length=0.0), "duty.free_length: "),
    (dict(longest_length=0.08), "duty.longest_length: "),
    (dict(shortest_length=0.065), "duty.shortest_length: "),
    (dict(cycles=float("nan")), "spring.cycles: "),
    (dict(seating=0.0), "spring.seating: "),
    (dict(temperatures_c=()), "duty.temperatures_c: "),
])
def test_bad_duty(kwargs, key):
    base = dict(rate=1500.0, free_length=0.070, longest_length=0.062, shortest_length=0.040)
    with pytest.raises(ValueError) as e:
        Duty(**{**base, **kwargs})
    assert str(e.value).startswith(key) and "\n" not in str(e.value)


def test_bad_design_arguments(lid_duty):
    with pytest.raises(ValueError, match=r"^spring\.material: unknown material 'steel'"):
        design(lid_duty, "steel")
    with pytest.raises(ValueError, match=r"^spring\.grade: EN 15800 grade must be 1, 2 or 3, "
                                         r"got 4$"):
        design(lid_duty, grade=4)
    with pytest.raises(ValueError, match=r"^spring\.max_outer_d: must be a positive number"):
        design(lid_duty, max_outer_d=-0.01)
    with pytest.raises(ValueError, match=r"^spring\.min_inner_d: 0\.02 m leaves no room"):
        design(lid_duty, max_outer_d=0.015, min_inner_d=0.02)


# -- the [spring] table and `softclose spring` (SPEC §14) -----------------------------------

#: a compression spring on the default lid (the fit example's design)
COMPRESSION = ['design.spring_kind="compression"', "design.spring_k=1914.709",
               "design.spring_rest_length=0.07925707"]


def _sets(*overrides):
    return [a for o in (*COMPRESSION, *overrides) for a in ("--set", o)]


def test_working_lengths_are_the_stroke_extremes():
    """The spring's longest and shortest |D - E| between the rim and theta0, against plain
    numpy kinematics on a fine grid (conftest.np_closure)."""
    from conftest import np_closure

    from softclose.config import load_config
    from softclose.optimiser.spring_order import spring_duty, working_lengths
    cfg = load_config(None, COMPRESSION)
    g = cfg.geometry
    near = math.radians(g.assembly[1])
    lengths = []
    for th in np.linspace(0.0, math.radians(18.0), 2001):
        phi, _ = np_closure(th, g, near)
        near = phi
        a = g.crank_oa * np.array([math.cos(phi), math.sin(phi)])
        c, s = math.cos(th), math.sin(th)
        e = a + np.array([c * g.lid_e[0] - s * g.lid_e[1], s * g.lid_e[0] + c * g.lid_e[1]])
        lengths.append(float(np.hypot(*(np.asarray(g.spring_anchor) - e))))
    longest, shortest = working_lengths(cfg)
    assert longest == pytest.approx(max(lengths), abs=1e-9)
    assert shortest == pytest.approx(min(lengths), abs=1e-9)
    assert longest >= max(lengths) - 1e-12 and shortest <= min(lengths) + 1e-12
    duty = spring_duty(cfg)
    assert (duty.rate, duty.free_length) == (1914.709, 0.07925707)
    assert (duty.longest_length, duty.shortest_length) == (longest, shortest)
    # a preload moves the coil spring's free length: L0 = l0 + F0 / k
    pre = spring_duty(cfg.update({"design.spring_preload": 19.14709}))
    assert pre.free_length == pytest.approx(0.07925707 + 0.01, rel=1e-12)


def test_spring_command_designs(capsys, tmp_path):
    from softclose.cli import main
    rc = main(["spring", "--json", "--out", str(tmp_path), *_sets("spring.max_outer_d=0.03")])
    out = json.loads(capsys.readouterr().out)
    assert rc == 0 and out["mode"] == "design" and out["success"]
    s = out["spring"]
    assert set(s) >= {"material", "wire_d", "coil_d", "outer_d", "inner_d", "active_coils",
                      "total_coils", "free_length", "solid_length", "min_working_length",
                      "rate", "forces", "stresses", "life", "buckling", "natural_frequency",
                      "mass", "tolerance"}
    assert set(s["stresses"]) == {"tau_k1", "tau_k2", "tau_kh", "tau_c", "tau_c_allowed",
                                  "tau_kh_allowed"}
    assert set(s["buckling"]) == {"s_k", "s_2", "safe"}
    assert set(s["tolerance"]) == {"grade", "force", "free_length"}
    assert all(set(c) >= {"name", "value", "limit", "ok"} and c["ok"] for c in out["checks"])
    assert s["outer_d"] <= 0.03 and s["wire_d"] in PREFERRED_WIRE_D
    assert s["free_length"] == 0.07925707 and s["material"] == "EN10270-1-SH"
    assert abs(s["rate"] / 1914.709 - 1) <= 0.125 / s["active_coils"]
    assert [c["mass"] for c in out["candidates"]] == sorted(c["mass"] for c in
                                                            out["candidates"])
    assert {p.name for p in tmp_path.iterdir()} == {"spring.json", "spring_checks.csv",
                                                   "spring_candidates.csv", "spring.png"}
    assert (tmp_path / "spring.png").read_bytes().startswith(b"\x89PNG")
    assert json.loads((tmp_path / "spring.json").read_text())["spring"] == s


def test_the_spring_figure_draws_the_checked_forces_and_stresses():
    """The figure's curves pass through the check's numbers: F1, F2 at the working lengths,
    tau_k1, tau_k2 (corrected) there, tau_c (uncorrected) at the solid length."""
    from softclose.present.figures.spring import plot_spring, spring_curves
    spring = CoilSpring(wire_d=0.002, coil_d=0.0272, active_coils=4.25)
    duty = Duty(rate=1914.709, free_length=0.07925707, longest_length=0.0584337386,
                shortest_length=0.0522687386)
    c = check(spring, duty)
    curves = spring_curves(c, n=2001)
    L = curves["length"][::-1]                     # increasing, for np.interp
    at = {k: (lambda x, k=k: float(np.interp(x, L, curves[k][::-1])))
          for k in ("force", "stress", "stress_corrected")}
    assert at["force"](duty.longest_length) == pytest.approx(c.forces["F1"], rel=1e-9)
    assert at["force"](duty.shortest_length) == pytest.approx(c.forces["F2"], rel=1e-9)
    assert at["stress_corrected"](duty.longest_length) == pytest.approx(
        c.stresses["tau_k1"], rel=1e-9)
    assert at["stress_corrected"](duty.shortest_length) == pytest.approx(
        c.stresses["tau_k2"], rel=1e-9)
    assert curves["stress"][-1] == pytest.approx(c.stresses["tau_c"], rel=1e-9)
    assert curves["length"][-1] == spring.solid_length
    fig = plot_spring(c)
    assert len(fig.axes) == 2 and fig.axes[1].get_ylabel() == "shear stress (MPa)"


def test_spring_command_checks(capsys):
    """The three geometry keys given: that spring is checked; it fails (exit 3, one line)."""
    from softclose.cli import main
    rc = main(["spring", *_sets("spring.wire_d=0.002", "spring.coil_d=0.016",
                                "spring.active_coils=17")])
    out, err = capsys.readouterr()
    assert rc == 3
    assert err.strip().splitlines() == [
        "softclose: error: the spring fails rate: 22.26 %, limit <= 0.7353 %; buckling: "
        "26.99 mm, limit < 9.601 mm"]
    assert "spring checked: EN10270-1-SH, d = 2 mm, D = 16 mm" in out
    # the designer's choice (d = 2 mm, D = 27.2 mm, n = 4.25) passes; with n for the exact
    # rate (4.2296) its stress at solid length exceeds 0.56 R_m by 0.2 %
    rc = main(["spring", "--json", *_sets("spring.wire_d=0.002", "spring.coil_d=0.0272",
                                          "spring.active_coils=4.25")])
    res = json.loads(capsys.readouterr().out)
    assert rc == 0 and res["mode"] == "check" and res["ok"] and res["candidates"] == []
    assert res["spring"]["rate"] == pytest.approx(81500e6 * 16e-12 / (8 * 0.0272 ** 3 * 4.25))
    n = 81500e6 * 0.002 ** 4 / (8 * 0.0272 ** 3 * 1914.709)
    rc = main(["spring", "--json", *_sets("spring.wire_d=0.002", "spring.coil_d=0.0272",
                                          f"spring.active_coils={n!r}")])
    res = json.loads(capsys.readouterr().out)
    assert rc == 3 and res["failed"] == ["static"] and res["exit_code"] == 3


@pytest.mark.parametrize("sets, message", [
    ((), "design.spring_kind: softclose spring makes a compression or an extension spring to "
         "order; the design's spring is 'linear' (set design.spring_kind = \"compression\" or "
         "\"extension\")"),
    (COMPRESSION + ["spring.wire_d=0.001", "spring.coil_d=0.025"],
     "spring.coil_d: the spring index w = D/d = 25 is outside EN 13906-1's 4 <= w <= 20 "
     "(d = 1 mm, D = 25 mm)"),
    (COMPRESSION + ["spring.active_coils=8"],
     "spring.active_coils: given without spring.wire_d; give the wire too (with "
     "spring.coil_d: a spring to check; without: its coil diameter designed), or leave it "
     "out to design one"),
    (COMPRESSION + ["spring.active_coils=1.5", "spring.wire_d=0.002", "spring.coil_d=0.016"],
     "spring.active_coils: 1.5 coils is outside the admissible range 2..1000 coils"),
    (COMPRESSION + ["spring.wire_d=-0.002"], "spring.wire_d: must be positive, got -0.002"),
    (COMPRESSION + ['spring.material="EN10270-3"'],
     "spring.material: expected one of EN10270-1-SH, EN10270-1-DH, EN10270-1-SH-peened; got "
     "'EN10270-3'"),
    (COMPRESSION + ["spring.grade=4"], "spring.grade: 4 is outside the admissible range 1..3"),
    (COMPRESSION + ["design.spring_rest_length=0.05"],
     "design.spring_rest_length: the compression spring's free length 50 mm is shorter than "
     "its longest length over the stroke, 58.43 mm: it would come loose (a longer free "
     "length or a preload keeps it in place)"),
])
def test_spring_command_bad_input(capsys, sets, message):
    from softclose.cli import main
    rc = main(["spring", "--json", *[a for o in sets for a in ("--set", o)]])
    out, err = capsys.readouterr()
    assert rc == 2
    assert err.strip().splitlines() == [f"softclose: error: {message}"]
    assert json.loads(out) == {"error": message, "exit_code": 2}
