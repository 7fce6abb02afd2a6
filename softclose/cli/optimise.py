"""``softclose optimise`` (alias ``optimize``) and ``softclose pareto``.

optimise: the verified soft-close design (exit 0), or a reported failure (exit 3) --
infeasible problem, solver failure, or an answer the adaptive reference does not confirm.
``--robust`` designs for the ``[tolerance]`` box instead. pareto: the verified front of the
objective against closing_time_max (exit 3 when a point is not verified).
"""

from __future__ import annotations

import argparse
import math

from ..errors import ConfigError
from ..files import write_text
from .common import (DESIGN_FILE, figures, stroke_files, Outcome, add_common, add_out,
                     add_slow_motion, interactive,
                     metrics_line, prepare_out, slow_motion, write_design, write_outputs,
                     wrote)
from .text import closing_time_text, design_text, hand_limits_text, objective_text
from ..problem import resolve

#: the default closing times of ``pareto`` (s)
PARETO_DEFAULT = "0.3:3:10:log"


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
    files = []
    if out is not None and res.design is not None:
        files = write_optimum(res, out, factor)
        payload["files"] = [str(f) for f in files]
    text = format_result(res) + wrote(files)
    return Outcome(payload, text, 0 if res.success else 3, tuple(files),
                   None if res.success else (res.message or f"no optimum ({res.status})"))


def _run_robust(cfg, args, out) -> Outcome:
    """``optimise --robust``: the robust command's own outcome (text, files) when it is
    installed; else the robust result printed as JSON."""
    try:
        from .robust import robust_outcome
    except ImportError:
        robust_outcome = None
    if robust_outcome is not None:
        return robust_outcome(cfg, args)
    from ..jsonio import dumps
    from ..robust import optimise_robust
    res = optimise_robust(cfg, progress=interactive(args))
    payload = res.to_json()
    try:
        from .robust import format_robust
        text = format_robust(res)
    except ImportError:
        text = dumps(payload, indent=1)
    files = []
    if out is not None:
        path = out / "robust.json"
        write_text(path, dumps(payload, indent=1))
        files.append(path)
        payload["files"] = [str(path)]
    ok = bool(getattr(res, "success", False))
    return Outcome(payload, text + wrote(files), 0 if ok else 3, tuple(files),
                   None if ok else (getattr(res, "message", "") or "no robust design"))


def write_optimum(res, out, slow_motion=None) -> list:
    """The optimum as a config file (``design.toml``), ``optimise.json``, its figure and its
    stroke (trajectory CSV, figures, animation)."""
    from .common import save_figure as save
    from ..jsonio import dumps
    from ..simulation.simulator import Simulator
    from .files import write_stroke_outputs
    files = [write_design(out / DESIGN_FILE, res.design_config(),
                          "the optimum of `softclose optimise`"
                          + ("" if res.success else " (NOT verified: see optimise.json)"),
                          [f"verified by the adaptive reference: "
                           f"{metrics_line(res.metrics, res.verified_objective)}"
                           if res.verification is not None else ""])]
    sim = Simulator(resolve(res.design_config()))   # its model carries the design
    stroke = sim.run(trajectory=True)
    files.append(out / "optimise.json")
    write_text(files[-1], dumps(res.to_json(), indent=1))
    files.append(save(res.plot(), out / "optimum.png"))
    cfg = res.design_config()
    if any("[" in k for k in res.design) or cfg.optimise.keep_out:   # where it attaches
        from ..optimiser.cache import get_model
        from ..present.figures.attachment import plot_attachments
        files.append(save(plot_attachments(get_model(cfg), cfg), out / "attachments.png"))
    files += write_stroke_outputs(sim.model, stroke, out, stem="optimum",
                                  slow_motion=slow_motion)
    return files


def _v(x, fmt=".9g") -> str:
    if x is None:
        return "—"
    if isinstance(x, bool):
        return "yes" if x else "no"
    return format(x, fmt)


