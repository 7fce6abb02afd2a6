"""Command line (SPEC §7): ``softclose {state,simulate,optimise,sweep,bench}``.

Every command takes ``--config FILE``, repeatable ``--set section.key=value`` and
``--json``. Exit codes: 0 success, 2 invalid input (one line on stderr, no traceback),
3 a numerical or optimiser failure that was detected and reported.

A command handler is ``handler(cfg, args) -> Outcome``; the handlers of the heavier
commands live with their features and are imported only when that command runs.
"""

from __future__ import annotations

import argparse
import importlib
import json
import math
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

from .errors import ConfigError, SoftcloseError


@dataclass
class Outcome:
    """What a command reports: a JSON-able payload, its text form and an exit code."""

    payload: dict
    text: str
    exit_code: int = 0
    files: list = field(default_factory=list)


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, exit code 2
        raise ConfigError(f"{self.prog}: {message}")


def _common(p: argparse.ArgumentParser) -> None:
    p.add_argument("--config", metavar="FILE", help="TOML config file (SPEC §6)")
    p.add_argument("--set", dest="overrides", action="append", default=[],
                   metavar="SECTION.KEY=VALUE",
                   help="override one config key; the value is read as TOML (repeatable)")
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="softclose", description="Design soft-closing lids on a four-bar linkage.")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    sub.required = True

    p = sub.add_parser("state", help="kinematics, theta'' and pin reactions at one state")
    _common(p)
    p.add_argument("--theta-deg", type=float, required=True, help="lid angle theta (deg)")
    p.add_argument("--theta-dot", type=float, default=0.0, help="theta' (rad/s), default 0")

    p = sub.add_parser("simulate", help="one closing stroke: SPEC §4 metrics")
    _common(p)
    p.add_argument("--out", metavar="DIR", help="also write the trajectory CSV and figures")

    p = sub.add_parser("optimise", aliases=["optimize"],
                       help="soft-close design by multiple shooting + Ipopt")
    _common(p)
    p.add_argument("--out", metavar="DIR", help="also write the optimum's trajectory and figures")

    p = sub.add_parser("sweep", help="metrics over a grid of config values")
    _common(p)
    p.add_argument("--grid", action="append", default=[], required=True,
                   metavar="KEY=START:STOP:COUNT", help="one swept key (repeatable)")
    p.add_argument("--out", metavar="DIR", required=True, help="folder for sweep.csv and figures")

    p = sub.add_parser("bench", help="run time against error for every integrator and step")
    _common(p)
    p.add_argument("--out", metavar="DIR", help="folder for the tables and figures")
    p.add_argument("--quick", action="store_true", help="fewer steps and repeats")
    return parser


