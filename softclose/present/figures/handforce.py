"""The hand-force figure (SPEC §13): F_open and F_close against the opening angle, the zones
shaded (handed a :class:`softclose.simulation.handforce.HandForce` or its JSON)."""

from __future__ import annotations

from . import plt

#: the zones' shading and labels
ZONE_STYLE = {"self_close": ("C0", "closes by itself"), "hold_open": ("C2", "hold-open"),
              "self_rise": ("C3", "rises by itself")}


def _draw(ax, hf, title: str, legend: bool = True) -> None:
    shown = set()
    for zone, lo, hi in hf.zones:
        colour, label = ZONE_STYLE[zone]
        ax.axvspan(lo, hi, color=colour, alpha=0.12, lw=0,
                   label=None if zone in shown else label)
        shown.add(zone)
    ax.plot(hf.theta_deg, hf.f_open, color="C1", lw=2, label=r"$F_\mathrm{open}$ (to lift)")
    ax.plot(hf.theta_deg, hf.f_close, color="C4", lw=2, ls="--",
            label=r"$F_\mathrm{close}$ (< 0: push down)")
    ax.axhline(0.0, color="k", lw=0.8)
    ax.set_xlabel(r"opening angle $\theta$ [deg]")
    ax.set_xlim(hf.theta_deg[0], hf.theta_deg[-1])
    ax.set_title(f"{title}: opening {hf.opening_force:.3g} N, closing {hf.closing_force:.3g} N",
                 fontsize=9)
    if legend:
        ax.legend(loc="best", fontsize=8)


def plot_hand_force(hf, title: str = "Hand force at the tip"):
    """F_open and F_close (N) against theta (deg), the self-close, hold-open and self-rise
    zones shaded, the largest opening and closing forces marked."""
    fig, ax = plt.subplots(figsize=(6.5, 4.2))
    _draw(ax, hf, title)
    ax.set_ylabel("force at the tip, normal to the lid [N]")
    fig.tight_layout()
    return fig


def plot_hand_force_by_temperature(curves):
    """The hand-force figure at each operating temperature: ``curves`` is a list of
    (temperature in °C, hand force); one panel each, on one force axis."""
    n = len(curves)
    fig, axes = plt.subplots(1, n, figsize=(4.2 * n, 4.0), sharey=True, squeeze=False)
    for i, (ax, (T, hf)) in enumerate(zip(axes[0], curves)):
        _draw(ax, hf, f"at {T:g} °C", legend=i == 0)
    axes[0][0].set_ylabel("force at the tip, normal to the lid [N]")
    fig.tight_layout()
    return fig


__all__ = ["plot_hand_force", "plot_hand_force_by_temperature"]
