"""How far can the four-bar of seed 003 turn before the lever ratio A0A/B0B is off by 1 %?

Input crank A0A = 60, output crank B0B = 40, coupler AB = 59.91, both cranks at 80 deg in the
reference position.  Compares the exact (closed-form, atan2) output angle with the linearised
one, theta_B = 80 deg + (A0A/B0B) phi, for phi = 0..50 deg.  relative_error is measured on the
output rotation psi = theta_B - 80 deg; the seed notebook's measure (relative to the absolute angle
theta_B in rad) is reported alongside, with its own 1 % limit.

Writes to studies/out/linearisation/:
  linearisation.png  exact and linearised output angle, and both relative errors, against phi
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from softclose.validation.textbook.linearisation import (LeverFourBar, compare_linearisation,
                                              compute_loop_residual, solve_error_limit,
                                              solve_output_angle)
from softclose.present.study import parse, print_files, print_json, save_figure, study_options



def draw(link, r, limit, limit_seed, out: Path) -> str:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out.mkdir(parents=True, exist_ok=True)
    phi = np.degrees(r["phi"])
    fig, ax = plt.subplots(1, 3, figsize=(15, 4.8))
    other = solve_output_angle(link.theta_ref + r["phi"], link, -r["branch"])
    ax[0].plot(phi, np.degrees(r["theta_b"]), lw=2, label="exact (reference branch)")
    ax[0].plot(phi, np.degrees(r["theta_b_linear"]), "--", lw=2, label=r"linearised, 80° + 1.5 $\phi$")
    ax[0].plot(phi, np.degrees(np.mod(other, 2 * np.pi)), ":", label="exact, other branch")
    ax[0].set_xlabel(r"input rotation $\phi$ (deg)")
    ax[0].set_ylabel(r"output angle $\theta_B$ (deg)")
    ax[0].legend(fontsize=8)
    ax[1].plot(phi, 100 * r["relative_error"], lw=2, label=r"on output rotation $\psi$")
    ax[1].plot(phi, 100 * r["relative_error_absolute_angle"], lw=2,
               label=r"seed's measure (on absolute $\theta_B$)")
    ax[1].axhline(1.0, color="k", lw=0.8)
    ax[1].axvline(limit, color="C0", ls="--", lw=0.8)
    ax[1].axvline(limit_seed, color="C1", ls="--", lw=0.8)
    ax[1].annotate(f"{limit:.1f}°", (limit, 3), color="C0", xytext=(-32, 0), textcoords="offset points")
    ax[1].annotate(f"{limit_seed:.1f}°", (limit_seed, 5), color="C1", xytext=(4, 0), textcoords="offset points")
    ax[1].set_ylim(0, 16)
    ax[1].set_xlabel(r"input rotation $\phi$ (deg)")
    ax[1].set_ylabel("relative error (%)")
    ax[1].legend(fontsize=8, loc="upper left")
    # the mechanism in the reference position and at phi = 50 deg
    for ph, style in ((0.0, "k-o"), (r["phi"][-1], "C3-o")):
        ta = link.theta_ref + ph
        tb = np.interp(ph, r["phi"], r["theta_b"])
        A = link.r_a * np.array([np.sin(ta), -np.cos(ta)])
        B = link.pivot_b + link.r_b * np.array([np.sin(tb), -np.cos(tb)])
        ax[2].plot([0, A[0], B[0], link.pivot_b[0]], [0, A[1], B[1], link.pivot_b[1]], style,
                   label=fr"$\phi$ = {np.degrees(ph):.0f}°")
    ax[2].plot([0, link.pivot_b[0]], [0, link.pivot_b[1]], "k^", ms=10)
    ax[2].annotate("A0", (0, 0), xytext=(8, -4), textcoords="offset points")
    ax[2].annotate("B0", link.pivot_b, xytext=(-18, -4), textcoords="offset points")
    ax[2].set_aspect("equal")
    ax[2].set_xlabel("x (m)")
    ax[2].set_ylabel("y (m)")
    ax[2].legend(fontsize=8)
    for a in ax:
        a.grid(alpha=0.3)
    fig.suptitle("Linearised lever ratio |A0A|/|B0B| = 1.5 against the exact four-bar")
    return save_figure(fig, out / "linearisation.png")


def main(argv=None) -> int:
    ap = study_options(__doc__, __file__, fast="smoke test: coarse grid", plots=True)
    ap.add_argument("--step-deg", type=float, default=0.1, help="grid step of phi (deg)")
    args = parse(ap, argv)

    step = 1.0 if args.fast else args.step_deg
    link = LeverFourBar()
    phi = np.radians(np.arange(0.0, 50.0 + step / 2, step))
    r = compare_linearisation(phi, link)
    limit = np.degrees(solve_error_limit(link, "relative_error"))
    limit_seed = np.degrees(solve_error_limit(link, "relative_error_absolute_angle"))
    report = {
        "phi_deg": np.degrees(phi).tolist(),
        "theta_b_deg": np.degrees(r["theta_b"]).tolist(),
        "theta_b_linear_deg": np.degrees(r["theta_b_linear"]).tolist(),
        "relative_error": r["relative_error"].tolist(),
        "max_phi_deg_below_1pct": limit,
        "relative_error_absolute_angle": r["relative_error_absolute_angle"].tolist(),
        "max_phi_deg_below_1pct_absolute_angle": limit_seed,
        "seed_claim_deg": 30.0,
        "transfer_ratio": r["ratio"],
        "max_loop_residual": float(np.max(compute_loop_residual(link.theta_ref + phi, r["theta_b"], link))),
    }
    if not args.no_plots:
        report["figures"] = [draw(link, r, limit, limit_seed, args.out)]
    if args.json:
        print_json(report)
    else:
        for k in range(0, len(phi), max(1, int(round(5 / step)))):
            print(f"phi = {report['phi_deg'][k]:5.1f} deg   theta_B = {report['theta_b_deg'][k]:8.3f}   "
                  f"linear = {report['theta_b_linear_deg'][k]:8.3f}   rel. error = {100 * r['relative_error'][k]:6.3f} %")
        print(f"1 % error on the output rotation reached at phi = {limit:.2f} deg")
        print(f"1 % error by the seed's measure (absolute angle) at phi = {limit_seed:.2f} deg (seed: 'up to 30 deg')")
        print_files(report.get("figures", []))
    return 0


if __name__ == "__main__":
    sys.exit(main())
