"""Spring wire of EN 10270: elastic constants, strength, fatigue data, preferred sizes.

Only wires whose tensile strength *and* fatigue (Goodman) data are sourced are offered:
patented cold-drawn unalloyed steel wire EN 10270-1, grades SH and DH, and SH shot-peened.
The numbers are the rows of springone's material table (``database/material.csv``,
``SpringLIB`` of the open-source springone designer, which follows EN 13906-1's fatigue
diagrams); they are copied as data, in MPa and mm as the standards state them, and turned
into SI (Pa, m) at the interface.

Strength (EN 10270-1, minimum tensile strength of the wire, ``d`` in mm)::

    R_m = min(R_max, A - B log10 d)                                  [MPa]

Fatigue at N = 10^7 cycles (EN 13906-1's Goodman diagram, a straight line between two
points in the plane lower stress tau_kU -> upper stress tau_kO, ``d`` in mm)::

    tau_kO  = a - b log10 d     upper stress at zero lower stress      [MPa]
    tau_kOm = c - e log10 d     the largest upper stress (yield line)  [MPa]
    tau_kU  = f - g log10 d     lower stress where the two lines meet  [MPa]

Temperature: the shear modulus, and with it a spring's rate and preload, falls with
temperature as ``G(T) = G (1 - gamma_G (T - T_ref))``, gamma_G = 2.5e-4 /K for the steel
wires of EN 10270-1 and -2 (stainless EN 10270-3: 4.0e-4 /K; not offered, for want of
sourced fatigue data). The wires are usable from -40 to 120 degC.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..errors import ConfigError

#: preferred wire diameters of the EN 10270 series (m); the designer picks among these
PREFERRED_WIRE_D = tuple(round(v * 1e-3, 8) for v in (
    0.50, 0.56, 0.63, 0.70, 0.80, 0.90, 1.00, 1.10, 1.25, 1.40, 1.60, 1.80, 2.00, 2.25,
    2.50, 2.80, 3.00, 3.20, 3.60, 4.00, 4.50, 5.00))

#: the cycles at which the Goodman data are given (EN 13906-1's 10^7 diagram)
CYCLES_DATA = 1e7
#: the cycles of the Basquin anchor: upper stress 0.95 tau_UT at zero lower stress
CYCLES_LOW = 1e3
#: the torsional ultimate strength as a share of R_m (von Mises: 1/sqrt(3) = 0.57735)
TAU_UT_FACTOR = 1.0 / math.sqrt(3.0)
#: the Basquin anchor at 10^3 cycles as a share of tau_UT
LOW_CYCLE_FACTOR = 0.95


@dataclass(frozen=True)
class Goodman:
    """The Goodman diagram of one wire diameter (Pa), EN 13906-1, extended below 10^7
    cycles as springone does.

    At N = 10^7 the upper stress tau_kO allowed at lower stress tau_k1 rises on a straight
    line from ``tau_kO7`` (tau_k1 = 0) to the yield line ``tau_kO_max`` (reached at
    tau_k1 = ``tau_kU7``) and stays on the yield line beyond. The permissible stroke
    stress is ``tau_kH = tau_kO(tau_k1) - tau_k1``.

    Below 10^7 cycles the upper stress at zero lower stress follows a Basquin line
    ``tau_kO(N) = A N^b`` through ``0.95 tau_UT`` at 10^3 cycles (tau_UT = R_m / sqrt 3)
    and ``tau_kO7`` at 10^7; the line of N runs from ``(0, tau_kO(N))`` towards the same
    point ``(tau*, tau*)`` of the diagonal (zero stroke) as the 10^7 line does,
    ``tau* = tau_kO7 / (1 - (tau_kO_max - tau_kO7) / tau_kU7)``, and is capped by the
    yield line. springone evaluates these lines at 10^5, 10^6 and 10^7 only (and
    interpolates a life between them); here they are evaluated at any N in
    [10^3, 10^7]. Fewer than 10^3 cycles take the 10^3 line, more than 10^7 the 10^7 line
    (the end of the data: EN 13906-1 treats it as the endurance strength).
    """

    tau_kO7: float
    tau_kO_max: float
    tau_kU7: float
    tau_ut: float

    @property
    def tau_kO3(self) -> float:
        """Upper stress at zero lower stress at 10^3 cycles: 0.95 tau_UT (Pa)."""
        return LOW_CYCLE_FACTOR * self.tau_ut

    @property
    def tau_star(self) -> float:
        """Where every line of the diagram meets the diagonal tau_kO = tau_kU (Pa)."""
        slope7 = (self.tau_kO_max - self.tau_kO7) / self.tau_kU7
        return self.tau_kO7 / (1.0 - slope7)

    @property
    def basquin_exponent(self) -> float:
        """b of ``tau_kO(N) = A N^b`` through (10^3, 0.95 tau_UT) and (10^7, tau_kO7)."""
        return math.log(self.tau_kO7 / self.tau_kO3) / math.log(CYCLES_DATA / CYCLES_LOW)

    def upper_stress_at_zero(self, cycles: float) -> float:
        """tau_kO(N) at zero lower stress (Pa), ``N`` clamped to [10^3, 10^7]."""
        n = min(max(float(cycles), CYCLES_LOW), CYCLES_DATA)
        return self.tau_kO3 * (n / CYCLES_LOW) ** self.basquin_exponent

    def upper_stress(self, tau_k1: float, cycles: float) -> float:
        """The largest upper stress tau_kO at lower stress ``tau_k1`` for ``cycles`` (Pa)."""
        t0 = self.upper_stress_at_zero(cycles)
        ts = self.tau_star              # at 10^7: slope (tau_kO_max - tau_kO7) / tau_kU7
        return min(self.tau_kO_max, t0 + (ts - t0) / ts * tau_k1)

    def permissible_stroke(self, tau_k1: float, cycles: float) -> float:
        """tau_kH: the stroke stress allowed at lower stress ``tau_k1`` (Pa)."""
        return self.upper_stress(tau_k1, cycles) - tau_k1

    def life(self, tau_k1: float, tau_kh: float) -> float:
        """The cycles a stroke stress ``tau_kh`` at lower stress ``tau_k1`` endures.

        10^7 when it lies under the 10^7 line (the data end there: "10^7 or more");
        0 when it lies above the 10^3 line (outside the fatigue data: a static failure);
        otherwise the N whose line passes through it (bisection in log N).
        """
        if tau_kh <= self.permissible_stroke(tau_k1, CYCLES_DATA):
            return CYCLES_DATA
        if tau_kh > self.permissible_stroke(tau_k1, CYCLES_LOW):
            return 0.0
        lo, hi = math.log10(CYCLES_LOW), math.log10(CYCLES_DATA)
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            if self.permissible_stroke(tau_k1, 10.0 ** mid) >= tau_kh:
                lo = mid
            else:
                hi = mid
        return 10.0 ** lo


@dataclass(frozen=True)
class Material:
    """One spring wire (EN 10270): its constants in SI, its strength and fatigue data in
    the standards' units (MPa, ``d`` in mm), see the module docstring for the formulas.

    Attributes
    ----------
    name : str
        The key of ``spring.material``, e.g. ``"EN10270-1-SH"``.
    E, G : float
        Young's and shear modulus at the reference temperature (Pa).
    rho : float
        Density (kg/m^3).
    d_min, d_max : float
        The wire diameters the data cover (m): ``d_min < d <= d_max``.
    rm_a, rm_b, rm_max : float
        ``R_m = min(rm_max, rm_a - rm_b log10 d)`` (MPa, d in mm).
    goodman_10e7 : tuple
        ``(a, b, c, e, f, g)``: tau_kO7 = a - b log10 d, tau_kO_max = c - e log10 d,
        tau_kU7 = f - g log10 d (MPa, d in mm), at 10^7 cycles.
    gamma_g : float
        Relative fall of G per kelvin (1/K).
    t_min, t_max : float
        Usable temperatures (degC).
    """

    name: str
    standard: str
    description: str
    E: float
    G: float
    rho: float
    d_min: float
    d_max: float
    rm_a: float
    rm_b: float
    rm_max: float
    goodman_10e7: tuple
    gamma_g: float
    t_min: float
    t_max: float

    def check_wire(self, d: float, key: str = "spring.wire_d") -> None:
        """Refuse a wire diameter the material's data do not cover (one line naming ``key``)."""
        if not (isinstance(d, (int, float)) and math.isfinite(d)) or d <= 0:
            raise ConfigError(f"{key}: the wire diameter must be a positive number of "
                              f"metres, got {d!r}")
        if not self.d_min < d <= self.d_max:
            raise ConfigError(f"{key}: d = {d * 1e3:g} mm is outside {self.name}'s "
                              f"{self.d_min * 1e3:g} < d <= {self.d_max * 1e3:g} mm")

    def tensile_strength(self, d: float) -> float:
        """R_m = min(R_max, A - B log10(d/mm)) (Pa) of wire diameter ``d`` (m)."""
        self.check_wire(d)
        ld = math.log10(d * 1e3)
        return min(self.rm_max, self.rm_a - self.rm_b * ld) * 1e6

    def goodman(self, d: float) -> Goodman:
        """The Goodman diagram (Pa) of wire diameter ``d`` (m): see :class:`Goodman`."""
        self.check_wire(d)
        a, b, c, e, f, g = self.goodman_10e7
        ld = math.log10(d * 1e3)
        return Goodman(tau_kO7=(a - b * ld) * 1e6, tau_kO_max=(c - e * ld) * 1e6,
                       tau_kU7=(f - g * ld) * 1e6,
                       tau_ut=TAU_UT_FACTOR * self.tensile_strength(d))

    def g_factor(self, temperature_c: float, reference_c: float = 23.0) -> float:
        """G(T)/G(T_ref) = 1 - gamma_G (T - T_ref): the factor on rate and preload."""
        return 1.0 - self.gamma_g * (temperature_c - reference_c)

    def to_json(self) -> dict:
        return {"name": self.name, "standard": self.standard,
                "description": self.description, "E": self.E, "G": self.G, "rho": self.rho,
                "d_min": self.d_min, "d_max": self.d_max, "gamma_G": self.gamma_g,
                "temperature_range_c": [self.t_min, self.t_max]}


