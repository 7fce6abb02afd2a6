"""Figures of robust design: yield histograms and Sobol bars."""

from __future__ import annotations

import numpy as np

from . import plt

_COLOURS = ("tab:red", "tab:blue", "tab:green", "tab:purple")


def plot_yield(results, labels, title: str | None = None):
    """Histograms of closing time and impact speed over the Monte Carlo samples of one or
    more designs (same bins; samples that did not close are counted in the legend), with the
    closing-time window and each design's yield."""
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    cts, ims = [], []
    for r in results:
        cols = r.data["cols"]
        closed = np.asarray(cols["closed"], bool)
        cts.append(np.asarray(cols["closing_time"], float)[closed])
        ims.append(np.abs(np.asarray(cols["impact_theta_dot"], float)[closed]))
    o_max = None
    if results:
        box = results[0]
        o_max = box.data.get("closing_time_max")
    allc = np.concatenate(cts) if cts else np.array([])
    alli = np.concatenate(ims) if ims else np.array([])
    bins_c = np.linspace(allc.min(), allc.max(), 60) if allc.size else 10
    bins_i = np.linspace(0.0, alli.max(), 60) if alli.size else 10
    for j, (r, lab, c, im) in enumerate(zip(results, labels, cts, ims)):
        col = _COLOURS[j % len(_COLOURS)]
        nc = r.samples - len(c)
        lo, hi = r.yield_ci
        leg = (f"{lab}: yield {100 * r.yield_:.2f} % [{100 * lo:.2f}, {100 * hi:.2f}]"
               + (f"; {nc} not closed" if nc else ""))
        axes[0].hist(c, bins=bins_c, color=col, alpha=0.55, label=leg)
        axes[1].hist(im, bins=bins_i, color=col, alpha=0.55, label=lab)
    if o_max is not None:
        axes[0].axvline(o_max, color="k", ls="--", lw=1, label=f"closing_time_max = {o_max:g} s")
    axes[0].set_xlabel("closing time [s]")
    axes[0].set_ylabel("samples [-]")
    axes[1].set_xlabel("impact speed |θ'| at closing [rad/s]")
    axes[1].set_ylabel("samples [-]")
    # the legends go below the panels: inside, they covered the tallest bars
    for ax in axes:
        ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=1,
                  frameon=False)
    n = results[0].samples if results else 0
    dist = results[0].distribution if results else ""
    fig.suptitle(title or f"Monte Carlo over the tolerance box ({n} samples, {dist}); "
                 "yield with its 95 % Wilson interval", fontsize=10)
    fig.tight_layout()
    return fig


def plot_sobol(result, title: str | None = None):
    """First-order and total Sobol indices per toleranced key, with 95 % intervals; one
    panel per output."""
    outputs = list(result.indices)
    fig, axes = plt.subplots(1, len(outputs), figsize=(5.5 * len(outputs), 4), squeeze=False)
    keys = list(result.keys)
    x = np.arange(len(keys))
    names = {"closing_time": "closing time", "impact_theta_dot": "impact θ'"}
    for ax, out in zip(axes[0], outputs):
        d = result.indices[out]
        for off, (name, conf, col) in zip((-0.18, 0.18), (("S1", "S1_conf", "tab:blue"),
                                                          ("ST", "ST_conf", "tab:orange"))):
            v = np.array([d[name][k] for k in keys])
            e = np.array([d[conf][k] for k in keys])
            ax.bar(x + off, v, 0.36, yerr=e, capsize=3, color=col,
                   label={"S1": "first order S1", "ST": "total ST"}[name])
        ax.set_xticks(x)
        ax.set_xticklabels([k.removeprefix("design.") for k in keys])
        ax.set_ylabel("Sobol index [-]")
        ax.set_title(names.get(out, out))
        ax.set_ylim(min(0.0, ax.get_ylim()[0]), max(1.05, ax.get_ylim()[1]))
        ax.axhline(0, color="k", lw=0.5)
        ax.legend(fontsize=8)
    extra = f"; {result.not_closed} strokes did not close (censored)" if result.not_closed else ""
    fig.suptitle(title or f"Sobol indices over the tolerance box (N = {result.base_samples}, "
                 f"{result.evaluations} strokes{extra})", fontsize=10)
    fig.tight_layout()
    return fig


__all__ = ["plot_yield", "plot_sobol"]
