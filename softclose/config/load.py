"""Loading a config: TOML file + ``--set`` overrides -> an immutable, validated :class:`Config`.

Every key is optional. Each section is a frozen dataclass whose fields are the section's key
records (:mod:`softclose.config.schema`); loading checks each value against its record's
kind and admissible range, derives the missing derived defaults, checks the work a config
asks for (steps per stroke, the optimiser's grid) and raises :class:`ConfigError` with a
one-line message naming the key. Geometry that cannot be assembled is checked by the model
(:mod:`softclose.model.kinematics`), which also raises ``ConfigError``.
"""

from __future__ import annotations

import dataclasses
import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterable

from ..errors import ConfigError
from .schema import BY_NAME, CRANK_KEYS, KEYS, RANGES, SCHEMA, SECTION_TYPES, SECTIONS
from ..model.life import check_life
from .free import free_table, read_free
from .tolerance import Tolerance, read_tolerance
from .values import check, fmt, in_range, number

#: most fixed steps one stroke may take (stroke.t_max / simulate.step): bounds its loop
#: (rk4 ~0.1 us, radau5 ~0.5 us a step; 60 s at 1.2 us or 5 s at 0.1 us)
STEP_BUDGET = 5e7
#: most rows of a stroke's trajectory (simulate --out: CSV, figures; ~0.8 GB of memory and
#: 150 MB of CSV at 1e6 rows)
TRAJECTORY_BUDGET = 1_000_000
#: most RK4 steps in the optimiser's NLP (optimise.nodes x optimise.substeps)
NLP_BUDGET = 2000
#: most fixed steps of a batch of strokes (designs x STEP_BUDGET-bounded steps per stroke):
#: 20 million designs at the default step; see :func:`check_batch`
BATCH_STEP_BUDGET = 5e10


def steps_per_stroke(cfg: "Config") -> int:
    """The most fixed steps one stroke of ``cfg`` can take (ceil(t_max / step))."""
    return int(math.ceil(cfg.stroke.t_max / cfg.simulate.step * (1 - 1e-12)))


def check_batch(cfg: "Config", strokes: int, what: str = "the batch",
                budget: float = BATCH_STEP_BUDGET) -> None:
    """Refuse (ConfigError, one line) a batch of ``strokes`` strokes whose steps could exceed
    ``budget``: designs x steps per stroke bounds every batch loop (sweeps, samples)."""
    steps = steps_per_stroke(cfg)
    if strokes * steps > budget:
        raise ConfigError(
            f"{what}: {strokes} strokes of up to {steps} steps (stroke.t_max / simulate.step) is "
            f"{strokes * steps:.3g} steps, above the budget of {budget:g}; use fewer points, a "
            "larger simulate.step or a shorter stroke.t_max")


@dataclass(frozen=True)
class Config:
    geometry: Geometry
    mass: Mass
    design: Design
    friction: Friction
    stroke: Stroke
    simulate: Simulate
    optimise: Optimise
    spring: Spring
    operating: Operating
    life: Life
    tolerance: "Tolerance"
    raw: dict = dataclasses.field(default_factory=dict, repr=False, compare=False)

    def replace(self, **sections: dict[str, Any]) -> "Config":
        """A copy with keys changed, e.g. ``cfg.replace(design={"spring_k": 300.0})``.

        Values are validated exactly as if they came from a file.
        """
        raw = {k: dict(v) for k, v in self.raw.items()}
        for section, values in sections.items():
            raw.setdefault(section, {}).update(values)
        return from_dict(raw)

    def set(self, key: str, value: Any) -> "Config":
        """A copy with one key changed: ``cfg.set("mass.lid", 0.6)``,
        ``cfg.set("geometry.pivot_b[0]", 0.062)`` (validated as if from a file)."""
        return self.update({key: value})

    def update(self, values: dict[str, Any]) -> "Config":
        """A copy with several keys changed, by their full names (``section.key`` or
        ``section.key[i]``), e.g. ``cfg.update({"mass.lid": 0.6, "design.damper_c": 900})``."""
        if not values:
            return self
        raw = {k: dict(v) for k, v in self.raw.items()}
        for key, value in values.items():
            if not isinstance(key, str):
                raise ConfigError(f"config key {key!r}: expected a string like 'mass.lid'")
            _set_raw(raw, key, value.item() if hasattr(value, "item") else value,
                     origin=f"{key}")
        return from_dict(raw)

    def with_design(self, **values) -> "Config":
        """A copy with some ``[design]`` values changed, by name (validated); None leaves a
        value as it is: ``cfg.with_design(spring_k=300.0, damper_c=None)``. An attachment
        point's component among them (``lid_e[0]``, as the optimiser names a free point)
        sets that ``geometry`` key."""
        points = {f"geometry.{k}": v for k, v in values.items() if "[" in k and v is not None}
        out = self.replace(design={k: v for k, v in values.items()
                                   if v is not None and "[" not in k})
        return out.update(points) if points else out


