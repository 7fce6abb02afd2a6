"""A compression spring to order: check a given spring against its duty, or design one.

A *duty* (:class:`Duty`) is what the lid asks of the spring: its rate R (N/m, at the
reference temperature), its free length L0, the longest and shortest lengths it works at
over the stroke, L1 and L2 (over every operating temperature), the cycles it must endure,
its seating coefficient nu and the operating temperatures. A *spring*
(:class:`CoilSpring`) is what a spring maker coils: wire material and diameter d, mean
coil diameter D, active coils n, end form.

:func:`check` judges a spring against a duty by EN 13906-1 (and gives its EN 15800
tolerances); :func:`design` searches the preferred wire diameters of EN 10270, coil
diameters on a 0.1 mm grid within the space, and n rounded to a quarter coil for the
rate, and ranks every spring that meets all checks by mass.

The checks (each ``value <relation> limit``):

- ``rate``: ``|R/R_req - 1| <= 0.125/n``, the rate is the request's within a quarter-coil
  rounding of n;
- ``min_working_length``: ``L_n = L_c + S_a <= L2``, the shortest working length keeps
  the minimum gaps between active coils (dynamic load);
- ``static``: ``tau_c <= 0.56 R_m``, the uncorrected stress at solid length (the spring
  must survive being pressed solid; at the reference temperature);
- ``fatigue``: ``tau_kh = tau_k2 - tau_k1 <= tau_kH(tau_k1, N)``, the corrected stroke
  stress under the material's Goodman line at N = ``cycles``
  (:class:`softclose.coil_spring.materials.Goodman`);
- ``buckling``: ``s_2 < s_K`` (always met when s_K does not exist);
- ``outer_d``: ``D_e = D + d <= max_outer_d`` and ``inner_d``: ``D_i = D - d >=
  min_inner_d``, when a space is given (the unloaded spring; the growth of D_e under load
  and the EN 15800 coil-diameter tolerance are not included);
- ``temperature_min``, ``temperature_max``: every operating temperature within the
  wire's usable range.

Temperature: G, and with it the rate, falls as ``1 - gamma_G (T - T_ref)``. The forces
reported are at the reference temperature; the working stresses tau_k1, tau_k2, tau_kh
are at the operating temperature where G is largest (the coldest), where they are
highest.

Extension springs (``Duty(kind="extension", initial_tension=F0)``, EN 13906-2,
:mod:`softclose.coil_spring.extension`): the body's checks, each ``value <relation> limit``:

- ``rate`` as above;
- ``body_length``: ``L_K = (n + 1) d <= L0 - 2 * 0.8 D_i``, the closed body fits within the
  free length with room for two hooks of at least 0.8 D_i each
  (:func:`softclose.coil_spring.extension.hook_room`);
- ``initial_tension``: ``tau_0 = 8 D F0 / (pi d^3)`` at the reference temperature within
  the upper end of the preferred range of initial stress at w
  (:func:`softclose.coil_spring.extension.initial_stress_range`): a body can be wound so;
- ``static``: ``tau_2 = 8 D F2 / (pi d^3) <= 0.45 R_m``, the uncorrected stress at the
  largest working force F2 = F0 + R (L2 - L0) (EN 13906-2 §10.2);
- ``fatigue``: the corrected stroke stress ``tau_kh = tau_k2 - tau_k1`` (tau_k1 at
  F1 = F0 + R (L1 - L0), the initial tension included) under the unpeened wire's Goodman
  line at N = ``cycles`` -- the body only;
- ``outer_d``, ``inner_d``, ``temperature_min``, ``temperature_max`` as above.

No buckling (an extension spring does not buckle), no solid length or coil gaps; the hooks are not
covered (``hooks`` in the result: EN 13906-2 §11 and Annex A; ask the maker); EN 15800's
tolerances are those of compression springs, so none are given.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..errors import ConfigError
from . import extension as en13906_2
from . import standard as en13906
from . import tolerances as en15800
from .checks import Check, SpringCheck, _check  # noqa: F401  (Check: re-exported)
from .materials import (DEFAULT_MATERIAL, Material, material as
                        get_material)

#: the default of ``spring.cycles``
DEFAULT_CYCLES = 1e5
#: the default of ``spring.seating`` (both ends pinned)
DEFAULT_SEATING = 1.0
#: the default reference temperature (degC)
DEFAULT_REFERENCE_C = 23.0
#: the grid of mean coil diameters the designer tries (m)
COIL_STEP = 0.1e-3
#: active coils are rounded to this (a quarter coil)
COIL_ROUNDING = 0.25


def _number(x) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)


def _positive(key: str, x, unit: str) -> float:
    if not _number(x) or x <= 0:
        raise ConfigError(f"{key}: must be a positive number ({unit}), got {x!r}")
    return float(x)


@dataclass(frozen=True)
class CoilSpring:
    """A cylindrical helical compression spring of round wire, cold coiled (EN 13906-1).

    Parameters
    ----------
    wire_d : float
        Wire diameter d (m).
    coil_d : float
        Mean coil diameter D (m); ``4 <= w = D/d <= 20``.
    active_coils : float
        Active coils n, ``n >= 2``.
    material : str
        A key of :data:`softclose.coil_spring.materials.MATERIALS`.
    ends : str
        ``"closed_ground"`` (default) or ``"closed"`` (not ground).

    Raises
    ------
    softclose.errors.ConfigError
        (a ValueError) in one line naming the key (``spring.wire_d``, ``spring.coil_d``,
        ``spring.active_coils``, ``spring.material``, ``spring.ends``).
    """

    wire_d: float
    coil_d: float
    active_coils: float
    material: str = DEFAULT_MATERIAL
    ends: str = "closed_ground"

    def __post_init__(self):
        mat = get_material(self.material)
        object.__setattr__(self, "material", mat.name)
        en13906.validate(self.wire_d, self.coil_d, self.active_coils, self.ends)
        mat.check_wire(self.wire_d)

    @property
    def mat(self) -> Material:
        """The wire's :class:`~softclose.coil_spring.materials.Material`."""
        return get_material(self.material)

    @property
    def index(self) -> float:
        """w = D/d."""
        return en13906.spring_index(self.wire_d, self.coil_d)

    @property
    def stress_correction(self) -> float:
        """k = (w + 0.5)/(w - 0.75)."""
        return en13906.stress_correction(self.index)

    @property
    def rate(self) -> float:
        """R = G d^4 / (8 D^3 n) (N/m) at the reference temperature."""
        return en13906.rate(self.mat.G, self.wire_d, self.coil_d, self.active_coils)

    def rate_at(self, temperature_c: float, reference_c: float = DEFAULT_REFERENCE_C) -> float:
        """R (1 - gamma_G (T - T_ref)) (N/m)."""
        return self.rate * self.mat.g_factor(temperature_c, reference_c)

    @property
    def total_coils(self) -> float:
        """n_t = n + 2."""
        return en13906.total_coils(self.active_coils)

    @property
    def solid_length(self) -> float:
        """L_c (m): n_t d (closed, ground) or (n_t + 1.5) d (closed)."""
        return en13906.solid_length(self.active_coils, self.wire_d, self.ends)

    @property
    def min_gap_sum(self) -> float:
        """S_a = 1.5 n (0.0015 D^2/d + 0.1 d) (m; the formula in mm)."""
        return en13906.min_gap_sum(self.active_coils, self.wire_d, self.coil_d)

    @property
    def min_working_length(self) -> float:
        """L_n = L_c + S_a (m): the shortest permissible working length."""
        return self.solid_length + self.min_gap_sum

    @property
    def outer_d(self) -> float:
        """D_e = D + d (m)."""
        return self.coil_d + self.wire_d

    @property
    def inner_d(self) -> float:
        """D_i = D - d (m)."""
        return self.coil_d - self.wire_d

    @property
    def tensile_strength(self) -> float:
        """R_m of the wire (Pa)."""
        return self.mat.tensile_strength(self.wire_d)

    @property
    def natural_frequency(self) -> float:
        """f_e = 3560 d/(n D^2) sqrt(G/rho) (Hz; d, D in mm, G in N/mm^2, rho in kg/dm^3)."""
        m = self.mat
        return en13906.natural_frequency(self.wire_d, self.coil_d, self.active_coils, m.G,
                                         m.rho)

    @property
    def wire_length(self) -> float:
        """pi D n_t (m)."""
        return en13906.wire_length(self.coil_d, self.active_coils)

    @property
    def mass(self) -> float:
        """rho (pi d^2/4) pi D n_t (kg)."""
        return en13906.mass(self.wire_d, self.coil_d, self.active_coils, self.mat.rho)

    def to_json(self) -> dict:
        return {"material": self.material, "wire_d": self.wire_d, "coil_d": self.coil_d,
                "active_coils": self.active_coils, "ends": self.ends}


