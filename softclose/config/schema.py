"""Every config key, one record each (:class:`softclose.model.keys.Key`), and the views read from them.

The linkage's own keys (lengths, masses, the stroke, the integrator, the optimiser's settings
and the ``[tolerance]`` options) are recorded here; each machine element records its keys in
its unit (:mod:`softclose.model.elements`). :data:`KEYS` is all of them, in the order of the
sections and, within a section, the linkage's keys first, then the elements' in the
registry's order. Everything else is derived from the records: :data:`SCHEMA` (kind and
default per section and key), :data:`RANGES` (admissible magnitudes), :data:`DEFAULT_SPREADS`
(``[tolerance]`` defaults), the frozen section classes (:data:`SECTION_TYPES`) and the key
tables of the docs (:mod:`softclose.config.docs`).
"""

from __future__ import annotations

from typing import Any

from ..coil_spring.materials import DEFAULT_MATERIAL, MATERIALS
from ..model import elements
from ..model.resolved import StrokeEnds
from ..model.keys import Key
from ..model.life import LIFE_KEYS

INTEGRATORS = ("rk4", "euler_cromer", "gauss4", "radau5")
HESSIANS = ("exact", "limited-memory")
#: the sections of a config, in order; "tolerance" holds spreads and their options
SECTIONS = ("geometry", "mass", "design", "friction", "stroke", "simulate", "optimise",
            "spring", "operating", "life")


#: the keys of the cranks: a hinge lid (``geometry.mechanism = "hinge"``) has none
CRANK_KEYS = (("geometry", "crank_oa"), ("geometry", "crank_bc"), ("geometry", "pivot_b"),
              ("geometry", "lid_c"), ("geometry", "assembly"), ("mass", "crank_oa"),
              ("mass", "crank_bc"), ("mass", "inertia_oa"), ("mass", "inertia_bc"))


def _half_length(v):
    return (v["geometry"]["lid_length"] / 2, 0.015)


def _rod(mass_key, length):
    return lambda v: v["mass"][mass_key] * length(v) ** 2 / 12


_L = lambda v: v["geometry"]["lid_length"]  # noqa: E731

