"""What do the objective, impact speed, peak tip speed and closing time look like around the optimal spring and damper?

Finds the centre -- the verified optimum of ``softclose.optimise`` (unless ``--fast``: then
the best feasible point of a coarse sweep over the whole design box) -- then sweeps the
three design variables (k, c, l0) on a window around it. A coarse sweep of the whole box
shows where the window lies. Infeasible regions (not closed, too slow, not held shut,
rebound) are masked and hatched in the maps; the best feasible point is marked.

Writes to studies/out/spring_damper_maps/:
  coarse/sweep.csv                the coarse sweep over the whole design box
  coarse/map_*.png                its maps (one per pair of design variables)
  window/sweep.csv                the fine sweep around the centre
  window/map_*.png                its maps: the report figures
  centre.json                     the centre, where it came from, and the best window point

Usage: python studies/spring_damper_maps.py [--fast] [--json] [--out DIR]
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

import softclose
from softclose.present.figures import save
from softclose.jsonio import dumps
from softclose.optimiser import optimise
from softclose.sweeps import sweep
from softclose.present.study import parse, print_files, study_options

#: the swept config keys and the optimiser's design key of each
KEYS = {"design.spring_k": "spring_k", "design.damper_c": "damper_c",
        "design.spring_rest_length": "spring_rest_length"}


def box(cfg) -> dict:
    """The design bounds of the problem, by swept key."""
    return {k: getattr(cfg.optimise, d) for k, d in KEYS.items()}


def write(res, out: Path) -> list[Path]:
    """The sweep's table and maps in ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    files = [out / "sweep.csv"]
    res.to_frame().to_csv(files[0], index=False)
    files += [save(fig, out / f"{stem}.png") for stem, fig in res.plot().items()]
    return files


def main(argv=None) -> int:
    ap = study_options(__doc__, __file__, fast="coarse grids, no optimiser")
    a = parse(ap, argv)
    cfg = softclose.default_config()
    n = 9 if a.fast else 41
    coarse = sweep(cfg, {k: np.linspace(lo, hi, n if k != "design.spring_rest_length"
                                        else (5 if a.fast else 21))
                         for k, (lo, hi) in box(cfg).items()}, progress=not a.json)
    files = write(coarse, a.out / "coarse")
    centre, source = None, "coarse sweep"
    if not a.fast:
        r = optimise(cfg, progress=not a.json)
        if r.success:
            centre = {k: r.design[d] for k, d in KEYS.items()}
            source = f"softclose.optimise (verified, J = {r.objective:.6g})"
        else:
            print(f"no verified optimum ({r.message}); using the coarse sweep's best point",
                  file=sys.stderr)
    if centre is None:
        if coarse.best is None:
            print("no feasible point on the coarse grid", file=sys.stderr)
            return 3
        centre = {k: float(coarse.best[k]) for k in KEYS}
    # the window: a quarter of each range either side (a tenth in the full study)
    frac, m = (0.25, 11) if a.fast else (0.1, 81)
    axes = {}
    for k, (lo, hi) in box(cfg).items():
        w = frac * (hi - lo)
        axes[k] = np.linspace(max(lo, centre[k] - w), min(hi, centre[k] + w),
                              m if k != "design.spring_rest_length" else max(5, m // 2))
    fine = sweep(cfg, axes, progress=not a.json)
    files += write(fine, a.out / "window")
    report = {"centre": centre, "centre_from": source,
              "window": {k: [float(v[0]), float(v[-1]), len(v)] for k, v in axes.items()},
              "coarse": coarse.to_json(), "window_summary": fine.to_json()}
    path = a.out / "centre.json"
    path.write_text(dumps(report, indent=1))
    report["files"] = [str(f) for f in files + [path]]
    if a.json:
        print(dumps(report))
    else:
        print(f"centre ({source}): " + ", ".join(f"{k} = {v:.6g}" for k, v in centre.items()))
        bw = fine.best
        if bw:
            print("best on the window: " + ", ".join(f"{k} = {bw[k]:.6g}" for k in KEYS)
                  + f", objective {bw['objective']:.6g}")
        print(f"coarse: {coarse.points} designs at {coarse.designs_per_second or 0:,.0f}/s; "
              f"window: {fine.points} at {fine.designs_per_second or 0:,.0f}/s")
        print_files(report["files"])
    return 0


if __name__ == "__main__":
    sys.exit(main())
