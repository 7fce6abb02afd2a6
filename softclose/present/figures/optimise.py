"""Figures of the optimiser: the optimal stroke and its design, and the Pareto front."""

from __future__ import annotations

import numpy as np

from . import place_label, plt

_BOX = {"boxstyle": "round,pad=0.2", "fc": "white", "ec": "none", "alpha": 0.85}
#: (design key, axis label, scale to the plotted unit)
_DESIGN = (("spring_k", "spring_k [N/m]", 1.0),
           ("spring_rest_length", "spring_rest_length [mm]", 1e3),
           ("damper_c", "damper_c [N s/m]", 1.0))


def plot_optimum(res):
    """Left: the optimal design's stroke (fixed-step trajectory) -- tip speed and theta
    against time, with the verified peak and impact marked. Right: where each design value
    sits within its bounds, active bounds in red."""
    fig, (a, b) = plt.subplots(1, 2, figsize=(12, 4.4), gridspec_kw={"width_ratios": [1.6, 1]},
                               layout="constrained")
    m = res.metrics or (res.optimiser or {})
    a2 = None
    marks = []
    if res.design is not None and res.config is not None:
        tr = res.simulate(trajectory=True).trajectory
        a.plot(tr["t"], tr["tip_speed"], color="C2", lw=2, label="tip speed")
        a2 = a.twinx()
        a2.plot(tr["t"], np.degrees(tr["theta"]), color="C0", lw=1.2, ls="--", label="theta")
        a2.set_ylabel(r"lid angle $\theta$ [deg]", color="C0")
        a2.grid(False)
        if m.get("peak_tip_speed") is not None:
            i = int(np.argmax(tr["tip_speed"]))
            a.plot([tr["t"][i]], [m["peak_tip_speed"]], "kv", ms=6)
            marks.append((f"peak {m['peak_tip_speed']:.4g} m/s",
                          (tr["t"][i], m["peak_tip_speed"])))
        if m.get("closing_time") is not None:
            a.axvline(m["closing_time"], color="k", ls=":", lw=1)
            a.plot([m["closing_time"]], [m["impact_tip_speed"]], "ko")
            marks.append((f"impact {m['impact_tip_speed']:.3g} m/s\nat {m['closing_time']:.6g} s",
                          (m["closing_time"], m["impact_tip_speed"])))
        for ax_ in (a, a2):          # room for the labels above the curves
            lo, hi = ax_.get_ylim()
            ax_.set_ylim(lo, hi + 0.25 * (hi - lo))
    a.set_xlabel("time t [s]")
    a.set_ylabel(r"tip speed $|v_T|$ [m/s]", color="C2")
    verified = "verified by the adaptive reference" if res.verified else "NOT verified"
    J = f"J = {res.objective:.6g}" if res.objective is not None else "no optimum"
    a.set_title(f"Optimal stroke ({J}; markers: {verified})", fontsize=10)
    # the design within its bounds
    bounds = (res.problem or {}).get("bounds", {})
    active = {(x.name, x.bound) for x in res.active}
    for i, (key, label, scale) in enumerate(_DESIGN):
        lo, hi = bounds.get(key, (0.0, 1.0))
        b.plot([0, 1], [i, i], color="0.7", lw=6, solid_capstyle="butt")
        if res.design is None:
            continue
        v = res.design[key]
        z = (v - lo) / (hi - lo) if hi > lo else 0.5
        hit = (key, "upper") in active or (key, "lower") in active
        b.plot([z], [i], "o", ms=10, color="C3" if hit else "C0")
        note = " (at its bound)" if hit else ""
        b.annotate(f"{v * scale:.5g}{note}", (z, i), xytext=(0, 9), textcoords="offset points",
                   ha="center", fontsize=9, bbox=_BOX)
        b.annotate(f"{lo * scale:g}", (0, i), xytext=(0, -14), textcoords="offset points",
                   ha="left", fontsize=8, color="0.4")
        b.annotate(f"{hi * scale:g}", (1, i), xytext=(0, -14), textcoords="offset points",
                   ha="right", fontsize=8, color="0.4")
    b.set_yticks(range(len(_DESIGN)), [lab for _, lab, _ in _DESIGN])
    b.set_ylim(-0.7, len(_DESIGN) - 0.3)
    b.set_xlim(-0.05, 1.05)
    b.set_xlabel("position within the bounds [fraction of (upper - lower), dimensionless]")
    lim = [x.name for x in res.active if x.kind == "constraint"]
    b.set_title("Design within its bounds" + (f"\nactive: {', '.join(lim)}" if lim else ""),
                fontsize=10)
    fig.labels = []                  # placed where they touch no curve (tests check)
    if marks:
        fig.canvas.draw()            # the layout, final
        for text, xy in marks:
            fig.labels.append(place_label(a, text, xy, avoid=fig.labels, twins=(a2,)))
    return fig


