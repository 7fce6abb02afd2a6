"""``[optimise.free]``: further design variables of the optimiser, each with its bounds.

Beside k, l0 and c (bounded by ``optimise.spring_k`` ...), the parameters of the other
machine elements may be chosen by the optimiser: a spring's preload, the torsion spring's
rate and free angle, the rotary damper's coefficient. A file names them in a table,

    [optimise.free]
    "design.spring_preload" = [0, 200]
    design.rotary_damper_c = [0, 2]          # (a dotted key reads the same)

and the command line as ``--free design.spring_preload=0:200`` (repeatable). The value is a
tuple of (key, lo, hi) in the parameter vector's order; empty: nothing more is free.
"""

from __future__ import annotations

from typing import Any

from ..model import elements
from ..errors import ConfigError, SoftcloseError
from .schema import BY_NAME, RANGES
from .values import fmt, in_range, number

#: what the optimiser may be given as further design variables: the numeric parameters of
#: the [design] section beyond k, l0, c
FREE_KEYS: tuple[str, ...] = tuple(
    q.key for q in elements.PARAMS
    if q.codes is None and q.key.startswith("design.")
    and q.name not in ("spring_k", "spring_rest_length", "damper_c"))
#: the attachment points the optimiser may place (SPEC §9): the spring's anchor D (world)
#: and its lid point E (lid frame), the dashpot's anchor and its lid point, per component
PLACEMENT_KEYS: tuple[str, ...] = tuple(
    f"geometry.{name}[{i}]" for name in ("spring_anchor", "lid_e", "dashpot_anchor",
                                         "dashpot_lid") for i in (0, 1))
#: every key that may be freed, in the order the NLP carries them
FREE_KEYS = FREE_KEYS + PLACEMENT_KEYS


def point_refusals(cfg, points: dict | None, n: int):
    """Why ``cfg`` refuses each row's attachment points (its one-line message, as
    ``cfg.update`` words it; "" where accepted), without a config per value: a component
    is accepted when it is a finite number within its key's range."""
    import numpy as np

    out = np.full(n, "", dtype=object)
    for k, v in (points or {}).items():
        lo, hi, _ = RANGES[k.split("[")[0]]
        v = np.asarray(v, float)
        with np.errstate(invalid="ignore"):
            bad = ~(np.isfinite(v) & (v >= lo) & (v <= hi)) & (out == "")
        if not bad.any():
            continue
        u, inv = np.unique(v[bad], return_inverse=True)
        words = []
        for x in u:
            try:
                cfg.update({k: float(x)})
                words.append(f"{k}: must be within [{lo:g}, {hi:g}], got {x:g}")
            except SoftcloseError as exc:
                words.append(str(exc).splitlines()[0])
        out[bad] = np.array(words, dtype=object)[np.asarray(inv).ravel()]
    return out


def config_value(cfg, key: str, number: bool = True):
    """The value of a key (``section.name`` or ``section.name[i]``) in ``cfg``: a float, or
    as the config holds it (a word for a coded key) when not ``number``. The one reader of a
    config value by its key."""
    section, name = key.split(".", 1)
    i = None
    if name.endswith("]"):
        name, i = name[:-1].split("[")
    v = getattr(getattr(cfg, section), name)
    v = v if i is None else v[int(i)]
    return float(v) if number else v


def _flat(table: dict, prefix: str = "") -> dict:
    out = {}
    for k, v in table.items():
        name = f"{prefix}{k}"
        if isinstance(v, dict):
            out.update(_flat(v, name + "."))
        else:
            out[name] = v
    return out


def why_not_free(key: str) -> str | None:
    """Why ``key`` cannot be a free design variable (None: it can)."""
    if key in FREE_KEYS:
        return None
    if key in ("design.spring_k", "design.spring_rest_length", "design.damper_c"):
        name = key.split(".")[1]
        return f"{key} is always a design variable: bound it with optimise.{name} = [lo, hi]"
    if key.split("[")[0] in BY_NAME and key.startswith("geometry."):
        return (f"{key}: of the geometry only the attachment points are design variables "
                f"(placement keys: {', '.join(PLACEMENT_KEYS)})")
    if key.split("[")[0] in BY_NAME:
        return f"{key} cannot be a design variable (free keys: {', '.join(FREE_KEYS)})"
    return f"unknown key {key!r} (free keys: {', '.join(FREE_KEYS)})"


def read_free(name: str, value: Any) -> tuple[tuple[str, float, float], ...]:
    """Check the ``[optimise.free]`` table (``name``: how messages call it)."""
    if not isinstance(value, dict):
        raise ConfigError(f"{name}: expected a table of KEY = [lo, hi], got {fmt(value)}")
    given = _flat(value)
    out = {}
    for key, b in given.items():
        why = why_not_free(key)
        if why:
            raise ConfigError(f"{name}: {why}")
        where = f"{name}.{key}"
        if not isinstance(b, (list, tuple)) or len(b) != 2:
            raise ConfigError(f"{where}: expected bounds [lo, hi], got {fmt(b)}")
        lo, hi = number(f"{where}[0]", b[0]), number(f"{where}[1]", b[1])
        if lo > hi:
            raise ConfigError(f"{where}: lower bound {lo:g} exceeds upper bound {hi:g}")
        base = key.split("[")[0]
        if BY_NAME[base].kind == "nonneg" and lo < 0:
            raise ConfigError(f"{where}: lower bound must be non-negative ({key} is), got "
                              f"{lo:g}")
        if base in RANGES:
            in_range(base, where, (lo, hi))
        out[key] = (lo, hi)
    return tuple((k, *out[k]) for k in FREE_KEYS if k in out)


def free_table(free) -> dict:
    """The checked value as the table a file holds ({key: [lo, hi]})."""
    return {k: [lo, hi] for k, lo, hi in free}


def parse_free_option(text: str) -> tuple[str, list]:
    """``KEY=LO:HI`` of ``--free`` as (key, [lo, hi]) (checked with the rest of the config)."""
    if "=" not in text or ":" not in text.split("=", 1)[1]:
        raise ConfigError(f"--free {text!r}: expected KEY=LO:HI, e.g. "
                          "--free design.spring_preload=0:200")
    key, rng = text.split("=", 1)
    lo, hi = rng.split(":", 1)
    vals = []
    for part, which in ((lo, "lower"), (hi, "upper")):
        try:
            vals.append(float(part))
        except ValueError:
            raise ConfigError(f"--free {text!r}: the {which} bound {part.strip()!r} is not a "
                              "number") from None
    return key.strip().strip("'\""), vals


__all__ = ["FREE_KEYS", "PLACEMENT_KEYS", "config_value", "read_free", "why_not_free", "free_table", "parse_free_option"]
