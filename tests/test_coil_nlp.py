"""The NLP's EN 13906-1 constraints on the spring made to order (softclose.optimiser.coil_nlp)
against the checks of softclose.coil_spring, a second formulation of the same standard: on
springs across the index range, the NLP's groups are the checks' values over their limits."""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pytest

from softclose.coil_spring import CoilSpring, Duty, check
from softclose.coil_spring.materials import material
from softclose.optimiser.coil_nlp import (COIL_PARAMS, GROUPS, MASS_WEIGHT, Z_SCALES,
                                          coil_checks)

SH = material("EN10270-1-SH")
L1, L2 = 0.0584337, 0.0522687


def _params(nu=1.0, cycles=1e5, outer=1.0, inner=0.0) -> np.ndarray:
    r = math.log10(cycles / 1e3) / 4.0
    v = dict(G=SH.G, g_over_e=SH.G / SH.E, rho=SH.rho, f_gov=1.0, nu=nu, L1=L1, L2=L2,
             ends_extra=0.0, rm_a=SH.rm_a, rm_b=SH.rm_b, rm_max=SH.rm_max,
             **dict(zip(("g_a", "g_b", "g_c", "g_e", "g_f", "g_g"), SH.goodman_10e7)),
             r_cycles=r, max_outer_d=outer, min_inner_d=inner, mass_weight=MASS_WEIGHT)
    return np.array([v[k] for k in COIL_PARAMS])


def _nlp(d, D, n, R, L0, C):
    z = ca.MX.sym("z", 3)
    R_, L0_ = ca.MX.sym("R"), ca.MX.sym("L0")
    P = ca.MX.sym("P", len(COIL_PARAMS))
    groups, mass = coil_checks(z, R_, L0_, P)
    f = ca.Function("f", [z, R_, L0_, P], [*groups.values(), mass])
    out = f(np.array([d, D, n]) / Z_SCALES, R, L0, C)
    return {k: np.asarray(v, float).ravel() for k, v in zip([*groups, "mass"], out)}


SPRINGS = [(0.0018, 0.0134, 9.0, 0.0800), (0.002, 0.02492, 5.5, 0.0792),
           (0.0016, 0.012, 20.25, 0.0793), (0.0025, 0.025, 9.0, 0.0793),
           (0.001, 0.011, 7.75, 0.0700), (0.0032, 0.016, 3.0, 0.0650)]


@pytest.mark.parametrize("d, D, n, L0", SPRINGS)
def test_the_nlp_constraints_are_the_checks_values_over_their_limits(d, D, n, L0):
    s = CoilSpring(d, D, n, "EN10270-1-SH")
    R = s.rate
    c = check(s, Duty(rate=R, free_length=L0, longest_length=L1, shortest_length=L2,
                      cycles=1e5, seating=1.0))
    g = _nlp(d, D, n, R, L0, _params())
    assert g["spring_rate"][0] == pytest.approx(0.0, abs=1e-12)
    ln = c.check_named("min_working_length")
    assert g["spring_working_length"][0] == pytest.approx(ln.value / ln.limit - 1, rel=1e-9,
                                                          abs=1e-12)
    st = c.stresses
    assert g["spring_static"].max() == pytest.approx(st["tau_c"] / st["tau_c_allowed"] - 1,
                                                     rel=1e-9, abs=1e-12)
    # fatigue: tau_kh <= tau_kH(tau_k1) is tau_k2 <= tau_kH + tau_k1, the upper stress
    upper = st["tau_kh_allowed"] + st["tau_k1"]
    assert g["spring_fatigue"].max() == pytest.approx(st["tau_k2"] / upper - 1, rel=1e-9,
                                                      abs=1e-12)
    # buckling: the NLP's expression is <= 0 exactly when the check holds
    assert (g["spring_buckling"][0] <= 0) == c.check_named("buckling").ok
    assert g["mass"][0] == pytest.approx(s.mass, rel=1e-12)
    # each group's verdict is the check's
    for group, name in (("spring_working_length", "min_working_length"),
                        ("spring_static", "static"), ("spring_fatigue", "fatigue")):
        assert (g[group].max() <= GROUPS[group][1]) == c.check_named(name).ok, name


def test_the_space_and_the_index_bound_the_diameters():
    d, D = 0.002, 0.016
    g = _nlp(d, D, 6.0, 5000.0, 0.08, _params(outer=0.0175, inner=0.0145))
    assert g["spring_space"][0] == pytest.approx((D + d) / 0.0175 - 1, rel=1e-12)
    assert g["spring_space"][1] == pytest.approx((0.0145 - (D - d)) / D, rel=1e-12)
    assert g["spring_index"] == pytest.approx([4 / 8 - 1, 8 / 20 - 1], rel=1e-12)


def test_the_required_cycles_move_the_goodman_line():
    """More cycles, a lower line: the fatigue group rises with N (10^3 .. 10^7)."""
    d, D, n, L0 = SPRINGS[0]
    R = CoilSpring(d, D, n, "EN10270-1-SH").rate
    rows = [_nlp(d, D, n, R, L0, _params(cycles=N))["spring_fatigue"][1]
            for N in (1e3, 1e4, 1e5, 1e6, 1e7)]
    assert np.all(np.diff(rows) > 0)