#: the kinds of coil spring a duty asks for
DUTY_KINDS = ("compression", "extension")


@dataclass(frozen=True)
class Duty:
    """What the lid asks of its coil spring (SI): a compression spring (the default) or an
    extension spring (``kind="extension"``).

    Parameters
    ----------
    rate : float
        Required rate R (N/m) at the reference temperature.
    free_length : float
        L0 (m).
    longest_length, shortest_length : float
        The longest and shortest length the spring works at over the stroke, over every
        operating temperature (m). Compression: L1 and L2, ``L2 <= L1 <= L0``; extension:
        L2 and L1, ``L0 <= L1 <= L2`` (the longest is the most loaded).
    cycles : float
        Design life N (strokes), default 1e5.
    seating : float
        Seating coefficient nu of the buckling check (default 1: both ends pinned).
    temperatures_c : tuple of float
        Operating temperatures (degC), default ``(23.0,)``.
    reference_temperature_c : float
        T_ref (degC) at which ``rate`` is given.
    kind : str
        ``"compression"`` (default) or ``"extension"``.
    initial_tension : float
        An extension spring's initial tension F0 (N, >= 0; at the reference temperature);
        0 for a compression spring.

    Raises
    ------
    softclose.errors.ConfigError
        (a ValueError) in one line naming the field (``duty.rate``, ...).
    """

    rate: float
    free_length: float
    longest_length: float
    shortest_length: float
    cycles: float = DEFAULT_CYCLES
    seating: float = DEFAULT_SEATING
    temperatures_c: tuple = (DEFAULT_REFERENCE_C,)
    reference_temperature_c: float = DEFAULT_REFERENCE_C
    kind: str = "compression"
    initial_tension: float = 0.0

    def __post_init__(self):
        _positive("duty.rate", self.rate, "N/m")
        L0 = _positive("duty.free_length", self.free_length, "m")
        L1 = _positive("duty.longest_length", self.longest_length, "m")
        L2 = _positive("duty.shortest_length", self.shortest_length, "m")
        if self.kind not in DUTY_KINDS:
            raise ConfigError(f"duty.kind: {self.kind!r} is not a coil spring made to order "
                              f"(one of {', '.join(DUTY_KINDS)})")
        F0 = self.initial_tension
        if not _number(F0) or F0 < 0:
            raise ConfigError(f"duty.initial_tension: must be a number of newtons >= 0, "
                              f"got {F0!r}")
        if self.kind == "compression" and F0:
            raise ConfigError("duty.initial_tension: only an extension spring has an initial "
                              "tension (a compression spring's preload moves its free length)")
        if self.kind == "extension":
            if L2 < L0:
                raise ConfigError(f"duty.shortest_length: {L2:.6g} m is shorter than the "
                                  f"extension spring's free length L0 = {L0:.6g} m (it "
                                  "would go slack)")
            if L2 > L1:
                raise ConfigError(f"duty.shortest_length: {L2:.6g} m is longer than the "
                                  f"longest working length {L1:.6g} m")
        elif L1 > L0:
            raise ConfigError(f"duty.longest_length: L1 = {L1:.6g} m is longer than the free "
                              f"length L0 = {L0:.6g} m (a compression spring would come loose)")
        if self.kind == "compression" and L2 > L1:
            raise ConfigError(f"duty.shortest_length: L2 = {L2:.6g} m is longer than the "
                              f"longest working length L1 = {L1:.6g} m")
        _positive("spring.cycles", self.cycles, "strokes")
        _positive("spring.seating", self.seating, "the buckling seating coefficient nu")
        temps = self.temperatures_c
        if _number(temps):
            temps = (temps,)
        temps = tuple(temps) if isinstance(temps, (list, tuple)) else None
        if not temps or not all(_number(t) and t > -273.15 for t in temps):
            raise ConfigError(f"duty.temperatures_c: must be a non-empty list of degC above "
                              f"-273.15, got {self.temperatures_c!r}")
        object.__setattr__(self, "temperatures_c", tuple(float(t) for t in temps))
        if not _number(self.reference_temperature_c) or self.reference_temperature_c <= -273.15:
            raise ConfigError(f"duty.reference_temperature_c: must be degC above -273.15, "
                              f"got {self.reference_temperature_c!r}")

    def to_json(self) -> dict:
        return {"rate": self.rate, "free_length": self.free_length,
                "longest_length": self.longest_length,
                "shortest_length": self.shortest_length, "cycles": self.cycles,
                "seating": self.seating, "temperatures_c": list(self.temperatures_c),
                "reference_temperature_c": self.reference_temperature_c, "kind": self.kind,
                "initial_tension": self.initial_tension}


