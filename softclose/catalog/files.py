"""Catalog files (SPEC §10): the springs and dampers one can buy, one part a CSV row.

Springs: ``part, kind, rate_N_per_m, free_length_m, preload_N, min_length_m, max_length_m,
rate_tolerance[, free_length_tolerance_m]``; the lengths and the rate may instead be given in
millimetres (``rate_N_per_mm, free_length_mm, min_length_mm, max_length_mm,
free_length_tolerance_mm``): the header names the unit. Kinds and how each maps onto
``design.spring_kind``:

- ``extension`` -> ``extension`` (pulls; the preload is its initial tension, valid from the
  free length up to ``max_length``);
- ``compression`` -> ``compression`` (pushes; the preload is usually 0, valid from
  ``min_length``, its solid length, up to the free length);
- ``gas_strut`` -> ``gas_strut`` (pushes with the gas law, SPEC §12): its extended length
  L_ext the free length (``design.spring_rest_length``), its force at full extension F1 the
  preload (``design.spring_preload``, > 0), its compressed length ``min_length`` (required:
  the stroke s = free length - min length is ``design.strut_stroke``). Its progression K
  (``design.strut_progression``, F at full compression / F1, 1..5) from the optional
  ``progression`` column, else from the rate as a linear spring's secant over the stroke:
  ``K = 1 + rate s / F1`` (the rate cell may be empty when ``progression`` is given; the
  entry's ``rate`` is then ``F1 (K - 1) / s``). Optional ``friction_band_N``: the
  datasheet's friction band F3 - F1 (N, >= 0), the strut's friction F_R = band / 2
  (``design.strut_friction``; empty: 0). Optional ``force_tolerance``: the relative spread
  of F1 (datasheets: ±5-10 %; empty: :data:`STRUT_FORCE_TOLERANCE`), the strut's own in
  place of ``rate_tolerance``, which does not apply to a strut (its cell may be empty).
  The free length's tolerance is read as for a coil spring.

Optional coil columns (compression and extension springs): ``wire_d_m`` (wire diameter d),
``coil_d_m`` (mean coil diameter D), ``active_coils`` (n) -- or ``wire_d_mm``, ``coil_d_mm``
-- and ``material`` (an EN 10270 wire of ``spring.material``; empty: EN10270-1-SH). A row
that gives them (all three, or none) is checked by ``select`` at its working lengths
(:mod:`.coil`: static stress, fatigue life, buckling); its rate must be the coil's,
``G d^4 / (8 D^3 n)``, within ``rate_tolerance`` (else the row is left out). Rows without
them are ranked as before.

An empty ``min_length``/``max_length`` cell is no limit. ``rate_tolerance`` is relative (0.1:
±10 %); ``free_length_tolerance`` absolute; absent (column or cell), the free length is held
to a spring maker's standard grade (:func:`standard_free_length_tolerance`).

Dampers: ``part, kind, c, pivot, c_tolerance`` -- ``dashpot`` (c in N s/m, between the lid's
``geometry.dashpot_lid`` and ``geometry.dashpot_anchor``; ``c_N_s_per_mm`` is accepted too) or
``rotary`` (c in N m s/rad at ``pivot``: lid, O, B, A or C). Optional
``temperature_coeff_per_K``: the damper's temperature coefficient beta (1/K, -0.1..0.1;
silicone oil about -0.005), its c(T) = c exp(beta (T - T_ref)): it sets
``design.damper_temperature_coeff`` for that damper (empty: the config's).

A row that cannot be used (a missing value, a negative rate, a free length above the maximum
length, an unknown kind, ...) is left out with a warning naming its line and column; a header
without a required column, or a file without one usable row, is a :class:`ConfigError`.
Lines starting with ``#`` are comments.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import ConfigError
from ..files import read_text

#: catalog kinds of spring -> design.spring_kind
SPRING_KINDS = {"extension": "extension", "compression": "compression",
                "gas_strut": "gas_strut"}
#: a gas strut's relative force tolerance when the row gives none (datasheets: ±5-10 % on F1)
STRUT_FORCE_TOLERANCE = 0.1
DAMPER_KINDS = ("dashpot", "rotary")
PIVOTS = ("lid", "O", "B", "A", "C", "H")

#: spring columns: name -> (alternative header names with their factor to SI)
_SPRING_COLS = {
    "rate": (("rate_N_per_m", 1.0), ("rate_N_per_mm", 1e3)),
    "free_length": (("free_length_m", 1.0), ("free_length_mm", 1e-3)),
    "preload": (("preload_N", 1.0),),
    "min_length": (("min_length_m", 1.0), ("min_length_mm", 1e-3)),
    "max_length": (("max_length_m", 1.0), ("max_length_mm", 1e-3)),
    "rate_tolerance": (("rate_tolerance", 1.0),),
    "free_length_tolerance": (("free_length_tolerance_m", 1.0),
                              ("free_length_tolerance_mm", 1e-3)),
    "progression": (("progression", 1.0),),
    "friction_band": (("friction_band_N", 1.0),),
    "force_tolerance": (("force_tolerance", 1.0),),
}
#: the optional spring columns (the last three a gas strut's)
_SPRING_OPTIONAL = ("free_length_tolerance", "progression", "friction_band", "force_tolerance")
#: the columns only a gas strut fills
_STRUT_ONLY = ("progression", "friction_band", "force_tolerance")
#: the optional coil columns of a spring: name -> (header names with their factor to SI)
_COIL_COLS = {
    "wire_d": (("wire_d_m", 1.0), ("wire_d_mm", 1e-3)),
    "coil_d": (("coil_d_m", 1.0), ("coil_d_mm", 1e-3)),
    "active_coils": (("active_coils", 1.0),),
}
#: the optional column naming a coil spring's wire
MATERIAL_COLUMN = "material"
#: the catalog kinds a coil can be given for
COIL_KINDS = ("compression", "extension")
_DAMPER_COLS = {
    "c": (("c", 1.0), ("c_N_s_per_m", 1.0), ("c_N_m_s_per_rad", 1.0), ("c_N_s_per_mm", 1e3)),
    "c_tolerance": (("c_tolerance", 1.0),),
    "temperature_coeff": (("temperature_coeff_per_K", 1.0),),
}


def standard_free_length_tolerance(free_length: float) -> float:
    """± free length (m) of a spring maker's standard grade (DIN 2097 grade 2 as makers'
    tables give it): ±0.9 mm up to 63 mm, ±1.3 mm up to 100 mm, ±1.5 % of the free length
    beyond (the published 40-63 mm and 63-100 mm bands are ±0.8-0.9 and ±1.1-1.3 mm: the
    upper figure is taken)."""
    if free_length <= 0.063:
        return 0.9e-3
    if free_length <= 0.100:
        return 1.3e-3
    return 0.015 * free_length


@dataclass(frozen=True)
class SpringEntry:
    """One spring of a catalog, in SI: its ``kind`` as the catalog names it, ``spring_kind``
    the model's (:data:`SPRING_KINDS`), lengths in m, the rate in N/m, the preload in N, the
    rate's relative and the free length's absolute (m) tolerance.

    A gas strut (kind ``gas_strut``) adds its ``stroke`` s (m: free length - min length), its
    ``progression`` K, its friction ``friction`` F_R (N: half the datasheet's friction band)
    and ``force_tolerance``, the relative spread of its F1 (``preload``); its ``rate`` is
    F1 (K - 1) / s (shown, not used) and ``rate_tolerance`` does not apply to it."""

    part: str
    kind: str
    rate: float
    free_length: float
    preload: float
    min_length: float | None
    max_length: float | None
    rate_tolerance: float
    free_length_tolerance: float
    line: int = field(default=0, compare=False)
    wire_d: float | None = None
    coil_d: float | None = None
    active_coils: float | None = None
    material: str | None = None
    stroke: float | None = None
    progression: float | None = None
    friction: float = 0.0
    force_tolerance: float | None = None

    @property
    def spring_kind(self) -> str:
        return SPRING_KINDS[self.kind]

    @property
    def is_strut(self) -> bool:
        return self.kind == "gas_strut"

    @property
    def coil(self):
        """The :class:`softclose.coil_spring.CoilSpring` of the row's coil columns (None
        when the row gives none)."""
        if self.wire_d is None:
            return None
        from ..coil_spring import DEFAULT_MATERIAL, CoilSpring
        return CoilSpring(self.wire_d, self.coil_d, self.active_coils,
                          self.material or DEFAULT_MATERIAL)

    def design(self) -> dict:
        """The [design] values of this spring (nominal); a gas strut's rate is 0 (unused)."""
        if self.is_strut:
            return {"spring_kind": "gas_strut", "spring_k": 0.0,
                    "spring_rest_length": self.free_length, "spring_preload": self.preload,
                    "strut_stroke": self.stroke, "strut_progression": self.progression,
                    "strut_friction": self.friction}
        return {"spring_kind": self.spring_kind, "spring_k": self.rate,
                "spring_rest_length": self.free_length, "spring_preload": self.preload}

    def to_json(self) -> dict:
        return {"part": self.part, "kind": self.kind, "rate_N_per_m": self.rate,
                "free_length_m": self.free_length, "preload_N": self.preload,
                "min_length_m": self.min_length, "max_length_m": self.max_length,
                "rate_tolerance": self.rate_tolerance,
                "free_length_tolerance_m": self.free_length_tolerance,
                **({} if self.wire_d is None else {
                    "wire_d_m": self.wire_d, "coil_d_m": self.coil_d,
                    "active_coils": self.active_coils, "material": self.material}),
                **({} if not self.is_strut else {
                    "stroke_m": self.stroke, "progression": self.progression,
                    "friction_band_N": 2 * self.friction,
                    "force_tolerance": self.force_tolerance})}


