"""A spring made to order as text: what ``softclose spring`` prints."""

from __future__ import annotations

from ..present.display import mm


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


def _format_extension(payload: dict, s: dict, life: str) -> list[str]:
    st, F = s["stresses"], s["forces"]
    return [
        f"extension spring {'checked' if payload['mode'] == 'check' else 'designed'}: "
        f"{s['material']}, d = {mm(s['wire_d'])}, D = {mm(s['coil_d'])} (outer "
        f"{mm(s['outer_d'])}, inner {mm(s['inner_d'])}), n = {s['active_coils']:g} active",
        f"  free length {mm(s['free_length'])} (body closed {mm(s['body_length'])}, "
        f"{mm(s['length_for_hooks'])} left for the hooks), works from "
        f"{mm(s['working_lengths'][0])} to {mm(s['working_lengths'][1])}",
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


def spring_text(payload: dict) -> str:
    """What ``softclose spring`` prints of a spring order's JSON: the spring, its stresses
    and life, its checks, the candidates, the verdict."""
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
        f"d = {mm(s['wire_d'])}, D = {mm(s['coil_d'])} (outer {mm(s['outer_d'])}, inner "
        f"{mm(s['inner_d'])}), n = {s['active_coils']:g} active of {s['total_coils']:g}, "
        f"ends {ends}",
        f"  free length {mm(s['free_length'])}, works from {mm(s['working_lengths'][0])} "
        f"to {mm(s['working_lengths'][1])}; solid length {mm(s['solid_length'])}, shortest "
        f"allowed {mm(s['min_working_length'])}",
        f"  rate {s['rate']:.5g} N/m (requested {s['rate_required']:.5g} N/m, "
        f"{s['rate_deviation']:+.2%}); forces F1 = {s['forces']['F1']:.4g} N, F2 = "
        f"{s['forces']['F2']:.4g} N, at solid length {s['forces']['Fc']:.4g} N",
        f"  stresses (MPa): tau_k1 = {_mpa(st['tau_k1'])}, tau_k2 = {_mpa(st['tau_k2'])}, "
        f"stroke tau_kh = {_mpa(st['tau_kh'])} (allowed {_mpa(st['tau_kh_allowed'])} for "
        f"{s['cycles']:.3g} strokes), solid tau_c = {_mpa(st['tau_c'])} (allowed "
        f"{_mpa(st['tau_c_allowed'])}); life {life}",
        "  buckling: " + (f"s_K = {mm(b['s_k'])} against s_2 = {mm(b['s_2'])}"
                           if b["s_k"] is not None else "cannot buckle")
        + f" (seating nu = {s['seating']:g}); natural frequency "
          f"{s['natural_frequency']:.4g} Hz; mass {s['mass'] * 1e3:.4g} g",
        f"  EN 15800 grade {tol['grade']}: free length ±{mm(tol['free_length'])}, F1 "
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


__all__ = ["spring_text"]
