"""What do the objective, impact speed, peak tip speed and closing time look like around the optimal spring and damper?

Finds the centre -- the optimiser's design (``softclose.optimise.optimise``) when that module
is available and not ``--fast``, else the best feasible point of a coarse sweep over the
whole SPEC §5 box -- then sweeps the three design pairs (k, c), (k, l0), (c, l0) on a window
around it with the third variable held at the centre. Infeasible regions (not closed, too
slow, not held shut, rebound) are masked and hatched; the best feasible point is marked.

Writes to studies/out/spring_damper_maps/:
  coarse/sweep.csv                the coarse sweep over the whole design box
  coarse/map_*.png                its maps (one per pair of design variables)
  window/sweep.csv                the fine sweep around the centre
  window/map_*.png                its maps: the report figures
  centre.json                     the centre, where it came from, and the best window point

Usage: python studies/spring_damper_maps.py [--fast] [--json]
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from softclose import sweep as sw  # noqa: E402
from softclose.config import default_config  # noqa: E402

OUT = Path(__file__).resolve().parent / "out" / "spring_damper_maps"
KEYS = ("design.spring_k", "design.damper_c", "design.spring_rest_length")


def centre_from_optimiser(cfg):
    try:
        from softclose.optimise import optimise
    except ImportError:
        return None
    try:
        r = optimise(cfg)
    except Exception as exc:  # the optimiser is someone else's: report and fall back
        print(f"optimiser failed ({exc}); using the coarse sweep's best point", file=sys.stderr)
        return None
    d = r.design if isinstance(r.design, dict) else dict(r.design)
    if not getattr(r, "success", True):
        return None
    return {"design.spring_k": d["spring_k"], "design.damper_c": d["damper_c"],
            "design.spring_rest_length": d["spring_rest_length"]}


def window(cfg, centre, frac, n):
    """Grid strings on a window of +-frac of each design range around centre, clipped."""
    o = cfg.optimise
    box = {"design.spring_k": o.spring_k, "design.damper_c": o.damper_c,
           "design.spring_rest_length": o.spring_rest_length}
    out = []
    for k in KEYS:
        lo, hi = box[k]
        w = frac * (hi - lo)
        a, b = max(lo, centre[k] - w), min(hi, centre[k] + w)
        out.append(f"{k}={a!r}:{b!r}:{n if k != 'design.spring_rest_length' else max(5, n // 2)}")
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fast", action="store_true", help="coarse grids, no optimiser")
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    ap.add_argument("--out", type=Path, default=OUT)
    a = ap.parse_args(argv)
    cfg = default_config()
    o = cfg.optimise
    n_coarse = 9 if a.fast else 41
    coarse_grid = [f"design.spring_k={o.spring_k[0]}:{o.spring_k[1]}:{n_coarse}",
                   f"design.damper_c={o.damper_c[0]}:{o.damper_c[1]}:{n_coarse}",
                   f"design.spring_rest_length={o.spring_rest_length[0]}:"
                   f"{o.spring_rest_length[1]}:{5 if a.fast else 21}"]
    coarse, files = sw.sweep(cfg, coarse_grid, a.out / "coarse")
    source, centre = "coarse sweep", None
    if not a.fast:
        centre = centre_from_optimiser(cfg)
        if centre is not None:
            source = "softclose.optimise.optimise"
    if centre is None:
        b = coarse.best
        if b is None:
            print("no feasible point on the coarse grid", file=sys.stderr)
            return 3
        centre = {k: float(coarse.X[b, j]) for j, k in enumerate(coarse.keys)}
    # the window: a quarter of each range either side (a tenth in the fine study)
    grid = window(cfg, centre, 0.25 if a.fast else 0.1, 11 if a.fast else 81)
    fine, ffiles = sw.sweep(cfg, grid, a.out / "window")
    files += ffiles
    report = {"centre": centre, "centre_from": source, "window": grid,
              "coarse": sw.summary(coarse), "window_summary": sw.summary(fine),
              "files": [str(f) for f in files]}
    (a.out / "centre.json").write_text(json.dumps(report, indent=1, default=float))
    report["files"].append(str(a.out / "centre.json"))
    if a.json:
        print(json.dumps(report, default=float))
    else:
        print(f"centre ({source}): " + ", ".join(f"{k} = {v:.6g}" for k, v in centre.items()))
        bw = report["window_summary"]["best"]
        if bw:
            print("best on the window: " + ", ".join(f"{k} = {bw[k]:.6g}" for k in KEYS)
                  + f", objective {bw['objective']:.6g}")
        print(f"coarse: {coarse.n} designs at {report['coarse']['designs_per_second']:,.0f}/s; "
              f"window: {fine.n} at {report['window_summary']['designs_per_second']:,.0f}/s")
        for f in report["files"]:
            print("wrote", f)
    return 0


if __name__ == "__main__":
    sys.exit(main())
