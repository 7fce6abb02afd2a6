"""The optimiser's results as text (what ``softclose optimise`` and ``softclose pareto``
print): a design with its units, the objective with its weights, the closing-time window
as solved, the optimum with its verification, the front."""

from __future__ import annotations

import math

from ..present.display import num


def design_text(d: dict) -> str:
    """A design as the reports quote it, every variable with its unit: 7 significant digits
    (enough to reproduce the default optimum within its active limits; the design file has
    every digit)."""
    from ..problem import UNITS
    unit = {k: UNITS.get(k) or ("m" if "[" in k else "") for k in d}   # (a point: m)
    return ", ".join(f"{k} = {v:.7g}" + (f" {unit[k]}" if unit[k] else "")
                     for k, v in d.items())


def objective_text(pr: dict) -> str:
    """J with its weights and their units: J is dimensionless (the weights are the inverse
    squares of a reference rate and a reference speed)."""
    wi, wp = pr["weight_impact"], pr["weight_peak_tip"]
    return (f"J = {wi:g} s²·impact_theta_dot² + {wp:g} s²/m²·peak_tip_speed² "
            "(dimensionless)")


def hand_limits_text(pr: dict) -> str:
    """The hand-force limits of the problem when set (", opening effort <= F N, closes by
    itself up to A deg"), else ""."""
    parts = []
    if pr.get("opening_force_max") is not None:
        parts.append(f"opening effort <= {pr['opening_force_max']:g} N")
    if pr.get("self_close_min_deg") is not None:
        parts.append(f"closes by itself up to {pr['self_close_min_deg']:g} deg")
    return "".join(", " + t for t in parts)


def closing_time_text(pr: dict) -> str:
    """The closing-time window of the problem, and the window the NLP solved when that
    differs (closing_time_min raised to the NLP's floor, a limit corrected for the NLP's own
    discretisation error or clamped to stroke.t_max)."""
    lo, hi = pr["closing_time_min"], pr["closing_time_max"]
    text = f"{lo:g} s <= closing_time <= {hi:g} s"
    solved = pr.get("closing_time_solved")
    if not solved or (solved[0] == lo and solved[1] == hi):
        return text
    from .nlp import T_FLOOR
    why = []
    if solved[0] != lo:
        why.append("closing_time_min raised to the NLP's floor of "
                   f"{T_FLOOR * 1e3:g} ms" if solved[0] == max(lo, T_FLOOR) else
                   "closing_time_min corrected for the NLP's discretisation error")
    if solved[1] != hi:
        why.append("closing_time_max corrected for the NLP's discretisation error (note)"
                   if solved[1] < hi and pr.get("t_max", math.inf) >= hi else
                   "closing_time_max clamped to stroke.t_max")
    return text + f" (solved as [{solved[0]:.9g}, {solved[1]:.9g}] s: {'; '.join(why)})"


def _v(x) -> str:
    """A metric in the verification table: yes/no (``closed``), else nine digits."""
    return num(x) if isinstance(x, bool) else num(x, spec=".9g")


def optimum_text(res) -> str:
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
            lines.append(f"  {k:<19} {_v(vv):>15} "
                         f"{_v(res.optimiser.get(k)):>15} "
                         f"{num(diff, spec='.2e') if diff is not None else '':>11} "
                         f"{num(a.get('tolerance'), spec='.1e') if a.get('tolerance') else '':>9}  "
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


def front_text(fr) -> str:
    """The Pareto front as text: one row per closing_time_max, the verdict, the notes."""
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
                     f"{p.objective:10.6g} {num(m.get('impact_tip_speed'), spec='12.5f'):>12} "
                     f"{num(m.get('peak_tip_speed'), spec='10.5f'):>10} "
                     f"{'yes' if p.success else 'NO':>8}  {act}")
    lines.append("  (speeds: the adaptive reference's simulation of each optimum; "
                 "J: the optimiser's, agreeing with the reference's to 1e-3; designs rounded "
                 "for the table: --out DIR writes each with every digit as "
                 "DIR/designs/design_<i>.toml)")
    if fr.message:
        lines.append(f"  {fr.message}")
    return "\n".join(lines)


def metrics_line(m: dict | None, J: float | None) -> str:
    """The metrics a design file's header quotes (one line)."""
    if not m or not m.get("closed"):
        return "does not close" if m else ""
    return (f"closes in {m['closing_time']:.7g} s, impact tip speed "
            f"{m['impact_tip_speed']:.4g} m/s, peak tip speed {m['peak_tip_speed']:.4g} m/s, "
            f"holding moment {m['holding_moment']:.7g} N m"
            + (f", the end damper engages at {m['engage_time']:.7g} s at theta' = "
               f"{m['engage_theta_dot']:.5g} rad/s" if m.get("engage_time") is not None
               else "")
            + (f"; J = {J:.7g}" if J is not None else ""))


__all__ = ["design_text", "objective_text", "hand_limits_text", "closing_time_text",
           "optimum_text", "front_text", "metrics_line"]
