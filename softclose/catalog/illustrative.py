"""The illustrative catalog (NOT real parts): standard rate and length series for the
examples, the benchmark and the study. ``python -m softclose.catalog.illustrative DIR`` writes
it as ``DIR/springs.csv`` and ``DIR/dampers.csv`` (what ``examples/catalogs/`` holds).

- compression springs: free lengths 56-80 mm x rates 500-10,000 N/m in ISO 3 R10 steps, solid
  length 40 % of the free length, rate ±10 %, the free length to the standard grade;
- extension springs: free lengths 30-50 mm x rates 100-1,600 N/m (R5) x initial tensions 2 and
  5 N, maximum length twice the free length, rate ±10 %;
- gas struts: extended lengths 60-80 mm, 20 mm stroke, forces F1 = 10-200 N in the usual
  steps, progression F2/F1 1.2-1.5 (:data:`PROGRESSION`, by extended length; the rate column
  the matching F1 (K - 1) / stroke), friction band F3 - F1 of 30 % of F1 up to 20 N, 20 % up
  to 60 N, 10 % above (:func:`friction_band`), force ±7 %, length ±1.5 mm;
- dampers: dashpots of 1,000-6,000 N s/m (±20 %), rotary dampers of 0.5-2 N m s/rad at pivots
  O and A (±30 %).

A few springs give their coil (:data:`COILS`: EN 10270-1 SH wire d, mean coil diameter D,
active coils n, the rate G d^4/(8 D^3 n) within 1 % of the row's, the solid length within
its minimum length), which ``select`` checks at the working lengths: on the default lid
CS-060-04000, CS-064-02500 and ES-040-0400-T2 pass; CS-062-03150 (D = 9.6 mm, L0/D = 6.5)
buckles; CS-070-02000 (two active coils of D = 21.6 mm) is overstressed at its solid length.
"""

from __future__ import annotations

import sys
from pathlib import Path

from .files import DamperEntry, SpringEntry, standard_free_length_tolerance
from ..files import write_text

HEADER = """\
# ILLUSTRATIVE CATALOG -- NOT REAL PARTS. Made up for softclose's examples, benchmark and study:
# standard rate and length series (ISO 3 R10 steps), not any maker's data. Replace it with your
# supplier's catalog export (see examples/catalogs/README.md) before buying anything.
"""
R10 = (500, 630, 800, 1000, 1250, 1600, 2000, 2500, 3150, 4000, 5000, 6300, 8000, 10000)


#: part -> (wire d, mean coil diameter D (m), active coils n) of EN 10270-1 SH wire
COILS = {
    "CS-060-04000": (0.0018, 0.0147, 8.5),
    "CS-062-03150": (0.0014, 0.0096, 14.0),
    "CS-064-02500": (0.0018, 0.0192, 6.0),
    "CS-070-02000": (0.0014, 0.0216, 2.0),
    "ES-040-0400-T2": (0.0009, 0.009, 23.0),
}
#: the wire of the springs of :data:`COILS`
COIL_MATERIAL = "EN10270-1-SH"
#: a gas strut's progression K by its extended length (mm)
PROGRESSION = {60: 1.2, 65: 1.25, 70: 1.3, 75: 1.4, 80: 1.5}
#: a gas strut's relative force tolerance (datasheets: ±5-10 % on F1)
STRUT_FORCE_TOLERANCE = 0.07


def friction_band(F1: float) -> float:
    """A small strut's friction band F3 - F1 (N): its seals' share of F1 falls as F1 grows
    (30 % up to 20 N, 20 % up to 60 N, 10 % above)."""
    return round(F1 * (0.3 if F1 <= 20 else 0.2 if F1 <= 60 else 0.1), 1)


def _with_coil(e: SpringEntry) -> SpringEntry:
    from dataclasses import replace
    if e.part not in COILS:
        return e
    d, D, n = COILS[e.part]
    return replace(e, wire_d=d, coil_d=D, active_coils=n, material=COIL_MATERIAL)


