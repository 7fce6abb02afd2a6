"""``softclose docs [TOPIC]``: the reference a pip install carries -- the commands, the design
problem and every config key with its default, unit and admissible range -- generated from
the same records the code runs on (docs/model.md in a clone of the repository says more)."""

from __future__ import annotations

import argparse
import textwrap

from .common import Outcome, add_common

TOPICS = ("overview", "keys", "problem", "files")

DESCRIPTION = f"""\
The installed reference, printed as text: TOPIC is one of {', '.join(TOPICS)} (default:
all of them). `keys`: every config key of every section with its default, unit, admissible
range and meaning; `problem`: the metrics of a stroke, the objective and the constraints;
`files`: the files the commands write; `overview`: the commands and how they fit together."""

WIDTH = 92


def register(sub) -> None:
    p = sub.add_parser("docs", help="the reference: commands, the design problem, every config "
                                    "key (default, unit, range)",
                       description=DESCRIPTION,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    add_common(p)
    p.add_argument("topic", nargs="?", choices=TOPICS, metavar="TOPIC",
                   help=f"one of {', '.join(TOPICS)} (default: all)")
    p.set_defaults(run=run)


def _wrap(text: str, indent: str = "  ") -> list[str]:
    return textwrap.wrap(text, WIDTH, initial_indent=indent, subsequent_indent=indent)


def overview() -> str:
    from . import build_parser
    parser = build_parser()
    sub = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)][0]
    lines = ["softclose: design soft-closing lids, on a four-bar linkage or a hinge", "",
             "commands (softclose COMMAND --help for each):"]
    seen = set()
    for choice in sub._choices_actions:
        if choice.dest in seen:
            continue
        seen.add(choice.dest)
        lines += textwrap.wrap(f"{choice.dest:<12} {choice.help}", WIDTH, initial_indent="  ",
                               subsequent_indent=" " * 15)
    lines += ["", "how they fit together:"]
    lines += _wrap("softclose optimise --out D finds the spring and damper and writes them as "
                   "D/design.toml: the whole config with the optimum as [design]. Every "
                   "command takes it with --config D/design.toml (softclose yield, "
                   "sensitivity, simulate ...). Without --config a command runs the defaults, "
                   "whose design has no spring and no damper (a lid that slams shut).")
    lines += _wrap("Every command takes --config FILE (TOML), --set SECTION.KEY=VALUE "
                   "(repeatable; the value is read as TOML) and --json (one JSON object on "
                   "stdout). Exit codes: 0 success, 2 invalid input (one line naming the "
                   "culprit), 3 a numerical or optimiser failure (reported, with what to "
                   "change), 130 interrupted.")
    return "\n".join(lines)


def keys() -> str:
    from ..config.docs import default_text, range_text
    from ..config.schema import DEFAULT_SPREADS, KEYS, SECTIONS, TOLERANCE_KEYS
    lines = ["config keys: a TOML file of sections; every key is optional (its default below)."]
    lines += _wrap("Set one on the command line with --set SECTION.KEY=VALUE, a vector "
                   "component with SECTION.KEY[i]=VALUE; `softclose optimise --out D` writes "
                   "D/design.toml, a whole config to start from.", "")

    def row(k):
        default = default_text(k).replace("`", "")
        head = f"{k.name} = {default}" + (f" {k.unit}" if k.unit and k.default is not None
                                          else "")
        out = _wrap(head, "  ")
        rng = range_text(k).replace("`", "")
        spread = f" (default tolerance ±{k.spread:.0%})" if k.spread else ""
        out += _wrap(f"{k.doc.replace('`', '')}{spread}; admissible: {rng}"
                     + (f" [{k.unit}]" if k.unit else ""), "      ")
        return out
    for section in SECTIONS:
        lines += ["", f"[{section}]"]
        for k in KEYS:
            if k.section == section:
                lines += row(k)
    lines += ["", "[tolerance]"]
    lines += _wrap("a key named like a config key carries a manufacturing spread: a plain "
                   "number is relative (nominal ± spread x |nominal|), {absolute = x} is in the "
                   "key's unit, 0 switches a default off. Defaults: "
                   + ", ".join(f'"{k}" = {v:g}' for k, v in DEFAULT_SPREADS.items()) + ".")
    for k in TOLERANCE_KEYS:
        lines += row(k)
    return "\n".join(lines)


