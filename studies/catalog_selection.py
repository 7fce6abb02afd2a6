"""What does buying stock parts cost in yield and worst-case J, against the continuous robust
optimum?

The continuous robust optimum (``softclose.optimise(cfg, robust=True)``) chooses any rate, free
length and damper coefficient; a buyer picks from a catalog's steps, and the parts come with
their own tolerances (a free length held to about ±1 mm by a standard grade, which the robust
optimiser's default box does not hold). This study ranks the illustrative catalog of
``examples/catalogs/`` (``softclose.select``: every spring x damper over its own tolerance box,
the best verified by the adaptive reference), once with its dampers and once with the
dashpot's c chosen per spring (what the damper's catalog steps cost), and judges the robust
optimum the same way -- as a made-to-order spring of the standard grade and a damper of the
[tolerance] spread -- so that all three stand on one footing. It reports per answer: feasible
at every corner, yield, worst-case J, and the price of the stock parts: worst-case J (best
pair) / the worst-case J the robust optimiser reports over its own box.

Writes to studies/out/catalog_selection/:
  comparison.json   the robust optimum (its own box and as a part), the best pairs, the prices
  ranking.csv       every pair of the catalog, best first (softclose select's table)
  selection.png     yield against worst-case J of every pair, the robust optimum marked
  report.html       the sign-off report of the best catalog pair
  report.pdf        the same, to print (A4)

Usage: python studies/catalog_selection.py [--fast] [--json] [--out DIR]
"""

from __future__ import annotations

import sys
from pathlib import Path

import softclose
from softclose.catalog import (DamperEntry, SpringEntry, read_dampers, read_springs,
                               standard_free_length_tolerance)
from softclose.present.figures import save
from softclose.present.study import add_report, parse, print_json, save_summary, study_options

ROOT = Path(__file__).resolve().parents[1]
CATALOG = ROOT / "examples" / "catalogs"


def as_part(cfg, res) -> tuple[SpringEntry, DamperEntry]:
    """The robust optimum as a made-to-order spring (the standard grade's free length
    tolerance, the [tolerance] rate spread) and dashpot (the [tolerance] c spread)."""
    d = res.design
    spread = {s.key: s.value for s in cfg.tolerance.spreads if s.relative}
    kind = res.kind or cfg.design.spring_kind
    l0 = d["spring_rest_length"]
    spring = SpringEntry("robust optimum (made to order)", kind, d["spring_k"], l0,
                         d.get("spring_preload", cfg.design.spring_preload), None, None,
                         spread.get("design.spring_k", 0.0),
                         standard_free_length_tolerance(l0))
    damper = DamperEntry("its dashpot", "dashpot", d["damper_c"], None,
                         spread.get("design.damper_c", 0.0))
    return spring, damper


def summary(e) -> dict:
    return {"spring": e["spring"], "damper": e["damper"], "feasible": e["feasible"],
            "yield": e["yield"], "worst_objective": e["worst_objective"],
            "verified": e["verified"], "reason": e["reason"], "design": e["design"]}


def draw(sel, own, path: Path) -> Path:
    fig = sel.plot()
    ax = fig.axes[0]
    e = own.best
    if e["worst_objective"] is not None:
        ax.scatter([e["worst_objective"]], [100 * e["yield"]], s=120, marker="D",
                   facecolors="none", edgecolors="k", zorder=6,
                   label="robust optimum as a part (free length ± standard grade)")
        ax.legend(fontsize=8, loc="center right")
    return save(fig, path)


