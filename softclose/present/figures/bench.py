"""Figures of the benchmark (:mod:`softclose.bench`): work precision, error against step,
and the optimiser's N and sub-steps.

The configured default (``cfg.simulate.integrator`` at ``cfg.simulate.step``) is the gold
diamond; when the designs of a run put a different setting cheapest, that one is a hollow
square of its own ("cheapest meeting the targets on these designs"), so that a quick run
never passes its cheapest setting off as the default.

The figures are handed the benchmark's data (``wp``: a :class:`softclose.bench.WorkPrecision`;
the optimiser's rows; the seed's report) and import none of its logic.
"""

from __future__ import annotations

import math

import numpy as np

from ...numerics.integrators import METHODS, SEED
from ...problem import RELATIVE, TARGETS
from ..display import num
from . import plt

_COLORS = {"rk4": "C0", "euler_cromer": "C3", "gauss4": "C2", "radau5": "C1",
           "reference": "k"}
_LABEL = {"closing_time": "|Δ closing_time| (s)", "impact_theta_dot":
          "|Δ impact_theta_dot| (rad/s)", "impact_tip_speed": "rel. Δ impact_tip_speed (-)",
          "peak_tip_speed": "rel. Δ peak_tip_speed (-)"}
#: the metrics of the work-precision figure (columns)
FIG_METRICS = ("closing_time", "impact_theta_dot", "peak_tip_speed")
#: errors below this are drawn at it (log axes)
BOTTOM = 1e-14


def default_label(default: dict) -> str:
    """Legend text of the configured default: what it is and whether this run confirms it."""
    lab = f"configured default: {default['method']}, h = {default['step']:g} s"
    if default.get("confirmed"):
        return lab + " (cheapest meeting the targets here)"
    if not default.get("meets_targets"):
        return lab + " (misses a target here)"
    if default.get("omitted_designs"):
        return lab + " (these designs cannot confirm it)"
    return lab


def cheapest_label(default: dict) -> str | None:
    """Legend text of the cheapest setting on these designs, if it is not the default."""
    c = default.get("cheapest") or {}
    if c.get("method") is None or (c["method"], c["step"]) == (default["method"],
                                                                default["step"]):
        return None
    return f"cheapest meeting the targets on these designs: {c['method']}, h = {c['step']:g} s"


def mark_target_and_floor(ax, bound, truth_floor, bottom, handles):
    """The accuracy target line and the band below the truth's own uncertainty (shared
    legend entries in ``handles``)."""
    handles.setdefault("target", ax.axhline(bound, color="gray", ls="-.", lw=1.0,
                                            label="accuracy target"))
    if truth_floor:
        handles.setdefault("floor", ax.axhspan(bottom, max(truth_floor, bottom), color="0.88",
                                               zorder=0,
                                               label="below the truth's own uncertainty"))
    ax.set_ylim(bottom=bottom / 2)


def _mark_settings(ax, r, x, y, m, default, handles):
    """Star on the seed's method, diamond on the default, square on the cheapest."""
    if (m, r["step"]) == SEED:
        hs, = ax.plot(x, y, "*", color="C3", ms=16, mec="k", zorder=5,
                      label="seed: Euler–Cromer at 1 kHz")
        handles.setdefault("seed", hs)
    if (m, r["step"]) == (default.get("method"), default.get("step")):
        hd, = ax.plot(x, y, "D", color="gold", ms=11, mec="k", zorder=5,
                      label=default_label(default))
        handles.setdefault("default", hd)
    lab = cheapest_label(default)
    c = default.get("cheapest") or {}
    if lab and (m, r["step"]) == (c.get("method"), c.get("step")):
        hc, = ax.plot(x, y, "s", mfc="none", mec="k", mew=2, ms=13, zorder=6, label=lab)
        handles.setdefault("cheapest", hc)


def _legend(fig, handles, ncol):
    fig.legend(list(handles.values()), [h.get_label() for h in handles.values()],
               loc="lower center", ncol=ncol, fontsize=9, frameon=False)


