"""``softclose yield`` and ``softclose sensitivity``; the text of ``optimise --robust``.

``yield``: Monte Carlo yield of the config's design over the ``[tolerance]`` box;
``sensitivity``: Sobol indices of closing time and impact speed per toleranced key. Both
take ``--samples N``, ``--seed S``, ``--out DIR`` (figures and tables) and ``--json``.
:func:`format_robust` and :func:`robust_outcome` serve ``softclose optimise --robust``.
"""

from __future__ import annotations

import argparse
import math

from .common import (Outcome, add_common, add_out, figures, prepare_out, write_outputs,
                     wrote)
from ..files import write_text
from .text import closing_time_text, design_text, hand_limits_text, objective_text


YIELD = """\
The share of produced lids that meet every constraint when the config's design is made
with the [tolerance] spreads (springs ±10 %, dampers ±20 %, lid mass ±5 % by default): Monte
Carlo over the tolerance box, a 95 % Wilson interval, why the failing lids fail, percentiles
of closing time, impact and peak tip speed and J, and adaptive-reference checks of the worst
samples. The report states the design it analysed and its nominal lid. The default config's
design has no spring and no damper: to judge the optimum, run `softclose optimise --out D`,
then `softclose yield --config D/design.toml`."""

SENSITIVITY = """\
Variance-based (Sobol) sensitivity of closing time and impact speed to each toleranced key
of the config's design: first-order and total indices with 95 % bootstrap intervals
(SALib). The report states the design it analysed; keys with no spread at that design (a
relative spread of a zero spring) are left out and named. To analyse the optimum: `softclose
optimise --out D`, then `softclose sensitivity --config D/design.toml`."""