def springs() -> list[SpringEntry]:
    out = []
    for L in (56, 58, 60, 62, 64, 66, 68, 70, 75, 80):
        for k in R10:
            l0 = L / 1e3
            out.append(SpringEntry(f"CS-{L:03d}-{k:05d}", "compression", float(k), l0, 0.0,
                                   round(0.4 * L) / 1e3, None, 0.10,
                                   standard_free_length_tolerance(l0)))
    for L in (30, 35, 40, 45, 50):
        for k in (100, 160, 250, 400, 630, 1000, 1600):
            for F0 in (2, 5):
                l0 = L / 1e3
                out.append(SpringEntry(f"ES-{L:03d}-{k:04d}-T{F0}", "extension", float(k), l0,
                                       float(F0), None, 2 * l0, 0.10,
                                       standard_free_length_tolerance(l0)))
    for L in (60, 65, 70, 75, 80):
        for F1 in (10, 20, 30, 40, 50, 60, 80, 100, 120, 150, 200):
            K = PROGRESSION[L]
            out.append(SpringEntry(f"GS-{L:03d}-F{F1:03d}", "gas_strut",
                                   round(F1 * (K - 1) / 0.020, 1), L / 1e3, float(F1),
                                   (L - 20) / 1e3, None, 0.0, 0.0015, stroke=0.020,
                                   progression=K, friction=friction_band(F1) / 2,
                                   force_tolerance=STRUT_FORCE_TOLERANCE))
    return [_with_coil(e) for e in out]


def dampers() -> list[DamperEntry]:
    out = [DamperEntry(f"DP-{c:04d}", "dashpot", float(c), None, 0.2)
           for c in (1000, 1500, 2000, 2500, 3000, 4000, 5000, 6000)]
    out += [DamperEntry(f"RD-{piv}-{c:g}".replace(".", "p"), "rotary", c, piv, 0.3)
            for piv, c in (("O", 0.5), ("O", 1.0), ("O", 2.0), ("A", 0.5), ("A", 1.0))]
    return out


def _cell(v) -> str:
    return "" if v is None else repr(v) if isinstance(v, float) else str(v)


def write(folder) -> tuple[Path, Path]:
    """Write the catalog as ``folder/springs.csv`` and ``folder/dampers.csv``."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    s = folder / "springs.csv"
    cols = ("part", "kind", "rate_N_per_m", "free_length_m", "preload_N", "min_length_m",
            "max_length_m", "rate_tolerance", "free_length_tolerance_m", "wire_d_m",
            "coil_d_m", "active_coils", "material", "progression", "friction_band_N",
            "force_tolerance")
    # (a row leaves the cells it has no value for empty, trailing ones off; a strut's rate
    # tolerance does not apply to it)
    lines = [",".join(cols)]
    for e in springs():
        cells = [e.part, e.kind, e.rate, e.free_length, e.preload, e.min_length,
                 e.max_length, None if e.is_strut else e.rate_tolerance,
                 e.free_length_tolerance]
        if e.wire_d is not None:
            cells += [e.wire_d, e.coil_d, e.active_coils, e.material]
        if e.is_strut:
            cells += [None] * 4 + [e.progression, 2 * e.friction, e.force_tolerance]
        lines.append(",".join(_cell(x) for x in cells))
    write_text(s, HEADER + "\n".join(lines) + "\n")
    d = folder / "dampers.csv"
    lines = ["part,kind,c,pivot,c_tolerance"] + [",".join(_cell(x) for x in (
        e.part, e.kind, e.c, e.pivot, e.c_tolerance)) for e in dampers()]
    write_text(d, HEADER + "\n".join(lines) + "\n")
    return s, d


if __name__ == "__main__":
    for p in write(sys.argv[1] if len(sys.argv) > 1 else "."):
        print(p)
