"""Figure of a fit: each record's data against the fitted model, and the residuals."""

from __future__ import annotations

import numpy as np

from . import plt


def plot_fit(result, title: str | None = None):
    """One column per record: top, the measured samples (grey: not fitted; a gyroscope's with
    its axis turned to theta' and its bias removed) and the model at the fitted ones, the
    release marked; bottom, the residuals with +-2 rms."""
    n = len(result.strokes)
    fig, axes = plt.subplots(2, n, figsize=(5.5 * n, 5.6), squeeze=False,
                             gridspec_kw={"height_ratios": [2.2, 1]}, sharex="col")
    for j, s in enumerate(result.strokes):
        top, bot = axes[0, j], axes[1, j]
        used = np.isfinite(s.model)
        what = "θ [deg]" if s.kind == "angle" else "θ' (bias removed) [rad/s]"
        b = 0.0 if s.kind == "angle" else s.bias * s.axis_sign   # (theta' way round)
        y, m = s.y - b, s.model - b
        top.plot(s.t[~used], y[~used], ".", color="0.7", ms=3, label="not fitted")
        top.plot(s.t[used], y[used], ".", color="tab:blue", ms=3, label="measured")
        top.plot(s.t[used], m[used], "-", color="tab:red", lw=1.2, label="fitted model")
        top.axvline(s.release_time, color="k", ls=":", lw=1,
                    label=f"release {s.release_time:.4f} s, {s.release_angle_deg:.3f} deg")
        top.set_ylabel(what)
        top.set_title(s.path if len(s.path) < 60 else "…" + s.path[-58:], fontsize=9)
        top.legend(fontsize=8, frameon=False)
        res = y[used] - m[used]
        bot.plot(s.t[used], res, ".", color="tab:blue", ms=3)
        bot.axhline(0, color="k", lw=0.8)
        for sgn in (-2, 2):
            bot.axhline(sgn * s.residual_rms, color="tab:red", ls="--", lw=0.8)
        bot.set_ylabel(f"residual [{s.unit}]")
        bot.set_xlabel("time [s]")
        bot.text(0.01, 0.95, f"rms {s.residual_rms:.3g} {s.unit} (dashed: ±2 rms)",
                 transform=bot.transAxes, fontsize=8, va="top")
    keys = ", ".join(f"{k.split('.')[-1]} = {result.values[k]:.4g} ± {result.std[k]:.2g}"
                     for k in result.keys)
    verdict = "" if result.identifiable else "  — NOT IDENTIFIABLE"
    fig.suptitle(title or f"fit: {keys}{verdict}", fontsize=10)
    fig.tight_layout()
    return fig


__all__ = ["plot_fit"]
