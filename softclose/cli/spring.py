"""``softclose spring [--out DIR]``: the design's compression or extension spring made to order
(SPEC §14)."""

from __future__ import annotations

import argparse
import json

from .common import Outcome, add_common, add_out, figures, prepare_out, wrote
from ..files import write_text, write_with

DESCRIPTION = """\
The design's compression spring (design.spring_kind = "compression", EN 13906-1) or extension
spring ("extension", EN 13906-2: its body) as a part a spring maker can coil: wire, mean coil
diameter and active coils, checked for the lengths it works at as the lid turns between
stroke.theta_closed_deg and stroke.theta0_deg.

With spring.wire_d, spring.coil_d and spring.active_coils all given, that spring is checked;
otherwise one is designed: preferred EN 10270 wire diameters (or the spring.wire_d given),
mean coil diameters on a 0.1 mm grid within spring.max_outer_d / spring.min_inner_d (or the
spring.coil_d given), the active coils rounded to a quarter coil for design.spring_k, every
check met for spring.cycles strokes, the lightest first.

Checks: the rate within the quarter-coil rounding; the shortest working length keeps the
minimum coil gaps S_a; the stress at solid length tau_c <= 0.56 R_m; the stroke stress under
the wire's Goodman line at spring.cycles; buckling (seating spring.seating); the space; the
wire's temperatures. The EN 15800 tolerances are those of spring.grade.

An extension spring (free length design.spring_rest_length with the body closed, initial
tension design.spring_preload): the rate; the closed body (n + 1) d within the free length,
leaving at least 0.8 D_i for each hook; the initial tension stress within the preferred range
at its index; the stress at the largest working force tau_2 <= 0.45 R_m (EN 13906-2); the
body's stroke stress under the unpeened wire's Goodman line; the space; the temperatures.
It does not buckle. Its hooks are not covered (EN 13906-2 §11 and Annex A: ask the maker).

Exit 3 when the spring checked fails a check, or no spring meets them all (the nearest miss
is shown). With --out: spring.json, the checks (spring_checks.csv) and the candidates
(spring_candidates.csv), and spring.png: the force and the stress over the spring's length
with the working range and the limits."""