def from_dict(raw: dict[str, Any]) -> Config:
    """Build a validated :class:`Config` from a nested dict (a parsed TOML file)."""
    if not isinstance(raw, dict):
        raise ConfigError("config: expected a table of sections")
    for section, table in raw.items():
        if section == "tolerance":
            continue                     # its keys are config keys: checked by read_tolerance
        if section not in SCHEMA:
            raise ConfigError(f"unknown config section [{section}] "
                              f"(known: {', '.join(SCHEMA)})")
        if not isinstance(table, dict):
            raise ConfigError(f"[{section}]: expected a table of keys, got {fmt(table)}")
        for key in table:
            if key not in SCHEMA[section]:
                raise ConfigError(unknown_key(section, key))
    _check_mechanism(raw)
    values: dict[str, dict[str, Any]] = {s: {} for s in SECTIONS}
    for k in KEYS:
        v = raw.get(k.section, {}).get(k.name, k.default)
        if k.kind == "free":             # a table of further design variables
            values[k.section][k.name] = None if v is None else (read_free(k.full, v) or None)
            continue
        values[k.section][k.name] = None if v is None else check(k.full, k.kind, v)
        if v is not None and k.full in RANGES:
            in_range(k.full, k.full, values[k.section][k.name])
    for k in KEYS:                       # derived defaults, from the checked values
        if values[k.section][k.name] is None and k.derive is not None:
            values[k.section][k.name] = k.derive(values)     # (else: optional, None)

    _pivots(raw, values)
    s = values["stroke"]
    if not s["theta0_deg"] > s["theta_closed_deg"]:
        raise ConfigError(f"stroke.theta0_deg: the release angle ({s['theta0_deg']}) must lie "
                          f"above stroke.theta_closed_deg ({s['theta_closed_deg']})")
    if not s["theta_open_deg"] > s["theta_closed_deg"]:
        raise ConfigError(f"stroke.theta_open_deg: the open angle ({s['theta_open_deg']}) must "
                          f"lie above stroke.theta_closed_deg ({s['theta_closed_deg']})")
    if values["simulate"]["step"] >= s["t_max"]:
        raise ConfigError(f"simulate.step: {values['simulate']['step']} s is not smaller than "
                          f"stroke.t_max = {s['t_max']} s")
    steps = s["t_max"] / values["simulate"]["step"]
    if steps > STEP_BUDGET * (1 + 1e-9):
        raise ConfigError(f"simulate.step: {values['simulate']['step']:g} s over stroke.t_max = "
                          f"{s['t_max']:g} s is {steps:.3g} steps a stroke, above the budget of "
                          f"{STEP_BUDGET:g}; use a larger simulate.step or a shorter stroke.t_max")
    o = values["optimise"]
    if o["closing_time_min"] >= o["closing_time_max"]:
        raise ConfigError(f"optimise.closing_time_min: {o['closing_time_min']} must be below "
                          f"optimise.closing_time_max = {o['closing_time_max']}")
    if o["closing_time_min"] >= s["t_max"]:   # a closing_time_max past t_max cannot bind: fine
        raise ConfigError(f"optimise.closing_time_min: {o['closing_time_min']:g} s is not below "
                          f"stroke.t_max = {s['t_max']:g} s, so no simulated stroke can meet it")
    if o["nodes"] * o["substeps"] > NLP_BUDGET:
        raise ConfigError(f"optimise.nodes x optimise.substeps: {o['nodes']} x {o['substeps']} "
                          f"= {o['nodes'] * o['substeps']} RK4 steps in the optimisation problem, "
                          f"above the budget of {NLP_BUDGET}; use fewer nodes or substeps")
    if o["spring_rest_length"][0] <= 0:
        raise ConfigError(f"optimise.spring_rest_length: lower bound must be positive, "
                          f"got {o['spring_rest_length'][0]}")
    for key in ("spring_k", "damper_c"):
        if o[key][0] < 0:
            raise ConfigError(f"optimise.{key}: lower bound must be non-negative, got {o[key][0]}")
    _check_spring(values["spring"])
    bad = check_life(values["life"])
    if bad:
        raise ConfigError(bad)
    sections = {name: SECTION_TYPES[name](**values[name]) for name in SECTIONS}
    tolerance = read_tolerance(raw.get("tolerance", {}), values)
    return Config(**sections, tolerance=tolerance, raw={k: dict(v) for k, v in raw.items()})


