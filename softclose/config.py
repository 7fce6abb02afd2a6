"""Configuration: TOML file + ``--set`` overrides -> immutable, validated objects.

Every key is optional (SPEC §6). Each section is a frozen dataclass whose fields are
declared once in ``_SCHEMA`` with their kind and default, and in ``RANGES`` with their
admissible magnitudes; loading checks kinds, ranges and the work a config asks for (steps per
stroke, the optimiser's grid) and raises :class:`ConfigError` with a one-line message naming
the key. Geometry that cannot be assembled is checked by the model
(:mod:`softclose.kinematics`), which also raises ``ConfigError``.
"""

from __future__ import annotations

import dataclasses
import math
import re
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterable

from .errors import ConfigError

INTEGRATORS = ("rk4", "euler_cromer", "gauss4", "radau5")
HESSIANS = ("exact", "limited-memory")


# kind: "pos" (> 0), "nonneg" (>= 0), "real", "vec2", "vec3", "bounds" (2 numbers lo <= hi),
#       "int+" (positive int), "str:<choices>", "bool"; default None = derived.
_SCHEMA: dict[str, dict[str, tuple[str, Any]]] = {
    "geometry": {
        "lid_length": ("pos", 0.500),
        "crank_oa": ("pos", 0.045),
        "crank_bc": ("pos", 0.080),
        "pivot_b": ("vec2", (0.060, 0.015)),
        "lid_c": ("vec2", (0.012, 0.013)),
        "lid_e": ("vec2", (0.004, 0.014)),
        "lid_g": ("vec2", None),
        "lid_tip": ("vec2", None),
        "spring_anchor": ("vec2", (-0.060, 0.020)),
        "assembly": ("vec3", (18.0, 108.6655, 146.8855)),
    },
    "mass": {
        "lid": ("pos", 0.5),
        "crank_oa": ("pos", 0.05),
        "crank_bc": ("pos", 0.05),
        "inertia_lid": ("pos", None),
        "inertia_oa": ("pos", None),
        "inertia_bc": ("pos", None),
        "gravity": ("nonneg", 9.81),
    },
    "design": {
        "spring_k": ("nonneg", 0.0),
        "spring_rest_length": ("pos", 0.05),
        "damper_c": ("nonneg", 0.0),
        "rotary_damper_c": ("nonneg", 0.0),
    },
    "stroke": {
        "theta0_deg": ("real", 18.0),
        "theta_closed_deg": ("real", 0.0),
        "t_max": ("pos", 5.0),
    },
    "simulate": {
        "integrator": ("str:" + ",".join(INTEGRATORS), "rk4"),
        "step": ("pos", 0.002),
        "reference_tol": ("pos", 1e-12),
    },
    "optimise": {
        "closing_time_max": ("pos", 1.0),
        "closing_time_min": ("nonneg", 0.0),
        "holding_moment_min": ("real", 0.1),
        "weight_impact": ("nonneg", 1.0),
        "weight_peak_tip": ("nonneg", 0.1),
        "spring_k": ("bounds", (0.0, 10000.0)),
        "spring_rest_length": ("bounds", (0.02, 0.12)),
        "damper_c": ("bounds", (0.0, 5000.0)),
        "nodes": ("int+", 10),
        "substeps": ("int+", 4),
        "hessian": ("str:" + ",".join(HESSIANS), "exact"),
        "linear_solver": ("str:mumps,ma27,ma57,ma86,ma97", "mumps"),
        "starts": ("int+", 6),
        "max_iter": ("int+", 500),
    },
}


@dataclass(frozen=True)
class Geometry:
    lid_length: float
    crank_oa: float
    crank_bc: float
    pivot_b: tuple[float, float]
    lid_c: tuple[float, float]
    lid_e: tuple[float, float]
    lid_g: tuple[float, float]
    lid_tip: tuple[float, float]
    spring_anchor: tuple[float, float]
    assembly: tuple[float, float, float]


@dataclass(frozen=True)
class Mass:
    lid: float
    crank_oa: float
    crank_bc: float
    inertia_lid: float
    inertia_oa: float
    inertia_bc: float
    gravity: float


@dataclass(frozen=True)
class Design:
    spring_k: float
    spring_rest_length: float
    damper_c: float
    rotary_damper_c: float


