"""Writing a config back as a TOML file that :func:`softclose.config.load_config` reads to the
same :class:`Config` (``load_config(path) == cfg``, every value to the last digit).

The file holds the *whole* config, every key of every section in the order of the key
records, each with its unit and meaning as a comment: a design handed on to another person,
command or version of softclose then means the same lid even if a default changes. A derived
key (``geometry.lid_g``, ``lid_tip``, the inertias) that was not given explicitly is written
as a comment showing its value, so that it keeps following what it derives from
(``--set mass.lid=0.6`` on the file still moves the lid's inertia). Floats are written with
the shortest text that reads back to the same float (``repr``).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

from .free import free_table
from .schema import CRANK_KEYS, DEFAULT_SPREADS, KEYS, SECTIONS, TOLERANCE_KEYS


def toml_value(v: Any) -> str:
    """One value as TOML text that reads back to the same value."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if not math.isfinite(v):
            raise ValueError(f"{v!r} has no TOML form in a config")
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v, ensure_ascii=False)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{json.dumps(k)} = {toml_value(x)}" for k, x in v.items()) + "}"
    raise TypeError(f"no TOML form for {type(v).__name__}")


def _comment(text: str) -> list[str]:
    return [f"# {line}".rstrip() for line in text.splitlines()]


def _key_comment(k) -> str:
    unit = f"{k.unit}; " if k.unit else ""
    return f"# {unit}{k.doc}".replace("`", "")


def to_toml(cfg, header: str = "") -> str:
    """The whole config ``cfg`` as TOML text, ``header`` (lines of text) as a comment on top.

    ``load_config`` of the text gives ``cfg`` back exactly (tests/test_design_file.py).
    """
    out = _comment(header) + ([""] if header else [])
    hinge = cfg.geometry.mechanism == "hinge"
    for section in SECTIONS:
        values = getattr(cfg, section)._asdict()
        given = cfg.raw.get(section, {})
        out.append(f"[{section}]")
        for k in (k for k in KEYS if k.section == section):
            v = values[k.name]
            if hinge and (section, k.name) in CRANK_KEYS:      # refused on a hinge lid
                out.append(f"# {k.name}: (a hinge lid has no cranks)")
                continue
            if k.kind == "free":                              # a table of bounds by key
                v = free_table(v) if v else None
            if v is None:                                     # optional, not set
                out.append(f"# {k.name} = (not set)   {_key_comment(k)[2:]}")
                continue
            text = f"{k.name} = {toml_value(_plain(v))}"
            if k.default is None and k.derive is not None and k.name not in given:
                out.append(f"# {text}   (derived: {k.derived})")   # keep it derived
            else:
                out.append(f"{text}   {_key_comment(k)}")
        out.append("")
    tol = cfg.tolerance
    out.append("[tolerance]")
    out.append("# a plain number: relative spread (nominal ± spread x |nominal|); "
               "{absolute = x}: in the key's unit")
    for s in tol.spreads:
        v = s.value if s.relative else {"absolute": s.value}
        out.append(f"{json.dumps(s.key)} = {toml_value(v)}")
    for key in DEFAULT_SPREADS:
        if key not in tol.keys:                                # a default switched off
            out.append(f"{json.dumps(key)} = 0   # the default spread, switched off")
    for k in TOLERANCE_KEYS:
        out.append(f"{k.name} = {toml_value(getattr(tol, k.name))}   {_key_comment(k)}")
    return "\n".join(out) + "\n"


def _plain(v):
    return list(v) if isinstance(v, tuple) else v


#: the file a design is handed on in (``optimise --out``, ``optimise --robust --out``)
DESIGN_FILE = "design.toml"


def write_design(path, cfg, what: str, lines=()) -> Path:
    """Write ``cfg`` (a config whose [design] is the design handed on) as a TOML config
    file every command takes with ``--config`` (:func:`softclose.config.to_toml`: the whole
    config, read back to the same config), with a header saying what it is."""
    from ..version import __version__
    from ..files import write_text
    path = Path(path)
    d = cfg.design
    head = [f"softclose {__version__}: {what}",
            f"design: spring_k = {d.spring_k!r} N/m, spring_rest_length = "
            f"{d.spring_rest_length!r} m, damper_c = {d.damper_c!r} N s/m"
            + (f", end_damper_c = {d.end_damper_c!r} N m s/rad below end_damper_angle_deg = "
               f"{d.end_damper_angle_deg!r} deg" if d.end_damper_c else ""),
            *[x for x in lines if x],
            f"Every command takes this file: softclose yield --config {path.name}, "
            f"softclose sensitivity --config {path.name}, softclose simulate --config "
            f"{path.name} (add --set KEY=VALUE to change a key).",
            "The whole config follows, each key with its unit; a derived key left as a "
            "comment keeps following the keys it derives from."]
    return write_text(path, to_toml(cfg, "\n".join(head)))


__all__ = ["to_toml", "toml_value", "write_design", "DESIGN_FILE"]
