"""``softclose optimise`` (transitional adapter: the optimise owner replaces this module)."""

from __future__ import annotations

from .common import Outcome, add_common, add_out, prepare_out


def register(sub) -> None:
    p = sub.add_parser("optimise", aliases=["optimize"],
                       help="soft-close design by multiple shooting + Ipopt")
    add_common(p)
    add_out(p, what="also write the optimum's trajectory and figures")
    p.set_defaults(run=run)


def run(cfg, args) -> Outcome:
    from .. import optimise as opt
    prepare_out(args.out)
    return opt.command(cfg, args)