def _finite(x: Any) -> Any:
    """JSON-safe: NaN/inf -> None, numpy scalars -> Python."""
    if isinstance(x, dict):
        return {k: _finite(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_finite(v) for v in x]
    if hasattr(x, "item") and not isinstance(x, (list, dict)):
        try:
            x = x.item()
        except (ValueError, AttributeError):
            pass
    if isinstance(x, float) and not math.isfinite(x):
        return None
    return x


# -- handlers of the light commands --------------------------------------------------
def _state(cfg, args) -> Outcome:
    from .model import LidModel
    if not math.isfinite(args.theta_deg):
        raise ConfigError(f"--theta-deg: expected a finite angle, got {args.theta_deg}")
    if not math.isfinite(args.theta_dot):
        raise ConfigError(f"--theta-dot: expected a finite rate, got {args.theta_dot}")
    model = LidModel(cfg)
    theta = math.radians(args.theta_deg)
    th_release = cfg.stroke.theta0
    toggle = model.toggle_between(th_release, theta)
    if toggle is not None:  # the branch followed from the stroke does not reach theta
        raise ConfigError(f"--theta-deg: the loop cannot close at {args.theta_deg} deg on this "
                          f"branch (toggle position at {math.degrees(toggle):.3f} deg)")
    s = model.state(theta, args.theta_dot)
    lines = [f"theta      = {args.theta_deg:.6g} deg   theta' = {s['theta_dot']:.6g} rad/s",
             f"theta''    = {s['theta_ddot']:.8g} rad/s^2",
             f"phi        = {math.degrees(s['phi']):.6f} deg   gamma = {math.degrees(s['gamma']):.6f} deg",
             f"phi'       = {s['phi_dot']:.6g} rad/s   gamma' = {s['gamma_dot']:.6g} rad/s",
             f"tip v      = [{s['tip_velocity'][0]:.6g}, {s['tip_velocity'][1]:.6g}] m/s",
             "reactions (N): " + ", ".join(f"R_{k} = [{v[0]:.5g}, {v[1]:.5g}]"
                                            for k, v in s["reactions"].items())]
    return Outcome(s, "\n".join(lines))


def _simulate(cfg, args) -> Outcome:
    from .simulate import Simulator
    sim = Simulator(cfg)
    res = sim.run(trajectory=bool(args.out))
    payload = res.metrics()
    payload.update({"integrator": res.integrator, "step": res.step, "steps": res.steps,
                    "status": res.status, "accuracy": res.accuracy})
    if not res.ok:
        payload["error"] = res.message
        return Outcome(payload, f"error: {res.message}", 3)
    files = []
    if args.out:
        from .plots import write_stroke_outputs
        files = write_stroke_outputs(sim, res, Path(args.out))
        payload["files"] = [str(f) for f in files]
    text = format_metrics(payload)
    if res.message:
        payload["warning"] = res.message
        text += f"\n  {res.message}"
    if files:
        text += "\n  wrote " + ", ".join(str(f) for f in files)
    return Outcome(payload, text, 0, files)


def format_metrics(m: dict) -> str:
    """Human-readable SPEC §4 metrics (with accuracy where known)."""
    acc = m.get("accuracy") or {}

    def line(key, unit, scale=1.0, fmt=".7g"):
        v = m.get(key)
        if v is None:
            return f"  {key:<19} —"
        e = acc.get(key)
        err = f"  (± {e:.1e})" if e is not None else ""
        return f"  {key:<19} {v * scale:{fmt}} {unit}{err}"
    out = [f"  {'closed':<19} {'yes' if m.get('closed') else 'no'}",
           line("closing_time", "s"), line("impact_theta_dot", "rad/s"),
           line("impact_tip_speed", "m/s"), line("peak_tip_speed", "m/s"),
           line("min_spring_length", "m"), line("max_spring_length", "m"),
           line("holding_moment", "N m")]
    if "integrator" in m:
        out.append(f"  ({m['integrator']}, step {m['step']:g} s, {m['steps']} steps; "
                   "± = estimated distance from the converged answer)")
    return "\n".join(out)


def _lazy(module: str, name: str = "command") -> Callable:
    def handler(cfg, args):
        return getattr(importlib.import_module(f"softclose.{module}"), name)(cfg, args)
    return handler


HANDLERS: dict[str, Callable] = {
    "state": _state, "simulate": _simulate,
    "optimise": _lazy("optimise"), "optimize": _lazy("optimise"),
    "sweep": _lazy("sweep"), "bench": _lazy("bench"),
}


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    as_json = "--json" in argv
    try:
        args = build_parser().parse_args(argv)
        from .config import load_config
        cfg = load_config(args.config, args.overrides)
        outcome = HANDLERS[args.command](cfg, args)
    except SoftcloseError as exc:
        msg = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        if as_json:
            print(json.dumps({"error": msg, "exit_code": exc.exit_code}))
        print(f"softclose: error: {msg}", file=sys.stderr)
        return exc.exit_code
    except KeyboardInterrupt:
        print("softclose: interrupted", file=sys.stderr)
        return 130
    if args.json:
        print(json.dumps(_finite(outcome.payload)))
    else:
        print(outcome.text)
    return outcome.exit_code


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
