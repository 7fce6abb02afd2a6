"""How accurate is the seed notebook's gravity-only drop (Euler–Cromer at 1 kHz)?

The seed (000) releases the default lid from rest at 18 deg under gravity alone and steps it
with Euler–Cromer at 1000 samples per second, reading the impact off the first sample at or
below theta = 0. This study repeats that computation with the library (the kernel's
Euler–Cromer, the same method and step) and compares it with an accurate answer: the
adaptive CVODES reference at tolerance 1e-12 (and RK4 at 1 ms with the event located inside
the step, softclose's default). It separates the two error sources of the seed: the method's
first-order error, and reading the event off the sample grid. It also shows how the
Euler–Cromer error falls with the step (order 1) against RK4 (order 4).

Writes to studies/out/seed_reproduction/:
  seed_reproduction.png   theta(t) and theta'(t) of the seed's drop against the reference,
                          and the error of closing_time and impact_theta_dot against the step
  seed_reproduction.json  the numbers (seed, located-event Euler–Cromer, RK4, reference)

Usage: python studies/seed_reproduction.py [--fast] [--json]
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from softclose import native  # noqa: E402
from softclose.config import default_config  # noqa: E402
from softclose.reference import Reference  # noqa: E402
from softclose.simulate import Simulator  # noqa: E402

OUT = Path(__file__).resolve().parent / "out" / "seed_reproduction"
SEED_STEP = 1e-3  # the seed's 1000 samples per second


def seed_reading(sim: Simulator) -> dict:
    """The seed's numbers: Euler–Cromer at 1 ms, impact read at the first sample theta <= 0."""
    res = sim.run(trajectory=True, estimate_error=False)
    tr = res.trajectory
    # the kernel stops at the located event; the sample the seed reads is one full step on
    # from the last node before it
    t, th, thd = tr["t"][-2], tr["theta"][-2], tr["theta_dot"][-2]
    x1 = native.kernel_step(sim.table, sim.method, sim.model.params(), sim.step,
                            np.array([th, thd]))
    v_T = np.asarray(sim.model.kin(np.array([x1[0], x1[1]]))[4]).ravel()
    tau = float(np.hypot(v_T[0], v_T[1]))
    return {"closing_time": t + sim.step, "impact_theta_dot": float(x1[1]),
            "impact_tip_speed": tau, "theta_at_sample_deg": math.degrees(x1[0]),
            "located_event": res.metrics(), "trajectory": tr}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fast", action="store_true", help="fewer steps in the convergence study")
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    ap.add_argument("--out", type=Path, default=OUT)
    a = ap.parse_args(argv)
    out = a.out
    out.mkdir(parents=True, exist_ok=True)

    cfg = default_config()  # gravity only: no spring, no damper (SPEC §8)
    ec = Simulator(cfg, integrator="euler_cromer", step=SEED_STEP)
    seed = seed_reading(ec)
    rk4 = Simulator(cfg, model=ec.model).run(trajectory=True)
    ref = Reference(ec.model).simulate()
    keys = ("closing_time", "impact_theta_dot", "impact_tip_speed")

    steps = SEED_STEP * 2.0 ** -np.arange(0, 4 if a.fast else 8)
    steps = np.r_[SEED_STEP * np.array([8, 4, 2]), steps]
    conv = {"step": steps.tolist()}
    for name in ("euler_cromer", "rk4"):
        for k in keys[:2]:
            conv[f"{name}_{k}_error"] = []
        for h in steps:
            r = Simulator(cfg, model=ec.model, integrator=name, step=float(h)).run(
                estimate_error=False)
            for k in keys[:2]:
                conv[f"{name}_{k}_error"].append(abs(getattr(r, k) - ref[k]))
    def fit_order(err):  # slope over the errors above the reference's own floor
        e = np.asarray(err)
        ok = e > 1e-8
        if ok.sum() < 2:
            return float("nan")
        return float(np.polyfit(np.log(steps[ok]), np.log(e[ok]), 1)[0])
    order = {n: fit_order(conv[f"{n}_impact_theta_dot_error"]) for n in ("euler_cromer", "rk4")}

    report = {
        "reference": {k: ref[k] for k in keys},
        "seed_grid_reading": {k: seed[k] for k in keys},
        "seed_errors": {k: seed[k] - ref[k] for k in keys},
        "euler_cromer_located_event": {k: seed["located_event"][k] for k in keys},
        "euler_cromer_located_errors": {k: seed["located_event"][k] - ref[k] for k in keys},
        "rk4_1ms": {k: getattr(rk4, k) for k in keys},
        "rk4_1ms_errors": {k: getattr(rk4, k) - ref[k] for k in keys},
        "observed_order": order, "convergence": conv,
    }

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    tr, rt = seed["trajectory"], rk4.trajectory
    fig, ax = plt.subplots(1, 3, figsize=(15, 4.6))
    ax[0].plot(rt["t"], np.degrees(rt["theta"]), "k-", lw=2.5, label="accurate (RK4 1 ms, event located)")
    ax[0].plot(tr["t"][:-1], np.degrees(tr["theta"][:-1]), "C1--", lw=1.5,
               label="seed: Euler–Cromer 1 kHz")
    ax[0].plot([seed["closing_time"]], [seed["theta_at_sample_deg"]], "C1o", ms=7,
               label=f"seed's impact sample t = {seed['closing_time']:.3f} s")
    ax[0].plot([ref["closing_time"]], [0.0], "k*", ms=13,
               label=f"reference closing {ref['closing_time']:.7f} s")
    ax[0].set_xlabel("time t [s]")
    ax[0].set_ylabel(r"lid angle $\theta$ [deg]")
    ax[0].legend(fontsize=8)
    ax[0].set_title("Gravity-only drop from 18°")
    nn = min(len(rt["t"]), len(tr["t"])) - 1  # common 1 ms nodes before the events
    ax[1].plot(tr["t"][:nn], tr["theta_dot"][:nn] - rt["theta_dot"][:nn], "C1-", lw=2,
               label=r"$\dot\theta$: seed − accurate [rad/s]")
    ax[1].plot(tr["t"][:nn], np.degrees(tr["theta"][:nn] - rt["theta"][:nn]), "C2--", lw=2,
               label=r"$\theta$: seed − accurate [deg]")
    ax[1].axhline(0, color="k", lw=0.8)
    ax[1].annotate(f"impact θ': seed {seed['impact_theta_dot']:.4f} rad/s,\n"
                   f"reference {ref['impact_theta_dot']:.6f} rad/s", (0.03, 0.06),
                   xycoords="axes fraction", fontsize=9)
    ax[1].set_xlabel("time t [s]")
    ax[1].set_ylabel("seed − accurate [rad/s] / [deg]")
    ax[1].legend(fontsize=8, loc="upper left")
    ax[1].set_title("Error of the seed's trajectory (same 1 ms nodes)")
    for name, c in (("euler_cromer", "C1"), ("rk4", "C0")):
        ax[2].loglog(steps, conv[f"{name}_impact_theta_dot_error"], "o-", color=c,
                     label=f"{name}: |Δ impact θ'| [rad/s]" + (
                         f" (order {order[name]:.2f})" if math.isfinite(order[name]) else ""))
        ax[2].loglog(steps, conv[f"{name}_closing_time_error"], "s--", color=c, ms=4,
                     label=f"{name}: |Δ closing time| [s]")
    ax[2].loglog([SEED_STEP], [abs(report["seed_errors"]["impact_theta_dot"])], "kX", ms=11,
                 label="seed's grid reading at 1 ms")
    ax[2].axhline(1e-6, color="0.5", lw=0.8, ls=":")
    ax[2].annotate("target 1e-6 rad/s", (steps.min(), 1.3e-6), fontsize=8, color="0.4")
    ax[2].annotate("floor: reference tol 1e-12 / table", (steps.min(), 3e-10), fontsize=8,
                   color="C0")
    ax[2].set_xticks(steps[::2] if len(steps) > 8 else steps)
    ax[2].set_xticklabels([f"{h * 1e3:g} ms" for h in (steps[::2] if len(steps) > 8 else steps)],
                          rotation=30, fontsize=8)
    ax[2].minorticks_off()
    ax[2].set_xlabel("step h [s]")
    ax[2].set_ylabel("error against CVODES 1e-12 [rad/s or s]")
    ax[2].legend(fontsize=7)
    ax[2].set_title("Error against the step (events located in the step)")
    fig.tight_layout()
    fig_path = out / "seed_reproduction.png"
    fig.savefig(fig_path, dpi=120)
    plt.close(fig)
    (out / "seed_reproduction.json").write_text(json.dumps(report, indent=1))
    report["files"] = [str(fig_path), str(out / "seed_reproduction.json")]
    if a.json:
        print(json.dumps({k: v for k, v in report.items() if k != "convergence"}))
    else:
        r, s = report["reference"], report["seed_grid_reading"]
        for k in keys:
            print(f"{k:18s} reference {r[k]: .9f}  seed (EC 1 kHz, grid) {s[k]: .6f}  "
                  f"error {s[k] - r[k]: .2e}  EC located {report['euler_cromer_located_errors'][k]: .2e}"
                  f"  RK4 1 ms {report['rk4_1ms_errors'][k]: .2e}")
        print(f"observed orders: {order}")
        for f in report["files"]:
            print("wrote", f)
    return 0


if __name__ == "__main__":
    sys.exit(main())
