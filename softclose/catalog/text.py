"""A catalog selection as text: what ``softclose select`` prints."""

from __future__ import annotations

from ..present.display import num


def _pair(e) -> str:
    return e["spring"] + (f" + {e['damper']}" if e["damper"] else
                          f" + dashpot c = {e['design']['damper_c']:.4g} N s/m")


def select_text(r, top: int = 15) -> str:
    """What ``softclose select`` prints: the screen, the ranking (its ``top`` pairs), the
    best pair with its parts, its damping and placement, the reference's verdict."""
    lines = [f"softclose select: {r.evaluated} of {r.pairs} pairs screened over their tolerance "
             f"boxes ({r.corners} corners, {r.samples} samples) in {r.seconds:.2f} s; the "
             f"best {r.verified_count} checked at every corner by the adaptive reference"]
    sc = r.screening
    if sc and sc.get("method") == "corners first":
        lines.append(f"  corners first: {sc['decided_by_corners']} pairs decided by their corners "
                     f"({sc['met_every_corner']} meet every one, {sc['failed_every_corner']} "
                     f"fail every one), {sc['sampled']} sampled ({sc['sample_rows_run']} of "
                     f"{sc['sample_rows_every']} sample strokes run)")
    if r.continuous:
        lines.append("  no damper catalog: the dashpot's c chosen per spring within "
                     "optimise.damper_c, made to [tolerance] design.damper_c")
    for w in r.warnings[:10]:
        lines.append(f"  warning: {w}")
    if len(r.warnings) > 10:
        lines.append(f"  ... {len(r.warnings) - 10} more rows left out")
    feas = sum(1 for e in r.ranking if e["feasible"])
    lines.append(f"  {feas} of {len(r.ranking)} pairs meet every constraint at every corner")
    lines.append(f"  {'#':>3} {'pair':<34} {'corners':>8} {'yield':>8} {'worst J':>10} "
                 f"{'verified':>9}  why not")
    for i, e in enumerate(r.ranking[:top], 1):
        ver = {None: "—", True: "yes", False: "DIFFERS"}[e["verified"]]
        lines.append(f"  {i:>3} {_pair(e)[:34]:<34} {e['corners_feasible']:>3}/{e['corners']:<4}"
                     f" {100 * e['yield']:>7.2f}% {num(e['worst_objective'], spec='.5g'):>10} "
                     f"{ver:>9}  {e['reason']}")
    if len(r.ranking) > top:
        lines.append(f"  ... {len(r.ranking) - top} more (--out DIR writes every pair)")
    b = r.best
    if b is not None:
        d = b["design"]
        part = (f"gas strut, F1 {d['spring_preload']:.4g} N, extended length "
                f"{1e3 * d['spring_rest_length']:.4g} mm, stroke {1e3 * d['strut_stroke']:.4g} "
                f"mm, progression {d['strut_progression']:.4g}, friction band "
                f"{2 * d['strut_friction']:.4g} N" if d["spring_kind"] == "gas_strut" else
                f"{d['spring_kind']} spring, rate {d['spring_k']:.6g} N/m, free length "
                f"{1e3 * d['spring_rest_length']:.4g} mm, preload {d['spring_preload']:.4g} N")
        lines.append(f"  best: {_pair(b)}: {part}"
                     + (f"; nominal lid closes in {b['nominal']['closing_time']:.4g} s"
                        if b["nominal"].get("closing_time") == b["nominal"].get("closing_time")
                        else ""))
        if b.get("nlp"):
            n = b["nlp"]
            lines.append("  its c by the robust NLP (the spring fixed, over its box): "
                         + (f"{n['c']:.6g} N s/m, worst-scenario J {n['objective']:.6g}"
                            if n["c"] is not None else f"no solution ({n['message']})")
                         + f"; the grid's {n['c_grid']:.6g} N s/m; kept the "
                         + ("NLP's" if n["kept"] == "nlp" else "grid's"))
        pl = b.get("placement")
        if pl:
            pts = ", ".join(f"{k.removeprefix('geometry.')} = {1e3 * v:.2f} mm"
                            for k, v in (pl["values"] or {}).items())
            lines.append("  mounted at " + (
                f"{pts} (its points by the robust co-design, worst-scenario J "
                f"{pl['objective']:.6g}; screened and verified there)" if pl["kept"] == "placed"
                else "the config's points" + (f" ({pl['message']})" if pl["message"] else
                                              " (its own points ranked no better)")))
        ref = b.get("reference")
        if ref:
            lines.append(f"  adaptive reference at its {len(ref['corners'])} corners: "
                         + ("every constraint met" if ref["feasible"] else
                            f"FAILS ({ref['reason']})")
                         + (", the kernel's verdicts agree" if ref["agree"] else
                            f"; the kernel's verdict differs at {', '.join(ref['differ'])}")
                         + (f"; worst J {ref['worst_objective']:.6g}"
                            if ref["worst_objective"] not in (None, float("inf")) else ""))
    if r.message:
        lines.append(f"  note: {r.message}")
    t = r.times
    lines.append("  (" + ", ".join(f"{k} {v:.2f} s" for k, v in t.items()) + ")")
    return "\n".join(lines)


__all__ = ["select_text"]
