"""Which integrator and step give the SPEC §4 metrics to the accuracy targets at the least run time?

For every fixed-step method (rk4, euler_cromer, gauss4, radau5) and a range of steps, the error
of closing_time, impact_theta_dot, impact_tip_speed and peak_tip_speed against CVODES at
tolerance 1e-14, on the SPEC §8 case and on spring + dashpot designs, against the C kernel's run
time per stroke (median of repeats); the adaptive reference at tolerances 1e-6 … 1e-12 and the
seed's method (Euler–Cromer at 1 kHz) are included. The default step is the cheapest setting that
meets |Δ closing_time| ≤ 1e-7 s, |Δ impact_theta_dot| ≤ 1e-6 rad/s and relative 1e-6 on both tip
speeds on every design. Also: the speed of model build, one stroke, the raw kernel, the reference
and the CLI end to end, and (when softclose.optimise exists) N and sub-steps of the optimiser
against the error of the optimal objective and the solve time. All of it is
``softclose.bench.run``; this script only chooses where the files go.

Writes to studies/out/work_precision/:
  work_precision.png  error against run time per stroke, one line per method, rows = designs
  error_vs_step.png   error of impact_theta_dot against the step, with the fitted orders
  optimiser.png       optimal-objective error against solve time (if the optimiser exists)
  work_precision.csv  one row per design, method and step (errors, run times, status)
  speed.csv           the speed measurements
  optimiser.csv       one row per N and sub-steps (if the optimiser exists)
  bench.md            the tables as Markdown (pasted into BENCHMARKS.md)
  bench.json          everything above, machine description included

Usage: python studies/work_precision.py [--fast] [--no-optimiser]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from softclose import bench  # noqa: E402
from softclose.config import default_config  # noqa: E402

OUT = Path(__file__).resolve().parent / "out" / "work_precision"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fast", action="store_true", help="fewer steps, designs and repeats")
    ap.add_argument("--no-optimiser", action="store_true", help="skip the optimiser section")
    ap.add_argument("--out", type=Path, default=OUT)
    a = ap.parse_args(argv)
    log = lambda *m: print(*m, flush=True)  # noqa: E731
    res = bench.run(default_config(), quick=a.fast, out=a.out, log=log,
                    optimiser=not a.no_optimiser)
    d = res["default"]
    print(f"default: {d['method']} at step {d['step']} s; per method: {d['per_method']}")
    print(f"{res['optimiser_note']}")
    print(f"written to {a.out} in {res['elapsed']:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
