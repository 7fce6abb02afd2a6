"""EN 13906-2: cylindrical helical extension springs of round wire, cold coiled -- the body.

An extension spring's body is close wound with an initial tension F0; it is pulled from its
free length L0 (between the hooks' inner edges, the body closed) to the working lengths
L1 <= L2. The body's formulas are those of EN 13906-1 (:mod:`.standard`): the rate
``R = G d^4 / (8 D^3 n)``, the shear stress ``tau = 8 F D / (pi d^3)``, the stress
correction ``k = (w + 0.5)/(w - 0.75)``, the natural frequency. What differs (EN 13906-2:2013):

- the force: ``F = F0 + R s``, s = L - L0 (the body opens only once F exceeds F0);
- the body length with its coils closed: ``L_K = (n_t + 1) d`` with n_t = n (§9: the hooks
  add no active coils), which must fit within the free length L0 with room for the two
  hooks: ``L_K + 2 L_H <= L0``, L_H at least ``0.8 D_i`` (the shortest whole German loop
  of the end forms of Annex A as makers publish them, 0.8-1.1 D_i; another end form, the
  maker's figure);
- cold coiled: ``d <= 20 mm``, ``n >= 3``, ``4 <= w <= 20`` (Table 1);
- static or quasi-static load: the uncorrected stress at the largest working force
  ``tau_2 = 8 D F2 / (pi d^3) <= tau_zul = 0.45 R_m`` (§10.2, cold coiled; the value spring
  makers quote for every spring steel: "tau_zul = 0.45 sigma_B" -- a spring stressed above it
  sets, i.e. loses part of its initial tension and does not return to its free length);
- the initial tension stress ``tau_0 = 8 D F0 / (pi d^3)`` (§10.4): the range a maker can
  wind depends on w and the coiling process. The standard's figure is not in the sourced
  data; the check uses the preferred range that Shigley's Mechanical Engineering Design
  (Budynas & Nisbett, §10-11, after Associated Spring) gives,
  ``tau_i = 231 / exp(0.105 w) -+ 6.9 (4 - (w - 3)/6.5)`` MPa, and refuses a tau_0 above
  its upper end (a body wound tighter than that cannot be coiled; a lower one can);
- dynamic load (§11): extension springs are preferably loaded statically; the standard gives
  no generally valid fatigue strength for them, because the hooks (bending and torsion at
  the bend) usually fail first. The body's stroke stress is checked here against the
  Goodman line of the unpeened wire (EN 13906-1's data, the compression spring's -- the
  close-wound body cannot be shot-peened effectively, so peened wire is refused), which
  bounds the body only;
- hooks and loops (§11, Annex A, the end forms): NOT covered -- their stresses depend on the
  end form and its bend radius: ask the maker (:data:`HOOKS_NOTE`).

Extension springs do not buckle. Every function takes and returns SI values.
"""

from __future__ import annotations

from ..errors import ConfigError

#: EN 13906-2's least number of active coils (cold coiled)
MIN_ACTIVE_COILS = 3.0
#: the static limit of the body: tau at the largest working force <= 0.45 R_m
STATIC_FACTOR = 0.45
#: the shortest hook (loop) length as a share of the inner diameter D_i (a whole German
#: loop: L_H = 0.8-1.1 D_i)
HOOK_LENGTH_FACTOR = 0.8
#: coils of wire in the two hooks together (for the mass: about one coil's wire each, as a
#: full German loop takes; the body has n)
HOOK_COILS = 2.0
#: what the checks leave out, stated in every extension spring's result
HOOKS_NOTE = ("hooks/loops not covered (hook stresses: EN 13906-2 §11 and Annex A, the end "
              "forms; ask the maker)")
#: wires whose fatigue data assume shot peening, which a close-wound body cannot take
PEENED_SUFFIX = "-peened"


def validate(n: float) -> None:
    """Refuse fewer than 3 active coils (EN 13906-2, cold coiled), naming
    ``spring.active_coils``."""
    if n < MIN_ACTIVE_COILS:
        raise ConfigError(f"spring.active_coils: n = {n:g} is below EN 13906-2's "
                          f"{MIN_ACTIVE_COILS:g} active coils of an extension spring")


def check_material(name: str) -> None:
    """Refuse a shot-peened wire for an extension spring, naming ``spring.material``."""
    if name.endswith(PEENED_SUFFIX):
        raise ConfigError(f"spring.material: {name} is shot-peened wire; the close-wound body "
                          "of an extension spring cannot be peened effectively (choose "
                          "EN10270-1-SH or EN10270-1-DH)")


def initial_stress_range(w: float) -> tuple[float, float]:
    """(lowest, highest) preferred initial tension stress tau_0 (Pa) of spring index ``w``:
    ``231 / exp(0.105 w) -+ 6.9 (4 - (w - 3)/6.5)`` MPa (Shigley, after Associated Spring;
    module docstring)."""
    import math
    mid = 231.0 / math.exp(0.105 * w)
    half = 6.9 * (4.0 - (w - 3.0) / 6.5)
    return (mid - half) * 1e6, (mid + half) * 1e6


def body_length(n: float, d: float) -> float:
    """Length of the body with its coils closed, ``L_K = (n + 1) d`` (m; EN 13906-2,
    n_t = n)."""
    return (n + 1.0) * d


def hook_room(D: float, d: float) -> float:
    """The free length the two hooks take at least, ``2 * 0.8 D_i`` (m), D_i = D - d."""
    return 2.0 * HOOK_LENGTH_FACTOR * (D - d)


def static_limit(tensile_strength: float) -> float:
    """Permissible uncorrected stress at the largest working force ``tau_zul = 0.45 R_m``
    (Pa; EN 13906-2 §10.2, cold coiled)."""
    return STATIC_FACTOR * tensile_strength


def wire_length(D: float, n: float) -> float:
    """Length of wire ``pi D (n + 2)`` (m): the body's n coils and about one coil's wire in
    each hook."""
    import math
    return math.pi * D * (n + HOOK_COILS)


def mass(d: float, D: float, n: float, rho: float) -> float:
    """Mass ``rho (pi d^2/4) pi D (n + 2)`` (kg), hooks included as about one coil each."""
    import math
    return rho * math.pi * d ** 2 / 4.0 * wire_length(D, n)


__all__ = ["MIN_ACTIVE_COILS", "STATIC_FACTOR", "HOOKS_NOTE", "validate", "check_material",
           "initial_stress_range", "body_length", "hook_room", "static_limit", "wire_length", "mass"]
