"""What does it cost to design with springs one can buy instead of the idealised one?

The seed's spring ``k (l - l0)`` pushes and pulls through its free length; a real extension
spring only pulls (l >= l0), a compression spring only pushes (l <= l0). This
study solves the default problem nominally and robustly (the default [tolerance] box), once
with the idealised spring (``optimise.spring_kinds = ["linear"]``) and once with the kinds
one can buy (compression, extension), and reports per kind the objective (nominal J, robust
worst-case J), the part to buy (free length, rate, preload, working lengths, largest force,
how precisely it must be made) and the price of buildability: J(buildable) / J(idealised).
The figure shows each design's spring force over the stroke: a compression spring must stay
on the pushing side (force <= 0) from release to closed, an extension spring on the pulling
side; the idealised robust design crosses zero, which no single part does.

Writes to studies/out/buildable_design/:
  designs.json       the four designs, every kind tried, parts, objectives, the prices
  kinds.csv          one row per (problem, kind): objective, success, why not
  spring_force.png   spring force over the stroke of each design, the valid sides shaded
  price.png          the objective of each kind, nominal and robust, against the idealised
  report.html        the sign-off report of the robust design with buildable springs
  report.pdf         the same, to print (A4)

Usage: python studies/buildable_design.py [--fast] [--json] [--out DIR]
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import softclose
from softclose.present.figures import save
from softclose.robust import optimise_robust
from softclose.present.study import (add_report, parse, print_json, save_summary, study_options,
                                     write_rows)

KINDS = {"idealised": ["linear"], "buildable": ["compression", "extension"]}


def solve(cfg, fast: bool) -> dict:
    """The four answers: {(problem, spring set): result}."""
    out = {}
    for name, kinds in KINDS.items():
        c = cfg.set("optimise.spring_kinds", kinds)
        out[("nominal", name)] = softclose.optimise(c)
        out[("robust", name)] = optimise_robust(c, samples=2000 if fast else None,
                                                progress=False)
    return out


def force_curve(cfg, res):
    """(theta in deg, spring force in N: > 0 pulls) over the stroke of a result's design."""
    kind = res.kind or "linear"
    design = {k: v for k, v in res.design.items() if k != "spring_kind"}
    r = softclose.simulate(cfg.with_design(spring_kind=kind, **design), trajectory=True)
    tr = r.trajectory
    s = {"linear": 0.0, "extension": 1.0, "compression": -1.0}[kind]
    F0 = design.get("spring_preload", cfg.design.spring_preload)
    force = [s * F0 + design["spring_k"] * (l - design["spring_rest_length"])
             for l in tr["spring_length"]]
    return [math.degrees(t) for t in tr["theta"]], force, kind


def draw_force(cfg, answers, path: Path) -> Path:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7.5, 4.5))
    ax.axhspan(0, 1e9, color="tab:blue", alpha=0.06, lw=0)
    ax.axhspan(-1e9, 0, color="tab:orange", alpha=0.06, lw=0)
    lo, hi = 0.0, 0.0
    styles = {("nominal", "buildable"): "-", ("robust", "buildable"): "--",
              ("nominal", "idealised"): ":", ("robust", "idealised"): "-."}
    for key, res in answers.items():
        if res.design is None:
            continue
        th, F, kind = force_curve(cfg, res)
        lo, hi = min(lo, min(F)), max(hi, max(F))
        dotted = styles[key] == ":"          # (on top of the line it may coincide with)
        ax.plot(th, F, styles[key], lw=3.0 if dotted else 1.8, zorder=3 if dotted else 2,
                label=f"{key[0]} {key[1]} ({kind})")
    pad = 0.1 * (hi - lo or 1.0)
    ax.set_ylim(lo - pad, hi + pad)
    ax.axhline(0, color="k", lw=0.8)
    ax.text(0.99, 0.97, "pulls: an extension spring's side", transform=ax.transAxes,
            ha="right", va="top", fontsize=8, color="tab:blue")
    ax.text(0.99, 0.03, "pushes: a compression spring's or gas strut's side",
            transform=ax.transAxes, ha="right", va="bottom", fontsize=8, color="tab:orange")
    ax.set_xlabel("lid angle θ (deg), released at the right, closed at 0")
    ax.set_ylabel("spring force along E–D (N), > 0 pulls")
    ax.set_title("Spring force over the stroke: a part must stay on one side")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="center left")
    fig.tight_layout()
    return save(fig, path)