def _space(key, x):
    if x is None:
        return None
    return _positive(key, x, "m")


def check(spring: CoilSpring, duty: Duty, *, grade: int = en15800.DEFAULT_GRADE,
          max_outer_d: float | None = None, min_inner_d: float | None = None) -> SpringCheck:
    """Judge ``spring`` against ``duty`` by EN 13906-1, with its EN 15800 tolerances.

    Parameters
    ----------
    spring : CoilSpring
    duty : Duty
    grade : int
        EN 15800 grade 1, 2 or 3.
    max_outer_d, min_inner_d : float, optional
        The space (m): the outer diameter D_e = D + d may not exceed ``max_outer_d``, the
        inner diameter D_i = D - d may not fall below ``min_inner_d`` (e.g. a guide rod).

    Returns
    -------
    SpringCheck
        Every value and check (see the module docstring for the checks).

    Notes
    -----
    With s = L0 - L the deflection: F = R s; tau = 8 F D / (pi d^3);
    tau_k = k tau, k = (w + 0.5)/(w - 0.75); tau_c at s_c = L0 - L_c; the stroke stress
    tau_kh = tau_k2 - tau_k1 against the Goodman line of the wire at ``duty.cycles``;
    buckling s_K with nu = ``duty.seating`` against s_2 = L0 - L2.
    """
    if not isinstance(spring, CoilSpring):
        raise ConfigError(f"spring: expected a CoilSpring, got {type(spring).__name__}")
    if not isinstance(duty, Duty):
        raise ConfigError(f"duty: expected a Duty, got {type(duty).__name__}")
    en15800.quality_factor(grade)
    max_outer_d = _space("spring.max_outer_d", max_outer_d)
    min_inner_d = _space("spring.min_inner_d", min_inner_d)
    if duty.kind == "extension":
        en13906_2.validate(spring.active_coils)
        en13906_2.check_material(spring.material)
    return _evaluate(spring, duty, grade, max_outer_d, min_inner_d)


