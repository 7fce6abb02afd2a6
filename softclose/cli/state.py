"""``softclose state --theta-deg X [--theta-dot Y]``: kinematics, theta'' and pin reactions."""

from __future__ import annotations

import math

from ..errors import ConfigError
from .common import Outcome, add_common


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


def run(cfg, args) -> Outcome:
    if not math.isfinite(args.theta_deg):
        raise ConfigError(f"--theta-deg: expected a finite angle, got {args.theta_deg}")
    if not math.isfinite(args.theta_dot):
        raise ConfigError(f"--theta-dot: expected a finite rate, got {args.theta_dot}")
    if not abs(args.theta_deg) <= 360.0:   # the toggle scan's length grows with the angle
        raise ConfigError(f"--theta-deg: {args.theta_deg:g} deg is outside -360..360 deg")
    if not abs(args.theta_dot) <= 1e4:     # its square enters the reactions
        raise ConfigError(f"--theta-dot: {args.theta_dot:g} rad/s is outside -1e4..1e4 rad/s")
    from .. import state
    s = state(cfg, args.theta_deg, args.theta_dot)
    return Outcome(s.to_json(), s.text())