def plot_front(fr):
    """The front against closing_time_max: the objective, the verified impact and peak tip
    speeds, and the optimal design (design values at a bound ringed)."""
    rows = [(t, p) for t, p in zip(fr.closing_times, fr.points) if p.design is not None]
    fig, ax = plt.subplots(2, 2, figsize=(11, 7.5), layout="constrained")
    if not rows:
        fig.suptitle("no point of the front has an optimum")
        return fig
    t = np.array([r[0] for r in rows])
    ok = np.array([r[1].success for r in rows])
    get = lambda key: np.array([np.nan if (p.metrics or {}).get(key) is None  # noqa: E731
                                else p.metrics[key] for _, p in rows], float)
    J = np.array([p.objective for _, p in rows], float)
    a = ax[0, 0]
    a.loglog(t, J, "-", color="C3", lw=1.5)
    a.loglog(t[ok], J[ok], "o", color="C3", label="verified")
    if (~ok).any():
        a.loglog(t[~ok], J[~ok], "x", color="k", ms=8, label="not verified")
    a.set_xlabel("closing_time_max [s]")
    pr = rows[0][1].problem or {}
    wi, wp = pr.get("weight_impact", 1.0), pr.get("weight_peak_tip", 0.1)
    a.set_ylabel(f"J = {wi:g} s²·θ'² + {wp:g} s²/m²·v_peak² [dimensionless]", fontsize=9)
    a.set_title("Optimal objective against the allowed closing time")
    a.legend(fontsize=8)
    a = ax[0, 1]
    a.loglog(t, get("peak_tip_speed"), "o-", color="C2", label="peak tip speed")
    a.loglog(t, get("impact_tip_speed"), "s-", color="C1", label="impact tip speed")
    a.set_xlabel("closing_time_max [s]")
    a.set_ylabel("tip speed (verified) [m/s]")
    a.set_title("Speeds at the optimum")
    a.legend(fontsize=8)
    for a, (key, label, scale), color in ((ax[1, 0], _DESIGN[0], "C4"),
                                          (ax[1, 1], _DESIGN[2], "C5")):
        _design_axis(a, rows, t, key, label, scale, color)
    a2 = ax[1, 1].twinx()
    _design_axis(a2, rows, t, *_DESIGN[1], "C7", ls="--")
    a2.grid(False)
    ax[1, 0].set_title("Optimal spring stiffness")
    ax[1, 1].set_title("Optimal damper (solid) and spring rest length (dashed)")
    for a in ax.flat:
        _log_ticks(a.xaxis)
    for a in ax[0]:
        _log_ticks(a.yaxis)
    n_ok = int(ok.sum())
    fig.suptitle(f"Soft-close optimum against closing_time_max: {n_ok} of {len(fr.points)} "
                 f"points verified, front in {fr.total_time:.2f} s (open rings: at a bound)")
    return fig


def _log_ticks(axis):
    """Plain numbers at 1, 2, 5 x 10^n on a log axis (no overlapping 3x10^-1 labels)."""
    from matplotlib.ticker import FormatStrFormatter, LogLocator, NullFormatter
    axis.set_major_locator(LogLocator(subs=(1.0, 2.0, 5.0)))
    axis.set_major_formatter(FormatStrFormatter("%g"))
    axis.set_minor_formatter(NullFormatter())


def _design_axis(a, rows, t, key, label, scale, color, ls="-"):
    v = np.array([p.design[key] for _, p in rows]) * scale
    at = np.array([any(x.name == key for x in p.active) for _, p in rows])
    a.semilogx(t, v, "o", ls=ls, color=color, ms=4)
    if at.any():
        a.semilogx(t[at], v[at], "o", mfc="none", mec="k", ms=10)
    a.set_xlabel("closing_time_max [s]")
    a.set_ylabel(label, color=color)


__all__ = ["plot_optimum", "plot_front"]