def register(sub) -> None:
    p = sub.add_parser("spring", help="the design's compression or extension spring made to "
                                      "order (EN 13906-1/-2 checks, EN 15800 tolerances)",
                       description=DESCRIPTION,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    add_common(p)
    add_out(p, what="also write spring.json, the checks and candidates as CSV and the "
                    "figure of the spring's force and stress over its length to this folder")
    p.set_defaults(run=run)


def _mm(x) -> str:
    return "—" if x is None else f"{x * 1e3:.4g} mm"


def _mpa(x) -> str:
    return f"{x / 1e6:.4g}"


def _check_line(c: dict) -> str:
    unit = c["unit"]
    scale, shown = {"m": (1e3, "mm"), "Pa": (1e-6, "MPa"), "1": (100.0, "%")}.get(
        unit, (1.0, unit))
    v = c["value"] * scale
    lim = "none" if c["limit"] is None else f"{c['limit'] * scale:.5g}"
    return (f"  {c['name']:<19} {v:>10.5g} {c['relation']:<2} {lim:<10} {shown:<4} "
            f"{'ok' if c['ok'] else 'FAILS'}")


def _failed(c: dict) -> str:
    """A failed check in words: 'buckling: 26.99 mm, limit < 13.62 mm'."""
    scale, shown = {"m": (1e3, "mm"), "Pa": (1e-6, "MPa"), "1": (100.0, "%")}.get(
        c["unit"], (1.0, c["unit"]))
    return (f"{c['name']}: {c['value'] * scale:.4g} {shown}, limit {c['relation']} "
            f"{c['limit'] * scale:.4g} {shown}")


def _format_extension(payload: dict, s: dict, life: str) -> list[str]:
    st, F = s["stresses"], s["forces"]
    return [
        f"extension spring {'checked' if payload['mode'] == 'check' else 'designed'}: "
        f"{s['material']}, d = {_mm(s['wire_d'])}, D = {_mm(s['coil_d'])} (outer "
        f"{_mm(s['outer_d'])}, inner {_mm(s['inner_d'])}), n = {s['active_coils']:g} active",
        f"  free length {_mm(s['free_length'])} (body closed {_mm(s['body_length'])}, "
        f"{_mm(s['length_for_hooks'])} left for the hooks), works from "
        f"{_mm(s['working_lengths'][0])} to {_mm(s['working_lengths'][1])}",
        f"  rate {s['rate']:.5g} N/m (requested {s['rate_required']:.5g} N/m, "
        f"{s['rate_deviation']:+.2%}); initial tension F0 = {F['F0']:.4g} N, forces F1 = "
        f"{F['F1']:.4g} N, F2 = {F['F2']:.4g} N",
        f"  stresses (MPa): initial tau_0 = {_mpa(st['tau_0'])} (at most "
        f"{_mpa(st['tau_0_allowed'])} at w = {s['index']:.3g}), tau_k1 = {_mpa(st['tau_k1'])}, "
        f"tau_k2 = {_mpa(st['tau_k2'])}, stroke tau_kh = {_mpa(st['tau_kh'])} (allowed "
        f"{_mpa(st['tau_kh_allowed'])} for {s['cycles']:.3g} strokes), at F2 tau_2 = "
        f"{_mpa(st['tau_2'])} (allowed 0.45 R_m = {_mpa(st['tau_2_allowed'])}); body life "
        f"{life}",
        f"  does not buckle; natural frequency {s['natural_frequency']:.4g} Hz; mass "
        f"{s['mass'] * 1e3:.4g} g (hooks as one coil each)",
        f"  {s['hooks']}",
        "checks (value, relation, limit):"]


def format_spring(payload: dict) -> str:
    """The text form of ``softclose spring``'s payload."""
    s = payload["spring"]
    if s is None:
        return f"  {payload['message']}"
    if s.get("kind") == "extension":
        return _format_rest(payload, _format_extension(payload, s, _life(s)))
    st, b, tol = s["stresses"], s["buckling"], s["tolerance"]
    ends = {"closed_ground": "closed and ground", "closed": "closed, not ground"}[s["ends"]]
    life = _life(s)
    lines = [
        f"spring {'checked' if payload['mode'] == 'check' else 'designed'}: {s['material']}, "
        f"d = {_mm(s['wire_d'])}, D = {_mm(s['coil_d'])} (outer {_mm(s['outer_d'])}, inner "
        f"{_mm(s['inner_d'])}), n = {s['active_coils']:g} active of {s['total_coils']:g}, "
        f"ends {ends}",
        f"  free length {_mm(s['free_length'])}, works from {_mm(s['working_lengths'][0])} "
        f"to {_mm(s['working_lengths'][1])}; solid length {_mm(s['solid_length'])}, shortest "
        f"allowed {_mm(s['min_working_length'])}",
        f"  rate {s['rate']:.5g} N/m (requested {s['rate_required']:.5g} N/m, "
        f"{s['rate_deviation']:+.2%}); forces F1 = {s['forces']['F1']:.4g} N, F2 = "
        f"{s['forces']['F2']:.4g} N, at solid length {s['forces']['Fc']:.4g} N",
        f"  stresses (MPa): tau_k1 = {_mpa(st['tau_k1'])}, tau_k2 = {_mpa(st['tau_k2'])}, "
        f"stroke tau_kh = {_mpa(st['tau_kh'])} (allowed {_mpa(st['tau_kh_allowed'])} for "
        f"{s['cycles']:.3g} strokes), solid tau_c = {_mpa(st['tau_c'])} (allowed "
        f"{_mpa(st['tau_c_allowed'])}); life {life}",
        f"  buckling: " + (f"s_K = {_mm(b['s_k'])} against s_2 = {_mm(b['s_2'])}"
                           if b["s_k"] is not None else "cannot buckle")
        + f" (seating nu = {s['seating']:g}); natural frequency "
          f"{s['natural_frequency']:.4g} Hz; mass {s['mass'] * 1e3:.4g} g",
        f"  EN 15800 grade {tol['grade']}: free length ±{_mm(tol['free_length'])}, F1 "
        f"±{tol['force']['F1']:.3g} N, F2 ±{tol['force']['F2']:.3g} N",
        "checks (value, relation, limit):"]
    return _format_rest(payload, lines)


def _life(s: dict) -> str:
    return ("10^7 strokes or more" if s["life"] >= 1e7 else
            "fewer than 10^3 strokes" if s["life"] < 1e3 else f"{s['life']:.3g} strokes")


def _format_rest(payload: dict, lines: list[str]) -> str:
    """The checks, the candidates and the message after the spring's lines."""
    lines = list(lines)
    lines += [_check_line(c) for c in payload["checks"]]
    cands = payload.get("candidates") or []
    if cands:
        lines.append("candidates (the lightest spring of each wire diameter, lightest first):")
        lines.append(f"  {'d mm':>6} {'D mm':>6} {'n':>6} {'rate N/m':>9} {'dev':>7} "
                     f"{'mass g':>8} {'outer mm':>8}")
        for c in cands[:10]:
            lines.append(f"  {c['wire_d'] * 1e3:>6.3g} {c['coil_d'] * 1e3:>6.4g} "
                         f"{c['active_coils']:>6g} {c['rate']:>9.5g} "
                         f"{c['rate_deviation']:>+7.2%} {c['mass'] * 1e3:>8.4g} "
                         f"{c['outer_d'] * 1e3:>8.4g}")
        if len(cands) > 10:
            lines.append(f"  ... {len(cands) - 10} more (--json, --out)")
    lines.append(f"  {payload['message']}")
    return "\n".join(lines)


def run(cfg, args) -> Outcome:
    from ..coil_spring import SpringCheck
    from ..jsonio import jsonable
    from ..optimiser.spring_order import spring_duty, spring_order
    out = prepare_out(args.out, ["spring.json", "spring_checks.csv", "spring_candidates.csv",
                                 *figures("spring")])
    duty = spring_duty(cfg)
    res = spring_order(cfg, duty)
    if isinstance(res, SpringCheck):
        payload = res.to_json()
        ok = res.ok
        message = ("the spring meets every check" if ok else
                   "the spring fails " + "; ".join(_failed(c) for c in payload["checks"]
                                                   if not c["ok"]))
        payload.update(mode="check", success=ok, message=message)
    else:
        payload = res.to_json()
        ok = res.success
        payload["mode"] = "design"
        if not ok and duty.kind == "extension":
            payload["message"] += (" (more room: spring.max_outer_d, spring.min_inner_d; "
                                   "fewer spring.cycles; a longer free length, a stiffer "
                                   "rate or a lower initial tension of the design)")
        elif not ok:
            payload["message"] += (" (more room: spring.max_outer_d, spring.min_inner_d; "
                                   "fewer spring.cycles; shot-peened wire; another free "
                                   "length or rate of the design)")
    payload["duty"] = duty.to_json()
    payload = jsonable(payload)
    files = []
    if out is not None:
        path = out / "spring.json"
        write_text(path, json.dumps(payload, indent=1, allow_nan=False) + "\n")
        files.append(path)
        best = res if isinstance(res, SpringCheck) else res.best
        if best is not None:
            write_with(out / "spring_checks.csv", lambda p: best.to_frame().to_csv(p, index=False))
            files.append(out / "spring_checks.csv")
        if not isinstance(res, SpringCheck):
            write_with(out / "spring_candidates.csv",
                       lambda p: res.to_frame().to_csv(p, index=False))
            files.append(out / "spring_candidates.csv")
        if best is not None:
            from .common import save_figure
            from ..present.figures.spring import plot_spring
            files.append(save_figure(plot_spring(best), out / "spring.png"))
        payload["files"] = [str(f) for f in files]
    text = format_spring(payload) + wrote(files)
    if ok:
        return Outcome(payload, text, 0, tuple(files))
    payload["exit_code"] = 3
    return Outcome(payload, text, 3, tuple(files), error=payload["message"])
