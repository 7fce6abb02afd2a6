"""``softclose yield`` and ``softclose sensitivity``; the text of ``optimise --robust``.

``yield``: Monte Carlo yield of the config's design over the ``[tolerance]`` box;
``sensitivity``: Sobol indices of closing time and impact speed per toleranced key. Both
take ``--samples N``, ``--seed S``, ``--out DIR`` (figures and tables) and ``--json``.
:func:`format_robust` and :func:`robust_outcome` serve ``softclose optimise --robust``.
"""

from __future__ import annotations

import math

from .common import Outcome, add_common, add_out, prepare_out, write_outputs, wrote


def register(sub) -> None:
    p = sub.add_parser("yield", help="Monte Carlo yield of the design under [tolerance]")
    add_common(p)
    add_out(p, what="write yield_samples.csv and yield_histograms.png to this folder")
    p.add_argument("--samples", type=int, metavar="N",
                   help="Monte Carlo samples (default: [tolerance] samples)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.set_defaults(run=run_yield)
    p = sub.add_parser("sensitivity",
                       help="Sobol indices of closing time and impact speed per toleranced key")
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
    return f"{v:.{digits}g} {unit}"


def format_yield(r, label: str = "design") -> list[str]:
    """Lines describing one yield estimate."""
    lo, hi = r.yield_ci
    d = r.design
    lines = [f"  {label}: spring_k = {d['spring_k']:.6g} N/m, spring_rest_length = "
             f"{d['spring_rest_length']:.6g} m, damper_c = {d['damper_c']:.6g} N s/m",
             f"    yield {100 * r.yield_:.2f} % (95 % Wilson interval {100 * lo:.2f} – "
             f"{100 * hi:.2f} %) over {r.samples} samples; required "
             f"{100 * r.required_yield:g} %: {'met' if r.meets_required else 'NOT met'}"]
    if r.failures:
        lines.append("    failing samples: " + ", ".join(
            f"{k} {v}" for k, v in sorted(r.failures.items(), key=lambda kv: -kv[1])))
    p = r.percentiles
    ct, it, vt = p["closing_time"], p["impact_theta_dot"], p["impact_tip_speed"]
    lines.append(f"    closing time  p1 {_pct(ct['p1'], 's')}, p50 {_pct(ct['p50'], 's')}, "
                 f"p99 {_pct(ct['p99'], 's')}")
    lines.append(f"    impact θ'     p1 {_pct(it['p1'], 'rad/s')}, p50 {_pct(it['p50'], 'rad/s')}"
                 f", p99 {_pct(it['p99'], 'rad/s')} (closed samples)")
    lines.append(f"    impact tip    p1 {_pct(vt['p1'], 'm/s')}, p50 {_pct(vt['p50'], 'm/s')}, "
                 f"p99 {_pct(vt['p99'], 'm/s')}")
    for c in r.reference:
        if "error" in c:
            lines.append(f"    reference at {c['label']}: failed ({c['error']})")
            continue
        agree = "agrees" if c.get("verdicts_agree") else "DISAGREES"
        diff = c.get("differences", {})
        dct = f", closing time differs by {diff['closing_time']:.1e} s" if "closing_time" in diff \
            else ""
        lines.append(f"    adaptive reference at the {c['label']}: "
                     f"{'feasible' if c['ok'] else 'infeasible'}, {agree} with the kernel{dct}")
    return lines


def _box_line(box: dict) -> str:
    parts = []
    for k, b in box.items():
        parts.append(f"{k} ±{100 * b['spread']:.3g} %" if b["relative"] else
                     f"{k} ±{b['spread']:g}")
    return ", ".join(parts)


def run_yield(cfg, args) -> Outcome:
    from ..robust import tolerance_analysis
    _check_samples(args.samples)
    seed = _seed(args)
    out = prepare_out(args.out)
    if not cfg.tolerance.spreads:
        from ..errors import ConfigError
        raise ConfigError("tolerance: no key has a spread; give at least one "
                          "(e.g. --set tolerance.design.spring_k=0.1)")
    r = tolerance_analysis(cfg, samples=args.samples, seed=seed)
    payload = r.to_json()
    lines = [f"softclose yield: tolerance box {_box_line(r.box)} ({r.distribution})"]
    lines += format_yield(r)
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


def run_sensitivity(cfg, args) -> Outcome:
    from ..robust import sensitivity
    _check_samples(args.samples)
    seed = _seed(args)
    out = prepare_out(args.out)
    r = sensitivity(cfg, samples=args.samples, seed=seed)
    payload = r.to_json()
    d = r.design
    lines = [f"softclose sensitivity: Sobol indices over the tolerance box "
             f"({r.distribution}; N = {r.base_samples}, {r.evaluations} strokes)",
             f"  design: spring_k = {d['spring_k']:.6g} N/m, spring_rest_length = "
             f"{d['spring_rest_length']:.6g} m, damper_c = {d['damper_c']:.6g} N s/m"]
    for name, idx in r.indices.items():
        lines.append(f"  {name}:  {'key':<22} {'S1':>14} {'ST':>14}")
        for k in r.keys:
            lines.append(f"  {'':<{len(name) + 1}} {k:<22} {idx['S1'][k]:>7.3f} ± "
                         f"{idx['S1_conf'][k]:<5.3f} {idx['ST'][k]:>7.3f} ± "
                         f"{idx['ST_conf'][k]:.3f}")
    lines.append(f"  (± : 95 % bootstrap interval) not closed: {r.not_closed} of {r.evaluations}"
                 + (" — counted as closing at stroke.t_max with impact θ' = 0" if r.not_closed
                    else ""))
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
    lines.append(f"  problem: minimise the {res.robust_objective} scenario's J = "
                 f"{pr['weight_impact']:g}·impact_theta_dot² + {pr['weight_peak_tip']:g}·"
                 f"peak_tip_speed², every scenario closing in [{pr['closing_time_min']:g}, "
                 f"{pr['closing_time_max']:g}] s, holding moment >= "
                 f"{pr['holding_moment_min']:g} N m, no rebound")
    lines.append(f"  tolerance box: {_box_line(res.box)}"
                 + (f" (widened x{res.box_scale:.3g})" if res.box_scale != 1 else ""))
    if res.design:
        d = res.design
        lines.append(f"  robust design: spring_k = {d['spring_k']:.6g} N/m, spring_rest_length ="
                     f" {d['spring_rest_length']:.6g} m, damper_c = {d['damper_c']:.6g} N s/m"
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
    cc = res.corner_check
    if cc:
        lines.append(f"  corner check (the kernel at every corner of the box): {cc['corners']} "
                     f"corners, {cc['in_nlp']} of them scenarios of the NLP; "
                     f"{len(cc['breaking'])} outside the NLP break a constraint")
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
        path = out / "robust.json"
        path.write_text(json.dumps(jsonable(payload), indent=1, allow_nan=False))
        files.append(path)
        if res.yield_result is not None:
            files.append(save(res.plot(), out / "robust_histograms.png"))
        payload["files"] = [str(f) for f in files]
    return Outcome(payload, format_robust(res) + wrote(files), 0 if res.success else 3,
                   tuple(files), error=None if res.success else res.message)
