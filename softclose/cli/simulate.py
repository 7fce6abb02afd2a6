"""``softclose simulate [--out DIR]``: one closing stroke and its metrics."""

from __future__ import annotations

from .common import Outcome, add_common, add_out, format_metrics, prepare_out, wrote


def register(sub) -> None:
    p = sub.add_parser("simulate", help="one closing stroke: its metrics, each with its accuracy")
    add_common(p)
    add_out(p, what="also write the trajectory CSV and figures to this folder")
    p.set_defaults(run=run)


def run(cfg, args) -> Outcome:
    from ..simulate import Simulator
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
        files = write_stroke_outputs(sim.model, res, out)
        payload["files"] = [str(f) for f in files]
    text = format_metrics(payload)
    if res.message:
        payload["warning"] = res.message
        text += f"\n  {res.message}"
    return Outcome(payload, text + wrote(files), 0, tuple(files))