@dataclass(frozen=True)
class DamperEntry:
    """One damper of a catalog: ``kind`` dashpot (c in N s/m) or rotary (c in N m s/rad at
    ``pivot``), ``c_tolerance`` relative; ``temperature_coeff`` its beta (1/K; None: the
    config's ``design.damper_temperature_coeff``)."""

    part: str
    kind: str
    c: float
    pivot: str | None
    c_tolerance: float
    line: int = field(default=0, compare=False)
    temperature_coeff: float | None = None

    def design(self) -> dict:
        """The [design] values of this damper: it replaces the config's dashpot and rotary
        damper (the other is 0), and its temperature coefficient when it gives one."""
        out = {"damper_c": self.c, "rotary_damper_c": 0.0} if self.kind == "dashpot" else \
            {"damper_c": 0.0, "rotary_damper_c": self.c, "rotary_damper_pivot": self.pivot}
        if self.temperature_coeff is not None:
            out["damper_temperature_coeff"] = self.temperature_coeff
        return out

    def to_json(self) -> dict:
        return {"part": self.part, "kind": self.kind, "c": self.c, "pivot": self.pivot,
                "c_tolerance": self.c_tolerance,
                **({} if self.temperature_coeff is None else
                   {"temperature_coeff_per_K": self.temperature_coeff})}


