"""How much softer can the lid close if it may take longer? The optimal soft-close design
against the allowed closing time.

For closing_time_max from 0.3 s to 3 s (log-spaced), ``softclose.front`` gives the verified
optimum of each: direct multiple shooting + Ipopt, warm-started from one point to the next
(plus the best sweep start of each point as a guard), every optimum re-simulated by the
adaptive reference (CVODES). The front is the objective and the impact and peak tip speeds
against closing_time_max (all fall as the lid is allowed more time); the table names what
limits each optimum (active bounds and constraints, with dJ per unit relaxation).

Writes to studies/out/pareto_closing_time/:
  pareto_closing_time.png   objective, verified speeds and the optimal design against
                            closing_time_max (design values at a bound ringed)
  pareto_closing_time.csv   one row per closing_time_max: design, objective, the verified
                            metrics, the reference's objective and the relative difference,
                            active limits, iterations, time
  pareto_closing_time.json  the front as JSON (every point with its verification)

Options: --fast (4 points, a smoke test), --points N, --json (print the JSON), --out DIR,
--config FILE, --set KEY=VALUE.
"""

from __future__ import annotations

import sys

import numpy as np

import softclose
from softclose.present.figures import save
from softclose.jsonio import dumps
from softclose.present.study import parse, print_files, study_options


def main(argv=None) -> int:
    ap = study_options(__doc__, __file__, fast="smoke test: 4 points")
    ap.add_argument("--points", type=int, default=10, help="number of closing_time_max values")
    ap.add_argument("--config", help="TOML config file")
    ap.add_argument("--set", dest="overrides", action="append", default=[],
                    metavar="SECTION.KEY=VALUE", help="config override (repeatable)")
    args = ap.parse_args(argv)
    try:
        cfg = softclose.load_config(args.config, args.overrides)
        args = parse(ap, argv)
        times = np.geomspace(0.3, 3.0, 4 if args.fast else args.points)
        fr = softclose.front(cfg, times, progress=not args.json)
    except softclose.SoftcloseError as exc:
        print(f"pareto_closing_time: error: {exc}", file=sys.stderr)
        return exc.exit_code
    frame = fr.to_frame()
    files = [args.out / "pareto_closing_time.csv", args.out / "pareto_closing_time.json"]
    frame.to_csv(files[0], index=False)
    files[1].write_text(dumps(fr.to_json(), indent=1))
    files.append(save(fr.plot(), args.out / "pareto_closing_time.png"))
    if args.json:
        print(dumps(fr.to_json()))
    else:
        cols = ["closing_time_max", "spring_k", "spring_rest_length", "damper_c", "objective",
                "impact_tip_speed", "peak_tip_speed", "objective_relative_difference",
                "success", "active"]
        print(frame[cols].to_string(index=False, float_format=lambda v: f"{v:.6g}"))
        print(f"front of {len(fr.points)} points in {fr.total_time:.2f} s, "
              f"{'every point verified' if fr.success else fr.message}")
        print_files(files)
    return 0 if fr.success else 3


if __name__ == "__main__":
    sys.exit(main())
