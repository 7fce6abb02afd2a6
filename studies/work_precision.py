"""Which integrator and step give the SPEC §4 metrics to the accuracy targets at the least run time?

For every fixed-step method (rk4, euler_cromer, gauss4, radau5) and a range of steps, the error
of closing_time, impact_theta_dot, impact_tip_speed and peak_tip_speed against CVODES at
tolerance 1e-14, on the SPEC §8 case and on spring + dashpot designs, against the C kernel's run
time per stroke (median of repeats); the adaptive reference at tolerances 1e-6 … 1e-12 and the
seed's method (Euler–Cromer at 1 kHz) are included. The configured default (rk4 at
simulate.step) is checked against the accuracy targets of ``softclose.problem`` on every design,
and the cheapest setting that meets them is reported next to it. Also: the speed of model build,
one stroke, the raw kernel, the reference and the CLI end to end (with the speed targets), and N
and sub-steps of the optimiser against the error of the optimal objective and the solve time.
The measuring is ``softclose.bench.run``; the tables and figures are what ``softclose bench
--out DIR`` writes (``BenchResult.save``). This script only chooses the folder.

Writes to studies/out/work_precision/:
  work_precision.png  error against run time per stroke, one line per method, rows = designs
  error_vs_step.png   error of impact_theta_dot against the step, with the fitted orders
  optimiser.png       optimal-objective error against solve time (if the optimiser ran)
  work_precision.csv  one row per design, method and step (errors, run times, status)
  speed.csv           the speed measurements, with their targets
  optimiser.csv       one row per N and sub-steps (if the optimiser ran)
  bench.md            the tables as Markdown (docs/performance.md quotes them)
  bench.json          everything above, machine, date and commit included

Usage: python studies/work_precision.py [--fast] [--no-optimiser] [--no-features] [--out DIR]
"""

from __future__ import annotations

import sys

import softclose
from softclose import bench
from softclose.bench.report import default_text
from softclose.present.study import parse, study_options


def main(argv=None) -> int:
    ap = study_options(__doc__, __file__, json_option=False,
                       fast="fewer steps, designs and repeats")
    ap.add_argument("--no-optimiser", action="store_true", help="skip the optimiser section")
    ap.add_argument("--no-features", action="store_true",
                    help="skip the sweep / robust / yield / Sobol speed entries")
    a = parse(ap, argv)
    log = lambda *m: print(*m, flush=True)  # noqa: E731
    res = bench.run(softclose.default_config(), quick=a.fast, log=log,
                    optimiser=not a.no_optimiser, features=not a.no_features)
    files = res.save(a.out)
    print(default_text(res.default))
    if res.optimiser_note:
        print(res.optimiser_note)
    print(f"wrote {len(files)} files to {a.out} in {res.elapsed:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
