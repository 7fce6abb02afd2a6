"""``softclose simulate [--out DIR]``: one closing stroke and its metrics."""

from __future__ import annotations

import argparse

from .common import (Outcome, add_common, add_out, add_slow_motion, format_metrics,
                     prepare_out, slow_motion, wrote)

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
    from ..simulate import Simulator
    factor = slow_motion(args)
    out = prepare_out(args.out)
    sim = Simulator(cfg, cached=True)
    res = sim.run(trajectory=out is not None)
    payload = res.to_json()
    payload["integrator"] = res.method
    if not res.ok:
        payload["error"] = res.message
        from ..stroke import StrokeStatus
        code = 2 if res.status is StrokeStatus.OUT_OF_RANGE else 3   # an invalid design
        return Outcome(payload, format_metrics(payload), code, error=res.message)
    files = []
    if out is not None:
        from .files import write_stroke_outputs
        files = write_stroke_outputs(sim.model, res, out, slow_motion=factor)
        payload["files"] = [str(f) for f in files]
    text = format_metrics(payload)
    if res.message:
        payload["warning"] = res.message
        text += f"\n  {res.message}"
    return Outcome(payload, text + wrote(files), 0, tuple(files))
