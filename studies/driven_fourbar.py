"""Driven four-bar in absolute coordinates (seed 002): where are the links, how fast, how hard accelerated?

Crank (0, 0)-p2, coupler p2-p3, rocker p3-(20, 0); L1 = 10, L2 = 26, L3 = 18, phi1 = 1.5 t for
10 s, assembled with p3 above the ground line at t = 0.  Prints q, q', q'' at the requested times
(order x1, y1, phi1, x2, y2, phi2, x3, y3, phi3) and the largest constraint residual.

Writes to studies/out/driven_fourbar/:
  motion.png        coordinates and angular velocities/accelerations against time
  trajectories.png  initial configuration and the paths of the revolute joints
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from softclose.validation.textbook.driven_fourbar import (DrivenFourBar, assemble_driven_fourbar,
                                               build_driven_fourbar, evaluate_constraints,
                                               locate_joints, track_motion)
from softclose.present.study import parse, print_files, print_json, study_options



def parse_times(text: str) -> list[float]:
    return sorted(float(v) for v in text.split(","))


def draw(p, t, Q, QD, QDD, out: Path) -> list[str]:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from softclose.present.figures import save

    out.mkdir(parents=True, exist_ok=True)
    fig, ax = plt.subplots(3, 1, figsize=(8, 9), sharex=True)
    for k, name in ((0, "x1"), (1, "y1"), (3, "x2"), (4, "y2"), (6, "x3"), (7, "y3")):
        ax[0].plot(t, Q[:, k], label=name)
    ax[0].set_ylabel("position (m)")
    ax[0].legend(ncol=3, fontsize=8)
    for k, name in ((2, r"$\phi_1$"), (5, r"$\phi_2$"), (8, r"$\phi_3$")):
        ax[1].plot(t, QD[:, k], label=name)
        ax[2].plot(t, QDD[:, k], label=name)
    ax[1].set_ylabel("angular velocity (rad/s)")
    ax[2].set_ylabel("angular acceleration (rad/s²)")
    ax[2].set_xlabel("time t (s)")
    for a in ax[1:]:
        a.legend(fontsize=8)
    for a in ax:
        a.grid(alpha=0.3)
    fig.suptitle(r"Driven four-bar, $\phi_1 = 1.5\,t$")
    fig.tight_layout()
    files = [out / "motion.png"]
    files[0] = save(fig, files[0])

    J = np.array([locate_joints(q, p) for q in Q])
    fig, ax = plt.subplots(figsize=(8, 6))
    for k, (name, style) in enumerate((("p2", "C0"), ("p3", "C1"))):
        ax.plot(J[:, k + 1, 0], J[:, k + 1, 1], style, lw=1.2, label=f"trajectory of {name}")
    j0 = J[0]
    ax.plot(j0[:, 0], j0[:, 1], "k-o", lw=2.5, label="configuration at t = 0")
    ax.plot([0, p.G], [0, 0], "k^", ms=12, label="ground pivots p1, p4")
    for k, name in enumerate(("p1", "p2", "p3", "p4")):
        ax.annotate(name, j0[k], textcoords="offset points", xytext=(6, 6))
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="lower right")
    ax.set_title("Initial configuration and joint trajectories (0–10 s)")
    fig.tight_layout()
    files.append(out / "trajectories.png")
    files[1] = save(fig, files[1])
    return [str(f) for f in files]


def main(argv=None) -> int:
    ap = study_options(__doc__, __file__, fast="smoke test: coarse plot grid", plots=True)
    ap.add_argument("--times", default="0,1,2.5,5,10", help="comma-separated times in s")
    args = parse(ap, argv)

    p = DrivenFourBar()
    system = build_driven_fourbar(p)
    q0 = assemble_driven_fourbar(p, upper=True)
    times = parse_times(args.times)
    Q, QD, QDD = track_motion(system, q0, times)
    residual = max(float(np.max(np.abs(evaluate_constraints(system, q, t)))) for q, t in zip(Q, times))
    report = {"t": times, "q": Q.tolist(), "qd": QD.tolist(), "qdd": QDD.tolist(),
              "max_constraint_residual": residual}
    if not args.no_plots:
        grid = np.linspace(0.0, 10.0, 101 if args.fast else 1001)
        report["figures"] = draw(p, grid, *track_motion(system, q0, grid), args.out)
    if args.json:
        print_json(report)
    else:
        np.set_printoptions(precision=5, suppress=True, linewidth=140)
        print("order: x1, y1, phi1, x2, y2, phi2, x3, y3, phi3")
        for k, t in enumerate(times):
            print(f"t = {t:g} s\n  q   = {Q[k]}\n  q'  = {QD[k]}\n  q'' = {QDD[k]}")
        print(f"max constraint residual: {residual:.2e}")
        print_files(report.get("figures", []))
    return 0


if __name__ == "__main__":
    sys.exit(main())