@dataclass(frozen=True)
class Catalog:
    """The usable parts of one file and a warning per row left out."""

    path: str
    parts: tuple
    warnings: tuple = field(default_factory=tuple)

    def __len__(self) -> int:
        return len(self.parts)


def _lines(path) -> list[tuple[int, list[str]]]:
    """(line number, fields) of every non-blank, non-comment line."""
    text = read_text(path, kind="a CSV file")
    out = []
    for i, line in enumerate(text.splitlines(), 1):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        try:
            fields = next(csv.reader([line], skipinitialspace=True))
        except csv.Error as exc:
            raise ConfigError(f"{path}: line {i}: not CSV ({exc})") from None
        out.append((i, [f.strip() for f in fields]))
    if not out:
        raise ConfigError(f"{path}: empty (expected a header line and one part a row)")
    return out


def _header(path, fields: list[str], line: int, cols: dict, base: tuple,
            optional: tuple = ()) -> dict:
    """Which column holds each quantity, and its factor to SI: {name: (index, factor, header)}."""
    where = {}
    seen = {}
    for j, h in enumerate(fields):
        if h in seen:
            raise ConfigError(f"{path}: line {line}, column {j + 1}: '{h}' appears twice")
        seen[h] = j
    for name in base:
        if name not in seen:
            raise ConfigError(f"{path}: line {line}: missing column '{name}' (the header "
                              f"has {', '.join(fields)})")
        where[name] = (seen[name], 1.0, name)
    for name, alts in cols.items():
        given = [(seen[h], f, h) for h, f in alts if h in seen]
        if len(given) > 1:
            raise ConfigError(f"{path}: line {line}: {' and '.join(g[2] for g in given)} "
                              "give the same quantity; keep one")
        if given:
            where[name] = given[0]
        elif name not in optional:
            names = " or ".join(h for h, _ in alts)
            raise ConfigError(f"{path}: line {line}: missing column {names} (the header has "
                              f"{', '.join(fields)})")
    return where