def _check_mechanism(raw: dict[str, Any]) -> None:
    """A hinge lid refuses the cranks' keys given explicitly (SPEC §15)."""
    geometry = raw.get("geometry", {})
    if geometry.get("mechanism", "four_bar") != "hinge":
        return
    for section, name in CRANK_KEYS:
        if name in raw.get(section, {}):
            raise ConfigError(f"{section}.{name}: a hinge lid (geometry.mechanism = \"hinge\") "
                              f"has no cranks; remove the key")
    for key in raw.get("tolerance", {}):           # a spread of a crank's key: none either
        if (key.split("[")[0].split(".")[0], key.split("[")[0].split(".")[-1]) in CRANK_KEYS:
            raise ConfigError(f"tolerance.{key}: a hinge lid (geometry.mechanism = "
                              f"\"hinge\") has no cranks; remove the spread")


def _pivots(raw: dict[str, Any], values: dict[str, dict[str, Any]]) -> None:
    """A hinge lid's cranks are massless and unused, its pivot elements sit at H; a four-bar
    has no pivot H."""
    d, given = values["design"], raw.get("design", {})
    hinge = values["geometry"]["mechanism"] == "hinge"
    if hinge:                            # no cranks: nothing of theirs moves
        values["mass"].update(crank_oa=0.0, crank_bc=0.0, inertia_oa=0.0, inertia_bc=0.0)
        if "torsion_pivot" not in given:
            d["torsion_pivot"] = "H"
    for key in ("torsion_pivot", "rotary_damper_pivot"):
        if hinge and d[key] not in ("H", "lid"):
            raise ConfigError(f"design.{key}: {d[key]!r} is a crank's pivot; a hinge lid "
                              f"(geometry.mechanism = \"hinge\") has the pivot H only")
        if not hinge and d[key] == "H":
            raise ConfigError(f"design.{key}: 'H' is the pivot of a hinge lid "
                              f"(geometry.mechanism = \"hinge\"); a four-bar has O, B, A, C")