def _room_and_temperature(s, m, duty, max_outer_d, min_inner_d) -> list:
    """The checks every spring kind shares: the room it fits (outer and inner diameter, when
    given) and the duty's temperatures within its material's range."""
    checks = []
    if max_outer_d is not None:
        checks.append(_check("outer_d", s.outer_d, max_outer_d, "<=", "m"))
    if min_inner_d is not None:
        checks.append(_check("inner_d", s.inner_d, min_inner_d, ">=", "m"))
    checks.append(_check("temperature_min", min(duty.temperatures_c), m.t_min, ">=", "degC"))
    checks.append(_check("temperature_max", max(duty.temperatures_c), m.t_max, "<=", "degC"))
    return checks


def _evaluate(spring, duty, grade, max_outer_d, min_inner_d) -> SpringCheck:
    if duty.kind == "extension":
        return _evaluate_extension(spring, duty, grade, max_outer_d, min_inner_d)
    s, m = spring, spring.mat
    d, D, n = s.wire_d, s.coil_d, s.active_coils
    L0, L1, L2 = duty.free_length, duty.longest_length, duty.shortest_length
    R = s.rate
    Lc, Ln = s.solid_length, s.min_working_length
    s1, s2, sn, sc = L0 - L1, L0 - L2, L0 - Ln, L0 - Lc
    forces = {"F1": R * s1, "F2": R * s2, "Fn": R * sn, "Fc": R * sc}
    k = s.stress_correction
    per_newton = en13906.shear_stress(1.0, d, D)          # tau per N of force
    Rm = s.tensile_strength
    # working stresses at the temperature where G (and the rate) is largest
    factors, t_gov, f_gov = _governing(m, duty)
    tau_k1 = k * per_newton * R * f_gov * s1
    tau_k2 = k * per_newton * R * f_gov * s2
    tau_kh = tau_k2 - tau_k1
    tau_c = per_newton * forces["Fc"]
    tau_c_allowed = en13906.static_limit(Rm)
    tau_kh_allowed, life = _fatigue(m, d, duty, tau_k1, tau_kh)
    s_k = en13906.buckling_deflection(L0, D, m.G, m.E, duty.seating)
    buckling = {"s_k": s_k, "s_2": s2, "safe": s_k is None or s2 < s_k}
    temps = tuple({"temperature_c": t, "rate": R * f, "F1": R * f * s1, "F2": R * f * s2}
                  for t, f in factors.items())
    tol = en15800.spring_tolerances(d, D, n, R, forces["F1"], forces["F2"], grade)
    checks = [_check("min_working_length", Ln, L2, "<=", "m"),
              _check("static", tau_c, tau_c_allowed, "<=", "Pa"),
              _check("fatigue", tau_kh, tau_kh_allowed, "<=", "Pa"),
              _check("buckling", s2, s_k, "<", "m")]
    return _spring_check(
        s, duty, grade, max_outer_d, min_inner_d, forces, checks,
        stresses={"tau_k1": tau_k1, "tau_k2": tau_k2, "tau_kh": tau_kh, "tau_c": tau_c,
                  "tau_c_allowed": tau_c_allowed, "tau_kh_allowed": tau_kh_allowed},
        life=life, buckling=buckling, natural_frequency=s.natural_frequency, mass=s.mass,
        tolerance=tol, governing_temperature_c=t_gov, temperatures=temps)