@dataclass(frozen=True)
class Stroke:
    theta0_deg: float
    theta_closed_deg: float
    t_max: float

    @property
    def theta0(self) -> float:
        return math.radians(self.theta0_deg)

    @property
    def theta_closed(self) -> float:
        return math.radians(self.theta_closed_deg)


@dataclass(frozen=True)
class Simulate:
    integrator: str
    step: float
    reference_tol: float


@dataclass(frozen=True)
class Optimise:
    closing_time_max: float
    closing_time_min: float
    holding_moment_min: float
    weight_impact: float
    weight_peak_tip: float
    spring_k: tuple[float, float]
    spring_rest_length: tuple[float, float]
    damper_c: tuple[float, float]
    nodes: int
    substeps: int
    hessian: str
    linear_solver: str
    starts: int
    max_iter: int


#: Admissible magnitudes: key -> (lowest, highest, unit), both ends included, SI units (angles
#: in degrees). They are wide -- a jewellery box to a car boot -- and they exist because
#: physics bounds every value: without them a 1e300 m lid overflows the inertia, a spring of
#: 1e300 N/m on a 2 kg m^2 lid overflows the linearisation, and an angle of 1e300 deg makes the
#: toggle scan unbounded. Vector keys: every component; ``bounds`` keys: both ends. Checked on
#: load after the kind (sign, type), so a negative length still reads "must be positive".
#: Derived defaults (lid_g, lid_tip, the inertias) always fall inside. docs/model.md lists them.
RANGES: dict[str, tuple[float, float, str]] = {
    "geometry.lid_length": (1e-4, 10.0, "m"),
    "geometry.crank_oa": (1e-4, 10.0, "m"),
    "geometry.crank_bc": (1e-4, 10.0, "m"),
    "geometry.pivot_b": (-10.0, 10.0, "m"),
    "geometry.lid_c": (-10.0, 10.0, "m"),
    "geometry.lid_e": (-10.0, 10.0, "m"),
    "geometry.lid_g": (-10.0, 10.0, "m"),
    "geometry.lid_tip": (-10.0, 10.0, "m"),
    "geometry.spring_anchor": (-10.0, 10.0, "m"),
    "geometry.assembly": (-360.0, 360.0, "deg"),
    "mass.lid": (1e-4, 1e3, "kg"),
    "mass.crank_oa": (1e-4, 1e3, "kg"),
    "mass.crank_bc": (1e-4, 1e3, "kg"),
    "mass.inertia_lid": (1e-15, 1e4, "kg m^2"),
    "mass.inertia_oa": (1e-15, 1e4, "kg m^2"),
    "mass.inertia_bc": (1e-15, 1e4, "kg m^2"),
    "mass.gravity": (0.0, 100.0, "m/s^2"),
    "design.spring_k": (0.0, 1e7, "N/m"),
    "design.spring_rest_length": (1e-4, 10.0, "m"),
    "design.damper_c": (0.0, 1e7, "N s/m"),
    "design.rotary_damper_c": (0.0, 1e5, "N m s/rad"),
    "stroke.theta0_deg": (-360.0, 360.0, "deg"),
    "stroke.theta_closed_deg": (-360.0, 360.0, "deg"),
    "stroke.t_max": (1e-6, 60.0, "s"),
    "simulate.step": (1e-7, 1.0, "s"),
    "simulate.reference_tol": (1e-14, 1e-3, ""),
    "optimise.closing_time_max": (1e-3, 60.0, "s"),
    "optimise.closing_time_min": (0.0, 60.0, "s"),
    "optimise.holding_moment_min": (-1e6, 1e6, "N m"),
    "optimise.weight_impact": (0.0, 1e6, ""),
    "optimise.weight_peak_tip": (0.0, 1e6, ""),
    "optimise.spring_k": (0.0, 1e7, "N/m"),
    "optimise.spring_rest_length": (1e-4, 10.0, "m"),
    "optimise.damper_c": (0.0, 1e7, "N s/m"),
    "optimise.nodes": (1, 1000, ""),
    "optimise.substeps": (1, 1000, ""),
    "optimise.starts": (1, 100, ""),
    "optimise.max_iter": (1, 10000, ""),
}
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
#: most Monte Carlo samples of a tolerance analysis (10^7: ~2 min of strokes at the defaults)
MAX_TOLERANCE_SAMPLES = 10_000_000


