"""Figures of an optimal grid (:class:`softclose.sweeps.optimal.OptimalGridResult`): the
optimal spring_k, spring_rest_length, damper_c and objective over the grid -- maps over two
keys, profiles over one. Points without a verified optimum are marked, never drawn as data.
"""

from __future__ import annotations

import numpy as np

from . import plt
from .sweep import label

#: what the panels show: (column, title, unit)
PANELS = (("spring_k", "optimal spring stiffness k", "N/m"),
          ("spring_rest_length", "optimal spring rest length l0", "m"),
          ("damper_c", "optimal damper c", "N s/m"),
          ("objective", "optimal objective J", "-"))


def _slice(res) -> tuple[list[int], tuple, str]:
    """The (at most two) varying axes shown, the index into the grid, and what is fixed."""
    shape = res.shape
    free = [j for j, n in enumerate(shape) if n > 1][:2]
    index = tuple(slice(None) if j in free else n // 2 for j, n in enumerate(shape))
    fixed = [f"{res.keys[j]} = {res.axes[j][index[j]]:.4g}" for j in range(len(shape))
             if j not in free and shape[j] > 1]
    return free, index, ", ".join(fixed)


def plot_optimal_grid(res):
    """Maps (two varying keys) or profiles (one) of the optimal design and objective; with
    more than two varying keys, the slice through the middle of the others (named)."""
    free, index, fixed = _slice(res)
    ok = res.grid("success")[index]
    fig, axs = plt.subplots(2, 2, figsize=(10.5, 8) if len(free) == 2 else (10, 7),
                            sharex=True, sharey=len(free) == 2)
    for ax, (col, title, unit) in zip(axs.ravel(), PANELS):
        Z = res.grid(col)[index]
        if len(free) == 2:
            _map(fig, ax, res, free, Z, ok, f"{title} [{unit}]")
        else:
            _profile(ax, res, free, Z, ok, f"{title} [{unit}]")
        ax.set_title(title)
    if len(free) == 2:
        for ax in axs[1]:
            ax.set_xlabel(label(res.keys[free[0]]))
        for ax in axs[:, 0]:
            ax.set_ylabel(label(res.keys[free[1]]))
    else:
        for ax in axs[1]:
            ax.set_xlabel(label(res.keys[free[0]]) if free else "grid point")
    n_bad = int((~ok).sum())
    what = "robust design" if res.robust else "optimal design"
    head = (f"The {what} at every grid point ({int(ok.sum())} of {ok.size} verified"
            + (f"; {n_bad} without a verified optimum marked ×" if n_bad else "") + ")")
    fig.suptitle(head + (f"\nslice at {fixed}" if fixed else ""))
    fig.tight_layout()
    return fig


def _map(fig, ax, res, free, Z, ok, cbar_label) -> None:
    j1, j2 = free
    x, y = res.axes[j1], res.axes[j2]
    X, Y = np.meshgrid(x, y, indexing="ij")
    Zm = np.ma.masked_where(~ok | ~np.isfinite(Z), Z)
    if Zm.count():
        pm = ax.pcolormesh(X, Y, Zm, shading="nearest", cmap="viridis")
        cb = fig.colorbar(pm, ax=ax)
        cb.set_label(cbar_label)
        if X.size > 64 and min(Zm.shape) >= 3:      # contours where cells are not labelled
            ax.contour(X, Y, Zm, levels=6, colors="k", linewidths=0.5)
    if (~ok).any():
        ax.plot(X[~ok], Y[~ok], "x", color="red", ms=9, mew=2, ls="none")
    if X.size <= 64:                      # small grids: the value of every verified cell
        for xi, yi, zi, oki in zip(X.ravel(), Y.ravel(), Zm.filled(np.nan).ravel(), ok.ravel()):
            if oki and np.isfinite(zi):
                ax.annotate(f"{zi:.4g}", (xi, yi), ha="center", va="center", fontsize=7,
                            color="white", bbox={"boxstyle": "round,pad=0.15", "fc": "0.2",
                                                 "ec": "none", "alpha": 0.5})


def _profile(ax, res, free, Z, ok, ylabel) -> None:
    x = res.axes[free[0]] if free else np.arange(Z.size)
    Z, ok = np.ravel(Z), np.ravel(ok)
    good = np.where(ok & np.isfinite(Z), Z, np.nan)
    ax.plot(x, good, "o-", color="C0", lw=2, ms=5, label="verified optimum")
    # no offset notation, and a value constant to solver tolerance (a design key at its bound)
    # is drawn flat in a window of +-0.5 %, not stretched into a trend of its last digits
    ax.ticklabel_format(axis="y", useOffset=False)
    v = good[np.isfinite(good)]
    if v.size:
        mid, span = 0.5 * (v.max() + v.min()), v.max() - v.min()
        floor = 1e-3 * abs(mid)
        if 0 < floor and span < floor:
            ax.set_ylim(mid - 5 * floor, mid + 5 * floor)
    if (~ok).any():
        lo = np.nanmin(good) if np.isfinite(good).any() else 0.0
        ax.plot(x[~ok], np.full(int((~ok).sum()), lo), "x", color="red", ms=9, mew=2,
                label="no verified optimum")
        ax.legend(fontsize=8)
    ax.set_ylabel(ylabel)