CORE: tuple[Key, ...] = (
    # [geometry]
    Key("geometry", "mechanism", "str:four_bar,hinge", "four_bar", "",
        "`four_bar` (the linkage of the cranks OA, BC) or `hinge` (the lid turns about the "
        "ground pivot `hinge`; the cranks' keys do not apply)"),
    Key("geometry", "hinge", "vec2", (0.0, 0.0), "m",
        "hinge H (world) of a `hinge` lid: its frame's offsets are measured from H",
        lo=-10.0, hi=10.0),
    Key("geometry", "lid_length", "pos", 0.500, "m",
        "lid length L (sets the defaults of `lid_g`, `lid_tip`, `mass.inertia_lid`)",
        lo=1e-4, hi=10.0),
    Key("geometry", "crank_oa", "pos", 0.045, "m", "length l2 of crank OA", lo=1e-4, hi=10.0),
    Key("geometry", "crank_bc", "pos", 0.080, "m", "length l3 of crank BC", lo=1e-4, hi=10.0),
    Key("geometry", "pivot_b", "vec2", (0.060, 0.015), "m", "ground pivot B (world)",
        lo=-10.0, hi=10.0),
    Key("geometry", "lid_c", "vec2", (0.012, 0.013), "m", "pin C, lid frame, from A",
        lo=-10.0, hi=10.0),
    Key("geometry", "lid_g", "vec2", None, "m", "lid centre of mass G1, lid frame, from A",
        lo=-10.0, hi=10.0, derived="[L/2, 0.015]", derive=_half_length),
    Key("geometry", "lid_tip", "vec2", None, "m", "lid tip T, lid frame, from A",
        lo=-10.0, hi=10.0, derived="[L, 0.0]", derive=lambda v: (_L(v), 0.0)),
    Key("geometry", "assembly", "vec3", (18.0, 108.6655, 146.8855), "deg",
        "[theta, phi, gamma]: theta is where the branch is entered (the loop must close "
        "there); phi, gamma select the branch by their side", lo=-360.0, hi=360.0),
    # [mass]
    Key("mass", "lid", "pos", 0.5, "kg", "lid mass m1", lo=1e-4, hi=1e3, spread=0.05),
    Key("mass", "crank_oa", "pos", 0.05, "kg", "crank OA mass m2", lo=1e-4, hi=1e3),
    Key("mass", "crank_bc", "pos", 0.05, "kg", "crank BC mass m3", lo=1e-4, hi=1e3),
    Key("mass", "inertia_lid", "pos", None, "kg m^2", "lid moment of inertia about G1",
        lo=1e-15, hi=1e4, derived="m1 L²/12", derive=_rod("lid", _L)),
    Key("mass", "inertia_oa", "pos", None, "kg m^2", "crank OA inertia about its midpoint",
        lo=1e-15, hi=1e4, derived="m2 l2²/12",
        derive=_rod("crank_oa", lambda v: v["geometry"]["crank_oa"])),
    Key("mass", "inertia_bc", "pos", None, "kg m^2", "crank BC inertia about its midpoint",
        lo=1e-15, hi=1e4, derived="m3 l3²/12",
        derive=_rod("crank_bc", lambda v: v["geometry"]["crank_bc"])),
    # [stroke]
    Key("stroke", "theta0_deg", "real", 18.0, "deg",
        "release angle (must exceed `theta_closed_deg`)", lo=-360.0, hi=360.0),
    Key("stroke", "theta_closed_deg", "real", 0.0, "deg", "closed angle (the rim)",
        lo=-360.0, hi=360.0),
    Key("stroke", "theta_open_deg", "real", None, "deg",
        "fully open angle: the end of the hand-force curve and its zones (must exceed "
        "`theta_closed_deg`)", lo=-360.0, hi=360.0, derived="theta0_deg",
        derive=lambda v: v["stroke"]["theta0_deg"]),
    Key("stroke", "t_max", "pos", 5.0, "s", "longest simulated time", lo=1e-6, hi=60.0),
    # [simulate]
    Key("simulate", "integrator", "str:" + ",".join(INTEGRATORS), "rk4", "",
        "fixed-step method: `rk4` (classical Runge–Kutta, order 4), `euler_cromer` "
        "(symplectic Euler, order 1), `gauss4` (Gauss–Legendre, implicit, order 4), `radau5` "
        "(Radau IIA, implicit, L-stable, order 5)"),
    Key("simulate", "step", "pos", 0.002, "s",
        "step size (below `t_max`); the cheapest rk4 step meeting the accuracy targets on the "
        "benchmark designs", lo=1e-7, hi=1.0),
    Key("simulate", "reference_tol", "pos", 1e-12, "",
        "relative and absolute tolerance of the adaptive reference (CVODES)",
        lo=1e-14, hi=1e-3),
    # [optimise]
    Key("optimise", "closing_time_max", "pos", 1.0, "s", "latest allowed closing time",
        lo=1e-3, hi=60.0, note="a limit past `stroke.t_max` is clamped to it"),
    Key("optimise", "closing_time_min", "nonneg", 0.0, "s",
        "earliest allowed closing time (below the maximum)", lo=0.0, hi=60.0,
        note="below `stroke.t_max`"),
    Key("optimise", "holding_moment_min", "real", 0.1, "N m", "least holding moment",
        lo=-1e6, hi=1e6),
    Key("optimise", "self_close_min_deg", "real", None, "deg",
        "the lid closes by itself from every angle up to this one (dV/dθ > friction "
        "moment: a constraint of the optimiser, verified by the hand force); none: not "
        "required",
        lo=-360.0, hi=360.0, note="at most `stroke.theta_open_deg`; not with free "
        "attachment points"),
    Key("optimise", "opening_force_max", "pos", None, "N",
        "largest opening effort allowed (the hand force at the tip that lifts the lid); "
        "none: not bounded", lo=1e-6, hi=1e6),
    Key("optimise", "weight_impact", "nonneg", 1.0, "s²", "weight of impact_theta_dot² in J",
        lo=0.0, hi=1e6),
    Key("optimise", "weight_peak_tip", "nonneg", 0.1, "s²/m²",
        "weight of peak_tip_speed² in J", lo=0.0, hi=1e6),
    Key("optimise", "spring_k", "bounds", (0.0, 10000.0), "N/m", "bounds of spring_k",
        lo=0.0, hi=1e7),
    Key("optimise", "spring_rest_length", "bounds", (0.02, 0.12), "m",
        "bounds of spring_rest_length (lower > 0)", lo=1e-4, hi=10.0),
    Key("optimise", "damper_c", "bounds", (0.0, 5000.0), "N s/m", "bounds of damper_c",
        lo=0.0, hi=1e7),
    Key("optimise", "spring_kinds", "words:compression,extension,linear,gas_strut",
        ("compression", "extension"), "",
        "the kinds of spring the optimiser may choose (one problem each, the best kept): "
        "springs one can buy; `linear` (the idealised element) and `gas_strut` only when "
        "listed"),
    Key("optimise", "free", "free", None, "",
        "further design variables, a table `KEY = [lo, hi]` in the key's own unit (also "
        "`--free KEY=LO:HI`): `design.spring_preload`, `design.torsion_k`, "
        "`design.torsion_free_angle_deg`, `design.rotary_damper_c` (nominal optimiser), and "
        "the attachment points `geometry.spring_anchor[i]`, `geometry.lid_e[i]`, "
        "`geometry.dashpot_anchor[i]`, `geometry.dashpot_lid[i]` (nominal and robust); "
        "none: k, l0 and c only",
        note="`[optimise.free]` in a file"),
    Key("optimise", "keep_out", "polygons", None, "m",
        "regions the spring's and the dashpot's lines must not cross over the stroke: a list "
        "of convex polygons in the ground frame, each a list of [x, y] vertices; none: no "
        "region (a constraint of the NLP with free attachment points, checked exactly "
        "afterwards)", note="e.g. `[[[-0.05, -0.02], [0.0, -0.02], [0.0, 0.0]]]`"),
    Key("optimise", "nodes", "int+", 10, "", "shooting intervals N", lo=1, hi=1000,
        note="with nodes × substeps ≤ 2000"),
    Key("optimise", "substeps", "int+", 4, "", "RK4 sub-steps per interval M", lo=1, hi=1000),
    Key("optimise", "hessian", "str:" + ",".join(HESSIANS), "exact", "",
        "`exact` or `limited-memory` (Ipopt)"),
    Key("optimise", "linear_solver", "str:mumps,ma27,ma57,ma86,ma97", "mumps", "",
        "Ipopt linear solver: `mumps`, `ma27`, `ma57`, `ma86`, `ma97`"),
    Key("optimise", "starts", "int+", 6, "", "number of starting designs (multistart)",
        lo=1, hi=100),
    Key("optimise", "max_iter", "int+", 500, "", "Ipopt iteration limit per start",
        lo=1, hi=10000),
)

