"""``softclose simulate [--out DIR]``: one closing stroke and its metrics."""

from __future__ import annotations

import argparse
import math

from .common import (Outcome, add_common, add_out, add_slow_motion, format_metrics,
                     prepare_out, slow_motion, wrote, figures, stroke_files)
from ..problem import at_temperature, resolve, sign_off_temperatures

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


def end_damper_note(cfg, res) -> str | None:
    """What the end damper did when that is not a crossing on the way down (none without
    one): engaged from the release (its angle at or above theta0), never (at or below the
    rim), or not reached (the lid stays above it). An angle outside the stroke is not an
    error: it says where the damper acts."""
    d, st = cfg.design, cfg.stroke
    if not d.end_damper_c:
        return None
    at = f"end_damper_angle_deg = {d.end_damper_angle_deg:g}"
    if d.end_damper_angle_deg <= st.theta_closed_deg:
        return (f"never acts: {at} is not above the rim (stroke.theta_closed_deg = "
                f"{st.theta_closed_deg:g})")
    if (res.engage_time is not None and res.engage_time < 1e-12
            and d.end_damper_angle_deg >= st.theta0_deg):
        return (f"acts from the release: {at} is not below stroke.theta0_deg = "
                f"{st.theta0_deg:g}")
    if res.engage_time is None and res.theta_min is not None:
        return (f"never engaged: the lid stays above {at} (lowest angle "
                f"{math.degrees(res.theta_min):.2f} deg)")
    return None


def _hand_forces(cfg, sim) -> list:
    """[(T, hand force)] at each sign-off temperature of ``operating.temperatures_c`` when it
    lists more than one (the design as given, its parts moved to each); else []."""
    from ..simulation.handforce import hand_force
    temps = sign_off_temperatures(cfg)
    if len(temps) < 2:
        return []
    return [(T, hand_force(sim.model, case=resolve(at_temperature(cfg, T)))) for T in temps]


def run(cfg, args) -> Outcome:
    from ..simulation.simulator import Simulator
    factor = slow_motion(args)
    out = prepare_out(args.out, [*stroke_files("stroke"),
                                 *figures("hand_force", "hand_force_temperatures")])
    sim = Simulator(resolve(cfg), cached=True)
    res = sim.run(trajectory=out is not None)
    payload = res.to_json()
    payload["integrator"] = res.method
    hf = None
    if res.ok:                           # the hand force and the zones (SPEC §13)
        from ..simulation.handforce import hand_force
        hf = hand_force(sim.model, case=sim.case)
        payload.update({k: v for k, v in hf.metrics().items() if k != "opening_force"})
    by_temperature = _hand_forces(cfg, sim) if res.ok else []
    if by_temperature:                   # at each sign-off temperature (SPEC §12, §13)
        payload["temperatures"] = [dict(h.metrics(), temperature_c=T)
                                   for T, h in by_temperature]
    if not res.ok:
        payload["error"] = res.message
        from ..simulation.stroke import StrokeStatus
        code = 2 if res.status is StrokeStatus.OUT_OF_RANGE else 3   # an invalid design
        return Outcome(payload, format_metrics(payload), code, error=res.message)
    files = []
    if out is not None:
        from .files import write_stroke_outputs
        files = write_stroke_outputs(sim.model, res, out, slow_motion=factor)
        from .common import save_figure
        from ..present.figures.handforce import plot_hand_force, plot_hand_force_by_temperature
        files.append(save_figure(plot_hand_force(hf), out / "hand_force.png"))
        if by_temperature:
            files.append(save_figure(plot_hand_force_by_temperature(by_temperature),
                                     out / "hand_force_temperatures.png"))
        payload["files"] = [str(f) for f in files]
    text = format_metrics(payload) + f"\n  hand force: {hf.describe()}"
    note = end_damper_note(cfg, res)
    if note:
        payload["end_damper"] = note
        text += f"\n  end damper: {note}"
    if res.message:
        payload["warning"] = res.message
        text += f"\n  {res.message}"
    return Outcome(payload, text + wrote(files), 0, tuple(files))
