"""The linkage at one state (SPEC §7 ``state``): the crank angles and rates, theta'' from the
equation of motion, the tip velocity and the pin reactions (Newton-Euler); a hinge lid has
no cranks and one reaction, the hinge's."""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..errors import ConfigError
from ..jsonio import jsonable


@dataclass(frozen=True)
class LinkageState:
    """One state of the lid (SI units, radians): ``values`` is :meth:`LidModel.state`'s dict,
    ``hinge`` whether the lid hangs on a single hinge."""

    values: dict
    hinge: bool

    @property
    def success(self) -> bool:
        return True

    def to_json(self) -> dict:
        return jsonable(self.values)

    def text(self) -> str:
        """What ``softclose state`` prints: angles in degrees, rates, theta'', the tip
        velocity, the reactions."""
        s = self.values
        lines = [f"theta      = {math.degrees(s['theta']) + 0.0:.6g} deg   "
                 f"theta' = {s['theta_dot']:.6g} rad/s",
                 f"theta''    = {s['theta_ddot']:.8g} rad/s^2"]
        if not self.hinge:
            lines += [f"phi        = {math.degrees(s['phi']):.6f} deg   "
                      f"gamma = {math.degrees(s['gamma']):.6f} deg",
                      f"phi'       = {s['phi_dot']:.6g} rad/s   gamma' = {s['gamma_dot']:.6g} rad/s"]
        lines += [f"tip v      = [{s['tip_velocity'][0]:.6g}, {s['tip_velocity'][1]:.6g}] m/s",
                  ("hinge reaction (N): " if self.hinge else "reactions (N): ")
                  + ", ".join(f"R_{k} = [{v[0]:.5g}, {v[1]:.5g}]"
                              for k, v in s["reactions"].items())]
        return "\n".join(lines)

    def __repr__(self) -> str:
        return self.text()


def linkage_state(model, theta0: float, theta: float, theta_dot: float = 0.0,
                  p=None) -> LinkageState:
    """The state of ``model`` (a :class:`~softclose.model.lid.LidModel`) at ``theta`` and
    ``theta_dot`` on the branch followed from the release angle ``theta0`` (rad), with the
    parameters ``p`` (default the model's design); a ConfigError when that branch does not
    reach ``theta`` (a toggle position between)."""
    toggle = model.toggle_between(theta0, theta)
    if toggle is not None:  # the branch followed from the stroke does not reach theta
        raise ConfigError(f"--theta-deg: the loop cannot close at {math.degrees(theta):g} deg "
                          f"on this branch (toggle position at {math.degrees(toggle):.3f} deg)")
    return LinkageState(model.state(theta, theta_dot, p), model.lid.mechanism == "hinge")


__all__ = ["LinkageState", "linkage_state"]