def _fmt_range(key: str) -> str:
    lo, hi, unit = RANGES[key]
    return f"{lo:g}..{hi:g}" + (f" {unit}" if unit else "")


def _in_range(key: str, name: str, value: Any) -> None:
    """ConfigError (one line: key, value, admissible range) when ``value`` (a number or each
    number of a vector) lies outside ``RANGES[key]``; ``name`` is how the message names it."""
    lo, hi, unit = RANGES[key]
    for i, x in enumerate(value if isinstance(value, tuple) else (value,)):
        if not lo <= x <= hi:
            which = f"{name}[{i}]" if isinstance(value, tuple) else name
            shown = f"{x:g}" if isinstance(x, float) or abs(x) < 10 ** 15 else \
                f"{str(x)[:4]}...({len(str(abs(x)))} digits)"
            raise ConfigError(f"{which}: {shown}{' ' + unit if unit else ''} is outside the "
                              f"admissible range {_fmt_range(key)}")


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


_SECTIONS = {"geometry": Geometry, "mass": Mass, "design": Design, "stroke": Stroke,
             "simulate": Simulate, "optimise": Optimise}


@dataclass(frozen=True)
class Config:
    geometry: Geometry
    mass: Mass
    design: Design
    stroke: Stroke
    simulate: Simulate
    optimise: Optimise
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

    def with_design(self, spring_k=None, spring_rest_length=None, damper_c=None,
                    rotary_damper_c=None) -> "Config":
        """A copy with some design values changed (validated)."""
        d = {k: v for k, v in dict(spring_k=spring_k, spring_rest_length=spring_rest_length,
                                    damper_c=damper_c, rotary_damper_c=rotary_damper_c).items()
             if v is not None}
        return self.replace(design=d)


def _fmt(v: Any) -> str:
    if isinstance(v, str):
        return repr(v)
    return str(v)


def _number(key: str, v: Any) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise ConfigError(f"{key}: expected a number, got {_fmt(v)}")
    try:
        x = float(v)
    except OverflowError:           # an integer beyond the floats (TOML allows any length)
        raise ConfigError(f"{key}: {str(v)[:12]}... is too large a number") from None
    if not math.isfinite(x):
        raise ConfigError(f"{key}: expected a finite number, got {_fmt(v)}")
    return x


def _check(key: str, kind: str, v: Any) -> Any:
    """Validate one value against its kind; return it normalised."""
    if kind in ("pos", "nonneg", "real"):
        x = _number(key, v)
        if kind == "pos" and not x > 0:
            raise ConfigError(f"{key}: must be positive, got {_fmt(v)}")
        if kind == "nonneg" and x < 0:
            raise ConfigError(f"{key}: must be non-negative, got {_fmt(v)}")
        return x
    if kind in ("vec2", "vec3", "bounds"):
        n = 3 if kind == "vec3" else 2
        if not isinstance(v, (list, tuple)) or len(v) != n:
            raise ConfigError(f"{key}: expected a list of {n} numbers, got {_fmt(v)}")
        xs = tuple(_number(f"{key}[{i}]", x) for i, x in enumerate(v))
        if kind == "bounds" and xs[0] > xs[1]:
            raise ConfigError(f"{key}: lower bound {xs[0]} exceeds upper bound {xs[1]}")
        return xs
    if kind == "int+":
        if isinstance(v, bool) or not isinstance(v, int):
            raise ConfigError(f"{key}: expected a whole number, got {_fmt(v)}")
        if v < 1:
            raise ConfigError(f"{key}: must be at least 1, got {v}")
        return v
    if kind == "bool":
        if not isinstance(v, bool):
            raise ConfigError(f"{key}: expected true or false, got {_fmt(v)}")
        return v
    if kind.startswith("str:"):
        choices = kind[4:].split(",")
        if not isinstance(v, str) or v not in choices:
            raise ConfigError(f"{key}: expected one of {', '.join(choices)}; got {_fmt(v)}")
        return v
    raise AssertionError(kind)


