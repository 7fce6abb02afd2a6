"""How accurate is the seed notebook's gravity-only drop (Euler–Cromer at 1 kHz)?

The seed (000) releases the default lid from rest at 18 deg under gravity alone and steps it
with Euler–Cromer at 1000 samples per second, reading the impact off the first sample at or
below theta = 0. ``softclose.bench.seed_reproduction`` repeats that computation with the
library (the kernel's Euler–Cromer, the same method and step) and compares it with an accurate
answer: the adaptive CVODES reference at tolerance 1e-12, and softclose's default (rk4 at
simulate.step, the event located inside the step). It separates the two error sources of the
seed: the method's first-order error, and reading the event off the sample grid. It also shows
how the Euler–Cromer error falls with the step (order 1) against rk4 (order 4).

Writes to studies/out/seed_reproduction/:
  seed_reproduction.png   theta(t) of the seed's drop against the accurate one, the seed's
                          error along it, and the error of closing_time and impact_theta_dot
                          against the step
  seed_reproduction.json  the numbers (seed, located-event Euler–Cromer, default, reference)

Usage: python studies/seed_reproduction.py [--fast] [--json] [--out DIR]
"""

from __future__ import annotations

import sys

import softclose
from softclose.bench import SEED_KEYS, seed_reproduction
from softclose.present.figures import save
from softclose.present.figures.bench import plot_seed_reproduction
from softclose.jsonio import dumps
from softclose.present.study import parse, print_files, study_options


def main(argv=None) -> int:
    ap = study_options(__doc__, __file__, fast="fewer steps in the convergence study")
    a = parse(ap, argv)
    rep = seed_reproduction(softclose.default_config(), fast=a.fast)  # SPEC §8: gravity only
    fig = save(plot_seed_reproduction(rep), a.out / "seed_reproduction.png")
    numbers = {k: v for k, v in rep.items() if k != "trajectories"}
    js = a.out / "seed_reproduction.json"
    js.write_text(dumps(numbers, indent=1))
    numbers["files"] = [str(fig), str(js)]
    if a.json:
        print(dumps({k: v for k, v in numbers.items() if k != "convergence"}))
        return 0
    r, s, d = rep["reference"], rep["seed_grid_reading"], rep["default"]
    for k in SEED_KEYS:
        print(f"{k:18s} reference {r[k]: .9f}  seed (EC 1 kHz, grid) {s[k]: .6f}  "
              f"error {s[k] - r[k]: .2e}  EC located {rep['euler_cromer_located_errors'][k]: .2e}"
              f"  {d['method']} {d['step'] * 1e3:g} ms {rep['default_errors'][k]: .2e}")
    print(f"observed orders: {rep['observed_order']}")
    print_files(numbers["files"])
    return 0


if __name__ == "__main__":
    sys.exit(main())
