"""``softclose state --theta-deg X [--theta-dot Y]``: kinematics, theta'' and pin reactions."""

from __future__ import annotations

import math

from ..errors import ConfigError
from .common import Outcome, add_common
from ..problem import resolve


def register(sub) -> None:
    p = sub.add_parser("state", help="kinematics, theta'' and pin reactions at one state",
                       description="The linkage at one state (lid angle --theta-deg, rate "
                                   "--theta-dot): the crank angles phi and gamma and their "
                                   "rates, theta'' from the equation of motion, the tip "
                                   "velocity and the eight pin-reaction components (Newton-"
                                   "Euler), for the config's geometry, masses and design. "
                                   "SI units, angles in degrees in the text, radians in "
                                   "--json.")
    add_common(p)
    p.add_argument("--theta-deg", type=float, required=True, help="lid angle theta (deg)")
    p.add_argument("--theta-dot", type=float, default=0.0, help="theta' (rad/s), default 0")
    p.set_defaults(run=run)


def _no_negative_zero(v):
    """``v`` (numbers, lists, dicts of them) with -0.0 as 0.0: at rest the rates are zero, not
    "-0" (the text and the JSON print what the sign of a zero product happened to be)."""
    if isinstance(v, dict):
        return {k: _no_negative_zero(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return type(v)(_no_negative_zero(x) for x in v)
    if isinstance(v, float):
        return v + 0.0
    if hasattr(v, "dtype") and getattr(v, "dtype").kind == "f":
        return v + 0.0
    return v


def run(cfg, args) -> Outcome:
    from ..model.lid import LidModel
    if not math.isfinite(args.theta_deg):
        raise ConfigError(f"--theta-deg: expected a finite angle, got {args.theta_deg}")
    if not math.isfinite(args.theta_dot):
        raise ConfigError(f"--theta-dot: expected a finite rate, got {args.theta_dot}")
    if not abs(args.theta_deg) <= 360.0:   # the toggle scan's length grows with the angle
        raise ConfigError(f"--theta-deg: {args.theta_deg:g} deg is outside -360..360 deg")
    if not abs(args.theta_dot) <= 1e4:     # its square enters the reactions
        raise ConfigError(f"--theta-dot: {args.theta_dot:g} rad/s is outside -1e4..1e4 rad/s")
    model = LidModel(resolve(cfg))
    theta = math.radians(args.theta_deg)
    toggle = model.toggle_between(cfg.stroke.theta0, theta)
    if toggle is not None:  # the branch followed from the stroke does not reach theta
        raise ConfigError(f"--theta-deg: the loop cannot close at {args.theta_deg} deg on this "
                          f"branch (toggle position at {math.degrees(toggle):.3f} deg)")
    s = _no_negative_zero(model.state(theta, args.theta_dot))
    hinge = cfg.geometry.mechanism == "hinge"
    if hinge:       # no cranks: their angles are none, the one reaction is the hinge's (A's)
        s = dict(s, phi=None, gamma=None, phi_dot=None, gamma_dot=None,
                 reactions={"H": s["reactions"]["A"]})
    lines = [f"theta      = {args.theta_deg + 0.0:.6g} deg   theta' = {s['theta_dot']:.6g} rad/s",
             f"theta''    = {s['theta_ddot']:.8g} rad/s^2"]
    if not hinge:
        lines += [f"phi        = {math.degrees(s['phi']):.6f} deg   "
                  f"gamma = {math.degrees(s['gamma']):.6f} deg",
                  f"phi'       = {s['phi_dot']:.6g} rad/s   gamma' = {s['gamma_dot']:.6g} rad/s"]
    lines += [f"tip v      = [{s['tip_velocity'][0]:.6g}, {s['tip_velocity'][1]:.6g}] m/s",
              ("hinge reaction (N): " if hinge else "reactions (N): ")
              + ", ".join(f"R_{k} = [{v[0]:.5g}, {v[1]:.5g}]" for k, v in s["reactions"].items())]
    return Outcome(s, "\n".join(lines))