def from_dict(raw: dict[str, Any]) -> Config:
    """Build a validated :class:`Config` from a nested dict (a parsed TOML file)."""
    if not isinstance(raw, dict):
        raise ConfigError("config: expected a table of sections")
    for section, table in raw.items():
        if section == "tolerance":
            continue                     # its keys are config keys: checked by _tolerance
        if section not in _SCHEMA:
            raise ConfigError(f"unknown config section [{section}] "
                              f"(known: {', '.join(_SCHEMA)})")
        if not isinstance(table, dict):
            raise ConfigError(f"[{section}]: expected a table of keys, got {_fmt(table)}")
        for key in table:
            if key not in _SCHEMA[section]:
                raise ConfigError(f"unknown config key {section}.{key} "
                                  f"(known in [{section}]: {', '.join(_SCHEMA[section])})")
    values: dict[str, dict[str, Any]] = {}
    for section, fields in _SCHEMA.items():
        table = raw.get(section, {})
        values[section] = {}
        for key, (kind, default) in fields.items():
            v = table.get(key, default)
            values[section][key] = None if v is None else _check(f"{section}.{key}", kind, v)
            if v is not None and f"{section}.{key}" in RANGES:
                _in_range(f"{section}.{key}", f"{section}.{key}", values[section][key])

    g, m = values["geometry"], values["mass"]
    if g["lid_g"] is None:
        g["lid_g"] = (g["lid_length"] / 2, 0.015)
    if g["lid_tip"] is None:
        g["lid_tip"] = (g["lid_length"], 0.0)
    if m["inertia_lid"] is None:
        m["inertia_lid"] = m["lid"] * g["lid_length"] ** 2 / 12
    if m["inertia_oa"] is None:
        m["inertia_oa"] = m["crank_oa"] * g["crank_oa"] ** 2 / 12
    if m["inertia_bc"] is None:
        m["inertia_bc"] = m["crank_bc"] * g["crank_bc"] ** 2 / 12

    s = values["stroke"]
    if not s["theta0_deg"] > s["theta_closed_deg"]:
        raise ConfigError(f"stroke.theta0_deg: the release angle ({s['theta0_deg']}) must lie "
                          f"above stroke.theta_closed_deg ({s['theta_closed_deg']})")
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
    sections = {name: cls(**values[name]) for name, cls in _SECTIONS.items()}
    tolerance = _tolerance(raw.get("tolerance", {}), values)
    return Config(**sections, tolerance=tolerance, raw={k: dict(v) for k, v in raw.items()})


def to_dict(cfg: Config) -> dict[str, dict[str, Any]]:
    """The config as a nested dict of plain values (lists for vectors)."""
    out = {}
    for name in _SECTIONS:
        sec = getattr(cfg, name)
        out[name] = {f.name: (list(v) if isinstance(v := getattr(sec, f.name), tuple) else v)
                     for f in dataclasses.fields(sec)}
    out["tolerance"] = cfg.tolerance.to_dict()
    return out




def parse_value(text: str) -> Any:
    """Read a command-line value as a TOML value; a bare word is a string."""
    try:
        return tomllib.loads(f"v = {text.strip()}")["v"]
    except tomllib.TOMLDecodeError:
        word = text.strip()
        if re.fullmatch(r"[A-Za-z_][\w\-]*", word):
            return word
        raise ConfigError(f"cannot read {text.strip()!r} as a value (use TOML syntax: "
                          f"1e4, true, [0.06, 0.015], \"rk4\")") from None


def apply_override(raw: dict[str, Any], text: str) -> None:
    """Apply one ``section.key=value`` or ``section.key[i]=value`` override to ``raw``."""
    if "=" not in text:
        raise ConfigError(f"--set {text!r}: expected section.key=value or section.key[i]=value")
    key, value_text = text.split("=", 1)
    _set_raw(raw, key.strip(), parse_value(value_text), origin=f"--set {text!r}")


_KEY = re.compile(r"^([A-Za-z_]\w*)\.([A-Za-z_]\w*)(?:\[(\d+)\])?$")