class _Bad(Exception):
    pass


def _cell(row, where, name, line, *, required=True):
    """The cell of quantity ``name`` as SI (None: empty and not required)."""
    j, factor, header = where[name]
    text = row[j] if j < len(row) else ""
    if text == "":
        if required:
            raise _Bad(f"line {line}, column {header}: missing value")
        return None
    try:
        v = float(text)
    except ValueError:
        raise _Bad(f"line {line}, column {header}: '{text}' is not a number") from None
    if not math.isfinite(v):
        raise _Bad(f"line {line}, column {header}: '{text}' is not a finite number")
    return v * factor


def _check(cond, line, header, what):
    if not cond:
        raise _Bad(f"line {line}, column {header}: {what}")


def _finish(path, parts, warnings, what) -> Catalog:
    if not parts:
        hint = f" ({warnings[0]}" + (f"; {len(warnings) - 1} more" if len(warnings) > 1
                                       else "") + ")" if warnings else ""
        raise ConfigError(f"{path}: no usable {what} in the file{hint}")
    names = {}
    for p in parts:
        if p.part in names:
            warnings.append(f"line {p.line}, column part: '{p.part}' also on line "
                            f"{names[p.part]}; both are kept")
        names.setdefault(p.part, p.line)
    return Catalog(str(path), tuple(parts), tuple(f"{path}: {w}" for w in warnings))


def _coil_header(path, head: list[str], line: int) -> dict:
    """Which columns hold the coil (``{name: (index, factor, header)}``, ``material``
    included when given); {} when the header has none. Some of d, D, n without the
    others is a :class:`ConfigError`."""
    where = _header(path, head, line, _COIL_COLS, (), tuple(_COIL_COLS))
    if where and len(where) < len(_COIL_COLS):
        missing = [" or ".join(h for h, _ in alts) for n, alts in _COIL_COLS.items()
                   if n not in where]
        raise ConfigError(f"{path}: line {line}: the coil columns come together: missing "
                          f"{', '.join(missing)}")
    if MATERIAL_COLUMN in head:
        if not where:
            raise ConfigError(f"{path}: line {line}: column {MATERIAL_COLUMN} without the "
                              "coil columns wire_d_m, coil_d_m, active_coils")
        where[MATERIAL_COLUMN] = (head.index(MATERIAL_COLUMN), 1.0, MATERIAL_COLUMN)
    return where


def _coil_cells(row, where: dict, line: int, kind: str, rate: float, rate_tol: float) -> dict:
    """The coil of one row (SI; {} when its cells are empty), checked: all three or none,
    a compression or extension spring, a wire and index EN 13906 covers, its rate the
    row's within ``rate_tolerance``."""
    if not where:
        return {}
    v = {n: _cell(row, where, n, line, required=False) for n in _COIL_COLS}
    j = where.get(MATERIAL_COLUMN, (None,))[0]
    mat = (row[j] if j is not None and j < len(row) else "") or None
    if all(x is None for x in v.values()):
        _check(mat is None, line, MATERIAL_COLUMN, "a material without wire_d, coil_d, "
                                                   "active_coils")
        return {}
    for n, x in v.items():
        _check(x is not None, line, where[n][2], "missing value (the coil columns come "
                                                 "together)")
    _check(kind in COIL_KINDS, line, "kind", f"a {kind} has no coil (leave the coil "
                                             "columns empty)")
    from ..coil_spring import CoilSpring, DEFAULT_MATERIAL
    try:
        coil = CoilSpring(v["wire_d"], v["coil_d"], v["active_coils"], mat or DEFAULT_MATERIAL)
        if kind == "extension":
            from ..coil_spring import extension
            extension.validate(coil.active_coils)
    except ConfigError as exc:
        key = str(exc).split(":", 1)[0]
        col = {"spring.wire_d": where["wire_d"][2], "spring.coil_d": where["coil_d"][2],
               "spring.active_coils": where["active_coils"][2],
               "spring.material": MATERIAL_COLUMN}.get(key, key)
        raise _Bad(f"line {line}, column {col}: {str(exc).split(': ', 1)[-1]}") from None
    off = coil.rate / rate - 1.0 if rate > 0 else math.inf
    _check(abs(off) <= rate_tol + 1e-12, line, "rate", f"the coil's rate G d^4/(8 D^3 n) = "
           f"{coil.rate:.5g} N/m is {off:+.1%} off the row's {rate:.5g} N/m, beyond its "
           f"rate_tolerance")
    return {**v, "material": coil.material}