def problem() -> str:
    from ..problem import CONSTRAINTS, METRICS, REASONS
    lines = _wrap("the closing stroke: the lid released from rest at stroke.theta0_deg falls "
                  "until theta reaches stroke.theta_closed_deg moving down (or stroke.t_max "
                  "passes).", "") + ["", "metrics of a stroke:"]
    for m in METRICS:
        lines += _wrap(f"{m.key:<19} [{m.unit or '-'}] {m.description}")
    lines += ["", "the design problem (softclose optimise):"]
    lines += _wrap("choose spring_k, spring_rest_length and damper_c within the bounds of "
                   "[optimise] to minimise J = weight_impact·impact_theta_dot² + "
                   "weight_peak_tip·peak_tip_speed². The weights carry the units s² and s²/m², "
                   "so J is dimensionless: with the defaults 1 s² and 0.1 s²/m², J = (impact "
                   "theta' / 1 rad/s)² + (peak tip speed / 3.16 m/s)².")
    lines += _wrap("subject to: " + ", ".join(CONSTRAINTS) + ". A design that breaks one is "
                   "labelled with the first of: " + ", ".join(REASONS) + ".")
    lines += _wrap("every optimum is re-simulated by the adaptive reference (CVODES): the "
                   "optimiser's J must agree with the reference's to 1e-3 (relative), every "
                   "constraint must hold in the reference's stroke.")
    return "\n".join(lines)


def files() -> str:
    rows = [("simulate --out D", "stroke_trajectory.csv (units in the header), stroke_time.png, "
             "stroke_linkage.png, stroke_animation.gif (slow motion: --slow-motion), "
             "hand_force.png, hand_force_temperatures.png (several operating.temperatures_c)"),
            ("optimise --out D", "design.toml (the whole config with the optimum as [design]; "
             "any command takes it with --config), optimise.json, optimum.png and the "
             "optimum's stroke files"),
            ("optimise --robust --out D", "design.toml (the robust design), robust.json, "
             "robust_histograms.png"),
            ("pareto --out D", "pareto.csv, pareto.png, designs/design_<i>.toml per point"),
            ("sweep --out D", "sweep.csv or sweep.parquet/, manifest.json, map_*.png or "
             "profile_*.png; with --optimise: optimal.csv, optimal.png, "
             "designs/design_<id>.toml"),
            ("yield --out D", "yield_samples.csv, yield_histograms.png (with several operating.temperatures_c: one pair per temperature, yield_samples_0C.csv, ...)"),
            ("sensitivity --out D", "sobol.csv, sobol.png"),
            ("select --out D", "select.csv (every pair, best first), select.json, select.png, pairs/NN_<spring>_<damper>.toml (the best ten pairs' configs)"),
            ("fit DATA --free KEY --out D", "calibrated.toml (the config with the fitted "
             "keys and a [tolerance] proposal; softclose optimise --robust --config "
             "D/calibrated.toml designs for it), fit.csv, samples.csv, fit.png"),
            ("spring --out D", "spring.json, spring_checks.csv, spring_candidates.csv, spring.png"),
            ("report --out D", "report.html (one self-contained page) and report.pdf "
             "(--format html|pdf|both)"),
            ("bench --out D", "work_precision.csv, speed.csv, optimiser.csv, bench.md, "
             "bench.json and figures")]
    lines = ["files the commands write (--out D is checked before any work):"]
    for cmd, what in rows:
        lines += _wrap(f"softclose {cmd}: {what}")
    return "\n".join(lines)


def run(cfg, args) -> Outcome:
    parts = {"overview": overview, "keys": keys, "problem": problem, "files": files}
    topics = [args.topic] if args.topic else list(TOPICS)
    text = "\n\n".join(parts[t]() for t in topics)
    return Outcome({"topics": topics, "text": text}, text)