def _set_raw(raw: dict[str, Any], key: str, value: Any, origin: str) -> None:
    """Set ``section.key`` or ``section.key[i]`` (or ``tolerance.<config key>``) in ``raw``."""
    if key.startswith("tolerance."):  # tolerance.<config key> = spread
        raw.setdefault("tolerance", {})[key[len("tolerance."):].strip().strip('"')] = value
        return
    m = _KEY.match(key)
    if not m:
        raise ConfigError(f"{origin}: expected section.key=value or section.key[i]=value")
    section, name, index = m.groups()
    if section not in _SCHEMA:
        raise ConfigError(f"{origin}: unknown config section [{section}]")
    if name not in _SCHEMA[section]:
        raise ConfigError(f"{origin}: unknown config key {section}.{name}")
    table = raw.setdefault(section, {})
    if index is None:
        table[name] = value
        return
    kind, default = _SCHEMA[section][name]
    if kind not in ("vec2", "vec3", "bounds"):
        raise ConfigError(f"{origin}: {section}.{name} is not a vector")
    current = table.get(name)
    if current is None:
        current = default if default is not None else _derived_default(raw, section, name)
    if not isinstance(current, (list, tuple)):   # set to a scalar earlier: no component i
        raise ConfigError(f"{origin}: {section}.{name} is {_fmt(current)}, not a list of "
                          "numbers; set the whole vector first")
    current = list(current)
    i = int(index)
    if i >= len(current):
        raise ConfigError(f"{origin}: {section}.{name} has {len(current)} components")
    current[i] = value
    table[name] = current


def _derived_default(raw: dict[str, Any], section: str, key: str) -> list[float]:
    length = raw.get("geometry", {}).get("lid_length", _SCHEMA["geometry"]["lid_length"][1])
    length = _number("geometry.lid_length", length)
    return [length / 2, 0.015] if key == "lid_g" else [length, 0.0]


def read_toml(path: str | Path) -> dict[str, Any]:
    """Parse a TOML config file; unreadable or malformed files raise ConfigError."""
    p = Path(path)
    try:
        text = p.read_text()
    except OSError as exc:
        raise ConfigError(f"--config {path}: cannot read the file ({exc.strerror})") from None
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


def numeric_keys() -> list[str]:
    """Every scalar key (and vector component) a sweep may vary."""
    out = []
    for section, fields in _SCHEMA.items():
        for key, (kind, _) in fields.items():
            if kind in ("pos", "nonneg", "real"):
                out.append(f"{section}.{key}")
            elif kind in ("vec2", "vec3"):
                out += [f"{section}.{key}[{i}]" for i in range(3 if kind == "vec3" else 2)]
    return out


# -- [tolerance]: spreads of config values (robust design, tolerance analysis) -----------------
#: the sections whose values are physical quantities of the lid and may carry a tolerance
TOLERANCE_SECTIONS = ("geometry", "mass", "design", "stroke")
#: spreads given unless the file says otherwise (relative: coil springs ±10 %, dampers ±20 %)
DEFAULT_SPREADS = {"design.spring_k": 0.10, "design.damper_c": 0.20, "mass.lid": 0.05}
#: the section's settings (kind, default); every other key names a toleranced config key
TOLERANCE_OPTIONS: dict[str, tuple[str, Any]] = {
    "distribution": ("str:uniform,normal", "uniform"),
    "required_yield": ("real", 0.99),
    "samples": ("int+", 10000),
    "robust_objective": ("str:worst,mean", "worst"),
}
_TOL_KEY = re.compile(r"^([a-z_]+)\.([a-z_0-9]+)(?:\[(\d)\])?$")


@dataclass(frozen=True)
class Spread:
    """The tolerance of one config value: the box is nominal ± :meth:`half_width`.

    ``value`` is what the file says: a fraction of the nominal (``relative``) or an amount in
    the key's own unit. With ``distribution = "normal"`` the spread is 3 sigma. A relative
    spread of a design key follows the design being judged (the optimiser moves it).
    """

    key: str
    value: float
    relative: bool
    kind: str             # the key's admissible range: "pos", "nonneg" or "real"

    def half_width(self, nominal: float) -> float:
        return self.value * abs(nominal) if self.relative else self.value


@dataclass(frozen=True)
class Tolerance:
    """The ``[tolerance]`` section: the toleranced keys and how samples are drawn."""

    spreads: tuple[Spread, ...]
    distribution: str
    required_yield: float
    samples: int
    robust_objective: str

    @property
    def keys(self) -> tuple[str, ...]:
        return tuple(s.key for s in self.spreads)

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {s.key: (s.value if s.relative else {"absolute": s.value})
                               for s in self.spreads}
        out.update(distribution=self.distribution, required_yield=self.required_yield,
                   samples=self.samples, robust_objective=self.robust_objective)
        return out


