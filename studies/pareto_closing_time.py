"""How much softer can the lid close if it may take longer? The optimal soft-close design
against the allowed closing time.

For closing_time_max from 0.3 s to 3 s (log-spaced), the optimiser (softclose.optimise.front:
direct multiple shooting + Ipopt, warm-started from one point to the next, plus the best
sweep start of each point as a guard) gives the optimal spring and damper; each optimum is
then re-simulated by the adaptive reference (CVODES), and its impact speed and peak tip speed
are reported with their verification differences. The front is the curve of impact speed
and peak tip speed against closing_time_max (both fall as the lid is allowed more time).

Writes to studies/out/pareto_closing_time/:
  pareto_closing_time.png   impact and peak tip speed against closing_time_max; the trade-off
                            between them; the optimal spring and damper against closing_time_max
  pareto_closing_time.csv   one row per closing_time_max: design, metrics, objective,
                            reference objective and relative difference, solve time
  pareto_closing_time.json  the same as JSON, plus the timing of the front

Options: --fast (4 points, a smoke test), --json (print the JSON report), --points N.
"""

from __future__ import annotations

import argparse
import csv
import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from softclose.config import load_config  # noqa: E402
from softclose.optimise import front, verify_design  # noqa: E402

OUT = Path(__file__).resolve().parent / "out" / "pareto_closing_time"


def run(points: int, config: str | None = None, overrides=()) -> dict:
    cfg = load_config(config, overrides)
    t_max = np.geomspace(0.3, 3.0, points)
    t0 = time.perf_counter()
    results = front(cfg, t_max)
    wall = time.perf_counter() - t0
    rows = []
    for tm, r in zip(t_max, results):
        row = {"closing_time_max": float(tm), "success": r.success, "status": r.status,
               "message": r.message, "solve_time": r.total_time, "iterations": r.iterations}
        if r.design is not None:
            c = cfg.replace(optimise={"closing_time_max": float(tm)})
            ver = verify_design(c, r.design, r.metrics, r.objective)
            row.update(r.design)
            row.update({k: r.metrics[k] for k in ("closing_time", "impact_theta_dot",
                                                  "impact_tip_speed", "peak_tip_speed",
                                                  "holding_moment")})
            row["objective"] = r.objective
            row["objective_reference"] = ver.get("objective")
            row["objective_relative_difference"] = ver.get("objective_relative_difference")
            row["impact_tip_speed_reference"] = ver.get("impact_tip_speed")
            row["peak_tip_speed_reference"] = ver.get("peak_tip_speed")
            row["closing_time_reference"] = ver.get("closing_time")
            row["verified"] = bool(ver.get("ok"))
            row["success"] = r.success and row["verified"]
        rows.append(row)
    return {"question": __doc__.splitlines()[0], "points": points, "front_time_s": wall,
            "config": config, "overrides": list(overrides),
            "rows": rows, "all_verified": all(r.get("verified") for r in rows)}