#: the coil spring made to order (SPEC §14: EN 13906-1, EN 10270, EN 15800)
SPRING: tuple[Key, ...] = (
    Key("spring", "material", "str:" + ",".join(MATERIALS), DEFAULT_MATERIAL, "",
        "spring wire: EN 10270-1 patented cold-drawn steel, grade SH or DH, or SH with the "
        "spring shot-peened (the wires with sourced strength and fatigue data)"),
    Key("spring", "wire_d", "pos", None, "m",
        "wire diameter d; none: designed (a preferred EN 10270 diameter)", lo=1e-4, hi=0.02,
        note="within the material's diameters (SH: above 0.28 mm, DH: above 0.05 mm)"),
    Key("spring", "coil_d", "pos", None, "m",
        "mean coil diameter D; none: designed (within the space)", lo=2e-4, hi=0.4,
        note="with `wire_d`: 4 ≤ D/d ≤ 20"),
    Key("spring", "active_coils", "pos", None, "coils",
        "active coils n; given with `wire_d` and `coil_d` the spring is checked, not "
        "designed; with `wire_d` alone the coil diameter is designed; none: designed (to a "
        "quarter coil for the rate)", lo=2.0, hi=1000.0, note="only with `wire_d`"),
    Key("spring", "ends", "str:closed_ground,closed", "closed_ground", "",
        "end coils: `closed_ground` (solid length n_t d) or `closed`, not ground "
        "((n_t + 1.5) d)"),
    Key("spring", "seating", "pos", 1.0, "1",
        "seating coefficient nu of the buckling check: 2 one end free, 1 both ends pinned, "
        "0.5 both ends clamped", lo=0.1, hi=10.0),
    Key("spring", "cycles", "pos", 1e5, "strokes",
        "design life: the fatigue check's Goodman line at this many strokes (the data span "
        "1e3..1e7: fewer take the 1e3 line, more the 1e7 line)", lo=1.0, hi=1e12),
    Key("spring", "max_outer_d", "pos", None, "m",
        "largest outer diameter D + d (a bore or the space); none: no limit", lo=1e-4,
        hi=1.0),
    Key("spring", "min_inner_d", "pos", None, "m",
        "smallest inner diameter D - d (a guide rod); none: no limit", lo=1e-5, hi=1.0,
        note="below `max_outer_d`"),
    Key("spring", "grade", "int+", 2, "", "EN 15800 tolerance grade: 1, 2 or 3", lo=1, hi=3),
    Key("operating", "temperature_c", "real", 23.0, "°C",
        "the temperature of a stroke: the parts' values, given at the reference temperature, "
        "follow their laws (coil springs' rate and preload, every damper's coefficient)",
        lo=-60.0, hi=150.0),
    Key("operating", "temperatures_c", "reals", (), "°C",
        "the temperatures at which a design must meet every constraint (robust design, "
        "yield, select, report); empty: `[temperature_c]`", lo=-60.0, hi=150.0),
    Key("operating", "reference_temperature_c", "real", 23.0, "°C",
        "the temperature at which the parts' values are given (datasheets: 23 °C)",
        lo=-60.0, hi=150.0),
    Key("design", "damper_temperature_coeff", "real", 0.0, "1/K",
        "beta: every viscous coefficient (dashpot, rotary, end damper) is c exp(beta (T - "
        "T_ref)); silicone-oil rotary dampers about -0.005", lo=-0.1, hi=0.1),
) + LIFE_KEYS