def _spring_check(s, duty, grade, max_outer_d, min_inner_d, forces, checks, **rest
                  ) -> SpringCheck:
    """The :class:`SpringCheck` of ``s`` for ``duty``: its rate's check, then ``checks`` (its
    kind's), then its room's and temperatures' (:func:`_room_and_temperature`); ``rest``:
    the kind's stresses, life, buckling, mass, tolerances and temperatures."""
    dev = s.rate / duty.rate - 1.0
    checks = [_check("rate", abs(dev), COIL_ROUNDING / 2 / s.active_coils, "<=", "1"),
              *checks, *_room_and_temperature(s, s.mat, duty, max_outer_d, min_inner_d)]
    return SpringCheck(spring=s, duty=duty, grade=int(grade), max_outer_d=max_outer_d,
                       min_inner_d=min_inner_d, rate=s.rate, rate_deviation=dev,
                       forces=forces, checks=tuple(checks), **rest)


def _fatigue(m, d, duty, tau_k1, tau_kh) -> tuple:
    """(the permissible stroke stress at the lower stress tau_k1 for the duty's cycles, the
    life at the stroke stress tau_kh) of the material ``m``'s Goodman diagram at wire d."""
    goodman = m.goodman(d)
    return goodman.permissible_stroke(tau_k1, duty.cycles), goodman.life(tau_k1, tau_kh)


