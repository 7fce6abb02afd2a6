"""Which four-bars carry a coupler point through five given points (Morgan & Wampler 1990)?

Solves the twelve precision-point equations completely by homotopy continuation (Bertini 2,
optional dependency `bertini2`) for five random points in [-1, 1]^2 and for the five collinear
points of Problem 7, with ground pivots (0, 0) and (1, 0).  Reports the number of finite
solutions, of real ones, of those whose coupler angles are ordered (the seed's criterion) and of
valid designs (real, all five positions on one circuit, passed in order), the largest residual,
and the solve times.

Writes to studies/out/synthesis/:
  straight_line.png  coupler curve of a valid Problem 7 design with the mechanism in its five positions
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from softclose.validation.textbook.synthesis import (PIVOT_A, PROBLEM7_POINTS, classify_solutions,
                                          locate_poses, make_design, solve_precision_points,
                                          trace_circuit)
from softclose.present.study import parse, print_files, print_json, save_figure, study_options



def summarise(result, flags) -> dict:
    return {"points": result.points.tolist(), "pivot_a": result.pivot_a.tolist(),
            "n_paths": result.n_paths, "n_at_infinity": result.n_at_infinity,
            "n_finite": flags["n_finite"], "n_real": flags["n_real"], "n_ordered": flags["n_ordered"],
            "n_valid": flags["n_valid"], "max_residual": flags["max_residual"],
            "seconds": round(result.seconds, 2)}


def pick_straight_line_design(result, flags):
    """The valid design with the shortest total link length (None if there is none)."""
    best, best_len = None, np.inf
    for z, ok in zip(result.solutions, flags["valid"]):
        if ok:
            total = sum(make_design(z.real, result.points, result.pivot_a).lengths.values())
            if total < best_len:
                best, best_len = z.real, total
    return best


def draw(result, z, out: Path) -> str:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out.mkdir(parents=True, exist_ok=True)
    d, a = result.points, result.pivot_a
    design = make_design(z, d, a)
    _, curve = trace_circuit(design, step=0.002)
    P, Q = locate_poses(z, d)
    fig, ax = plt.subplots(figsize=(8, 7))
    ax.plot(curve[:, 0], curve[:, 1], "C3", lw=1.5, label="coupler curve (this circuit)")
    for j in range(5):
        col = plt.cm.viridis(j / 4.5)
        ax.plot([0, P[j, 0], Q[j, 0], a[0]], [0, P[j, 1], Q[j, 1], a[1]], "-o", color=col, lw=1.2, ms=3,
                label="mechanism in positions 0–4" if j == 0 else None)
        ax.fill([P[j, 0], Q[j, 0], d[j, 0]], [P[j, 1], Q[j, 1], d[j, 1]], color=col, alpha=0.15)
        ax.plot([P[j, 0], d[j, 0], Q[j, 0]], [P[j, 1], d[j, 1], Q[j, 1]], color=col, lw=0.8)
    ax.plot(d[:, 0], d[:, 1], "ko", ms=6, label="precision points")
    for j in range(5):
        ax.annotate(str(j), d[j], xytext=(-12, 6), textcoords="offset points", fontsize=11)
    ax.plot([0, a[0]], [0, a[1]], "k^", ms=12, label="ground pivots")
    L = design.lengths
    ax.set_title("Straight-line design, Morgan & Wampler Problem 7\n"
                 f"crank {L['crank_O']:.3f}, coupler {L['coupler']:.3f}, rocker {L['crank_a']:.3f}, "
                 f"ground {L['ground']:.3f}")
    ax.set_aspect("equal")
    ax.set_xlabel("x (length unit)")
    ax.set_ylabel("y (length unit)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="lower right")
    return save_figure(fig, out / "straight_line.png")


def main(argv=None) -> int:
    ap = study_options(__doc__, __file__, fast="smoke test: Problem 7 only", plots=True)
    ap.add_argument("--seed", type=int, default=0, help="seed of the random points")
    args = parse(ap, argv)

    try:
        import bertini  # noqa: F401
    except ImportError:
        print("synthesis needs the optional dependency bertini2 (pip install bertini2)", file=sys.stderr)
        return 2

    report = {"random": None}
    if not args.fast:
        d = np.random.default_rng(args.seed).uniform(-1.0, 1.0, (5, 2))
        r = solve_precision_points(d, PIVOT_A, seed=args.seed + 1)
        report["random"] = summarise(r, classify_solutions(r))
    r7 = solve_precision_points(PROBLEM7_POINTS, PIVOT_A, seed=args.seed + 1)
    f7 = classify_solutions(r7)
    report["problem7"] = summarise(r7, f7)
    z = pick_straight_line_design(r7, f7)
    if z is not None:
        report["problem7"]["design"] = {"x": z[8:10].tolist(), "y": z[10:12].tolist(),
                                        "coupler_angles": np.arctan2(z[1:8:2], z[0:8:2]).tolist(),
                                        **make_design(z, r7.points, r7.pivot_a).lengths}
        if not args.no_plots:
            report["figures"] = [draw(r7, z, args.out)]
    if args.json:
        print_json(report)
    else:
        for name in ("random", "problem7"):
            s = report[name]
            if s is None:
                continue
            print(f"{name}: {s['n_paths']} paths, {s['n_finite']} finite, {s['n_real']} real, "
                  f"{s['n_ordered']} with ordered coupler angles, {s['n_valid']} valid designs; "
                  f"max residual {s['max_residual']:.1e}; {s['seconds']:.1f} s")
        print_files(report.get("figures", []))
    return 0


if __name__ == "__main__":
    sys.exit(main())