def _strut(v: dict, h: dict, line: int, part: str, lo, hi, flt) -> SpringEntry:
    """The gas strut of one row (module docstring): its stroke from its compressed length,
    its progression given or from the rate, its friction and force tolerance."""
    from ..model.elements.springs import Spring
    k_lo, k_hi = next((k.lo, k.hi) for k in Spring.keys if k.name == "strut_progression")
    F1 = v["preload"]
    _check(F1 > 0, line, h["preload"], "a gas strut's preload is its force F1 at full "
                                       "extension: must be > 0")
    _check(lo is not None, line, h["min_length"], "a gas strut needs its compressed length "
                                                  "(its stroke is free length - min length)")
    s = float(f"{v['free_length'] - lo:.12g}")
    K = v.get("progression")
    if K is None:
        _check(v["rate"] is not None, line, h["rate"],
               "missing value (a gas strut gives its rate or its progression)")
        K = float(f"{1.0 + v['rate'] * s / F1:.12g}")
        col, how = h["rate"], " (1 + rate x stroke / F1)"
    else:
        col, how = h["progression"], ""
    _check(k_lo <= K <= k_hi, line, col, f"a gas strut's progression F2/F1{how} within "
                                         f"[{k_lo:g}, {k_hi:g}], got {K:.4g}")
    band = v.get("friction_band")
    if band is not None:
        _check(band >= 0, line, h["friction_band"], "a friction band F3 - F1 must be >= 0 N")
    ft = v.get("force_tolerance")
    if ft is None:
        ft = STRUT_FORCE_TOLERANCE
    else:
        _check(0 <= ft < 1, line, h["force_tolerance"],
               "a relative tolerance in [0, 1) (0.07 is ±7 %)")
    return SpringEntry(part, "gas_strut", float(f"{F1 * (K - 1) / s:.12g}"), v["free_length"], F1, lo, hi,
                       v["rate_tolerance"] or 0.0, flt, line, stroke=s, progression=K,
                       friction=0.0 if band is None else band / 2, force_tolerance=ft)


def read_springs(path) -> Catalog:
    """The springs of a catalog file (module docstring); rows that cannot be used are left
    out with a warning naming their line and column."""
    lines = _lines(path)
    hline, head = lines[0]
    where = _header(path, head, hline, _SPRING_COLS, ("part", "kind"), _SPRING_OPTIONAL)
    coil_where = _coil_header(path, head, hline)
    parts, warnings = [], []
    for line, row in lines[1:]:
        try:
            if len(row) > len(head):
                raise _Bad(f"line {line}: {len(row)} fields, the header has {len(head)}")
            part = row[where["part"][0]] if where["part"][0] < len(row) else ""
            _check(part != "", line, "part", "missing value")
            kind = row[where["kind"][0]] if where["kind"][0] < len(row) else ""
            _check(kind in SPRING_KINDS, line, "kind",
                   f"unknown kind '{kind}' (extension, compression or gas_strut)")
            strut = kind == "gas_strut"
            optional = ("min_length", "max_length") + _SPRING_OPTIONAL + (
                ("rate", "rate_tolerance") if strut else ())
            v = {n: _cell(row, where, n, line, required=n not in optional)
                 for n in where if n not in ("part", "kind")}
            h = {n: where[n][2] for n in where}
            if not strut:
                for n in _STRUT_ONLY:
                    _check(v.get(n) is None, line, h.get(n), f"a {kind} spring has no {h.get(n)}"
                           " (a gas strut's; leave it empty)")
            if v["rate"] is not None:
                _check(v["rate"] >= 0, line, h["rate"], f"negative rate {v['rate']:g} N/m")
            _check(v["free_length"] > 0, line, h["free_length"], "the free length must be > 0")
            _check(v["preload"] >= 0, line, h["preload"], "negative preload")
            if not strut:
                _check(v["rate"] > 0 or v["preload"] > 0, line, h["rate"],
                       "no rate and no preload: the part exerts no force")
            if v["rate_tolerance"] is not None:
                _check(0 <= v["rate_tolerance"] < 1, line, h["rate_tolerance"],
                       "a relative tolerance in [0, 1) (0.1 is ±10 %)")
            lo, hi = v.get("min_length"), v.get("max_length")
            if lo is not None:
                _check(lo > 0, line, h["min_length"], "must be > 0")
                _check(lo < v["free_length"] or kind == "extension", line, h["min_length"],
                       "the minimum (solid) length must be below the free length")
            if hi is not None:
                _check(hi >= v["free_length"], line, h["max_length"],
                       f"the free length {v['free_length'] * 1e3:g} mm is above the maximum "
                       f"length {hi * 1e3:g} mm")
            if lo is not None and hi is not None:
                _check(lo < hi, line, h["min_length"], "above the maximum length")
            flt = v.get("free_length_tolerance")
            if flt is None:
                flt = standard_free_length_tolerance(v["free_length"])
            else:
                _check(0 <= flt < v["free_length"], line, h["free_length_tolerance"],
                       "must be >= 0 and below the free length")
            coil = _coil_cells(row, coil_where, line, kind, v["rate"], v["rate_tolerance"])
            if strut:
                parts.append(_strut(v, h, line, part, lo, hi, flt))
                continue
            parts.append(SpringEntry(part, kind, v["rate"], v["free_length"], v["preload"],
                                     lo, hi, v["rate_tolerance"], flt, line, **coil))
        except _Bad as exc:
            warnings.append(f"{exc}; row left out")
    return _finish(path, parts, warnings, "spring")