#: the options of the [tolerance] section (every other key there names a toleranced key)
TOLERANCE_KEYS: tuple[Key, ...] = (
    Key("tolerance", "distribution", "str:uniform,normal", "uniform", "",
        "`uniform` over nominal ± spread, or `normal` with spread = 3 sigma"),
    Key("tolerance", "required_yield", "real", 0.99, "",
        "fraction of produced lids that must meet every constraint", lo=0.0, hi=1.0,
        note="above 0"),
    Key("tolerance", "samples", "int+", 10000, "", "Monte Carlo samples of a yield estimate",
        lo=1, hi=10_000_000),
    Key("tolerance", "robust_objective", "str:worst,mean", "worst", "",
        "what the robust optimiser minimises over the scenarios: `worst` case or `mean`"),
)


def _ordered(keys) -> tuple[Key, ...]:
    return tuple(k for s in SECTIONS for k in keys if k.section == s)


#: every config key of the sections, one record each
KEYS: tuple[Key, ...] = _ordered(CORE + elements.KEYS + SPRING)
BY_NAME: dict[str, Key] = {k.full: k for k in KEYS + TOLERANCE_KEYS}
#: kind and default per section and key: {section: {name: (kind, default)}}
SCHEMA: dict[str, dict[str, tuple[str, Any]]] = {
    s: {k.name: (k.kind, k.default) for k in KEYS if k.section == s} for s in SECTIONS}
