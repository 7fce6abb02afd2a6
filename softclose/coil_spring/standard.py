"""EN 13906-1: cylindrical helical compression springs of round wire, cold coiled.

Every function takes and returns SI values (m, N, N/m, Pa, kg, Hz); each docstring states
the standard's formula in its own symbols and units where they differ (d, D in mm, F in N,
stresses in MPa, G in N/mm^2, rho in kg/dm^3). The standard applies to d <= 20 mm,
n >= 2 and 4 <= w <= 20; :func:`validate` refuses anything else.

Symbols: d wire diameter, D mean coil diameter, w = D/d spring index, n active coils,
n_t total coils, L0 free length, L_c solid length, S_a sum of minimum gaps between active
coils, R rate, F force, s deflection (L0 - L), tau shear stress, k stress correction
factor, tau_k = k tau the corrected stress, nu seating coefficient, s_K buckling
deflection, f_e natural frequency, G and E the moduli, rho the density.
"""

from __future__ import annotations

import math

from ..errors import ConfigError

#: the end forms of ``spring.ends``: closed and ground (the default), closed not ground
ENDS = ("closed_ground", "closed")
#: EN 13906-1's range of the spring index w = D/d (cold coiled)
INDEX_RANGE = (4.0, 20.0)
#: EN 13906-1's least number of active coils
MIN_ACTIVE_COILS = 2.0
#: EN 13906-1's largest wire diameter, cold coiled (m)
MAX_WIRE_D = 20e-3
#: the static limit: tau_c at solid length <= 0.56 R_m
STATIC_FACTOR = 0.56
#: the dead coils a compression spring carries besides its active ones (n_t = n + 2)
DEAD_COILS = 2.0


def _finite(x) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)


def validate(d: float, D: float, n: float, ends: str = "closed_ground") -> None:
    """Refuse a spring EN 13906-1 does not cover, in one line naming the key.

    Parameters
    ----------
    d, D : float
        Wire and mean coil diameter (m); positive, ``d <= 20 mm``.
    n : float
        Active coils, ``n >= 2``.
    ends : str
        ``"closed_ground"`` or ``"closed"``.

    Raises
    ------
    softclose.errors.ConfigError
        (a ValueError) naming ``spring.wire_d``, ``spring.coil_d``,
        ``spring.active_coils`` or ``spring.ends``.
    """
    if not _finite(d) or d <= 0:
        raise ConfigError(f"spring.wire_d: the wire diameter d must be a positive number "
                          f"of metres, got {d!r}")
    if d > MAX_WIRE_D:
        raise ConfigError(f"spring.wire_d: d = {d * 1e3:g} mm is above EN 13906-1's "
                          f"{MAX_WIRE_D * 1e3:g} mm (cold coiled)")
    if not _finite(D) or D <= 0:
        raise ConfigError(f"spring.coil_d: the mean coil diameter D must be a positive "
                          f"number of metres, got {D!r}")
    check_index(d, D)
    if not _finite(n):
        raise ConfigError(f"spring.active_coils: must be a number of coils >= "
                          f"{MIN_ACTIVE_COILS:g}, got {n!r}")
    if n < MIN_ACTIVE_COILS:
        raise ConfigError(f"spring.active_coils: n = {n:g} is below EN 13906-1's "
                          f"{MIN_ACTIVE_COILS:g} active coils")
    if ends not in ENDS:
        raise ConfigError(f"spring.ends: unknown end form {ends!r} (one of "
                          f"{', '.join(ENDS)})")


def check_index(d: float, D: float) -> None:
    """Refuse a spring index ``w = D/d`` outside 4..20, in one line naming ``spring.coil_d``."""
    w = D / d
    lo, hi = INDEX_RANGE
    if not lo <= w <= hi:
        raise ConfigError(f"spring.coil_d: the spring index w = D/d = {w:.4g} is outside "
                          f"EN 13906-1's {lo:g} <= w <= {hi:g} (d = {d * 1e3:g} mm, "
                          f"D = {D * 1e3:g} mm)")


def spring_index(d: float, D: float) -> float:
    """Spring index ``w = D/d``."""
    return D / d


def stress_correction(w: float) -> float:
    """Stress correction factor ``k = (w + 0.5)/(w - 0.75)`` (EN 13906-1, after Bergstraesser)."""
    return (w + 0.5) / (w - 0.75)


def rate(G: float, d: float, D: float, n: float) -> float:
    """Spring rate ``R = G d^4 / (8 D^3 n)`` (N/m with G in Pa, d and D in m)."""
    return G * d ** 4 / (8.0 * D ** 3 * n)