def plot_work_precision(wp):
    """Error against run time per stroke, log-log, one line per method; rows = designs,
    columns = :data:`FIG_METRICS`.

    Dotted lines are guides of slope -order through each method's first asymptotic point
    (error ~ h^p ~ time^-p); the star is the seed's method, the diamond the configured
    default, a hollow square the cheapest setting on these designs when it differs.
    """
    dnames = list(wp.truths)
    fig, axes = plt.subplots(len(dnames), len(FIG_METRICS),
                             figsize=(5.0 * len(FIG_METRICS), 3.6 * len(dnames) + 0.8),
                             squeeze=False)
    handles = {}
    for i, dname in enumerate(dnames):
        for j, k in enumerate(FIG_METRICS):
            ax = axes[i][j]
            tf = wp.truth_floor[dname].get(k) or 0.0
            scale = 1.0 if k in RELATIVE else \
                abs(getattr(wp.truths[dname], k) or 1.0)
            for m in list(METHODS) + ["reference"]:
                rs = [r for r in wp.rows_of(dname, m) if r[f"err_{k}"] is not None]
                if not rs:
                    continue
                x = [r["time_per_stroke"] * 1e6 for r in rs]
                y = [max(r[f"err_{k}"], BOTTOM) for r in rs]
                lab = ("adaptive reference (CVODES, tol 1e-6 … 1e-12)" if m == "reference"
                       else f"{m} (order {METHODS[m].order})")
                h, = ax.loglog(x, y, "o-" if m != "reference" else "s--", color=_COLORS[m],
                               ms=4, lw=1.4, label=lab)
                handles.setdefault(lab, h)
                if m == "reference":
                    continue
                lo = max(30 * tf, 1e-12 * scale)  # slope guide through the first asymptotic point
                asym = [(xx, yy) for xx, yy in zip(x, y) if yy > lo and yy / scale <= 1e-2]
                if asym:
                    x0, y0 = asym[0]
                    p = METHODS[m].order
                    xs = np.array([x0, x0 * 10 ** (2.5 / p)])
                    g, = ax.loglog(xs, y0 * (xs / x0) ** (-p), ":", color=_COLORS[m], lw=2.2,
                                   alpha=0.6, label="guides: slope −order")
                    handles.setdefault("guide", g)
                for r, xx, yy in zip(rs, x, y):
                    _mark_settings(ax, r, xx, yy, m, wp.default, handles)
            mark_target_and_floor(ax, TARGETS[k], tf, BOTTOM, handles)
            ax.set_xlabel("run time per stroke (µs)")
            ax.set_ylabel(_LABEL[k])
            ax.set_title(f"{dname}: {k}", fontsize=10)
            ax.grid(True, which="major", alpha=0.3)
    _legend(fig, handles, 3)
    fig.suptitle("Work precision of the closing stroke: error against run time per stroke "
                 "(C kernel, one thread, median of repeats)", fontsize=12)
    fig.tight_layout(rect=(0, 0.1 if len(dnames) <= 2 else 0.07, 1, 0.98))
    return fig


