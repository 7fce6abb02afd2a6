"""One closing stroke's result, whichever integrator produced it.

:class:`StrokeStatus` names how a stroke ended (the values are the C kernel's status
codes); :class:`StrokeResult` holds its metrics (:data:`softclose.problem.METRICS`), how it
was computed, how accurate it is, and -- when asked for -- its trajectory. The fixed-step
:class:`softclose.simulation.simulator.Simulator` and the adaptive :class:`softclose.simulation.reference.Reference`
both return it, so a result can be compared with its verification field by field.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from enum import IntEnum

from ..present.display import Display, Displayed, Table, pm, with_unit
from ..problem import METRIC_KEYS, METRICS, UNITS
from ..jsonio import jsonable


class StrokeStatus(IntEnum):
    """How a stroke ended (values: the stroke kernel's status codes, 0 to 5; 6 is set in
    Python). The one table of the codes and their text."""

    CLOSED = 0
    NOT_CLOSED = 1
    UNSTABLE = 2
    LEFT_RANGE = 3
    NON_FINITE = 4
    IMPLICIT_FAILED = 5
    #: integrated to its end, but an element left its valid range (a spring past its free
    #: length): an invalid design, whose metrics are not reported as the stroke's
    OUT_OF_RANGE = 6

    @property
    def ok(self) -> bool:
        """True when the stroke was integrated to its end (closed or not)."""
        return self in (StrokeStatus.CLOSED, StrokeStatus.NOT_CLOSED)

    @property
    def text(self) -> str:
        return _TEXT[self]

    def __str__(self) -> str:
        return self.text


_TEXT = {StrokeStatus.CLOSED: "closed", StrokeStatus.NOT_CLOSED: "not closed",
         StrokeStatus.UNSTABLE: "unstable", StrokeStatus.LEFT_RANGE: "left the tabulated range",
         StrokeStatus.NON_FINITE: "non-finite",
         StrokeStatus.IMPLICIT_FAILED: "implicit solve failed",
         StrokeStatus.OUT_OF_RANGE: "invalid design"}
#: the statuses of a stroke the method could not integrate (a numerical failure)
NUMERICAL_FAILURES = (StrokeStatus.UNSTABLE, StrokeStatus.LEFT_RANGE, StrokeStatus.NON_FINITE,
                      StrokeStatus.IMPLICIT_FAILED)


@dataclass(frozen=True, repr=False)
class StrokeResult(Displayed):
    """The metrics of one stroke and how they were obtained.

    ``ok`` is False when the method could not integrate the stroke; ``message`` then says
    why and what to change (and otherwise carries a warning, if any). ``accuracy`` holds the
    estimated distance of each fixed-step metric from the converged answer (None for the
    adaptive reference, whose tolerance is ``tolerance``). ``reason`` says why a stroke that
    ran to its end did not close, when that is known.
    """

    closed: bool
    closing_time: float | None
    impact_theta_dot: float | None
    impact_tip_speed: float | None
    peak_tip_speed: float | None
    min_spring_length: float | None
    max_spring_length: float | None
    holding_moment: float
    status: StrokeStatus
    method: str
    step: float | None = None
    steps: int = 0
    tolerance: float | None = None
    message: str | None = None
    reason: str | None = None
    accuracy: dict | None = None
    theta_min: float | None = None
    theta_max: float | None = None
    theta_dot_max: float | None = None
    opening_force: float | None = None
    #: the angle the ``reason`` of a stroke that did not close names (rad): where friction
    #: holds the lid, the well that holds it open, the top of the barrier it cannot pass
    stop_theta: float | None = None
    #: with an end damper (``design.end_damper_c`` > 0): when the lid first reaches its
    #: engagement angle moving down (s) and theta' there (rad/s, the engagement speed); None
    #: when it has none or never gets there
    engage_time: float | None = None
    engage_theta_dot: float | None = None
    trajectory: dict | None = field(default=None, repr=False, compare=False)
    #: with ``hand_force=True`` (:func:`softclose.simulate`): the hand force and the lid's
    #: zones (:class:`softclose.simulation.handforce.HandForce`), at each sign-off
    #: temperature too when there are several (``((T, HandForce), ...)``), and what the end
    #: damper did when that is not a crossing on the way down
    hand_force: object | None = field(default=None, repr=False, compare=False)
    hand_forces: tuple = field(default=(), repr=False, compare=False)
    end_damper: str | None = None
    #: with ``trajectory=True`` (:func:`softclose.simulate`): the lid's model, which draws
    #: the linkage and the animation (:meth:`save`)
    model: object | None = field(default=None, repr=False, compare=False)
    #: with ``hand_force=True`` and ``[life]`` changing a part (SPEC §17): the stroke in each
    #: state, ``(("new", StrokeResult), ("end_of_life", StrokeResult))`` (this one among them)
    states: tuple = field(default=(), repr=False, compare=False)

    @property
    def ok(self) -> bool:
        return self.status.ok

    @property
    def success(self) -> bool:
        """The stroke was integrated (closed or not): the public API's success flag."""
        return self.ok

    @property
    def integrator(self) -> str:
        return self.method

    def metrics(self) -> dict:
        """The metrics as a dict (:data:`softclose.problem.METRIC_KEYS`)."""
        return {k: getattr(self, k) for k in METRIC_KEYS}

    def to_json(self) -> dict:
        """Plain JSON values: the metrics, then how they were computed (no trajectory)."""
        out = self.metrics()
        out.update({"status": self.status.text, "method": self.method, "step": self.step,
                    "steps": self.steps, "accuracy": self.accuracy})
        for k in ("tolerance", "message", "reason", "engage_time", "engage_theta_dot"):
            if getattr(self, k) is not None:
                out[k] = getattr(self, k)
        out["integrator"] = self.method
        if self.hand_force is not None:     # the hand force and the zones (SPEC §13)
            out.update({k: v for k, v in self.hand_force.metrics().items()
                        if k != "opening_force"})
        if self.hand_forces:                # at each sign-off temperature (SPEC §12, §13)
            out["temperatures"] = [dict(h.metrics(), temperature_c=T)
                                   for T, h in self.hand_forces]
        if self.states:                     # new and at the end of life (SPEC §17)
            out["states"] = [dict(r.metrics(), state=st, status=r.status.text,
                                  **({} if r.hand_force is None else {
                                      k: v for k, v in r.hand_force.metrics().items()
                                      if k != "opening_force"}),
                                  **({"error": r.message} if not r.ok else {}))
                             for st, r in self.states]
        if not self.ok:
            out["error"] = self.message
        else:
            if self.end_damper:
                out["end_damper"] = self.end_damper
            if self.message:
                out["warning"] = self.message
        return jsonable(out)

    def text(self) -> str:
        """What ``softclose simulate`` prints: the metrics with their accuracy, the hand
        force and what the end damper did (when asked for), a warning."""
        lines = [metrics_text(self.to_json())]
        if not self.ok:
            return lines[0]
        if self.hand_force is not None:
            lines.append(f"  hand force: {self.hand_force.describe()}")
        if self.end_damper:
            lines.append(f"  end damper: {self.end_damper}")
        for st, r in self.states:
            lines.append(f"  {st.replace('_', ' ')}: " + (
                (f"closes in {r.closing_time:.4g} s, impact tip speed "
                 f"{r.impact_tip_speed:.4g} m/s, peak {r.peak_tip_speed:.4g} m/s"
                 if r.closed else "does not close") +
                f", holding moment {r.holding_moment:.4g} N m" if r.ok else
                f"{r.status.text}: {r.message}"))
        if self.message:
            lines.append(f"  {self.message}")
        return "\n".join(lines)

    def to_frame(self):
        """One row (pandas DataFrame): the metrics and the status. With a trajectory, use
        :meth:`trajectory_frame` for the time histories."""
        import pandas as pd
        row = self.metrics()
        row["status"] = self.status.text
        for k in ("engage_time", "engage_theta_dot"):   # (as in the JSON: where it engages)
            if getattr(self, k) is not None:
                row[k] = getattr(self, k)
        return pd.DataFrame([row])

    def trajectory_frame(self):
        """The time histories (one row per step, from the release to the rim) as a pandas
        DataFrame, in SI: t (s), theta, phi, gamma (rad), theta_dot (rad/s), theta_ddot
        (rad/s^2), tip_speed (m/s), spring_length (m), energy (J). A result without a
        trajectory (``simulate(cfg)`` without ``trajectory=True``) raises ValueError."""
        import pandas as pd
        if self.trajectory is None:
            raise ValueError("this result has no trajectory: simulate(cfg, trajectory=True)")
        return pd.DataFrame(self.trajectory)

    def _display(self) -> Display:
        how = (f"{self.method}, step {self.step:g} s, {self.steps} steps" if self.step else
               f"{self.method}, tolerance {self.tolerance:g}" if self.tolerance else self.method)
        acc = self.accuracy or {}
        rows = [(m.key, pm(getattr(self, m.key), acc.get(m.key), m.unit) if m.key != "closed"
                 else ("yes" if self.closed else "no"), m.description) for m in METRICS]
        facts = [("status", self.status.text)]
        facts += [(k, with_unit(getattr(self, k), u)) for k, u in
                  (("closing_time", "s"), ("impact_tip_speed", "m/s"), ("peak_tip_speed", "m/s"))
                  if getattr(self, k) is not None]
        if self.engage_time is not None:
            facts.append(("end damper engages", f"at t = {self.engage_time:.6g} s, theta' = "
                          f"{self.engage_theta_dot:.6g} rad/s"))
        if self.reason:
            facts.append(("why not closed", self.reason))
        note = ("± is the estimated distance from the converged answer (Richardson at half "
                "the step, plus the table's interpolation error)") if acc else ""
        return Display(f"StrokeResult ({how})", self.ok,
                       self.message or "", tuple(facts),
                       (Table("metrics", ("metric", "value", "what"), rows, note),))

    def plot(self):
        """Time histories of the stroke (needs ``trajectory=True``): a matplotlib Figure."""
        from ..present.figures.stroke import plot_time_histories
        if self.trajectory is None:
            raise ValueError("this result has no trajectory: simulate(cfg, trajectory=True)")
        return plot_time_histories(self)

    def save(self, folder, slow_motion: float | None = None, figure_format: str = "png",
             figure_style: str | None = None) -> list:
        """The stroke in ``folder`` (what ``softclose simulate --out`` writes): its
        trajectory CSV, time histories, linkage drawing and animation (``slow_motion``: the
        GIF's factor), and the hand force (at each sign-off temperature too) when it was
        asked for; the paths. Needs ``softclose.simulate(cfg, trajectory=True)``."""
        from pathlib import Path

        from ..present.figures import save
        from .folder import write_stroke_outputs
        if self.trajectory is None or self.model is None:
            raise ValueError("this result has no trajectory: simulate(cfg, trajectory=True)")
        out = Path(folder)
        files = write_stroke_outputs(self.model, self, out, slow_motion=slow_motion,
                                     figure_format=figure_format, figure_style=figure_style)
        if self.hand_force is not None:
            from ..present.figures.handforce import (plot_hand_force,
                                                     plot_hand_force_by_temperature)
            files.append(save(plot_hand_force(self.hand_force),
                              out / f"hand_force.{figure_format}", figure_style))
            if self.hand_forces:
                files.append(save(plot_hand_force_by_temperature(self.hand_forces),
                                  out / f"hand_force_temperatures.{figure_format}",
                                  figure_style))
        return files


