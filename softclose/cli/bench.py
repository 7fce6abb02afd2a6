"""``softclose bench`` (transitional adapter: the bench owner replaces this module)."""

from __future__ import annotations

from .common import Outcome, add_common, add_out, prepare_out


def register(sub) -> None:
    p = sub.add_parser("bench", help="run time against error for every integrator and step")
    add_common(p)
    add_out(p)
    p.add_argument("--quick", action="store_true", help="fewer steps and repeats")
    p.set_defaults(run=run)


def run(cfg, args) -> Outcome:
    from .. import bench
    prepare_out(args.out)
    return bench.command(cfg, args)