def draw(report: dict, out: Path) -> str:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import FormatStrFormatter, NullFormatter

    def ticks(axis, values):
        axis.set_major_formatter(FormatStrFormatter("%g"))
        axis.set_minor_formatter(NullFormatter())
        axis.set_ticks(values)

    rows = [r for r in report["rows"] if r.get("objective") is not None]
    tm = np.array([r["closing_time_max"] for r in rows])
    imp = np.array([r["impact_tip_speed"] for r in rows])
    peak = np.array([r["peak_tip_speed"] for r in rows])
    thd = np.array([-r["impact_theta_dot"] for r in rows])
    fig, ax = plt.subplots(1, 3, figsize=(15, 4.6))
    a = ax[0]
    a.loglog(tm, peak, "o-", lw=2, color="C2", label="peak tip speed |v_T|max (m/s)")
    a.loglog(tm, imp, "s-", lw=2, color="C1", label="impact tip speed (m/s)")
    a.loglog(tm, thd, "^--", lw=1.2, color="C0", label=r"impact $|\dot\theta|$ (rad/s)")
    a.set_xlabel("closing_time_max (s)")
    a.set_ylabel("speed at the optimum")
    a.set_title("Optimal speeds against the allowed closing time")
    a.legend(fontsize=8)
    a.grid(True, which="both", alpha=0.3)
    ticks(a.xaxis, [0.3, 0.5, 1, 2, 3])
    ticks(a.yaxis, [0.02, 0.05, 0.1, 0.2, 0.5, 1])
    a = ax[1]
    a.plot(imp, peak, "o-", lw=2, color="C3")
    for x, y, t in zip(imp, peak, tm):
        a.annotate(f"{t:.2g} s", (x, y), xytext=(5, 3), textcoords="offset points", fontsize=8)
    a.set_xscale("log")
    a.set_yscale("log")
    a.set_xlabel("impact tip speed (m/s)")
    a.set_ylabel("peak tip speed (m/s)")
    a.set_title("The front: peak against impact speed\n(labels: closing_time_max)")
    a.grid(True, which="both", alpha=0.3)
    ticks(a.xaxis, [0.02, 0.05, 0.1, 0.2])
    ticks(a.yaxis, [0.2, 0.3, 0.5, 0.8, 1])
    a = ax[2]
    k = np.array([r["spring_k"] for r in rows])
    c = np.array([r["damper_c"] for r in rows])
    l0 = np.array([r["spring_rest_length"] for r in rows])
    a.semilogx(tm, k, "o-", color="C4", label="spring_k (N/m)")
    a.semilogx(tm, c, "s-", color="C5", label="damper_c (N s/m)")
    a.set_xlabel("closing_time_max (s)")
    a.set_ylabel("spring_k, damper_c")
    a2 = a.twinx()
    a2.semilogx(tm, 1000 * l0, "^--", color="C7", label="spring_rest_length (mm)")
    a2.set_ylabel("spring_rest_length (mm)")
    h1, l1 = a.get_legend_handles_labels()
    h2, l2 = a2.get_legend_handles_labels()
    a.legend(h1 + h2, l1 + l2, fontsize=8, loc="upper center")
    cfg = load_config(report.get("config"), report.get("overrides", []))
    at_k = [f"{t:.2g}" for t, v in zip(tm, k) if v >= cfg.optimise.spring_k[1] * (1 - 1e-6)]
    at_c = [f"{t:.2g}" for t, v in zip(tm, c) if v >= cfg.optimise.damper_c[1] * (1 - 1e-6)]
    sub = []
    if at_k:
        sub.append(f"k at its bound: {', '.join(at_k)} s")
    if at_c:
        sub.append(f"c at its bound: {', '.join(at_c)} s")
    a.set_title("Optimal design against closing_time_max" + ("\n" + "; ".join(sub) if sub else ""),
                fontsize=9 if sub else None)
    a.grid(True, which="both", alpha=0.3)
    ticks(a.xaxis, [0.3, 0.5, 1, 2, 3])
    rel = max(abs(r["objective_relative_difference"]) for r in rows)
    fig.suptitle(f"Soft-close optimum against closing_time_max ({len(rows)} points, front in "
                 f"{report['front_time_s']:.2f} s; every point verified by CVODES, objective "
                 f"agreement <= {rel:.1e})")
    fig.tight_layout()
    out.mkdir(parents=True, exist_ok=True)
    path = out / "pareto_closing_time.png"
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return str(path)


def write_tables(report: dict, out: Path) -> list[str]:
    out.mkdir(parents=True, exist_ok=True)
    keys = ["closing_time_max", "spring_k", "spring_rest_length", "damper_c", "closing_time",
            "impact_theta_dot", "impact_tip_speed", "peak_tip_speed", "holding_moment",
            "objective", "objective_reference", "objective_relative_difference", "verified",
            "success", "status", "iterations", "solve_time"]
    p = out / "pareto_closing_time.csv"
    with open(p, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(keys)
        for r in report["rows"]:
            w.writerow([r.get(k, "") for k in keys])
    j = out / "pareto_closing_time.json"
    j.write_text(json.dumps(report, indent=1, default=float))
    return [str(p), str(j)]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fast", action="store_true", help="smoke test: 4 points")
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    ap.add_argument("--points", type=int, default=10, help="number of closing_time_max values")
    ap.add_argument("--config", help="TOML config file")
    ap.add_argument("--set", dest="overrides", action="append", default=[],
                    help="config override section.key=value (repeatable)")
    ap.add_argument("--no-plots", action="store_true")
    args = ap.parse_args(argv)
    report = run(4 if args.fast else args.points, args.config, args.overrides)
    files = write_tables(report, OUT)
    if not args.no_plots:
        files.append(draw(report, OUT))
    report["files"] = files
    if args.json:
        print(json.dumps(report, default=float))
    else:
        print(f"{'T_max (s)':>9} {'k (N/m)':>9} {'l0 (m)':>8} {'c (Ns/m)':>9} {'impact (m/s)':>12} "
              f"{'peak (m/s)':>10} {'J':>10} {'J rel. diff':>11} ok")
        for r in report["rows"]:
            if r.get("objective") is None:
                print(f"{r['closing_time_max']:9.3g}  failed: {r['message']}")
                continue
            print(f"{r['closing_time_max']:9.3g} {r['spring_k']:9.1f} "
                  f"{r['spring_rest_length']:8.5f} {r['damper_c']:9.1f} "
                  f"{r['impact_tip_speed']:12.5f} {r['peak_tip_speed']:10.5f} "
                  f"{r['objective']:10.6f} {r['objective_relative_difference']:11.1e} "
                  f"{'yes' if r['success'] else 'NO'}")
        print(f"front of {report['points']} points in {report['front_time_s']:.2f} s "
              f"(verification not included)")
        for f in files:
            print("wrote", f)
    return 0 if report["all_verified"] else 3


if __name__ == "__main__":
    sys.exit(main())
