"""Does every stressed stroke give an answer the adaptive reference confirms, or a clear report of why not?

Runs the stress cases of ``softclose.validation.stress.stress_cases``: damping from 0 to 1e6 N s/m, spring
stiffness up to 1e6 N/m, steps far too large and very small, long undamped runs (energy drift
reported), a geometry driven near a toggle position, a release angle near the edge of the
assembly, and a few other edges. Each case is simulated with the fixed-step kernel; an answer is
compared with CVODES (tolerance 1e-12): each metric must lie within the accuracy target or
within 4 x the stroke's own error estimate (``softclose.validation.stress.confirm``). A failed stroke must
come with a one-line report; an unstable one is re-run at the step the report recommends. A
NaN, a traceback or a mismatch is a finding (exit code 1).

Writes to studies/out/stress_survey/:
  stress.md    the stress table (Markdown; docs/performance.md quotes it)
  stress.csv   the same, one row per case
  stress.json  the same, machine-readable

Usage: python studies/stress_survey.py [--fast] [--out DIR]
"""

from __future__ import annotations

import sys

from softclose.validation import stress
from softclose.bench.report import write_csv
from softclose.jsonio import dumps
from softclose.present.study import parse, study_options


def show(r: dict) -> None:
    print(f"{r['name']:<34} {r['outcome']:<13} {r['status']:<26} {r['time_s']:6.2f} s  "
          f"{r['message'][:110]}", flush=True)


def main(argv=None) -> int:
    ap = study_options(__doc__, __file__, json_option=False,
                       fast="the representative subset the tests use")
    a = parse(ap, argv)
    rows = stress.run_survey(fast=a.fast, log=show)
    (a.out / "stress.md").write_text(stress.stress_markdown(rows) + "\n")
    write_csv(rows, a.out / "stress.csv")
    (a.out / "stress.json").write_text(dumps(rows, indent=1))
    bad = stress.findings(rows)
    print(f"{len(rows)} cases, {len(bad)} findings: {', '.join(r['name'] for r in bad) or 'none'}")
    print(f"written to {a.out}")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