def draw_price(rows, path: Path) -> Path:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6.5, 4))
    labels, values, colours = [], [], []
    for r in rows:
        if r["objective"] is None:
            continue
        labels.append(f"{r['problem']}\n{r['kind']}")
        values.append(r["objective"])
        colours.append("tab:grey" if r["kind"] == "linear" else
                       "tab:orange" if r["kind"] == "compression" else "tab:blue")
    ax.bar(range(len(values)), values, color=colours)
    for i, v in enumerate(values):
        ax.text(i, v, f"{v:.4f}", ha="center", va="bottom", fontsize=8)
    ax.set_xticks(range(len(values)), labels, fontsize=8)
    ax.set_ylabel("J (nominal) or worst-case J (robust)")
    ax.set_title("The price of each spring kind (grey: the idealised spring)")
    ax.grid(axis="y", alpha=0.3)
    fig.tight_layout()
    return save(fig, path)


def main(argv=None) -> int:
    ap = study_options(__doc__, __file__,
                       fast="2,000 Monte Carlo samples for the robust designs' yields")
    a = parse(ap, argv)
    cfg = softclose.default_config()
    answers = solve(cfg, a.fast)
    rows, designs = [], {}
    for (problem, name), res in answers.items():
        designs[f"{problem}_{name}"] = {
            "success": res.success, "kind": res.kind, "design": res.design,
            "objective": res.objective, "message": res.message,
            "part": None if res.part is None else res.part.to_json(),
            "kinds": list(res.kinds)}
        for k in res.kinds:
            rows.append({"problem": problem, "springs": name, "kind": k["kind"],
                         "objective": k["objective"], "success": k["success"],
                         "message": k.get("message") or ""})
    price = {}
    for problem in ("nominal", "robust"):
        ideal = answers[(problem, "idealised")].objective
        build = answers[(problem, "buildable")].objective
        price[problem] = (build / ideal if ideal and build is not None else None)
    files = [write_rows(rows, a.out / "kinds.csv")]
    files.append(draw_force(cfg, answers, a.out / "spring_force.png"))
    files.append(draw_price(rows, a.out / "price.png"))
    summary = {"designs": designs, "price": price,
               "note": "price: J with the springs one can buy over J with the idealised one"}
    chosen = answers[("robust", "buildable")]
    if chosen.design is not None:                  # its sign-off report
        add_report(summary, files, softclose.report(
            chosen.design_config(), optimiser=chosen.to_json(), samples=2000 if a.fast else None),
            a.out, "the robust design with buildable springs")
    save_summary(summary, a.out / "designs.json", files)
    if a.json:
        print_json(summary)
    else:
        for key, d in designs.items():
            part = d["part"]
            print(f"{key:<20} kind {d['kind'] or '-':<12} J = "
                  + (f"{d['objective']:.6g}" if d["objective"] is not None else "-")
                  + (f"  part: free length {part['free_length'] * 1e3:.2f} mm, rate "
                     f"{part['rate']:.0f} N/m, largest force {part['largest_force']:.1f} N"
                     if part else ""))
        for problem, p in price.items():
            print(f"price of buildability ({problem}): "
                  + (f"J x {p:.3f}" if p is not None else "no answer"))
        print("wrote " + ", ".join(str(f) for f in files))
    ok = all(answers[(p, "buildable")].success for p in ("nominal", "robust"))
    return 0 if ok else 3


if __name__ == "__main__":
    sys.exit(main())