def metrics_text(m: dict) -> str:
    """A stroke's metrics (its JSON) as an aligned table, each with its accuracy where
    known, the end damper's engagement, why it did not close, how it was integrated."""
    acc = m.get("accuracy") or {}
    out = []
    for key in METRIC_KEYS:
        v = m.get(key)
        if key == "closed":
            out.append(f"  {key:<19} {'yes' if v else 'no'}")
        elif v is None:
            out.append(f"  {key:<19} —")
        else:
            e = acc.get(key)
            err = f"  (± {e:.1e})" if e is not None else ""
            out.append(f"  {key:<19} {v:.7g} {UNITS[key]}{err}")
    # the end damper's first engagement, where the lid reaches it (StrokeResult.engage_time)
    for key, unit in (("engage_time", "s"), ("engage_theta_dot", "rad/s")):
        if m.get(key) is not None:
            e = acc.get(key)
            err = f"  (± {e:.1e})" if e is not None else ""
            out.append(f"  {key:<19} {m[key]:.7g} {unit}{err}")
    if m.get("reason"):
        why = "invalid design" if m.get("status") == "invalid design" else "why not closed"
        out.append(f"  {why}: {m['reason']}")
    if "method" in m and m.get("step") is not None:
        out.append(f"  ({m['method']}, step {m['step']:g} s, {m['steps']} steps; "
                   "± = estimated distance from the converged answer)")
    return "\n".join(out)


