"""The ``[tolerance]`` section: which config values carry a manufacturing spread, and how
samples are drawn (robust design, tolerance analysis, sensitivity)."""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any

from ..errors import ConfigError
from .schema import (DEFAULT_SPREADS, SCHEMA, TOLERANCE_KEYS, TOLERANCE_OPTIONS,
                     TOLERANCE_SECTIONS)
from .values import check, fmt, number

#: most Monte Carlo samples of a tolerance analysis (10^7: ~2 min of strokes at the defaults)
MAX_TOLERANCE_SAMPLES = int(next(k.hi for k in TOLERANCE_KEYS if k.name == "samples"))
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


def read_tolerance(table: Any, values: dict[str, dict[str, Any]]) -> Tolerance:
    """Read the [tolerance] table against the checked nominal ``values`` of the config."""
    if not isinstance(table, dict):
        raise ConfigError(f"[tolerance]: expected a table of keys, got {fmt(table)}")
    opts = {}
    for name, (kind, default) in TOLERANCE_OPTIONS.items():
        opts[name] = check(f"tolerance.{name}", kind, table.get(name, default))
    if opts["samples"] > MAX_TOLERANCE_SAMPLES:
        raise ConfigError(f"tolerance.samples: {opts['samples']} is outside the admissible "
                          f"range 1..{MAX_TOLERANCE_SAMPLES:g}")
    if not 0 < opts["required_yield"] <= 1:
        raise ConfigError(f"tolerance.required_yield: must lie in (0, 1], got "
                          f"{opts['required_yield']}")
    given = {k: v for k, v in table.items() if k not in TOLERANCE_OPTIONS}
    defaults = dict(DEFAULT_SPREADS)
    if values["design"].get("spring_kind") == "gas_strut":
        # a gas strut has no rate: its force F1 carries the spring's default spread (the
        # datasheets' ±5-10 % on F1), and a spread of the unused rate is none
        rate = defaults.pop("design.spring_k", None)
        given.pop("design.spring_k", None)
        if rate is not None:
            defaults.setdefault("design.spring_preload", rate)
    spreads = []
    for key, v in {**defaults, **given}.items():
        name = f"tolerance.{key}"
        m = _TOL_KEY.match(key) if isinstance(key, str) else None
        if m is None or m.group(1) not in SCHEMA or m.group(2) not in SCHEMA[m.group(1)]:
            raise ConfigError(f"{name}: unknown key (a tolerance names a numeric config key "
                              "such as design.spring_k, mass.lid or geometry.pivot_b[0], or is "
                              f"one of {', '.join(TOLERANCE_OPTIONS)})")
        section, field, idx = m.groups()
        kind = SCHEMA[section][field][0]
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
                                  f"{{absolute = x}} / {{relative = x}}, got {fmt(v)}")
            relative = "relative" in v
            v = next(iter(v.values()))
        x = number(name, v)
        if x < 0:
            raise ConfigError(f"{name}: a spread must be non-negative, got {fmt(v)}")
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