def _governing(m, duty):
    """({temperature: G factor}, the temperature where G is largest, its factor)."""
    t_ref = duty.reference_temperature_c
    factors = {t: m.g_factor(t, t_ref) for t in duty.temperatures_c}
    t_gov = max(factors, key=lambda t: (factors[t], -t))
    return factors, t_gov, factors[t_gov]


def _evaluate_extension(spring, duty, grade, max_outer_d, min_inner_d) -> SpringCheck:
    """EN 13906-2's body checks (module docstring): F = F0 + R (L - L0)."""
    s, m = spring, spring.mat
    d, D, n = s.wire_d, s.coil_d, s.active_coils
    L0, F0 = duty.free_length, duty.initial_tension
    L1, L2 = duty.shortest_length, duty.longest_length
    R = s.rate
    s1, s2 = L1 - L0, L2 - L0
    forces = {"F0": F0, "F1": F0 + R * s1, "F2": F0 + R * s2}
    k = s.stress_correction
    per_newton = en13906.shear_stress(1.0, d, D)          # tau per N of force
    Rm = s.tensile_strength
    # rate and initial tension scale with G: the working stresses where G is largest
    factors, t_gov, f_gov = _governing(m, duty)
    tau_k1 = k * per_newton * f_gov * forces["F1"]
    tau_k2 = k * per_newton * f_gov * forces["F2"]
    tau_kh = tau_k2 - tau_k1
    tau_0 = per_newton * F0                                # as wound (T_ref)
    tau_0_allowed = en13906_2.initial_stress_range(s.index)[1]
    tau_2 = per_newton * f_gov * forces["F2"]
    tau_2_allowed = en13906_2.static_limit(Rm)
    tau_kh_allowed, life = _fatigue(m, d, duty, tau_k1, tau_kh)
    temps = tuple({"temperature_c": t, "rate": R * f, "F0": F0 * f,
                   "F1": forces["F1"] * f, "F2": forces["F2"] * f}
                  for t, f in factors.items())
    Lk = en13906_2.body_length(n, d)
    checks = [_check("body_length", Lk, L0 - en13906_2.hook_room(D, d), "<=", "m"),
              _check("initial_tension", tau_0, tau_0_allowed, "<=", "Pa"),
              _check("static", tau_2, tau_2_allowed, "<=", "Pa"),
              _check("fatigue", tau_kh, tau_kh_allowed, "<=", "Pa")]
    return _spring_check(
        s, duty, grade, max_outer_d, min_inner_d, forces, checks,
        stresses={"tau_0": tau_0, "tau_0_allowed": tau_0_allowed, "tau_k1": tau_k1,
                  "tau_k2": tau_k2, "tau_kh": tau_kh,
                  "tau_2": tau_2, "tau_2_allowed": tau_2_allowed,
                  "tau_kh_allowed": tau_kh_allowed},
        life=life, buckling={"s_k": None, "s_2": None, "safe": True},
        natural_frequency=s.natural_frequency,
        mass=en13906_2.mass(d, D, n, m.rho), tolerance=None, governing_temperature_c=t_gov,
        temperatures=temps)
