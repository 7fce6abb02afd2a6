"""``softclose bench [--quick] [--structures] [--peers] [--out DIR]``: run time against error,
speeds, optimiser; the NLP structures; the peers.

The measuring is :func:`softclose.bench.run`; its result prints and saves itself
(:meth:`softclose.bench.BenchResult.save`: the files ``--out DIR`` holds, checked before any
work).
"""

from __future__ import annotations

import sys

from .common import FIGURES, Outcome, add_common, add_out, interactive, prepare_out, wrote


def register(sub) -> None:
    p = sub.add_parser("bench", help="run time against error for every integrator and step; "
                                     "speed of the calls; optimiser N and sub-steps",
                       description="The benchmark every published timing and error comes from: the error of every "
                                   "integrator and step against a tight adaptive reference, "
                                   "against its run time, the default step that follows, the "
                                   "speed of the user-facing calls against their targets "
                                   "(each row with the load average it was measured under: "
                                   "the targets are for an idle machine) and the optimiser's "
                                   "N and sub-steps against the error of J. --quick: fewer "
                                   "designs and repeats (cannot confirm the default step).")
    add_common(p)
    add_out(p, what="write the tables (CSV, Markdown, JSON) and figures to this folder")
    p.add_argument("--quick", action="store_true",
                   help="fewer designs, steps and repeats (cannot confirm the default step)")
    p.add_argument("--structures", action="store_true",
                   help="also measure the NLP structures of the main commands (optimise, --robust, "
                        "the co-designs): variables, parameters, generated C and the time to "
                        "build and compile it (minutes)")
    p.add_argument("--peers", action="store_true",
                   help="also solve the default design problem in rockit and in a scipy "
                        "notebook, each timed to its optimum beside `softclose optimise` and "
                        "re-simulated by the adaptive reference (minutes; needs the peers "
                        'extra: pip install "softclose[peers]")')
    p.set_defaults(run=run)


def run(cfg, args) -> Outcome:
    if args.peers:               # the extra is missing: one line, before any work
        from ..bench.peers import require_peers
        require_peers()
    out = prepare_out(args.out)
    from .. import bench
    # progress on a terminal only: a failing run's stderr is then its one-line error
    log = (lambda *a: print(*a, file=sys.stderr, flush=True)) if interactive(args) else \
        (lambda *a: None)
    res = bench.run(cfg, quick=args.quick, log=log, structures=args.structures,
                    peers=args.peers)
    files = res.save(out, FIGURES["format"], FIGURES["style"]) if out is not None else []
    payload = res.to_json()
    payload["files"] = [str(f) for f in files]
    return Outcome(payload, res.text() + wrote(files), 0, tuple(files))


__all__ = ["register", "run"]