def end_damper_note(res: StrokeResult, end_damper_c: float, angle_deg: float,
                    theta0_deg: float, theta_closed_deg: float) -> str | None:
    """What the end damper did when that is not a crossing on the way down (None without
    one): engaged from the release (its angle at or above theta0), never (at or below the
    rim), or not reached (the lid stays above it). An angle outside the stroke is not an
    error: it says where the damper acts."""
    if not end_damper_c:
        return None
    at = f"end_damper_angle_deg = {angle_deg:g}"
    if angle_deg <= theta_closed_deg:
        return (f"never acts: {at} is not above the rim (stroke.theta_closed_deg = "
                f"{theta_closed_deg:g})")
    if (res.engage_time is not None and res.engage_time < 1e-12
            and angle_deg >= theta0_deg):
        return (f"acts from the release: {at} is not below stroke.theta0_deg = "
                f"{theta0_deg:g}")
    if res.engage_time is None and res.theta_min is not None:
        return (f"never engaged: the lid stays above {at} (lowest angle "
                f"{math.degrees(res.theta_min):.2f} deg)")
    return None


def none_if_nan(x) -> float | None:
    """A float, or None for NaN/inf/None (how metrics of strokes that did not close read)."""
    if x is None:
        return None
    x = float(x)
    return x if math.isfinite(x) else None


__all__ = ["StrokeStatus", "StrokeResult", "none_if_nan"]