def _tolerance(table: Any, values: dict[str, dict[str, Any]]) -> Tolerance:
    """Read the [tolerance] table against the checked nominal ``values`` of the config."""
    if not isinstance(table, dict):
        raise ConfigError(f"[tolerance]: expected a table of keys, got {_fmt(table)}")
    opts = {}
    for name, (kind, default) in TOLERANCE_OPTIONS.items():
        opts[name] = _check(f"tolerance.{name}", kind, table.get(name, default))
    if opts["samples"] > MAX_TOLERANCE_SAMPLES:
        raise ConfigError(f"tolerance.samples: {opts['samples']} is outside the admissible "
                          f"range 1..{MAX_TOLERANCE_SAMPLES:g}")
    if not 0 < opts["required_yield"] <= 1:
        raise ConfigError(f"tolerance.required_yield: must lie in (0, 1], got "
                          f"{opts['required_yield']}")
    given = {k: v for k, v in table.items() if k not in TOLERANCE_OPTIONS}
    spreads = []
    for key, v in {**DEFAULT_SPREADS, **given}.items():
        name = f"tolerance.{key}"
        m = _TOL_KEY.match(key) if isinstance(key, str) else None
        if m is None or m.group(1) not in _SCHEMA or m.group(2) not in _SCHEMA[m.group(1)]:
            raise ConfigError(f"{name}: unknown key (a tolerance names a numeric config key "
                              "such as design.spring_k, mass.lid or geometry.pivot_b[0], or is "
                              f"one of {', '.join(TOLERANCE_OPTIONS)})")
        section, field, idx = m.groups()
        kind = _SCHEMA[section][field][0]
        vector = kind in ("vec2", "vec3")
        if section not in TOLERANCE_SECTIONS or not (
                kind in ("pos", "nonneg", "real") and idx is None or vector and idx is not None):
            raise ConfigError(f"{name}: {key} cannot carry a tolerance (numbers of "
                              f"[{'], ['.join(TOLERANCE_SECTIONS)}] can, vector components "
                              "as key[i])")
        if vector and int(idx) >= (3 if kind == "vec3" else 2):
            raise ConfigError(f"{name}: {section}.{field} has {3 if kind == 'vec3' else 2} "
                              "components")
        relative = True
        if isinstance(v, dict):
            if len(v) != 1 or next(iter(v)) not in ("relative", "absolute"):
                raise ConfigError(f"{name}: expected a number (relative spread) or "
                                  f"{{absolute = x}} / {{relative = x}}, got {_fmt(v)}")
            relative = "relative" in v
            v = next(iter(v.values()))
        x = _number(name, v)
        if x < 0:
            raise ConfigError(f"{name}: a spread must be non-negative, got {_fmt(v)}")
        if x == 0:
            continue                                   # 0 switches a default tolerance off
        kind = "real" if vector else kind
        if relative and x >= 1 and kind == "pos":
            raise ConfigError(f"{name}: a relative spread of a positive quantity must be below "
                              f"1 (it would take {key} to zero or below), got {x:g}")
        if relative and x > 1 and kind == "nonneg":
            raise ConfigError(f"{name}: a relative spread of a non-negative quantity must be at "
                              f"most 1 (it would take {key} below zero), got {x:g}")
        nominal = values[section][field]
        nominal = float(nominal[int(idx)] if vector else nominal)
        if section != "design":   # design values move with the optimiser: checked where used
            if relative and nominal == 0 and key in given:
                raise ConfigError(f"{name}: {key} is 0, so a relative spread is no spread; "
                                  "give an absolute one, e.g. {absolute = 0.001}")
            half = x * abs(nominal) if relative else x
            if kind == "pos" and nominal - half <= 0 or kind == "nonneg" and nominal - half < 0:
                raise ConfigError(f"{name}: the spread {x:g} (absolute) takes {key} = "
                                  f"{nominal:g} to {nominal - half:g}, below its range")
        spreads.append(Spread(key, x, relative, kind))
    return Tolerance(tuple(spreads), **opts)