def plot_error_vs_step(wp, metric: str = "impact_theta_dot"):
    """Error of ``metric`` against the step, one panel per design (2 columns), with the
    fitted orders in each panel's title; the configured default (diamond), the cheapest
    setting on these designs (square, if different) and the seed's method (star) are
    marked; the grey band is below the truth's own uncertainty."""
    dnames = list(wp.truths)
    ncol = 2 if len(dnames) > 1 else 1
    nrow = math.ceil(len(dnames) / ncol)
    fig, axes = plt.subplots(nrow, ncol, figsize=(6.2 * ncol, 4.4 * nrow + 1.0), squeeze=False)
    handles = {}
    short = {"rk4": "rk4", "euler_cromer": "E–C", "gauss4": "gauss4", "radau5": "radau5"}
    for idx, dname in enumerate(dnames):
        ax = axes[idx // ncol][idx % ncol]
        orders = []
        for m in METHODS:
            rs = wp.rows_of(dname, m)
            ok = [r for r in rs if r[f"err_{metric}"] is not None]
            bad = [r for r in rs if r["status"] not in ("closed", "not closed")]
            orders.append(f"{short.get(m, m)} {num(wp.orders.get((dname, m, metric)), spec='.2f')}")
            if ok:
                lab = f"{m} (stated order {METHODS[m].order})"
                h, = ax.loglog([r["step"] for r in ok],
                               [max(r[f"err_{metric}"], BOTTOM) for r in ok],
                               "o-", color=_COLORS[m], ms=4, lw=1.4, label=lab)
                handles.setdefault(lab, h)
                for r in ok:
                    _mark_settings(ax, r, r["step"], max(r[f"err_{metric}"], BOTTOM), m,
                                   wp.default, handles)
            for r in bad:
                hv = ax.axvline(r["step"], color=_COLORS[m], ls=":", lw=0.8,
                                label="unstable step")
                handles.setdefault("unstable", hv)
        mark_target_and_floor(ax, TARGETS[metric], wp.truth_floor[dname].get(metric) or 0.0,
                              BOTTOM, handles)
        ax.set_xlabel("step h (s)")
        ax.set_ylabel(_LABEL[metric])
        ax.set_title(f"{dname} — fitted order: " + ", ".join(orders), fontsize=10)
        ax.grid(True, which="major", alpha=0.3)
    for idx in range(len(dnames), nrow * ncol):
        axes[idx // ncol][idx % ncol].set_visible(False)
    _legend(fig, handles, 3)
    fig.suptitle(f"Error of {metric} against the step (fitted order: slope over the "
                 "asymptotic points; — where too few lie above the floor)", fontsize=12)
    fig.tight_layout(rect=(0, 0.12 if nrow > 1 else 0.19, 1, 0.97))
    return fig


def plot_optimiser(rows: list, default=(10, 4)):
    """Optimal-objective error against solve time, and the objective's discretisation
    error against N x sub-steps; the default (nodes, sub-steps) is circled. None when no
    row has an error to draw."""
    ok = [r for r in rows if r.get("objective_error") is not None]
    if not ok:
        return None
    fig, ax = plt.subplots(1, 2, figsize=(13, 5.2))
    # left: colour = sub-steps, marker = N (no labels to collide); right: lines per sub-steps
    node_marks = dict(zip(sorted({r["nodes"] for r in ok}), "osD^vPX*"))
    handles = {}
    for i, s in enumerate(sorted({r["substeps"] for r in ok})):
        rs = sorted([r for r in ok if r["substeps"] == s], key=lambda r: r["nodes"])
        hc, = ax[0].plot([], [], "-", color=f"C{i}", lw=6, label=f"{s} sub-steps")
        handles.setdefault(f"s{s}", hc)
        for r in rs:
            x, y = r["solve_time"], max(r["objective_error"], 1e-16)
            ax[0].loglog(x, y, node_marks[r["nodes"]], color=f"C{i}", ms=8, mec="k", mew=0.6)
            if (r["nodes"], r["substeps"]) == tuple(default):
                for a, xx, yy in ((ax[0], x, y), (ax[1], r["nodes"] * r["substeps"],
                                                  max(r["discretisation_error"], 1e-16))):
                    hd, = a.plot(xx, yy, "o", ms=20, mfc="none", mec="gold", mew=3, zorder=6,
                                 label=f"default: N = {default[0]}, {default[1]} sub-steps")
                handles.setdefault("default", hd)
        ax[1].loglog([r["nodes"] * r["substeps"] for r in rs],
                     [max(r["discretisation_error"], 1e-16) for r in rs], "o-",
                     color=f"C{i}", ms=max(11 - 3 * i, 4), lw=max(2.5 - 0.6 * i, 1.0))
    for n, mk in node_marks.items():
        hn, = ax[0].plot([], [], mk, color="0.6", mec="k", ms=8, label=f"N = {n}")
        handles.setdefault(f"n{n}", hn)
    ax[0].set_xlabel("Ipopt solve time (s), one cold solve")
    ax[0].set_ylabel("|J_N − J*| (-)")
    ax[0].set_title("optimal objective error against solve time")
    ax[1].set_xlabel("RK4 steps over the stroke, N × sub-steps (-)")
    ax[1].set_ylabel("|J_N − J_reference(design_N)| (-)")
    ax[1].set_title("discretisation error of the objective at the optimum\n"
                    "(depends on N × sub-steps only: the lines coincide)", fontsize=11)
    for a in ax:
        a.grid(True, alpha=0.3)
    fig.legend(list(handles.values()), [h.get_label() for h in handles.values()],
               loc="lower center", ncol=len(handles), fontsize=10, frameon=False)
    fig.tight_layout(rect=(0, 0.08, 1, 1))
    return fig


def plot_seed_reproduction(rep: dict):
    """The seed's drop (:func:`softclose.bench.seed_reproduction`): theta(t) against the
    accurate stroke, the seed's error along the trajectory, and the error of closing_time
    and impact_theta_dot against the step for Euler-Cromer and rk4."""
    tr, rt = rep["trajectories"]["seed"], rep["trajectories"]["default"]
    ref, seed = rep["reference"], rep["seed_grid_reading"]
    d = rep["default"]
    acc = f"accurate ({d['method']} {d['step'] * 1e3:g} ms, event located)"
    conv, order = rep["convergence"], rep["observed_order"]
    steps = np.asarray(conv["step"])
    fig, ax = plt.subplots(1, 3, figsize=(15, 4.8))
    ax[0].plot(rt["t"], np.degrees(rt["theta"]), "k-", lw=2.5, label=acc)
    ax[0].plot(tr["t"][:-1], np.degrees(tr["theta"][:-1]), "C1--", lw=1.5,
               label="seed: Euler–Cromer 1 kHz")
    ax[0].plot([seed["closing_time"]], [rep["seed_theta_at_sample_deg"]], "C1o", ms=7,
               label=f"seed's impact sample t = {seed['closing_time']:.3f} s")
    ax[0].plot([ref["closing_time"]], [0.0], "k*", ms=13,
               label=f"reference closing {ref['closing_time']:.7f} s")
    ax[0].set_xlabel("time t (s)")
    ax[0].set_ylabel(r"lid angle $\theta$ (deg)")
    ax[0].legend(fontsize=8)
    ax[0].set_title("Gravity-only drop from 18°")
    # the seed's error on the nodes the two trajectories share
    t_acc = np.asarray(rt["t"])
    t_seed = np.asarray(tr["t"][:-1])
    common = t_seed[t_seed <= t_acc[-1]]
    th_acc = np.interp(common, t_acc, rt["theta"])
    thd_acc = np.interp(common, t_acc, rt["theta_dot"])
    n = len(common)
    ax[1].plot(common, np.asarray(tr["theta_dot"][:n]) - thd_acc, "C1-", lw=2,
               label=r"$\dot\theta$: seed − accurate (rad/s)")
    ax[1].plot(common, np.degrees(np.asarray(tr["theta"][:n]) - th_acc), "C2--", lw=2,
               label=r"$\theta$: seed − accurate (deg)")
    ax[1].axhline(0, color="k", lw=0.8)
    ax[1].annotate(f"impact θ': seed {seed['impact_theta_dot']:.4f} rad/s,\n"
                   f"reference {ref['impact_theta_dot']:.6f} rad/s", (0.03, 0.06),
                   xycoords="axes fraction", fontsize=9)
    ax[1].set_xlabel("time t (s)")
    ax[1].set_ylabel("seed − accurate (rad/s or deg)")
    ax[1].legend(fontsize=8, loc="upper left")
    ax[1].set_title("Error of the seed's trajectory")
    for name, c in (("euler_cromer", "C1"), ("rk4", "C0")):
        o = order[name]
        ax[2].loglog(steps, conv[f"{name}_impact_theta_dot_error"], "o-", color=c,
                     label=f"{name}: |Δ impact θ'| (rad/s)"
                     + (f" (order {o:.2f})" if o is not None and math.isfinite(o) else ""))
        ax[2].loglog(steps, conv[f"{name}_closing_time_error"], "s--", color=c, ms=4,
                     label=f"{name}: |Δ closing time| (s)")
    ax[2].loglog([SEED[1]], [abs(rep["seed_errors"]["impact_theta_dot"])], "kX", ms=11,
                 label="seed's grid reading at 1 ms")
    ax[2].axhline(TARGETS["impact_theta_dot"], color="0.5", lw=0.8, ls=":",
                  label=f"target {TARGETS['impact_theta_dot']:g} rad/s")
    ax[2].annotate(f"rk4 levels off at the reference's own error (CVODES {rep['reference_tol']:g})",
                   (0.03, 0.03), xycoords="axes fraction", fontsize=8, color="C0")
    ticks = steps[::2] if len(steps) > 8 else steps
    ax[2].set_xticks(ticks)
    ax[2].set_xticklabels([f"{h * 1e3:g} ms" for h in ticks], rotation=30, fontsize=8)
    ax[2].minorticks_off()
    ax[2].set_xlabel("step h (s)")
    ax[2].set_ylabel(f"error against CVODES {rep['reference_tol']:g} (rad/s or s)")
    ax[2].legend(fontsize=7)
    ax[2].set_title("Error against the step (events located in the step)")
    fig.tight_layout()
    return fig


__all__ = ["plot_seed_reproduction", "plot_work_precision", "plot_error_vs_step", "plot_optimiser",
           "mark_target_and_floor", "default_label", "cheapest_label", "FIG_METRICS"]