def format_result(res) -> str:
    """The optimisation as text: verdict, problem, design, objective, the verified metrics
    beside the optimiser's own, constraints, active limits, starts, notes."""
    from ..problem import ENGAGE_KEYS, METRIC_KEYS, UNITS, VERIFY_RTOL
    head = ("optimum found and verified" if res.success else
            "optimum found, NOT verified" if res.verification is None and res.design else
            "NO verified optimum")
    lines = [f"softclose optimise: {head} (Ipopt: {res.status})"]
    if res.message:
        lines.append(f"  {res.message}")
    pr = res.problem
    if pr:
        lines.append(f"  problem: {objective_text(pr)}, {closing_time_text(pr)}, holding "
                     f"moment >= {pr['holding_moment_min']:g} N m{hand_limits_text(pr)}")
    if res.design:
        lines.append("  design: " + design_text(res.design)
                     + (f" ({res.kind} spring)" if getattr(res, "kind", None) else ""))
        part = getattr(res, "part", None)
        if part is not None:
            lines.append("  to buy: " + part.text().replace("\n", "\n  "))
    ver = res.verification
    if res.objective is not None:
        s = (f"  objective J = {res.objective:.8g} (the optimiser's: its own discretisation "
             "of the stroke, at the design above)")
        if ver is not None and ver.objective is not None:
            rel = ((res.objective - ver.objective) / abs(ver.objective) if ver.objective
                   else math.inf)
            s += (f"; the reference's J = {ver.objective:.8g} (relative difference {rel:.1e}, "
                  f"allowed {VERIFY_RTOL:g})")
        lines.append(s)
    if res.optimiser:
        agr = ver.agreement if ver is not None else {}
        lines.append(f"  {'metric':<19} {'verified':>15} {'optimiser':>15} {'difference':>11} "
                     f"{'allowed':>9}  unit   (verified = adaptive reference, CVODES)")
        engage = tuple(k for k in ENGAGE_KEYS if res.optimiser.get(k) is not None
                       or (res.metrics or {}).get(k) is not None)
        for k in METRIC_KEYS + engage:
            a = agr.get(k, {})
            vv = res.metrics.get(k) if res.metrics else None
            diff = a.get("difference")
            flag = "" if a.get("ok", True) else "  <-- DISAGREES"
            lines.append(f"  {k:<19} {_v(vv):>15} {_v(res.optimiser.get(k)):>15} "
                         f"{_v(diff, '.2e') if diff is not None else '':>11} "
                         f"{_v(a.get('tolerance'), '.1e') if a.get('tolerance') else '':>9}  "
                         f"{UNITS[k]}{flag}")
    if ver is not None and ver.constraints:
        bad = [k for k, c in ver.constraints.items() if not c["ok"]]
        lines.append("  constraints in the reference simulation: " +
                     ("all hold" if not bad else "VIOLATED: " + ", ".join(bad)))
    if res.active:
        lines.append("  what limits the design (dJ: change of J per unit relaxation, from "
                     "Ipopt's multipliers):")
        for a in res.active:
            lines.append(f"    {a.describe(res.objective)}")
    elif res.design:
        lines.append("  no bound or constraint is active: an interior optimum")
    if res.starts:
        Js = [st["objective"] for st in res.starts if st.get("objective") is not None]
        moved = res.objective is not None and Js and \
            abs(min(Js) - res.objective) > 1e-9 * abs(res.objective)
        lines.append(f"  starts ({len(res.starts)}, from a coarse sweep of the design box"
                     + ("; each J as its solve ended, before the best answer was refined and "
                        "its closing-time bound corrected (notes), which moves J to the "
                        "objective above" if moved else "") + "):")
        for i, s in enumerate(res.starts, 1):
            st = s["start"]
            J = f"{s['objective']:.8g}" if s.get("objective") is not None else "—"
            lines.append(f"    {i}. from k={st['spring_k']:.4g}, "
                         f"l0={st['spring_rest_length']:.4g}, c={st['damper_c']:.4g}: "
                         f"{s['status']}, {s['iterations']} it, {s['solve_time']:.3f} s, J = {J}")
    for n in res.notes:
        lines.append(f"  note: {n}")
    grid = (f"{res.nodes} shooting intervals x {res.substeps} RK4 sub-steps" if not
            getattr(res, "substeps_engaged", None) else
            f"two phases switched at the end damper's engagement: {res.nodes} shooting "
            f"intervals x {res.substeps} RK4 sub-steps before it, {res.nodes} x "
            f"{res.substeps_engaged} after it")
    lines.append(f"  ({grid}, {res.hessian} Hessian; total {res.total_time:.2f} s)")
    return "\n".join(lines)


# -- pareto --------------------------------------------------------------------------------
def parse_closing_times(text: str):
    """``START:STOP:COUNT`` (linear) or ``START:STOP:COUNT:log`` -> array of closing times."""
    import numpy as np
    from ..optimiser.pareto import MAX_POINTS
    parts = str(text).split(":")
    bad = f"--closing-times {text}: "
    if len(parts) not in (3, 4) or (len(parts) == 4 and parts[3] != "log"):
        raise ConfigError(bad + "expected START:STOP:COUNT or START:STOP:COUNT:log")
    try:
        a, b = float(parts[0]), float(parts[1])
        n = int(parts[2])
    except ValueError:
        raise ConfigError(bad + "START and STOP must be numbers (s), COUNT a whole number") \
            from None
    if not (math.isfinite(a) and math.isfinite(b) and 0 < a <= b):
        raise ConfigError(bad + "expected 0 < START <= STOP (finite, in s)")
    if not 1 <= n <= MAX_POINTS:
        raise ConfigError(bad + f"COUNT must lie in 1..{MAX_POINTS}, got {n}")
    if a == b and n > 1:
        raise ConfigError(bad + "START equals STOP: use COUNT 1")
    return np.geomspace(a, b, n) if len(parts) == 4 else np.linspace(a, b, n)


