"""The figure of ``softclose select``: yield against worst-case J for every pair."""

from __future__ import annotations

import numpy as np

from . import plt


def plot_select(result, title: str | None = None):
    """Every screened pair as a point (yield over its tolerance box against its worst-case
    J; feasible at every corner filled, the others hollow; pairs whose worst case did not
    close are counted in the legend), the chosen (first-ranked) pair marked."""
    fig, ax = plt.subplots(figsize=(7, 4.6))
    R = result.ranking
    y = np.array([np.nan if e["yield"] is None else 100 * e["yield"] for e in R], float)
    J = np.array([np.nan if e["worst_objective"] is None else e["worst_objective"] for e in R],
                 float)
    F = np.array([bool(e["feasible"]) for e in R], bool)
    shown = np.isfinite(J)
    n_open = int((~shown).sum())
    ax.scatter(J[shown & F], y[shown & F], s=16, color="tab:blue",
               label=f"feasible at every corner ({int((shown & F).sum())})")
    ax.scatter(J[shown & ~F], y[shown & ~F], s=16, facecolors="none", edgecolors="tab:gray",
               label=f"fails at a corner ({int((shown & ~F).sum())})")
    if len(R) and shown[0]:
        b = R[0]
        name = b["spring"] + (f" + {b['damper']}" if b["damper"] else "")
        ax.scatter([J[0]], [y[0]], s=160, marker="*", color="tab:red", zorder=5,
                   label=f"chosen: {name}")
    if n_open:
        ax.plot([], [], " ", label=f"{n_open} pairs with a stroke that does not close "
                                   "(no worst-case J): not shown")
    if shown.any() and np.nanmin(J[shown]) > 0 and np.nanmax(J[shown]) / np.nanmin(J[shown]) > 30:
        ax.set_xscale("log")
    ax.set_xlabel("worst-case J over the tolerance box [-]")
    ax.set_ylabel("yield [%]")
    ax.set_ylim(-3, 103)
    ax.legend(fontsize=8, loc="center right")
    ax.set_title(title or f"{result.evaluated} catalog pairs, each over its own tolerance box "
                 f"({result.samples} samples)", fontsize=10)
    fig.tight_layout()
    return fig
