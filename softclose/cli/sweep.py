"""``softclose sweep`` (transitional adapter: the sweep owner replaces this module)."""

from __future__ import annotations

from .common import Outcome, add_common, prepare_out


def register(sub) -> None:
    p = sub.add_parser("sweep", help="metrics over a grid of config values")
    add_common(p)
    p.add_argument("--grid", action="append", default=[], required=True,
                   metavar="KEY=START:STOP:COUNT", help="one swept key (repeatable)")
    p.add_argument("--out", metavar="DIR", required=True, help="folder for sweep.csv and figures")
    p.set_defaults(run=run)


def run(cfg, args) -> Outcome:
    from .. import sweep
    prepare_out(args.out)
    return sweep.command(cfg, args)