def read_dampers(path) -> Catalog:
    """The dampers of a catalog file (module docstring)."""
    lines = _lines(path)
    hline, head = lines[0]
    where = _header(path, head, hline, _DAMPER_COLS, ("part", "kind", "pivot"),
                    ("temperature_coeff",))
    parts, warnings = [], []
    for line, row in lines[1:]:
        try:
            if len(row) > len(head):
                raise _Bad(f"line {line}: {len(row)} fields, the header has {len(head)}")
            get = (lambda n: row[where[n][0]] if where[n][0] < len(row) else "")
            part, kind, pivot = get("part"), get("kind"), get("pivot")
            _check(part != "", line, "part", "missing value")
            _check(kind in DAMPER_KINDS, line, "kind",
                   f"unknown kind '{kind}' (dashpot or rotary)")
            c = _cell(row, where, "c", line)
            tol = _cell(row, where, "c_tolerance", line)
            hc = where["c"][2]
            _check(c > 0, line, hc, f"the coefficient must be > 0, got {c:g}")
            if kind == "dashpot" and hc == "c_N_m_s_per_rad":
                raise _Bad(f"line {line}, column {hc}: a dashpot's c is in N s/m")
            if kind == "rotary" and hc == "c_N_s_per_mm":
                raise _Bad(f"line {line}, column {hc}: a rotary damper's c is in N m s/rad")
            _check(0 <= tol < 1, line, where["c_tolerance"][2],
                   "a relative tolerance in [0, 1) (0.2 is ±20 %)")
            if kind == "rotary":
                _check(pivot in PIVOTS, line, "pivot",
                       f"unknown pivot '{pivot}' ({', '.join(PIVOTS)})")
            else:
                _check(pivot == "", line, "pivot", "a dashpot has no pivot (leave it empty)")
            beta = _cell(row, where, "temperature_coeff", line, required=False) \
                if "temperature_coeff" in where else None
            if beta is not None:
                _check(-0.1 <= beta <= 0.1, line, where["temperature_coeff"][2],
                       f"a temperature coefficient in [-0.1, 0.1] 1/K (silicone oil about "
                       f"-0.005), got {beta:g}")
            parts.append(DamperEntry(part, kind, c, pivot or None, tol, line, beta))
        except _Bad as exc:
            warnings.append(f"{exc}; row left out")
    return _finish(path, parts, warnings, "damper")


def as_catalog(x, reader) -> Catalog:
    """A Catalog from a path, a Catalog, or a list of entries."""
    if x is None or isinstance(x, Catalog):
        return x
    if isinstance(x, (str, Path)):
        return reader(x)
    parts = tuple(x)
    if not parts:
        raise ConfigError("catalog: no parts given")
    return Catalog("<list>", parts)
