"""``softclose simulate [--out DIR]``: one closing stroke and its metrics."""

from __future__ import annotations

import argparse

from .common import (Outcome, add_common, add_out, add_slow_motion, prepare_out, slow_motion,
                     saved, wrote, figures, stroke_files)

DESCRIPTION = """\
One closing stroke of the config's design: the lid released from rest at stroke.theta0_deg
falls to stroke.theta_closed_deg, integrated by simulate.integrator at simulate.step. Every
metric (closing time, impact speeds, peak tip speed, spring lengths, holding moment) comes
with its estimated distance from the converged answer (±). With --out: the trajectory CSV
(units in its header), time histories, a linkage drawing and a GIF (in slow motion)."""


def register(sub) -> None:
    p = sub.add_parser("simulate", help="one closing stroke: its metrics, each with its accuracy",
                       description=DESCRIPTION,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    add_common(p)
    add_out(p, what="also write the trajectory CSV and figures to this folder")
    add_slow_motion(p)
    p.set_defaults(run=run)


def run(cfg, args) -> Outcome:
    from .. import simulate
    factor = slow_motion(args)
    out = prepare_out(args.out, [*stroke_files("stroke"),
                                 *figures("hand_force", "hand_force_temperatures")])
    res = simulate(cfg, trajectory=out is not None, hand_force=True)
    payload = res.to_json()
    if not res.ok:
        from ..simulation.stroke import StrokeStatus
        code = 2 if res.status is StrokeStatus.OUT_OF_RANGE else 3   # an invalid design
        return Outcome(payload, res.text(), code, error=res.message)
    files = saved(res, out, payload, factor)
    return Outcome(payload, res.text() + wrote(files), 0, tuple(files))
