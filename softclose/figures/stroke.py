"""Figures of one stroke: time histories, the linkage at several angles, an animation."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from . import plt


def plot_time_histories(res, title: str = "Closing stroke"):
    """theta, theta' and the tip speed against time, with the event and the peak marked."""
    tr = res.trajectory
    box = {"boxstyle": "round,pad=0.2", "fc": "white", "ec": "none", "alpha": 0.85}
    fig, ax = plt.subplots(3, 1, figsize=(6.5, 6.5), sharex=True)
    ax[0].plot(tr["t"], np.degrees(tr["theta"]), color="C0", lw=2)
    ax[0].set_ylabel(r"$\theta$ [deg]")
    ax[1].plot(tr["t"], tr["theta_dot"], color="C1", lw=2)
    ax[1].set_ylabel(r"$\dot\theta$ [rad/s]")
    ax[2].plot(tr["t"], tr["tip_speed"], color="C2", lw=2)
    ax[2].set_ylabel(r"tip speed $|v_T|$ [m/s]")
    ax[2].set_xlabel("time t [s]")
    if res.closed:
        for a in ax:
            a.axvline(res.closing_time, color="k", ls="--", lw=1)
        ax[0].annotate(f"closed at {res.closing_time:.4f} s", (res.closing_time, 0),
                       xytext=(-10, 20), textcoords="offset points", ha="right", bbox=box)
        ax[1].plot([res.closing_time], [res.impact_theta_dot], "ko")
        ax[1].annotate(f"impact {res.impact_theta_dot:.3f} rad/s",
                       (res.closing_time, res.impact_theta_dot), xytext=(-10, 0),
                       textcoords="offset points", ha="right", va="center", bbox=box)
    i = int(np.argmax(tr["tip_speed"]))
    ax[2].plot([tr["t"][i]], [res.peak_tip_speed], "kv", ms=5)
    late = tr["t"][i] > 0.8 * tr["t"][-1]  # a peak at the end is labelled on its left
    ax[2].annotate(f"peak {res.peak_tip_speed:.3f} m/s", (tr["t"][i], res.peak_tip_speed),
                   xytext=(-8 if late else 8, -2), textcoords="offset points",
                   ha="right" if late else "left", va="top", bbox=box)
    fig.suptitle(f"{title} ({res.method}, step {res.step:g} s)")
    return fig


def linkage_points(model, theta: float) -> dict:
    k = model.kin(np.array([theta, 0.0]))
    names = ["A", "C", "E", "T", "G1"]
    pts = {n: np.asarray(k[5 + i]).ravel() for i, n in enumerate(names)}
    pts["O"] = np.zeros(2)
    pts["B"] = np.asarray(model.geo.pivot_b)
    pts["D"] = np.asarray(model.geo.spring_anchor)
    return pts


def _draw(ax, model, theta, alpha=1.0, label=None, spring=True):
    p = linkage_points(model, theta)
    R = np.array([[math.cos(theta), -math.sin(theta)], [math.sin(theta), math.cos(theta)]])
    L = model.geo.lid_length
    hgt = 0.02
    corners = np.array([[0, -hgt / 2], [L, -hgt / 2], [L, hgt / 2], [0, hgt / 2]])
    lid = p["A"] + corners @ R.T
    ax.fill(lid[:, 0], lid[:, 1], color="#c8a26a", alpha=0.5 * alpha, ec="k", lw=0.8)
    ax.plot([0, p["A"][0]], [0, p["A"][1]], "-o", color="C0", lw=2.5, ms=4, alpha=alpha)
    ax.plot([p["B"][0], p["C"][0]], [p["B"][1], p["C"][1]], "-o", color="C3", lw=2.5, ms=4,
            alpha=alpha)
    ax.plot([p["A"][0], p["C"][0]], [p["A"][1], p["C"][1]], "-", color="k", lw=1, alpha=alpha)
    if spring:
        ax.plot([p["E"][0], p["D"][0]], [p["E"][1], p["D"][1]], ":", color="C2", lw=1.5,
                alpha=alpha)
    if label:
        ax.annotate(label, p["T"], xytext=(4, 0), textcoords="offset points", fontsize=8)


def plot_linkage(model, thetas, labels=None, title="Linkage"):
    """The linkage drawn at several angles (full view and a zoom on the cranks)."""
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(12, 4.4), gridspec_kw={"width_ratios": [2.2, 1]},
                                 layout="constrained")
    n = len(thetas)
    for i, th in enumerate(thetas):
        lab = labels[i] if labels else f"{math.degrees(th):.1f}°"
        alpha = 0.35 + 0.65 * (i + 1) / n
        _draw(a1, model, th, alpha, lab)
        _draw(a2, model, th, alpha)
    for a in (a1, a2):
        pts = linkage_points(model, thetas[0])
        a.plot([0, pts["B"][0]], [0, pts["B"][1]], "ks", ms=7)
        a.plot(*pts["D"], "g^", ms=7)
        a.set_aspect("equal")
        a.set_xlabel("x [m]")
        a.set_ylabel("y [m]")
    a1.set_title(title)
    a2.set_xlim(-0.09, 0.12)
    a2.set_ylim(-0.03, 0.11)
    a2.set_title("zoom: cranks OA (blue), BC (red),\nspring E–D (green); pins at the last position",
                 fontsize=9)
    # the moving pins A, C, E lie within ~1.5 cm of each other: label them at the last
    # position only, each pushed out along its own direction from their centroid, with a
    # leader line, so that the labels never overlap each other or the points
    q = linkage_points(model, thetas[-1])
    centre = np.mean([q[n] for n in ("A", "C", "E")], axis=0)
    for name in ("A", "C", "E"):
        d = q[name] - centre
        d = d / (np.linalg.norm(d) or 1.0)
        a2.annotate(name, q[name], xytext=(28 * d[0], 28 * d[1]), textcoords="offset points",
                    fontsize=9, ha="center", va="center", color="0.1",
                    arrowprops={"arrowstyle": "-", "color": "0.4", "lw": 0.6})
    for name, off in (("O", (-12, -10)), ("B", (5, -10)), ("D", (-4, -13))):
        a2.annotate(name, pts[name], xytext=off, textcoords="offset points", fontsize=9,
                    weight="bold")
    return fig


def write_animation(model, traj: dict, path: Path, fps: int = 25) -> Path | None:
    """A GIF of the stroke (Pillow writer, shipped with matplotlib); None if unavailable."""
    from matplotlib import animation
    if not animation.writers.is_available("pillow"):
        return None
    t = traj["t"]
    frames = np.searchsorted(t, np.arange(0, t[-1] + 1e-12, 1 / fps))
    frames = np.unique(np.r_[frames[frames < len(t)], len(t) - 1])
    fig, ax = plt.subplots(figsize=(6, 3.2))
    L = model.geo.lid_length

    def update(i):
        ax.clear()
        _draw(ax, model, traj["theta"][i])
        ax.set_xlim(-0.1, L + 0.05)
        ax.set_ylim(-0.05, 0.25)
        ax.set_aspect("equal")
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
        ax.set_title(f"t = {t[i]:.3f} s   θ = {math.degrees(traj['theta'][i]):.2f}°")
    anim = animation.FuncAnimation(fig, update, frames=frames)
    anim.save(path, writer=animation.PillowWriter(fps=fps))
    plt.close(fig)
    return path
