"""The robust design's results as text: what ``softclose yield``, ``softclose sensitivity``
and ``softclose optimise --robust`` print."""

from __future__ import annotations

import math

from ..optimiser.text import closing_time_text, design_text, hand_limits_text, objective_text


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


def yield_lines(r, label: str = "design") -> list[str]:
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


def box_line(box: dict) -> str:
    """The tolerance box in one line: each key with its spread."""
    parts = []
    for k, b in box.items():
        zero = " (of 0: no spread)" if b["relative"] and b.get("nominal") == 0 else ""
        parts.append(f"{k} ±{100 * b['spread']:.3g} %{zero}" if b["relative"] else
                     f"{k} ±{b['spread']:g}")
    return ", ".join(parts)


def yield_text(r, source: str = "design") -> str:
    """What ``softclose yield`` prints: the box, the design (``source``: where it comes
    from), its nominal lid, the yield, the failures, percentiles, the reference's checks."""
    lines = [f"softclose yield: tolerance box {box_line(r.box)} ({r.distribution})"]
    lines += yield_lines(r, source)
    if r.warnings:
        lines.append(f"  {TO_THE_OPTIMUM}")
    if r.message:
        lines.append(f"  note: {r.message}")
    return "\n".join(lines)


def yield_by_temperature_text(t, source: str = "design") -> str:
    """What ``softclose yield`` prints over several sign-off temperatures: each one's
    yield on the same samples and the joint one; ``source`` says where the design
    comes from."""
    first = t.results[0]
    from ..problem import condition_text
    lines = [f"softclose yield: tolerance box {box_line(first.box)} ({first.distribution}), "
             f"at {', '.join(condition_text(T) for T in t.temperatures)}, the same samples "
             "at each"]
    for T, r in zip(t.temperatures, t.results):
        lines.append(f"  at {condition_text(T)}:")
        lines += ["  " + x for x in yield_lines(r, source)]
    for st in t.state_yields():
        lines.append(f"  {st['state'].replace('_', ' ')}, at every temperature: yield "
                     f"{100 * st['yield']:.2f} %")
    lo, hi = t.yield_ci
    lines.append(f"  at every condition: yield {100 * t.yield_:.2f} % (95 % Wilson interval "
                 f"{100 * lo:.2f} – {100 * hi:.2f} %) of {t.samples} samples; required "
                 f"{100 * t.required_yield:g} %: {'met' if t.meets_required else 'NOT met'}; "
                 f"lowest at {condition_text(t.limiting)}")
    return "\n".join(lines)


def sensitivity_text(r, source: str = "design") -> str:
    """What ``softclose sensitivity`` prints: the Sobol indices with their intervals."""
    lines = [f"softclose sensitivity: Sobol indices over the tolerance box "
             f"({r.distribution}; N = {r.base_samples}, {r.evaluations} strokes)",
             f"  {source}: {design_text(r.design)}"]
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
    return "\n".join(lines)


def robust_text(res) -> str:
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
    lines.append(f"  tolerance box: {box_line(res.box)}"
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
    states = tuple(getattr(res, "states", ()) or ())
    if len(states) > 1:
        by_state = {}
        for t in (cc or {}).get("temperatures", ()):
            st = t.get("state", "new")
            w = t["worst_margin"]
            by_state[st] = w if st not in by_state else min(by_state[st], w)
        lines.append("  sign-off states (every scenario in each): " + ", ".join(
            st.replace("_", " ") + (f" (smallest corner margin {by_state[st]:.3g})"
                                    if by_state.get(st) is not None else "")
            for st in states))
        if res.limiting_state is not None:
            lines.append(f"  limiting state: {res.limiting_state.replace('_', ' ')}")
    if res.yield_result is not None:
        lines.append("  Monte Carlo, both designs on the same samples:")
        lines += ["  " + x for x in yield_lines(res.yield_result, "robust design")]
        if res.nominal_yield is not None:
            lines += ["  " + x for x in yield_lines(res.nominal_yield, "nominal optimum")]
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


__all__ = ["yield_text", "yield_by_temperature_text", "sensitivity_text", "robust_text",
           "yield_lines", "nominal_text", "box_line", "TO_THE_OPTIMUM"]
