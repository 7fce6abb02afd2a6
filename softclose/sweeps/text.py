"""Sweeps as text: what ``softclose sweep`` prints of a sweep or a sample and of an
optimal design at every grid point."""

from __future__ import annotations

from ..present.display import num


def sweep_text(res, payload: dict, files, resume: str | None) -> str:
    """What ``softclose sweep`` prints: designs computed and feasible, the speed, the best
    feasible design, the best by word key, the files, how to resume. ``payload`` is the
    result's JSON with the run's ``stages`` (seconds)."""
    rate = payload["designs_per_second"] or 0.0
    kind = "sample" if res.kind == "sample" else "sweep"
    new = payload["stages"].get("evaluated", 0)
    speed = f"{new} evaluated at {rate:,.0f} designs/s" if new else "nothing left to evaluate"
    lines = [f"{kind} over {', '.join(res.keys)}: {res.computed} of {res.points} designs, "
             f"{res.feasible} feasible; {speed}, {payload['stages']['total']:.2f} s in all"]
    if res.reasons:
        lines.append("  infeasible: " + ", ".join(f"{k} {v}" for k, v in res.reasons.items()))
    b = res.best
    if b:
        lines.append(f"  best feasible (id {b['id']}): "
                     + ", ".join(f"{k} = {num(b[k], spec='.6g')}" for k in res.keys)
                     + f"; objective {b['objective']:.6g}, closing_time "
                       f"{b['closing_time']:.4f} s, impact {b['impact_theta_dot']:.4f} rad/s, "
                       f"peak tip {b['peak_tip_speed']:.4f} m/s")
    elif res.computed:
        lines.append("  no feasible design")
    lines += _best_per_word(res)
    lines += [f"  wrote {f}" for f in files]
    if resume:
        lines.append(f"  interrupted: the finished chunks are kept; resume with: {resume}")
    return "\n".join(lines)


def _best_per_word(res) -> list[str]:
    """For a swept word key (a spring's kind): the best feasible objective of each word --
    what each kind costs over the rest of the grid (rows held in memory only)."""
    import numpy as np

    from ..problem import WORD_PARAMS, word_text
    if res.columns is None:
        return []
    out = []
    feas = np.asarray(res.columns["feasible"], bool)
    J = np.asarray(res.columns["objective"], float)
    for k in res.keys:
        if k not in WORD_PARAMS:
            continue
        x = np.asarray(res.columns[k], float)
        parts = []
        for c in np.unique(x[np.isfinite(x)]):
            m = feas & (x == c)
            best = f"{J[m].min():.6g}" if m.any() else "none feasible"
            parts.append(f"{word_text(k, c)} {best} ({int(m.sum())} feasible)")
        out.append(f"  best objective by {k}: " + ", ".join(parts))
    return out


def optimal_grid_text(res) -> str:
    """The table as text: one line per point (up to 40 points), else the ranges."""
    import numpy as np
    keys = list(res.keys)
    head = (f"optimal {'robust ' if res.robust else ''}design over {', '.join(keys)}: "
            f"{res.verified} of {res.points} points verified, {res.seconds:.1f} s "
            f"({res.where})")
    lines = [head]
    c = res.columns
    if res.points <= 40:
        w = [max(len(k), 9) for k in keys]
        lines.append("  " + "  ".join(f"{k:>{n}}" for k, n in zip(keys, w))
                     + f"  {'spring_k':>9}  {'rest_len':>8}  {'damper_c':>9}  {'objective':>9}"
                       "  verified  start")
        for i in range(res.points):
            vals = "  ".join(f"{c[k][i]:>{n}.5g}" for k, n in zip(keys, w))
            if np.isfinite(c["objective"][i]):
                des = (f"{c['spring_k'][i]:>9.6g}  {c['spring_rest_length'][i]:>8.5g}  "
                       f"{c['damper_c'][i]:>9.6g}  {c['objective'][i]:>9.6g}")
            else:
                des = f"{'—':>9}  {'—':>8}  {'—':>9}  {'—':>9}"
            lines.append(f"  {vals}  {des}  {'yes' if c['success'][i] else 'NO':>8}  "
                         f"{c['start'][i]}")
    else:
        ok = c["success"]
        for k, u in (("spring_k", "N/m"), ("spring_rest_length", "m"),
                     ("damper_c", "N s/m"), ("objective", "")):
            v = c[k][ok]
            if v.size:
                lines.append(f"  {k}: {v.min():.6g} .. {v.max():.6g} {u}".rstrip())
    if not res.success and not res.interrupted:
        lines.append(f"  {res.message}")
    return "\n".join(lines)


__all__ = ["sweep_text", "optimal_grid_text"]