def main(argv=None) -> int:
    ap = study_options(__doc__, __file__,
                       fast="every 4th spring, 64 samples a pair, the best 3 verified, c from "
                            "the kernel's grid only (no NLP)")
    a = parse(ap, argv)
    cfg = softclose.default_config()
    samples, verify = (64, 3) if a.fast else (256, 10)
    springs = read_springs(CATALOG / "springs.csv")
    dampers = read_dampers(CATALOG / "dampers.csv")
    spring_list = list(springs.parts)[::4] if a.fast else list(springs.parts)
    robust = softclose.optimise(cfg, robust=True)
    if robust.design is None:
        print(f"no robust optimum: {robust.message}", file=sys.stderr)
        return 3
    sel = softclose.select(cfg, spring_list, list(dampers.parts), samples=samples,
                           verify=verify)
    sel_c = softclose.select(cfg, spring_list, samples=samples, verify=verify, nlp=not a.fast)
    own = softclose.select(cfg, [as_part(cfg, robust)[0]], [as_part(cfg, robust)[1]],
                           samples=samples, verify=1)
    best, best_c, mine = sel.best, sel_c.best, own.best

    def price(e):     # against the worst-case J the robust optimiser reports (its own box)
        if e["worst_objective"] is None or robust.objective is None:
            return None
        return e["worst_objective"] / robust.objective
    y = robust.yield_result
    out = {
        "robust_optimum": {
            "design": robust.design, "kind": robust.kind, "verified": robust.success,
            "worst_objective_own_box": robust.objective,
            "yield_own_box": None if y is None else y.yield_,
            "own_box": robust.box,
            "as_a_part": summary(mine)},
        "best_catalog_pair": summary(best),
        "best_catalog_spring_with_c_chosen": summary(best_c),
        "price_of_stock_parts": {
            "worst_objective_ratio_pair": price(best),
            "worst_objective_ratio_spring_c_chosen": price(best_c),
            "yield_difference_pair": None if mine["yield"] is None else
            best["yield"] - mine["yield"]},
        "catalog": {"springs": len(spring_list), "dampers": len(dampers.parts),
                    "pairs": sel.evaluated, "samples": samples, "verified": verify,
                    "feasible_pairs": sum(1 for e in sel.ranking if e["feasible"]),
                    "seconds": sel.seconds, "seconds_c_chosen": sel_c.seconds},
        "note": ("the catalog is illustrative (examples/catalogs/README.md); worst-case J: "
                 "the largest J over the corners and samples of each part's own box"),
    }
    files = []
    path = a.out / "ranking.csv"
    sel.to_frame().to_csv(path, index=False)
    files.append(path)
    files.append(draw(sel, own, a.out / "selection.png"))
    if best is not None:                  # the best pair, signed off
        from softclose.catalog import pair_config
        add_report(out, files, softclose.report(pair_config(cfg, best), samples=samples), a.out,
                   "the best catalog pair")
    save_summary(out, a.out / "comparison.json", files)
    if a.json:
        print_json(out)
    else:
        r = out["robust_optimum"]
        print(f"robust optimum ({r['kind']}): worst-case J {r['worst_objective_own_box']:.5g} "
              f"over its own box, yield {100 * (r['yield_own_box'] or 0):.2f} %")
        tol = 1e3 * as_part(cfg, robust)[0].free_length_tolerance
        print(f"  as a part (free length ± {tol:.1f} mm): feasible at every corner {mine['feasible']}, yield "
              f"{100 * mine['yield']:.2f} %, worst-case J {mine['worst_objective']}"
              + (f"; {mine['reason']}" if mine["reason"] else ""))
        for name, e in (("best catalog pair", best), ("best spring, c chosen", best_c)):
            print(f"{name}: {e['spring']} + {e['damper'] or round(e['design']['damper_c'])}: "
                  f"feasible {e['feasible']}, yield {100 * e['yield']:.2f} %, worst-case J "
                  f"{e['worst_objective']}, verified {e['verified']}")
        p = out["price_of_stock_parts"]
        print(f"price (worst-case J / the robust optimum's over its own box): pair "
              f"{p['worst_objective_ratio_pair']}, spring with c chosen "
              f"{p['worst_objective_ratio_spring_c_chosen']}")
        print("wrote " + ", ".join(out["files"]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
