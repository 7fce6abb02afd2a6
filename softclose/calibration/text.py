"""A calibration as text: what ``softclose fit`` prints."""

from __future__ import annotations

import math


def fit_text(res) -> str:
    """What ``softclose fit`` prints: each estimate with its interval, the correlations, the
    verdict on identifiability, each stroke's release and residual, the notes."""
    from ..present.display import num
    payload = res.to_json()
    lines = []
    w = max(len(k) for k in res.keys)
    for k in res.keys:
        p = payload["parameters"][k]
        rel = (f" ({p['std'] / abs(p['value']):.2%})" if p["value"] and p["std"] is not None
               and math.isfinite(p["std"]) else "")
        lines.append(f"  {k:<{w}} {num(p['value'], 7)} ± {num(p['std'], 3)}{rel}  "
                     f"95 %: [{num(p['ci95'][0], 6)}, {num(p['ci95'][1], 6)}] {p['unit']}")
    if len(res.keys) > 1:
        lines.append("  correlation:")
        for a in res.keys:
            lines.append(f"    {a:<{w}} " + " ".join(f"{res.correlation[a][b]:+.3f}"
                                                     for b in res.keys))
    lines.append(f"  identifiable: {'yes' if res.identifiable else 'NO' if res.identifiable is False else '—'}")
    for s in res.strokes:
        lines.append(f"  {s.path}: release at {s.release_time:.4f} s from "
                     f"{s.release_angle_deg:.3f} deg, fitted up to {s.t_last:.4f} s, "
                     f"{s.samples_used} samples, rms residual {num(s.residual_rms, 3)} {s.unit}"
                     + (f", bias {s.bias:.4g} rad/s" if s.kind == "rate" else ""))
    lines.append(f"  ({res.iterations} Ipopt iterations, {res.substeps} sub-step(s) a frame: "
                 f"integration error {res.integration_error:.1e} of the noise)")
    if res.message:
        lines.append(f"  note: {res.message}")
    return "\n".join(lines)


__all__ = ["fit_text"]
