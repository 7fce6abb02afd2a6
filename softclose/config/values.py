"""Checking one value against its key's kind and admissible range (one-line errors)."""

from __future__ import annotations

import math
from typing import Any

from ..errors import ConfigError
from .schema import RANGES


def fmt(v: Any) -> str:
    """A value as a message shows it (a string quoted, so that "500" reads as text)."""
    if isinstance(v, str):
        return repr(v)
    return str(v)


def fmt_range(key: str) -> str:
    lo, hi, unit = RANGES[key]
    return f"{lo:g}..{hi:g}" + (f" {unit}" if unit else "")


def in_range(key: str, name: str, value: Any) -> None:
    """ConfigError (one line: key, value, admissible range) when ``value`` (a number or each
    number of a vector) lies outside ``RANGES[key]``; ``name`` is how the message names it."""
    lo, hi, unit = RANGES[key]
    for i, x in enumerate(value if isinstance(value, tuple) else (value,)):
        if not lo <= x <= hi:
            which = f"{name}[{i}]" if isinstance(value, tuple) else name
            shown = f"{x:g}" if isinstance(x, float) or abs(x) < 10 ** 15 else \
                f"{str(x)[:4]}...({len(str(abs(x)))} digits)"
            raise ConfigError(f"{which}: {shown}{' ' + unit if unit else ''} is outside the "
                              f"admissible range {fmt_range(key)}")


def got(v: Any) -> str:
    """What a value is, as a message names it: a string says it is one (``the string
    '500'``: quoted in TOML, so text, not a number)."""
    if isinstance(v, str):
        return f"the string {v!r}"
    if isinstance(v, bool):
        return "true" if v else "false"
    return fmt(v)


def _unquote_hint(v: Any) -> str:
    """' (without the quotes: 500)' when a string reads as a number."""
    if isinstance(v, str):
        try:
            x = float(v)
        except ValueError:
            return ""
        if math.isfinite(x):
            return f" (without the quotes it is a number: {v.strip()})"
    return ""


def number(key: str, v: Any) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise ConfigError(f"{key}: expected a number, got {got(v)}{_unquote_hint(v)}")
    try:
        x = float(v)
    except OverflowError:           # an integer beyond the floats (TOML allows any length)
        raise ConfigError(f"{key}: {str(v)[:12]}... is too large a number") from None
    if not math.isfinite(x):
        raise ConfigError(f"{key}: expected a finite number, got {fmt(v)}")
    return x


def check(key: str, kind: str, v: Any) -> Any:
    """Validate one value against its kind; return it normalised."""
    if kind in ("pos", "nonneg", "real"):
        x = number(key, v)
        if kind == "pos" and not x > 0:
            raise ConfigError(f"{key}: must be positive, got {fmt(v)}")
        if kind == "nonneg" and x < 0:
            raise ConfigError(f"{key}: must be non-negative, got {fmt(v)}")
        return x
    if kind in ("vec2", "vec3", "bounds"):
        n = 3 if kind == "vec3" else 2
        if not isinstance(v, (list, tuple)) or len(v) != n:
            raise ConfigError(f"{key}: expected a list of {n} numbers, got {got(v)}")
        xs = tuple(number(f"{key}[{i}]", x) for i, x in enumerate(v))
        if kind == "bounds" and xs[0] > xs[1]:
            raise ConfigError(f"{key}: lower bound {xs[0]} exceeds upper bound {xs[1]}")
        return xs
    if kind == "reals":                  # a list of numbers (may be empty)
        if not isinstance(v, (list, tuple)):
            raise ConfigError(f"{key}: expected a list of numbers, got {got(v)}")
        return tuple(number(f"{key}[{i}]", x) for i, x in enumerate(v))
    if kind == "int+":
        if isinstance(v, bool) or not isinstance(v, int):
            raise ConfigError(f"{key}: expected a whole number, got {got(v)}"
                              f"{_unquote_hint(v)}")
        if v < 1:
            raise ConfigError(f"{key}: must be at least 1, got {v}")
        return v
    if kind == "bool":
        if not isinstance(v, bool):
            raise ConfigError(f"{key}: expected true or false, got {got(v)}")
        return v
    if kind.startswith("words:"):          # a non-empty list of distinct words of the choices
        choices = kind[6:].split(",")
        if not isinstance(v, (list, tuple)) or not v:
            raise ConfigError(f"{key}: expected a list of one or more of {', '.join(choices)}; "
                              f"got {fmt(v)}")
        for w in v:
            if not isinstance(w, str) or w not in choices:
                raise ConfigError(f"{key}: expected a list of {', '.join(choices)}; got "
                                  f"{fmt(w)} in it")
        if len(set(v)) != len(v):
            raise ConfigError(f"{key}: {fmt(list(v))} names a word twice")
        return tuple(v)
    if kind.startswith("str:"):
        choices = kind[4:].split(",")
        if not isinstance(v, str) or v not in choices:
            raise ConfigError(f"{key}: expected one of {', '.join(choices)}; got {fmt(v)}")
        return v
    if kind == "polygons":               # convex polygons: lists of >= 3 [x, y] vertices
        if not isinstance(v, (list, tuple)):
            raise ConfigError(f"{key}: expected a list of polygons (each a list of [x, y] "
                              f"vertices), got {got(v)}")
        out = []
        for i, poly in enumerate(v):
            where = f"{key}[{i}]"
            if not isinstance(poly, (list, tuple)) or len(poly) < 3:
                raise ConfigError(f"{where}: expected a polygon of at least 3 [x, y] vertices, "
                                  f"got {fmt(poly)}")
            pts = tuple(check(f"{where}[{j}]", "vec2", q) for j, q in enumerate(poly))
            for j, q in enumerate(pts):
                if max(abs(q[0]), abs(q[1])) > 10.0:
                    raise ConfigError(f"{where}[{j}]: {fmt(list(q))} m is outside the "
                                      "admissible range -10 .. 10 m")
            n = len(pts)
            turns = [(pts[(j + 1) % n][0] - pts[j][0]) * (pts[(j + 2) % n][1] - pts[j][1])
                     - (pts[(j + 1) % n][1] - pts[j][1]) * (pts[(j + 2) % n][0] - pts[j][0])
                     for j in range(n)]
            if not (all(t > 0 for t in turns) or all(t < 0 for t in turns)):
                raise ConfigError(f"{where}: the polygon must be convex with distinct corners "
                                  "(split a concave region into convex ones)")
            out.append(pts)
        return tuple(out)
    raise AssertionError(kind)