def _check_spring(sp: dict[str, Any]) -> None:
    """The [spring] keys against each other and the wire (SPEC §14): the material's wire
    diameters, the spring index 4..20 of EN 13906-1, n only with d, the space."""
    from ..coil_spring import material, standard
    d, D = sp["wire_d"], sp["coil_d"]
    if d is not None:
        material(sp["material"]).check_wire(d)
    if d is not None and D is not None:
        standard.check_index(d, D)
    if sp["active_coils"] is not None and d is None:
        raise ConfigError("spring.active_coils: given without spring.wire_d; give the wire "
                          "too (with spring.coil_d: a spring to check; without: its coil "
                          "diameter designed), or leave it out to design one")
    lo, hi = sp["min_inner_d"], sp["max_outer_d"]
    if lo is not None and hi is not None and lo >= hi:
        raise ConfigError(f"spring.min_inner_d: {lo:g} m leaves no room below "
                          f"spring.max_outer_d = {hi:g} m")


def _nearest(word: str, known, before: str = "", after: str = "") -> str:
    """'; did you mean X?' for the closest of ``known`` to ``word`` ('' when none is close)."""
    import difflib
    near = difflib.get_close_matches(str(word), list(known), n=1, cutoff=0.6)
    return f"; did you mean {before}{near[0]}{after}?" if near else ""


def unknown_key(section: str, name: str, origin: str = "") -> str:
    """The message of an unknown key: the nearest valid key and every key of its section
    (the same for a --set and a config file)."""
    where = f"{origin}: " if origin else ""
    return (f"{where}unknown config key {section}.{name}"
            f"{_nearest(name, SCHEMA[section], section + '.')} "
            f"(known in [{section}]: {', '.join(SCHEMA[section])})")


def to_dict(cfg: Config) -> dict[str, dict[str, Any]]:
    """The config as a nested dict of plain values (lists for vectors)."""
    out = {}
    for name in SECTIONS:
        sec = getattr(cfg, name)
        out[name] = {k: (free_table(v) if BY_NAME[f"{name}.{k}"].kind == "free" and v
                         else list(v) if isinstance(v, tuple) else v)
                     for k, v in sec._asdict().items()}
    out["tolerance"] = cfg.tolerance.to_dict()
    return out




def parse_value(text: str, key: str | None = None) -> Any:
    """Read a command-line value as a TOML value; a bare word is a string. ``key`` (the key
    it is for) is named when the text cannot be read."""
    import tomllib     # (only when there is a value to read: its regexes cost ~15 ms)
    try:
        return tomllib.loads(f"v = {text.strip()}")["v"]
    except tomllib.TOMLDecodeError:
        word = text.strip()
        if re.fullmatch(r"[A-Za-z_][\w\-]*", word):
            return word
        where = f"--set {key}={word}: " if key else ""
        m = re.fullmatch(r"([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*([A-Za-z/^²\s.*]+)",
                         word)
        if m and key:                   # a number with a unit: the unit is the key's
            unit, typed = _unit(key), m.group(2).strip()
            same = typed.replace(" ", "") == unit.replace(" ", "")
            raise ConfigError(f"{where}cannot read {word!r} as a value: give the number "
                              f"alone, in {unit}" + (f" (--set {key}={m.group(1)})" if same
                                                     else f", not in {typed}")) from None
        raise ConfigError(f"{where}cannot read {word!r} as a value (use TOML syntax: "
                          f"1e4, true, [0.06, 0.015], \"rk4\")") from None


def _unit(key: str) -> str:
    """The unit of a config key as a message names it ('the key's unit' if it has none)."""
    k = BY_NAME.get(key.split("[", 1)[0])
    return k.unit if k is not None and k.unit else "the key's unit"


def apply_override(raw: dict[str, Any], text: str) -> None:
    """Apply one ``section.key=value`` or ``section.key[i]=value`` override to ``raw``."""
    if "=" not in text:
        raise ConfigError(f"--set {text!r}: expected section.key=value or section.key[i]=value")
    key, value_text = text.split("=", 1)
    _set_raw(raw, key.strip(), parse_value(value_text, key.strip()), origin=f"--set {text!r}")