_STEEL = dict(E=206000e6, G=81500e6, rho=7850.0, gamma_g=2.5e-4, t_min=-40.0, t_max=120.0)
_UNPEENED = (506.0, 175.0, 1118.0, 410.0, 832.0, 322.0)
_PEENED = (601.0, 193.0, 1119.0, 409.0, 698.0, 273.0)

#: the wires on offer, by the name ``spring.material`` takes
MATERIALS: dict[str, Material] = {m.name: m for m in (
    Material("EN10270-1-SH", "EN 10270-1", "patented cold-drawn unalloyed steel wire, "
             "grade SH (high tensile, static and dynamic duty)", d_min=0.28e-3, d_max=20e-3,
             rm_a=2220.0, rm_b=820.0, rm_max=2660.0, goodman_10e7=_UNPEENED, **_STEEL),
    Material("EN10270-1-DH", "EN 10270-1", "patented cold-drawn unalloyed steel wire, "
             "grade DH (high tensile, dynamic duty)", d_min=0.05e-3, d_max=20e-3,
             rm_a=2218.0, rm_b=817.0, rm_max=2800.0, goodman_10e7=_UNPEENED, **_STEEL),
    Material("EN10270-1-SH-peened", "EN 10270-1", "grade SH wire, the spring shot-peened "
             "(higher fatigue strength)", d_min=0.28e-3, d_max=20e-3,
             rm_a=2220.0, rm_b=820.0, rm_max=2660.0, goodman_10e7=_PEENED, **_STEEL),
)}

#: the default of ``spring.material``
DEFAULT_MATERIAL = "EN10270-1-SH"


def material(name) -> Material:
    """The :class:`Material` called ``name``; an unknown name is refused in one line
    naming ``spring.material`` and the names on offer."""
    if isinstance(name, Material):
        return name
    try:
        return MATERIALS[name]
    except (KeyError, TypeError):
        raise ConfigError(f"spring.material: unknown material {name!r} (one of "
                          f"{', '.join(MATERIALS)}; other wires lack sourced strength "
                          "and fatigue data)") from None
