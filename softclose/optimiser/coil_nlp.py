"""The compression spring made to order inside the NLP (SPEC §14): its wire d, mean coil
diameter D and active coils n are decision variables tied to the rate, and EN 13906-1's
checks are constraints.

With ``spring.material`` given and the spring's geometry not, the optimiser's compression
spring is a part to wind, not a rate and a free length: the NLP carries
z = (d / mm, D / (10 mm), n / 10) after its other variables, and these constraints (d, D in
mm, forces in N, stresses in MPa; R = k the design's rate, L0 = l0 + F0 / k the free length,
L1 >= L2 the longest and shortest length the spring works at over the stroke, f the largest
G(T)/G(T_ref) over the operating temperatures)::

    rate           ln(G d^4 / (8 D^3 n)) - ln R                          = 0
    working        L_n = (n + 2) d + e d + 1.5 n (0.0015 D^2/d + 0.1 d)  <= L2
                   (e = 0 ground ends, 1.5 closed ends: L_n = L_c + S_a)
    static         tau_c = 8 R (L0 - L_c) D / (pi d^3)                  <= 0.56 R_m(d)
    fatigue        tau_k2 <= tau_kO_max(d),   tau_k2 <= t0 + (t* - t0)/t* tau_k1
                   (tau_ki = k_w f R (L0 - Li) 8 D / (pi d^3), k_w = (w + 0.5)/(w - 0.75),
                   the Goodman line at the required cycles: t0 = tau_kO3^(1-r) tau_kO7^r,
                   r = log(N / 10^3) / log(10^4))
    buckling       1 - c (pi D / (nu L0))^2 - max(0, 1 - 2 (1 - G/E) s2 / L0)^2 <= 0
                   (c = (1 - G/E)/(0.5 + G/E): s2 < s_K, or a negative radicand)
    space          D + d <= max_outer_d,   D - d >= min_inner_d
    index          4 <= D / d <= 20

the same formulas as :mod:`softclose.coil_spring` (the tests compare the two on springs of
EN 13906-1's range). R_m = min(R_max, A - B log10 d): each branch is a constraint. The
material's numbers are NLP parameters, so one structure serves every wire. The objective
gains the spring's mass times a small weight, so the NLP's spring is the lightest of those
that realise its rate (the checks depend on the rate, the lengths and z; J does not depend
on z). The answer's d, D and n are then rounded to a preferred wire, a coil diameter and a
quarter coil (:mod:`softclose.optimiser.made_to_order`).
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np

from ..coil_spring import standard as en13906
from ..coil_spring.materials import (CYCLES_DATA, CYCLES_LOW, LOW_CYCLE_FACTOR,
                                     TAU_UT_FACTOR, material)
from ..problem import PARAM_KEYS

#: the parameters of the spring's block at the end of the NLP's parameters, in order
COIL_PARAMS = ("G", "g_over_e", "rho", "f_gov", "nu", "L1", "L2", "ends_extra", "rm_a",
               "rm_b", "rm_max", "g_a", "g_b", "g_c", "g_e", "g_f", "g_g", "r_cycles",
               "max_outer_d", "min_inner_d", "mass_weight")
#: the scales of z: d in mm, D in 10 mm, n in 10 coils
Z_SCALES = np.array([1e-3, 1e-2, 10.0])
#: the constraint groups, with (lower, upper) bounds
GROUPS = {"spring_rate": (0.0, 0.0), "spring_working_length": (-np.inf, 0.0),
          "spring_static": (-np.inf, 0.0), "spring_fatigue": (-np.inf, 0.0),
          "spring_buckling": (-np.inf, 0.0), "spring_space": (-np.inf, 0.0),
          "spring_index": (-np.inf, 0.0)}
#: the mass term's weight, relative to J_ref (a tie-break among springs of one rate)
MASS_WEIGHT = 1e-4
#: the mass the weight is of (kg)
MASS_REF = 0.01
#: no space given: an outer diameter this large, an inner this small (m)
NO_SPACE = (1.0, 0.0)
_PRELOAD = PARAM_KEYS.index("spring_preload")
#: the keys of a spring's geometry in ``[spring]``: all three given, the spring is checked
GEOMETRY = ("wire_d", "coil_d", "active_coils")


def made_to_order(cfg) -> bool:
    """Does ``cfg`` ask for a coil spring made to order (``spring.material`` given, its
    geometry not)?"""
    raw = cfg.raw.get("spring", {}) if isinstance(cfg.raw, dict) else {}
    return "material" in raw and not all(k in raw for k in GEOMETRY)


def _log10(x):
    return ca.log(x) / math.log(10.0)


def coil_checks(z, R, L0, C) -> tuple[dict, ca.MX]:
    """({group: expression}, mass (kg)) of the spring z (scaled) of rate ``R`` (N/m) and
    free length ``L0`` (m) under the parameters ``C`` (:data:`COIL_PARAMS`, symbolic or
    numbers): each group's expressions lie within :data:`GROUPS`' bounds when the spring
    meets the check. EN 13906-1's formulas are :mod:`softclose.coil_spring.standard`'s own
    (SI); the strength and the Goodman line, which that module takes with a min and a
    clamp, are written here with each branch a row."""
    c = dict(zip(COIL_PARAMS, [C[i] for i in range(len(COIL_PARAMS))]))
    d, D, n = z[0] * Z_SCALES[0], z[1] * Z_SCALES[1], z[2] * Z_SCALES[2]   # m, m, coils
    L1, L2 = c["L1"], c["L2"]
    rate = en13906.rate(c["G"], d, D, n)
    Lc = en13906.solid_length(n, d) + c["ends_extra"] * d
    Ln = Lc + en13906.min_gap_sum(n, d, D)
    w = en13906.spring_index(d, D)
    kw = en13906.stress_correction(w)
    per_newton = en13906.shear_stress(1.0, d, D) * 1e-6         # MPa per N
    ld = _log10(d * 1e3)                                        # the data's d in mm
    rm_line = c["rm_a"] - c["rm_b"] * ld
    Rm = ca.fmin(c["rm_max"], rm_line)
    tau_c = per_newton * R * (L0 - Lc)
    tau_k1 = kw * per_newton * R * c["f_gov"] * (L0 - L1)
    tau_k2 = kw * per_newton * R * c["f_gov"] * (L0 - L2)
    t_o7 = c["g_a"] - c["g_b"] * ld
    t_omax = c["g_c"] - c["g_e"] * ld
    t_u7 = c["g_f"] - c["g_g"] * ld
    t_o3 = LOW_CYCLE_FACTOR * TAU_UT_FACTOR * Rm
    r = c["r_cycles"]
    t0 = ca.exp((1.0 - r) * ca.log(t_o3) + r * ca.log(t_o7))
    t_star = t_o7 / (1.0 - (t_omax - t_o7) / t_u7)
    ge = c["g_over_e"]
    radicand = 1.0 - (1.0 - ge) / (0.5 + ge) * (math.pi * D / (c["nu"] * L0)) ** 2
    q = 1.0 - 2.0 * (1.0 - ge) * (L0 - L2) / L0
    groups = {
        "spring_rate": ca.log(rate) - ca.log(R),
        "spring_working_length": (Ln - L2) / L2,
        "spring_static": ca.vertcat(tau_c / (en13906.STATIC_FACTOR * c["rm_max"]) - 1.0,
                                    tau_c / (en13906.STATIC_FACTOR * rm_line) - 1.0),
        "spring_fatigue": ca.vertcat(tau_k2 / t_omax - 1.0,
                                     tau_k2 / (t0 + (t_star - t0) / t_star * tau_k1) - 1.0),
        "spring_buckling": radicand - ca.fmax(q, 0.0) ** 2,
        "spring_space": ca.vertcat((D + d) / c["max_outer_d"] - 1.0,
                                   (c["min_inner_d"] - (D - d)) / D),
        "spring_index": ca.vertcat(en13906.INDEX_RANGE[0] / w - 1.0,
                                   w / en13906.INDEX_RANGE[1] - 1.0),
    }
    return groups, en13906.mass(d, D, n, c["rho"])


def nlp_terms(z, design, C) -> tuple[dict, ca.MX]:
    """The NLP's spring groups and its mass term (weighted, relative to J_ref = 1) for the
    design vector ``design`` (k first, l0 second, the preload at its column)."""
    R, l0, F0 = design[0], design[1], design[_PRELOAD]
    groups, mass = coil_checks(z, R, l0 + F0 / R, C)
    return groups, C[COIL_PARAMS.index("mass_weight")] * mass / MASS_REF


def coil_params(cfg) -> np.ndarray:
    """The spring block's numbers (:data:`COIL_PARAMS`) of ``cfg``: its material, the
    operating temperatures' largest G factor, the seating, the working lengths over the
    stroke, the ends, the cycles and the space."""
    from .spring_order import working_lengths
    sp = cfg.spring
    m = material(sp.material)
    op = cfg.operating
    temps = list(getattr(op, "temperatures_c", None) or [op.temperature_c])
    f_gov = max(m.g_factor(t, op.reference_temperature_c) for t in temps)
    L1, L2 = working_lengths(cfg)
    cycles = min(max(float(sp.cycles), CYCLES_LOW), CYCLES_DATA)
    r = math.log(cycles / CYCLES_LOW) / math.log(CYCLES_DATA / CYCLES_LOW)
    outer = NO_SPACE[0] if sp.max_outer_d is None else sp.max_outer_d
    inner = NO_SPACE[1] if sp.min_inner_d is None else sp.min_inner_d
    values = dict(G=m.G, g_over_e=m.G / m.E, rho=m.rho, f_gov=f_gov, nu=sp.seating, L1=L1,
                  L2=L2, ends_extra=0.0 if sp.ends == "closed_ground" else 1.5,
                  rm_a=m.rm_a, rm_b=m.rm_b, rm_max=m.rm_max,
                  **dict(zip(("g_a", "g_b", "g_c", "g_e", "g_f", "g_g"), m.goodman_10e7)),
                  r_cycles=r, max_outer_d=outer, min_inner_d=inner, mass_weight=MASS_WEIGHT)
    return np.array([float(values[k]) for k in COIL_PARAMS])


def z_bounds(cfg) -> tuple[np.ndarray, np.ndarray]:
    """(lo, hi) of z (scaled): the material's wires, n >= 2 active coils, D within the space
    (and 4 d .. 20 d, as constraints)."""
    sp = cfg.spring
    m = material(sp.material)
    d_lo, d_hi = m.d_min * 1.0001, min(m.d_max, en13906.MAX_WIRE_D)
    D_hi = NO_SPACE[0] if sp.max_outer_d is None else sp.max_outer_d
    lo = np.array([d_lo, en13906.INDEX_RANGE[0] * d_lo, en13906.MIN_ACTIVE_COILS])
    hi = np.array([d_hi, D_hi, 1000.0])
    for i, key in enumerate(GEOMETRY):                                # given: held
        v = getattr(sp, key)
        if v is not None:
            lo[i] = hi[i] = float(v)
    return lo / Z_SCALES, hi / Z_SCALES


def z_start(cfg, rate: float) -> np.ndarray:
    """A spring of ``rate`` (N/m) to start from (scaled z): index 8 and 8 coils where the
    material's wires allow, D and n from the rate, inside the bounds."""
    m = material(cfg.spring.material)
    lo, hi = z_bounds(cfg)
    w, n = 8.0, 8.0
    rate = max(float(rate), 1.0)
    d = float(np.clip(8.0 * w ** 3 * n * rate / m.G, lo[0] * Z_SCALES[0], hi[0] * Z_SCALES[0]))
    D = w * d
    if cfg.spring.max_outer_d is not None:
        D = min(D, 0.9 * cfg.spring.max_outer_d - d)
    n = max(m.G * d ** 4 / (8.0 * D ** 3 * rate), en13906.MIN_ACTIVE_COILS)
    return np.clip(np.array([d, D, n]) / Z_SCALES, lo, hi)


def spring_of(z) -> dict:
    """{wire_d, coil_d, active_coils} (SI) of a scaled z."""
    d, D, n = np.asarray(z, float) * Z_SCALES
    return {"wire_d": float(d), "coil_d": float(D), "active_coils": float(n)}


__all__ = ["made_to_order", "GEOMETRY", "COIL_PARAMS", "GROUPS", "Z_SCALES", "coil_checks",
           "nlp_terms", "coil_params", "z_bounds", "z_start", "spring_of"]