def default_closing_times(cfg) -> str:
    """:data:`PARETO_DEFAULT` scaled to the config's closing-time window: its ends times
    optimise.closing_time_max (in s), the first above 1.05 x closing_time_min (the
    default config's: unchanged)."""
    a, b, n, kind = PARETO_DEFAULT.split(":")
    o = cfg.optimise
    lo = max(float(a) * o.closing_time_max, 1.05 * o.closing_time_min)
    hi = max(float(b) * o.closing_time_max, lo)
    return f"{lo:.6g}:{hi:.6g}:{n if hi > lo else 1}:{kind}"


def run_pareto(cfg, args) -> Outcome:
    out = prepare_out(args.out, ["pareto.csv", *figures("pareto"), "designs/"])
    times = parse_closing_times(args.closing_times or default_closing_times(cfg))
    from ..optimiser import front
    fr = front(cfg, times, progress=interactive(args))
    payload = fr.to_json()
    files = []
    if out is not None:
        designs = write_front_designs(fr, out)
        frame = fr.to_frame()
        frame["design_file"] = [str(designs[i].relative_to(out)) if i in designs else ""
                                for i in range(len(fr.points))]
        files = write_outputs(out, "pareto.csv", frame, "pareto.png", fr.plot)
        files += list(designs.values())
        payload["files"] = [str(f) for f in files]
        for i, pt in enumerate(payload["points"]):
            pt["design_file"] = str(designs[i]) if i in designs else None
    text = format_front(fr) + wrote(files)
    return Outcome(payload, text, 0 if fr.success else 3, tuple(files),
                   None if fr.success else fr.message)


def write_front_designs(fr, out) -> dict:
    """Each point of the front with a design as ``out/designs/design_<i>.toml`` (its config:
    closing_time_max the point's); {point index: path}."""
    folder = out / "designs"
    paths = {}
    for i, (t, p) in enumerate(zip(fr.closing_times, fr.points)):
        if p.design is None or p.config is None:
            continue
        folder.mkdir(exist_ok=True)
        paths[i] = write_design(
            folder / f"design_{i:02d}.toml", p.design_config(),
            f"point {i} of `softclose pareto`: the optimum for closing_time_max = {t:g} s"
            + ("" if p.success else " (NOT verified)"),
            [f"verified by the adaptive reference: "
             f"{metrics_line(p.metrics, p.verified_objective)}"
             if p.verification is not None else ""])
    return paths


def format_front(fr) -> str:
    head = "every point verified" if fr.success else "NOT every point verified"
    lines = [f"softclose pareto: {len(fr.points)} points, {head} ({fr.total_time:.2f} s)",
             f"  {'T_max [s]':>9} {'k [N/m]':>9} {'l0 [m]':>8} {'c [N s/m]':>9} {'J':>10} "
             f"{'impact [m/s]':>12} {'peak [m/s]':>10} {'verified':>8}  active"]
    for t, p in zip(fr.closing_times, fr.points):
        if p.design is None:
            lines.append(f"  {t:9.4g}  no optimum: {p.message}")
            continue
        m = p.metrics or {}
        act = ", ".join(f"{a.name} ({a.bound})" for a in p.active)
        lines.append(f"  {t:9.4g} {p.design['spring_k']:9.1f} "
                     f"{p.design['spring_rest_length']:8.5f} {p.design['damper_c']:9.1f} "
                     f"{p.objective:10.6g} {_v(m.get('impact_tip_speed'), '12.5f'):>12} "
                     f"{_v(m.get('peak_tip_speed'), '10.5f'):>10} "
                     f"{'yes' if p.success else 'NO':>8}  {act}")
    lines.append("  (speeds: the adaptive reference's simulation of each optimum; "
                 "J: the optimiser's, agreeing with the reference's to 1e-3; designs rounded "
                 "for the table: --out DIR writes each with every digit as "
                 "DIR/designs/design_<i>.toml)")
    if fr.message:
        lines.append(f"  {fr.message}")
    return "\n".join(lines)