_KEY = re.compile(r"^([A-Za-z_]\w*)\.([A-Za-z_]\w*)(?:\[(\d+)\])?$")


def _set_raw(raw: dict[str, Any], key: str, value: Any, origin: str) -> None:
    """Set ``section.key`` or ``section.key[i]`` (or ``tolerance.<config key>``, or
    ``optimise.free.<config key>``) in ``raw``."""
    if key.startswith("tolerance."):  # tolerance.<config key> = spread
        raw.setdefault("tolerance", {})[key[len("tolerance."):].strip().strip('"')] = value
        return
    if key.startswith("optimise.free."):  # optimise.free.<config key> = [lo, hi]
        opt = raw.setdefault("optimise", {})
        if not isinstance(opt.get("free"), dict):
            opt["free"] = {}
        opt["free"][key[len("optimise.free."):].strip().strip('"')] = value
        return
    m = _KEY.match(key)
    if not m:
        raise ConfigError(f"{origin}: expected section.key=value or section.key[i]=value")
    section, name, index = m.groups()
    if section not in SCHEMA:
        raise ConfigError(f"{origin}: unknown config section [{section}]"
                          f"{_nearest(section, list(SCHEMA) + ['tolerance'], '[', ']')} "
                          f"(known: {', '.join(SCHEMA)}, tolerance)")
    if name not in SCHEMA[section]:
        raise ConfigError(unknown_key(section, name, origin))
    table = raw.setdefault(section, {})
    if index is None:
        table[name] = value
        return
    kind, default = SCHEMA[section][name]
    if kind not in ("vec2", "vec3", "bounds"):
        raise ConfigError(f"{origin}: {section}.{name} is not a vector")
    current = table.get(name)
    if current is None:
        current = default if default is not None else _derived_default(raw, section, name)
    if not isinstance(current, (list, tuple)):   # set to a scalar earlier: no component i
        raise ConfigError(f"{origin}: {section}.{name} is {fmt(current)}, not a list of "
                          "numbers; set the whole vector first")
    current = list(current)
    i = int(index)
    if i >= len(current):
        raise ConfigError(f"{origin}: {section}.{name} has {len(current)} components")
    current[i] = value
    table[name] = current


def _derived_default(raw: dict[str, Any], section: str, key: str) -> list[float]:
    """A derived vector default (lid_g, lid_tip) from the raw values it depends on: the keys
    of its section as given (or their defaults), checked as numbers."""
    given, known, errors = raw.get(section, {}), {}, []
    for k in KEYS:
        if k.section == section and k.kind in ("pos", "nonneg", "real") and \
                (k.name in given or k.default is not None):
            try:
                known[k.name] = number(k.full, given.get(k.name, k.default))
            except ConfigError as exc:
                errors.append(exc)
        elif k.section == section and k.kind == "vec2" and k.default is not None:
            v = given.get(k.name, k.default)     # (a vector another one derives from)
            if isinstance(v, (list, tuple)) and len(v) == 2:
                known[k.name] = tuple(v)
    try:
        return list(BY_NAME[f"{section}.{key}"].derive({section: known}))
    except KeyError:                    # what it derives from is not a number: say so
        if not errors:
            raise ConfigError(f"{section}.{key}: set the keys it derives from first") from None
        raise errors[0] from None


def read_toml(path: str | Path) -> dict[str, Any]:
    """Parse a TOML config file; unreadable or malformed files raise ConfigError."""
    import tomllib
    from ..files import read_text
    text = read_text(path, f"--config {path}", "a TOML config file")
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"--config {path}: not valid TOML ({exc})") from None


def load_config(path: str | Path | None = None, overrides: Iterable[str] = ()) -> Config:
    """Load the config: defaults, then the TOML file at ``path``, then ``overrides``."""
    raw = read_toml(path) if path is not None else {}
    for text in overrides:
        apply_override(raw, text)
    return from_dict(raw)


def default_config() -> Config:
    return from_dict({})


