"""``softclose optimise`` (alias ``optimize``) and ``softclose pareto``.

optimise: the verified soft-close design (exit 0), or a reported failure (exit 3) --
infeasible problem, solver failure, or an answer the adaptive reference does not confirm.
``--robust`` designs for the ``[tolerance]`` box instead. pareto: the verified front of the
objective against closing_time_max (exit 3 when a point is not verified).
"""

from __future__ import annotations

import argparse

from .common import (FIGURES, Outcome, add_common, add_out, add_slow_motion,
                     figures, interactive, prepare_out, saved, slow_motion, stroke_files, wrote)
from ..config.write import DESIGN_FILE
from ..problem import PARETO_DEFAULT


OPTIMISE = """\
The soft-close design: the spring (spring_k, spring_rest_length) and damper (damper_c)
within the [optimise] bounds that minimise
  J = weight_impact·impact_theta_dot² + weight_peak_tip·peak_tip_speed²
(weights in s² and s²/m²: J is dimensionless) while the lid closes within
[closing_time_min, closing_time_max], stays shut (holding_moment >= holding_moment_min) and
does not rebound. Direct multiple shooting (optimise.nodes x optimise.substeps RK4 steps)
solved by Ipopt from optimise.starts starts, then re-simulated by the adaptive reference
(CVODES): every reported metric is the reference's, the optimiser's own beside it. The
report names the bounds and constraints that limit the design, with dJ per unit relaxation.

--out D writes D/design.toml (the whole config with the optimum as [design]: give it to any
command with --config D/design.toml), optimise.json, figures and the optimum's stroke.
--robust designs for the [tolerance] box instead: the design that meets every constraint in
every scenario of the box (exit 3 when none can, saying which constraint and by how much)."""

PARETO = """\
The trade-off between a soft impact and a short closing time: the verified optimum for each
closing_time_max of --closing-times (each point solved from its neighbour, re-simulated by
the adaptive reference). --out D writes pareto.csv, pareto.png and each point's design as
D/designs/design_<i>.toml (a config every command takes with --config)."""


def register(sub) -> None:
    p = sub.add_parser("optimise", aliases=["optimize"],
                       help="soft-close design by multiple shooting + Ipopt, verified",
                       description=OPTIMISE,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    add_common(p)
    add_out(p, what="also write design.toml (the optimum as a config file), optimise.json, "
                    "figures and the optimum's stroke")
    p.add_argument("--robust", action="store_true",
                   help="design for the [tolerance] box (yield, scenarios) instead")
    p.add_argument("--free", action="append", default=[], metavar="KEY=LO:HI",
                   help="also choose this element parameter within [LO, HI], in its own "
                        "unit, e.g. design.spring_preload=0:200 (repeatable; the file's "
                        "[optimise.free])")
    add_slow_motion(p)
    p.set_defaults(run=run_optimise)
    q = sub.add_parser("pareto", help="verified front of the objective against closing_time_max",
                       description=PARETO,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    add_common(q)
    add_out(q, what="write pareto.csv, pareto.png and designs/design_<i>.toml to this folder")
    q.add_argument("--closing-times", default=None, metavar="START:STOP:COUNT[:log]",
                   help=f"closing_time_max values in s (default {PARETO_DEFAULT}: 10 "
                        "log-spaced values, times optimise.closing_time_max / 1 s and above "
                        "optimise.closing_time_min: a toilet seat's 5-8 s window gives "
                        "5.25:24:10:log)")
    q.set_defaults(run=run_pareto)


# -- optimise ------------------------------------------------------------------------------
def optimise_files() -> list[str]:
    """The files ``optimise --out`` writes."""
    return [DESIGN_FILE, "optimise.json", *figures("optimum", "attachments"),
            *stroke_files("optimum")]


def robust_files() -> list[str]:
    """The files ``optimise --robust --out`` writes."""
    return [DESIGN_FILE, "robust.json", *figures("robust_histograms", "attachments")]


def run_optimise(cfg, args) -> Outcome:
    factor = slow_motion(args)
    out = prepare_out(args.out, robust_files() if args.robust else optimise_files())
    if args.robust:
        return _run_robust(cfg, args, out)
    from ..optimiser import optimise
    res = optimise(cfg, progress=interactive(args))
    payload = res.to_json()
    files = saved(res, out if res.design is not None else None, payload, factor)
    text = res.text() + wrote(files)
    return Outcome(payload, text, 0 if res.success else 3, tuple(files),
                   None if res.success else (res.message or f"no optimum ({res.status})"))


def _run_robust(cfg, args, out) -> Outcome:
    """``optimise --robust``: the robust command's outcome (text, files)."""
    from .robust import robust_outcome
    return robust_outcome(cfg, args)


# -- pareto --------------------------------------------------------------------------------
def run_pareto(cfg, args) -> Outcome:
    out = prepare_out(args.out, ["pareto.csv", *figures("pareto"), "designs/"])
    from ..optimiser import front
    from ..optimiser.pareto import closing_times
    times = closing_times(cfg, args.closing_times)
    fr = front(cfg, times, progress=interactive(args))
    payload = fr.to_json()
    files = []
    if out is not None:
        designs = fr.save_designs(out)
        frame = fr.to_frame()
        frame["design_file"] = [str(designs[i].relative_to(out)) if i in designs else ""
                                for i in range(len(fr.points))]
        from ..present.figures import save_with_table
        files = save_with_table(out, "pareto.csv", frame, "pareto", fr.plot,
                                FIGURES["format"], FIGURES["style"])
        files += list(designs.values())
        payload["files"] = [str(f) for f in files]
        for i, pt in enumerate(payload["points"]):
            pt["design_file"] = str(designs[i]) if i in designs else None
    text = fr.text() + wrote(files)
    return Outcome(payload, text, 0 if fr.success else 3, tuple(files),
                   None if fr.success else fr.message)