def register(sub) -> None:
    p = sub.add_parser("yield", help="Monte Carlo yield of the design under [tolerance]",
                       description=YIELD, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_common(p)
    add_out(p, what="write yield_samples.csv and yield_histograms.png to this folder")
    p.add_argument("--samples", type=int, metavar="N",
                   help="Monte Carlo samples (default: [tolerance] samples)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.set_defaults(run=run_yield)
    p = sub.add_parser("sensitivity",
                       help="Sobol indices of closing time and impact speed per toleranced key",
                       description=SENSITIVITY,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    add_common(p)
    add_out(p, what="write sobol.csv and sobol.png to this folder")
    p.add_argument("--samples", type=int, metavar="N", default=1024,
                   help="Sobol base samples N, a power of 2 (N (D + 2) strokes; default 1024)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.set_defaults(run=run_sensitivity)


def _check_samples(n, what="--samples"):
    from ..errors import ConfigError
    if n is not None and n < 1:
        raise ConfigError(f"{what} {n}: must be at least 1")
    if n is not None and n > 10_000_000:
        raise ConfigError(f"{what} {n}: more than 10^7 samples; use fewer")


def _seed(args):
    from ..errors import ConfigError
    if args.seed < 0:
        raise ConfigError(f"--seed {args.seed}: must be non-negative")
    return args.seed


def _pct(v, unit, digits=4) -> str:
    if v is None:
        return "—"
    if math.isinf(v):
        return "not closed"
    return f"{v:.{digits}g} {unit}".rstrip()


def nominal_text(n: dict) -> str:
    """The nominal lid of a yield or sensitivity report in one line: metrics, J, verdict."""
    if not n:
        return ""
    if not n.get("closed"):
        return ("nominal lid: does not close within stroke.t_max"
                + (f"; peak tip speed {n['peak_tip_speed']:.4g} m/s"
                   if n.get("peak_tip_speed") is not None else "")
                + f"; breaks: {n.get('reason') or 'not closed'}")
    verdict = ("meets every constraint" if n.get("feasible") else
               f"breaks a constraint: {n.get('reason')}")
    return (f"nominal lid: closes in {n['closing_time']:.4g} s, impact tip speed "
            f"{n['impact_tip_speed']:.4g} m/s (θ' {n['impact_theta_dot']:.4g} rad/s), peak "
            f"{n['peak_tip_speed']:.4g} m/s, holding moment {n['holding_moment']:.4g} N m; "
            f"J = {n['objective']:.6g}; {verdict}")


#: how to analyse the optimum instead of a design without spring or damper
TO_THE_OPTIMUM = ("to judge the optimum instead: softclose optimise --out D, then "
                  "softclose yield --config D/design.toml")


def format_yield(r, label: str = "design") -> list[str]:
    """Lines describing one yield estimate: the design, its nominal lid, the yield, why the
    failing samples fail, percentiles, the adaptive reference's checks."""
    lo, hi = r.yield_ci
    lines = [f"  {label}: {design_text(r.design)}"]
    if r.nominal:
        lines.append(f"    {nominal_text(r.nominal)}")
    for w in r.warnings:
        lines.append(f"    NOTE: {w}")
    lines.append(f"    yield {100 * r.yield_:.2f} % (95 % Wilson interval {100 * lo:.2f} – "
                 f"{100 * hi:.2f} %) over {r.samples} samples; required "
                 f"{100 * r.required_yield:g} %: {'met' if r.meets_required else 'NOT met'}")
    if r.failures:
        lines.append("    failing samples: " + ", ".join(
            f"{k} {v}" for k, v in sorted(r.failures.items(), key=lambda kv: -kv[1])))
    p = r.percentiles
    lines.append("    percentiles (closing time over every sample, a lid that did not close "
                 "counting as the slowest; the others over the samples that closed):")
    rows = (("closing time", "closing_time", "s"), ("impact θ'", "impact_theta_dot", "rad/s"),
            ("impact tip", "impact_tip_speed", "m/s"), ("peak tip", "peak_tip_speed", "m/s"),
            ("J", "objective", ""))
    for name, key, unit in rows:
        if key not in p:
            continue
        q = p[key]
        lines.append(f"      {name:<13} p1 {_pct(q['p1'], unit)}, p50 {_pct(q['p50'], unit)}, "
                     f"p99 {_pct(q['p99'], unit)}")
    for c in r.reference:
        if "error" in c:
            lines.append(f"    adaptive reference at the {c['label']}: failed ({c['error']})")
            continue
        agree = "agrees" if c.get("verdicts_agree") else "DISAGREES"
        diff = c.get("differences", {})
        dct = f", closing time differs by {diff['closing_time']:.1e} s" if "closing_time" in diff \
            else ""
        lines.append(f"    adaptive reference at the {c['label']}: "
                     f"{'feasible' if c['ok'] else 'infeasible'}, {agree} with the kernel{dct}")
    return lines


def _source(args) -> str:
    """Where the analysed design comes from, as the report says it."""
    where = f"from {args.config}" if getattr(args, "config", None) else "the defaults"
    if any(o.split("=", 1)[0].strip().startswith("design.")
           for o in getattr(args, "overrides", ()) or ()):
        where += " with --set"
    return f"design ({where})"


def _box_line(box: dict) -> str:
    parts = []
    for k, b in box.items():
        zero = " (of 0: no spread)" if b["relative"] and b.get("nominal") == 0 else ""
        parts.append(f"{k} ±{100 * b['spread']:.3g} %{zero}" if b["relative"] else
                     f"{k} ±{b['spread']:g}")
    return ", ".join(parts)


def run_yield(cfg, args) -> Outcome:
    from ..robust import tolerance_analysis
    from ..problem import sign_off_temperatures
    _check_samples(args.samples)
    seed = _seed(args)
    out = prepare_out(args.out, ["yield_samples.csv", *figures("yield_histograms")])
    if not cfg.tolerance.spreads:
        from ..errors import ConfigError
        raise ConfigError("tolerance: no key has a spread; give at least one "
                          "(e.g. --set tolerance.design.spring_k=0.1)")
    if len(sign_off_temperatures(cfg)) > 1:
        return _yield_by_temperature(cfg, args, seed, out)
    r = tolerance_analysis(cfg, samples=args.samples, seed=seed)
    payload = r.to_json()
    lines = [f"softclose yield: tolerance box {_box_line(r.box)} ({r.distribution})"]
    lines += format_yield(r, _source(args))
    if r.warnings:
        lines.append(f"  {TO_THE_OPTIMUM}")
    if r.message:
        lines.append(f"  note: {r.message}")
    files = []
    if out is not None:
        files = write_outputs(out, "yield_samples.csv", r.to_frame(),
                              "yield_histograms.png", r.plot)
        payload["files"] = [str(f) for f in files]
    code = 0 if r.success else 3
    return Outcome(payload, "\n".join(lines) + wrote(files), code, tuple(files),
                   error=None if r.success else r.message)


def _yield_by_temperature(cfg, args, seed, out) -> Outcome:
    """``softclose yield`` over several sign-off temperatures (operating.temperatures_c):
    each temperature's yield (the same samples) and the joint one."""
    from ..robust import yield_by_temperature
    t = yield_by_temperature(cfg, samples=args.samples, seed=seed)
    first = t.results[0]
    payload = t.to_json()
    payload.update(design=first.design, box=first.box, distribution=first.distribution,
                   seed=first.seed)
    lines = [f"softclose yield: tolerance box {_box_line(first.box)} ({first.distribution}), "
             f"at {', '.join(f'{T:g}' for T in t.temperatures)} °C, the same samples at each"]
    for T, r in zip(t.temperatures, t.results):
        lines.append(f"  at {T:g} °C:")
        lines += ["  " + x for x in format_yield(r, _source(args))]
    lo, hi = t.yield_ci
    lines.append(f"  at every temperature: yield {100 * t.yield_:.2f} % (95 % Wilson interval "
                 f"{100 * lo:.2f} – {100 * hi:.2f} %) of {t.samples} samples; required "
                 f"{100 * t.required_yield:g} %: {'met' if t.meets_required else 'NOT met'}; "
                 f"lowest at {t.limiting:g} °C")
    files = []
    if out is not None:
        for T, r in zip(t.temperatures, t.results):
            files += write_outputs(out, f"yield_samples_{T:g}C.csv", r.to_frame(),
                                   f"yield_histograms_{T:g}C.png", r.plot)
        payload["files"] = [str(f) for f in files]
    message = (f"the yield at every temperature is {100 * t.yield_:.2f} %, below the "
               f"required {100 * t.required_yield:g} % (lowest at {t.limiting:g} °C)")
    payload["success"] = t.meets_required
    payload["message"] = "" if t.meets_required else message
    return Outcome(payload, "\n".join(lines) + wrote(files), 0 if t.meets_required else 3,
                   tuple(files), error=None if t.meets_required else message)


def run_sensitivity(cfg, args) -> Outcome:
    from ..robust import sensitivity
    _check_samples(args.samples)
    seed = _seed(args)
    out = prepare_out(args.out, ["sobol.csv", *figures("sobol")])
    r = sensitivity(cfg, samples=args.samples, seed=seed)
    payload = r.to_json()
    lines = [f"softclose sensitivity: Sobol indices over the tolerance box "
             f"({r.distribution}; N = {r.base_samples}, {r.evaluations} strokes)",
             f"  {_source(args)}: {design_text(r.design)}"]
    if r.nominal:
        lines.append(f"    {nominal_text(r.nominal)}")
    for w in r.warnings:
        lines.append(f"    NOTE: {w}")
    if r.fixed:
        lines.append(f"  left out (no spread at this design): {', '.join(r.fixed)}")
    for name, idx in r.indices.items():
        lines.append(f"  {name}:  {'key':<22} {'S1':>14} {'ST':>14}")
        for k in r.keys:
            lines.append(f"  {'':<{len(name) + 1}} {k:<22} {idx['S1'][k]:>7.3f} ± "
                         f"{idx['S1_conf'][k]:<5.3f} {idx['ST'][k]:>7.3f} ± "
                         f"{idx['ST_conf'][k]:.3f}")
    lines.append(f"  (± : 95 % bootstrap interval) not closed: {r.not_closed} of {r.evaluations}"
                 + (" — counted as closing at stroke.t_max with impact θ' = 0" if r.not_closed
                    else ""))
    if r.warnings:
        lines.append(f"  {TO_THE_OPTIMUM.replace('softclose yield', 'softclose sensitivity')}")
    files = []
    if out is not None:
        files = write_outputs(out, "sobol.csv", r.to_frame(), "sobol.png", r.plot)
        payload["files"] = [str(f) for f in files]
    return Outcome(payload, "\n".join(lines) + wrote(files), 0, tuple(files))


def format_robust(res) -> str:
    """Human-readable report of a robust optimisation (``softclose optimise --robust``)."""
    head = "robust design found and verified" if res.success else "NO verified robust design"
    lines = [f"softclose optimise --robust: {head} (Ipopt: {res.status})"]
    if res.message:
        lines.append(f"  {res.message}")
    pr = res.problem
    lines.append(f"  problem: minimise the {res.robust_objective} scenario's "
                 f"{objective_text(pr)}, every scenario: {closing_time_text(pr)}, holding "
                 f"moment >= {pr['holding_moment_min']:g} N m{hand_limits_text(pr)}, no "
                 "rebound")
    lines.append(f"  tolerance box: {_box_line(res.box)}"
                 + (f" (widened x{res.box_scale:.3g})" if res.box_scale != 1 else ""))
    if res.design:
        lines.append(f"  robust design: {design_text(res.design)}"
                     + (f" ({res.kind} spring)" if getattr(res, "kind", None) else ""))
        if getattr(res, "part", None) is not None:
            lines.append("  to buy: " + res.part.text().replace("\n", "\n  "))
        lines.append(f"  {res.robust_objective}-case objective J = {res.objective:.6g}")
    if res.scenarios:
        lines.append(f"  scenarios ({len(res.scenarios)}; closing time and J from the NLP, "
                     "reference = adaptive re-simulation):")
        for s in res.scenarios:
            ref = s.get("reference") or {}
            rt = ref.get("closing_time")
            ok = {True: "holds", False: "FAILS", None: "not verified"}[s.get("verified")]
            mark = "  <- worst" if s.get("worst") else ""
            lines.append(f"    {s['label']:<48} T = {s['metrics']['closing_time']:.5f} s"
                         f" (ref {rt:.5f})" if rt is not None else
                         f"    {s['label']:<48} T = {s['metrics']['closing_time']:.5f} s")
            lines[-1] += f", J = {s['objective']:.5g}, {ok}{mark}"
    if res.active:
        lines.append(f"  what limits the design (dJ: change of the {res.robust_objective}-case J "
                     "per unit relaxation, from Ipopt's multipliers):")
        for a in res.active:
            where = ""
            if a.scenarios:
                where = (f"; holds in {len(a.scenarios)} of {len(res.scenarios)} scenarios: "
                         + "; ".join(a.scenarios))
            lines.append(f"    {a.describe(res.objective)}{where}")
    elif res.design:
        lines.append("  no bound or constraint is active: an interior robust optimum")
    cc = res.corner_check
    if cc:
        lines.append(f"  corner check (the kernel at every corner of the box): {cc['corners']} "
                     f"corners, {cc['in_nlp']} of them scenarios of the NLP; "
                     f"{len(cc['breaking'])} outside the NLP break a constraint")
    temps = tuple(getattr(res, "temperatures", ()) or ())
    ref = getattr(getattr(res.config, "operating", None), "reference_temperature_c", None)
    if temps and temps != (ref,):
        lim = res.limiting_temperature_c
        by_T = {t["temperature_c"]: t["worst_margin"] for t in (cc or {}).get("temperatures", ())}
        lines.append("  sign-off temperatures (every scenario at each; the design's values at "
                     f"{ref:g} °C): " + ", ".join(
                         f"{T:g} °C" + (f" (smallest corner margin {by_T[T]:.3g})"
                                        if by_T.get(T) is not None else "") for T in temps))
        if lim is not None:
            lines.append(f"  limiting temperature: {lim:g} °C (its corner is the closest of "
                         "all to breaking a constraint)")
    if res.yield_result is not None:
        lines.append("  Monte Carlo, both designs on the same samples:")
        lines += ["  " + x for x in format_yield(res.yield_result, "robust design")]
        if res.nominal_yield is not None:
            lines += ["  " + x for x in format_yield(res.nominal_yield, "nominal optimum")]
    if res.infeasibility:
        inf = res.infeasibility
        if inf.get("feasible_spreads"):
            lines.append("  spreads a robust design can meet: " + ", ".join(
                f"{k} {v:.3g}" for k, v in inf["feasible_spreads"].items()))
    for r in res.rounds:
        s = r.get("search")
        extra = ""
        if s:
            extra = (f"; interior search: {s['violating']} of {s['samples']} samples violating"
                     + (f", added {', '.join(s['added'])}" if s["added"] else ""))
        lines.append(f"  solve with {r['scenarios']} scenarios: {r['status']}, "
                     f"{r['iterations']} iterations, {r['solve_time']:.2f} s{extra}")
    for n in res.notes:
        lines.append(f"  note: {n}")
    lines.append(f"  (total {res.times.get('total', 0.0):.2f} s)")
    return "\n".join(lines)


def robust_outcome(cfg, args) -> Outcome:
    """``softclose optimise --robust [--json] [--out DIR]``: 0 verified robust design meeting
    the required yield, 3 otherwise (the reason on stderr)."""
    import json

    from ..robust import optimise_robust
    out = prepare_out(getattr(args, "out", None))
    from .common import interactive
    res = optimise_robust(cfg, progress=interactive(args))
    payload = res.to_json()
    files = []
    if out is not None:
        from .common import save_figure as save
        from ..jsonio import jsonable
        from .common import DESIGN_FILE, metrics_line, write_design
        if res.design is not None:
            y = res.yield_result
            files.append(write_design(
                out / DESIGN_FILE, res.design_config(),
                "the robust design of `softclose optimise --robust`"
                + ("" if res.success else " (NOT verified: see robust.json)"),
                [f"nominal lid, verified by the adaptive reference: "
                 f"{metrics_line(res.metrics, None)}",
                 f"{res.robust_objective}-case J over the tolerance box = {res.objective:.7g}",
                 f"yield {100 * y.yield_:.2f} % (95 % interval {100 * y.yield_ci[0]:.2f} – "
                 f"{100 * y.yield_ci[1]:.2f} %) over {y.samples} samples"
                 if y is not None else ""]))
        path = out / "robust.json"
        write_text(path, json.dumps(jsonable(payload), indent=1, allow_nan=False))
        files.append(path)
        if res.yield_result is not None:
            files.append(save(res.plot(), out / "robust_histograms.png"))
        if res.design and any("[" in k for k in res.design):   # the chosen attachment points
            from ..optimiser.cache import get_model
            from ..present.figures.attachment import plot_attachments
            files.append(save(plot_attachments(get_model(res.design_config()),
                                               res.design_config()),
                              out / "attachments.png"))
        payload["files"] = [str(f) for f in files]
    return Outcome(payload, format_robust(res) + wrote(files), 0 if res.success else 3,
                   tuple(files), error=None if res.success else res.message)