#: admissible magnitudes: full key -> (lowest, highest, unit), both ends included, SI units
#: (angles in degrees). They are wide -- a jewellery box to a car boot -- and they exist
#: because physics bounds every value: without them a 1e300 m lid overflows the inertia, a
#: spring of 1e300 N/m on a 2 kg m^2 lid overflows the linearisation, and an angle of 1e300
#: deg makes the toggle scan unbounded. Vector keys: every component; ``bounds`` keys: both
#: ends. Checked on load after the kind (sign, type), so a negative length still reads "must
#: be positive". Derived defaults (lid_g, lid_tip, the inertias) always fall inside.
RANGES: dict[str, tuple[float, float, str]] = {k.full: k.range for k in KEYS
                                                if k.range is not None}
#: spreads given unless the [tolerance] section says otherwise (relative): the design's
#: first, then the lid's (the order of the tolerance box's axes and of its samples' columns)
DEFAULT_SPREADS: dict[str, float] = {
    k.full: k.spread for s in ("design", "mass", "geometry", "stroke") for k in KEYS
    if k.section == s and k.spread is not None}
#: the [tolerance] options: name -> (kind, default)
TOLERANCE_OPTIONS: dict[str, tuple[str, Any]] = {k.name: (k.kind, k.default)
                                                 for k in TOLERANCE_KEYS}
#: the sections whose values are physical quantities of the lid and may carry a tolerance
TOLERANCE_SECTIONS = ("geometry", "mass", "design", "friction", "stroke")


class Section:
    """The checked values of one config section: attributes by key name, immutable, equal
    and hashed by value (so configs key caches), picklable."""

    __slots__ = ()
    _section = ""
    _fields: tuple[str, ...] = ()

    def __init__(self, **values):
        for name in self._fields:
            object.__setattr__(self, name, values.pop(name))
        if values:
            raise TypeError(f"[{self._section}] has no key {', '.join(values)}")

    def __setattr__(self, name, value):
        raise AttributeError(f"[{self._section}] is immutable: use cfg.set(...)")

    def _asdict(self) -> dict[str, Any]:
        return {name: getattr(self, name) for name in self._fields}

    def _values(self) -> tuple:
        return tuple(getattr(self, name) for name in self._fields)

    def __eq__(self, other):
        return type(other) is type(self) and other._values() == self._values()

    def __hash__(self):
        return hash((self._section, self._values()))

    def __repr__(self):
        return f"{type(self).__name__}(" + ", ".join(
            f"{k}={v!r}" for k, v in self._asdict().items()) + ")"

    def __reduce__(self):
        return (_section, (self._section, self._asdict()))


class _StrokeAngles:
    """The stroke's angles in radians, as the resolved stroke gives them."""
    __slots__ = ()
    theta0 = StrokeEnds.theta0
    theta_closed = StrokeEnds.theta_closed


def _section_type(section: str):
    """The class of one section, its fields the section's keys in order."""
    fields = tuple(k.name for k in KEYS if k.section == section)
    bases = (_StrokeAngles, Section) if section == "stroke" else (Section,)
    return type(section.capitalize(), bases, {
        "__slots__": fields, "_fields": fields, "_section": section, "__module__": __name__,
        "__doc__": f"The checked values of the [{section}] section."})


def _section(section: str, values: dict) -> Section:
    return SECTION_TYPES[section](**values)


#: the section classes, by section
SECTION_TYPES = {s: _section_type(s) for s in SECTIONS}
Geometry, Mass, Design, Friction, Stroke, Simulate, Optimise, Spring, Operating, Life = (
    SECTION_TYPES[s] for s in SECTIONS)


def numeric_keys() -> list[str]:
    """Every scalar key (and vector component) a sweep may vary."""
    out = []
    for k in KEYS:
        if k.kind in ("pos", "nonneg", "real"):
            out.append(k.full)
        elif k.kind in ("vec2", "vec3"):
            out += [f"{k.full}[{i}]" for i in range(k.size)]
    return out