def active_coils_for_rate(G: float, d: float, D: float, R: float) -> float:
    """The (unrounded) active coils ``n = G d^4 / (8 D^3 R)`` that give rate ``R``."""
    return G * d ** 4 / (8.0 * D ** 3 * R)


def coil_d_for_rate(G: float, d: float, n: float, R: float) -> float:
    """The mean coil diameter ``D = (G d^4 / (8 n R))^(1/3)`` that gives rate ``R`` with
    wire ``d`` and ``n`` active coils (m)."""
    return (G * d ** 4 / (8.0 * n * R)) ** (1.0 / 3.0)


def total_coils(n: float) -> float:
    """Total coils ``n_t = n + 2`` (one dead coil at each end)."""
    return n + DEAD_COILS


def solid_length(n: float, d: float, ends: str = "closed_ground") -> float:
    """Solid length of a cold-coiled spring (m).

    ``L_c = n_t d`` with ends closed and ground, ``L_c = (n_t + 1.5) d`` closed, not
    ground (n_t = n + 2).
    """
    nt = total_coils(n)
    if ends == "closed_ground":
        return nt * d
    if ends == "closed":
        return (nt + 1.5) * d
    raise ConfigError(f"spring.ends: unknown end form {ends!r} (one of {', '.join(ENDS)})")


def min_gap_sum(n: float, d: float, D: float) -> float:
    """Sum of the minimum gaps between active coils under dynamic load (m).

    ``S_a = 1.5 n (0.0015 D^2/d + 0.1 d)`` (mm, d and D in mm): the static value of
    EN 13906-1 times 1.5 for a dynamically loaded, cold-coiled spring. The shortest
    permissible working length is ``L_n = L_c + S_a``.
    """
    d_mm, D_mm = d * 1e3, D * 1e3
    return 1.5 * n * (0.0015 * D_mm ** 2 / d_mm + 0.1 * d_mm) * 1e-3


def shear_stress(F: float, d: float, D: float) -> float:
    """Uncorrected shear stress ``tau = 8 F D / (pi d^3)`` (Pa; MPa with mm and N)."""
    return 8.0 * F * D / (math.pi * d ** 3)


def static_limit(tensile_strength: float) -> float:
    """Permissible uncorrected stress at solid length ``tau_c,zul = 0.56 R_m`` (Pa)."""
    return STATIC_FACTOR * tensile_strength


def buckling_deflection(L0: float, D: float, G: float, E: float, nu: float) -> float | None:
    """Deflection at which the spring buckles, ``s_K`` (m), or None if it never does.

    ``s_K = L0 * 0.5/(1 - G/E) * (1 - sqrt(1 - (1 - G/E)/(0.5 + G/E) * (pi D/(nu L0))^2))``

    with the seating coefficient nu (2: one end free; 1: both ends pinned/guided and
    floating; 0.5: both ends clamped). A negative radicand means the spring is stable at
    any deflection (None); otherwise it is safe while the largest working deflection
    ``s_2 < s_K``.
    """
    g_e = G / E
    radicand = 1.0 - (1.0 - g_e) / (0.5 + g_e) * (math.pi * D / (nu * L0)) ** 2
    if radicand < 0.0:
        return None
    return L0 * 0.5 / (1.0 - g_e) * (1.0 - math.sqrt(radicand))


def natural_frequency(d: float, D: float, n: float, G: float, rho: float) -> float:
    """First natural frequency, both ends seated, one excited (Hz).

    ``f_e = 3560 d / (n D^2) * sqrt(G / rho)`` with d, D in mm, G in N/mm^2, rho in
    kg/dm^3 (3560 rounds 1e3 sqrt(1e3) / (2 pi sqrt 2) = 3558.8 of
    ``f_e = d / (2 pi n D^2) sqrt(G / (2 rho))`` in SI; the standard's constant is kept).
    """
    d_mm, D_mm = d * 1e3, D * 1e3
    return 3560.0 * d_mm / (n * D_mm ** 2) * math.sqrt((G * 1e-6) / (rho * 1e-3))


def wire_length(D: float, n: float) -> float:
    """Length of wire ``l = pi D n_t`` (m)."""
    return math.pi * D * total_coils(n)


def mass(d: float, D: float, n: float, rho: float) -> float:
    """Mass ``m = rho (pi d^2 / 4) pi D n_t`` (kg)."""
    return rho * math.pi * d ** 2 / 4.0 * wire_length(D, n)
