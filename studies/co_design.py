"""What does each co-design lever buy? Where the spring and the dashpot attach, and a damper
that engages only near the rim, co-designed with k, l0 and c, nominally and over the default
tolerance box.

Levers (a compression spring throughout, the default problem):

- ``today``: the points of the default geometry (D, E, the dashpot from C to O);
- ``spring``: the spring's anchor D within (-90..-30, -10..50) mm and its lid point E within
  (-6..44, 4..24) mm (the issue's box: D +- 30 mm, E -10..+40, +-10 mm);
- ``dashpot``: the dashpot's ground anchor within +-30 mm of O and its lid point within
  (-10..+40, +-10) mm of pin C;
- ``both``: the two together;
- ``end_damper``: the engagement-angle lever -- an end damper on the lid's rotation (a
  barrel or plunger damper the lid meets near the rim) with its coefficient c_e within
  0..2 N m s/rad and its engagement angle within 1..10 deg above the rim, at today's points
  (the optimiser's two-phase multiple shooting; over the box its c_e carries the default
  +-20 % like the dashpot's c).

Each is solved by ``softclose.optimise`` (nominal, verified by the adaptive reference) and
``softclose.optimise(..., robust=True)`` (worst case over the box, every scenario verified);
the gain is J(lever) / J(today) - 1. The end damper's answer sits on its bounds (the
strongest damper, engaging as late as allowed): its gain is set by them, and the table says
where it engages and how fast (``engage``).

Writes to studies/out/co_design/:
  levers.csv          one row per (problem, lever): J, success, the points, the end damper
                      and its engagement (time, theta'), time
  levers.json         the same with every design, and the gains against today's points
  gains.png           J of each lever, nominal and robust
  attachments.png     the best robust design's points, lines over the stroke, its boxes
  report.html         the sign-off report of the best robust design
  report.pdf          the same, to print (A4)

Usage: python studies/co_design.py [--fast] [--json] [--out DIR]
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import softclose
from softclose.present.figures import save
from softclose.present.study import (add_report, parse, print_json, save_summary, study_options,
                                     write_rows)

SPRING = {"geometry.spring_anchor[0]": [-0.09, -0.03], "geometry.spring_anchor[1]": [-0.01, 0.05],
          "geometry.lid_e[0]": [-0.006, 0.044], "geometry.lid_e[1]": [0.004, 0.024]}
DASHPOT = {"geometry.dashpot_anchor[0]": [-0.03, 0.03],
           "geometry.dashpot_anchor[1]": [-0.03, 0.03],
           "geometry.dashpot_lid[0]": [0.002, 0.052], "geometry.dashpot_lid[1]": [0.003, 0.023]}
END_DAMPER = {"design.end_damper_c": [0.0, 2.0], "design.end_damper_angle_deg": [1.0, 10.0]}
LEVERS = {"today": {}, "spring": SPRING, "dashpot": DASHPOT, "both": {**SPRING, **DASHPOT},
          "end_damper": END_DAMPER}
#: the levers solved with --fast: nominally, and robustly (a robust co-design takes 20-40 s;
#: the test suite solves the spring's on its own, tests/test_placement.py)
FAST_NOMINAL = ("today", "spring", "dashpot", "end_damper")
FAST_ROBUST = ("today",)


def solve(cfg, fast: bool) -> dict:
    """{(problem, lever): (result, seconds)}."""
    out = {}
    for name, box in LEVERS.items():
        if fast and name not in FAST_NOMINAL:
            continue
        c = cfg.set("optimise.free", box) if box else cfg
        t0 = time.perf_counter()
        out[("nominal", name)] = (softclose.optimise(c), time.perf_counter() - t0)
        if fast and name not in FAST_ROBUST:
            continue
        t0 = time.perf_counter()
        cr = c.set("tolerance.samples", 2000) if fast else c
        out[("robust", name)] = (softclose.optimise(cr, robust=True), time.perf_counter() - t0)
    return out


def draw_gains(rows, path: Path) -> Path:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 2, figsize=(9, 3.8), layout="constrained")
    for ax, problem in zip(axes, ("nominal", "robust")):
        rs = [r for r in rows if r["problem"] == problem and r["objective"] is not None]
        ax.bar(range(len(rs)), [r["objective"] for r in rs],
               color=["tab:grey" if r["lever"] == "today" else "tab:green" for r in rs])
        for i, r in enumerate(rs):
            ax.text(i, r["objective"], f"{r['objective']:.4f}\n({r['gain']:+.1%})"
                    if r["gain"] is not None else f"{r['objective']:.4f}",
                    ha="center", va="bottom", fontsize=8)
        ax.set_xticks(range(len(rs)), [r["lever"] for r in rs])
        ax.set_ylabel("J" if problem == "nominal" else "worst-case J")
        ax.set_title(f"{problem}: J per co-design lever")
        ax.grid(axis="y", alpha=0.3)
        ax.margins(y=0.2)
    return save(fig, path)


def main(argv=None) -> int:
    ap = study_options(__doc__, __file__,
                       fast="no `both` lever, robust only for today's points, 2,000 samples")
    a = parse(ap, argv)
    cfg = softclose.default_config().set("optimise.spring_kinds", ["compression"])
    answers = solve(cfg, a.fast)
    rows = []
    for (problem, lever), (res, seconds) in answers.items():
        today = answers[(problem, "today")][0].objective
        gain = (res.objective / today - 1.0) if res.objective is not None and today else None
        points = {k: v for k, v in (res.design or {}).items() if "[" in k}
        end = {k: v for k, v in (res.design or {}).items() if k.startswith("end_damper")}
        m = res.metrics or {}
        engage = ({"time": m["engage_time"], "theta_dot": m["engage_theta_dot"]}
                  if m.get("engage_time") is not None else {})
        rows.append({"problem": problem, "lever": lever, "objective": res.objective,
                     "gain": gain, "success": res.success, "seconds": seconds,
                     "points": json.dumps(points), "end_damper": json.dumps(end),
                     "engage": json.dumps(engage), "message": res.message or ""})
    files = [write_rows(rows, a.out / "levers.csv")]
    files.append(draw_gains(rows, a.out / "gains.png"))
    robust = [(res.objective, lever, res) for (p, lever), (res, _) in answers.items()
              if p == "robust" and res.success and res.objective is not None]
    best = min(robust, key=lambda x: x[0])[2]
    from softclose.present.figures.attachment import plot_attachments
    files.append(save(plot_attachments(softclose.LidModel.from_config(best.design_config()),
                                       best.design_config(), title="Best robust design",
                                       before=softclose.LidModel.from_config(cfg)),
                      a.out / "attachments.png"))
    summary = {"levers": rows,
               "designs": {f"{p}_{lever}": {"design": res.design, "objective": res.objective,
                                            "success": res.success,
                                            "active": [x.name for x in res.active]}
                           for (p, lever), (res, _) in answers.items()},
               "bounds": {k: v for k, v in LEVERS.items() if k != "today"},
               "note": "gain: J(lever) / J(today's points) - 1; compression spring; the end "
                       "damper lever's answer sits on its bounds (active: end_damper_c upper, "
                       "end_damper_angle_deg lower)"}
    add_report(summary, files, softclose.report(
        best.design_config(), optimiser=best.to_json(), samples=2000 if a.fast else None),
        a.out, "the best robust co-design")
    save_summary(summary, a.out / "levers.json", files)
    if a.json:
        print_json(summary)
    else:
        for r in rows:
            print(f"{r['problem']:<8} {r['lever']:<8} J = "
                  + (f"{r['objective']:.6g}" if r["objective"] is not None else "-")
                  + (f" ({r['gain']:+.1%} against today's points)" if r["gain"] else "")
                  + f"  {'verified' if r['success'] else 'NOT verified: ' + r['message']}"
                  + f"  {r['seconds']:.1f} s"
                  + (f"  end damper {r['end_damper']}, engages {r['engage']}"
                     if r["end_damper"] != "{}" else ""))
        print("wrote " + ", ".join(str(f) for f in files))
    ok = all(res.success for res, _ in answers.values())
    return 0 if ok else 3


if __name__ == "__main__":
    sys.exit(main())
