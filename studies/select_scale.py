"""How long does ``select`` take on a maker's catalog ten times the shipped one, screened corners
first and with every pair sampled, and do the two rank every pair the same?

The ten-times catalog is made of scaled variants of the shipped springs
(``examples/catalogs/springs.csv``): each spring ``variants`` times, its rate -- a gas
strut's F1 and rate -- times a factor from 0.91 to 1.09 (a coil's mean diameter divided by
its cube root, so that its coil stays its rate), named ``<part>-v<j>``; the shipped
dampers as they are.
With 265 springs x 13 dampers shipped, that is 2,650 springs, 34,450 pairs.

It reports per catalog (shipped, ten times) and screening (corners first; every sample,
unless --no-compare): the seconds (screening, verification, total), how many pairs the
corners decided (met every corner, failed every corner) and how many were sampled, and
whether the two screenings rank every pair the same (order, feasible, yield, worst J,
reason).

Writes to studies/out/select_scale/:
  springs_scaled.csv  the scaled spring catalog (ten times the shipped one; --fast: twice)
  summary.json      the numbers above

Usage: python studies/select_scale.py [--fast] [--json] [--variants N] [--no-compare]
                                      [--shipped-only] [--out DIR]
(--fast: two variants of each spring, the every-sample screening of the shipped catalog only)
"""

from __future__ import annotations

import csv
import json
import sys
import time
from pathlib import Path

import softclose
from softclose.catalog import select
from softclose.files import write_text, write_with
from softclose.present.study import parse, print_json, study_options

ROOT = Path(__file__).resolve().parents[1]
CATALOG = ROOT / "examples" / "catalogs"


def factors(variants: int) -> list[float]:
    """The rate factors of the variants: evenly from 0.91 to 1.09 (1 alone for one)."""
    if variants == 1:
        return [1.0]
    return [0.91 + 0.18 * j / (variants - 1) for j in range(variants)]


def scaled_springs(src: Path, dst: Path, variants: int = 10) -> Path:
    """``src``'s springs, each ``variants`` times scaled (module docstring), in ``dst``."""
    lines = [ln for ln in src.read_text().splitlines() if ln and not ln.startswith("#")]
    rows = list(csv.DictReader(lines))
    out = []
    for row in rows:
        for j, f in enumerate(factors(variants)):
            r = dict(row)
            r["part"] = f"{row['part']}-v{j}"
            r["rate_N_per_m"] = f"{float(row['rate_N_per_m']) * f:.6g}"
            if row["kind"] == "gas_strut":
                r["preload_N"] = f"{float(row['preload_N']) * f:.6g}"
            if row.get("coil_d_m"):        # (the coil's rate G d^4 / (8 D^3 n))
                r["coil_d_m"] = f"{float(row['coil_d_m']) / f ** (1 / 3):.6g}"
            out.append(r)
    def write(path):
        with open(path, "w", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=list(rows[0]))
            w.writeheader()
            w.writerows(out)
    dst.parent.mkdir(parents=True, exist_ok=True)
    return write_with(dst, write)


def run(cfg, springs, dampers, every_sample: bool) -> tuple[dict, list]:
    t0 = time.perf_counter()
    r = select(cfg, springs, dampers, every_sample=every_sample)
    wall = time.perf_counter() - t0
    keys = [(e["spring"], e["damper"], e["feasible"], e["yield"], e["worst_objective"],
             e["reason"]) for e in r.ranking]
    return {"pairs": r.pairs, "seconds": wall, "times": r.times,
            "screening": r.screening}, keys


def main(argv=None) -> int:
    ap = study_options(__doc__, __file__, fast="two variants of each spring; every pair "
                       "sampled on the shipped catalog only")
    ap.add_argument("--variants", type=int, default=10)
    ap.add_argument("--no-compare", dest="compare", action="store_false")
    ap.add_argument("--shipped-only", action="store_true")
    a = parse(ap, argv)
    if a.fast:
        a.variants = 2
    out = Path(a.out)
    cfg = softclose.default_config()
    dampers = CATALOG / "dampers.csv"
    catalogs = {"shipped": CATALOG / "springs.csv"}
    if not a.shipped_only:
        catalogs[f"x{a.variants}"] = scaled_springs(CATALOG / "springs.csv",
                                                    out / "springs_scaled.csv",
                                                    a.variants)
    select(cfg, CATALOG / "springs.csv", dampers, samples=16, verify=0)   # tables built
    summary = {}
    for name, springs in catalogs.items():
        first, keys = run(cfg, springs, dampers, False)
        summary[name] = {"corners first": first}
        print(f"{name}: corners first {first['seconds']:.2f} s {first['times']} "
              f"{first['screening']}", file=sys.stderr, flush=True)
        if a.compare and not (a.fast and name != "shipped"):
            every, keys_every = run(cfg, springs, dampers, True)
            summary[name]["every sample"] = every
            summary[name]["same ranking"] = keys == keys_every
            print(f"{name}: every sample {every['seconds']:.2f} s {every['times']}; the "
                  f"same ranking: {keys == keys_every}", file=sys.stderr, flush=True)
    out.mkdir(parents=True, exist_ok=True)
    write_text(out / "summary.json", json.dumps(summary, indent=1))
    if a.json:
        print_json(summary)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
