"""Figures of one stroke: time histories, the linkage at several angles, an animation."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from . import place_label, plt
from ...files import write_with


def plot_time_histories(res, title: str = "Closing stroke"):
    """theta, theta' and the tip speed against time, with the event and the peak marked (and
    the end damper's engagement, where it has one that engages: a dotted line, theta' there);
    each label sits where it touches no curve (:func:`softclose.present.figures.place_label`)."""
    tr = res.trajectory
    fig, ax = plt.subplots(3, 1, figsize=(6.5, 6.5), sharex=True)
    ax[0].plot(tr["t"], np.degrees(tr["theta"]), color="C0", lw=2)
    ax[0].set_ylabel(r"$\theta$ [deg]")
    ax[1].plot(tr["t"], tr["theta_dot"], color="C1", lw=2)
    ax[1].set_ylabel(r"$\dot\theta$ [rad/s]")
    ax[2].plot(tr["t"], tr["tip_speed"], color="C2", lw=2)
    ax[2].set_ylabel(r"tip speed $|v_T|$ [m/s]")
    ax[2].set_xlabel("time t [s]")
    fig.suptitle(f"{title} ({res.method}, step {res.step:g} s)")
    i = int(np.argmax(tr["tip_speed"]))
    if res.closed:
        for a in ax:
            a.axvline(res.closing_time, color="k", ls="--", lw=1)
        ax[0].plot([res.closing_time], [np.degrees(tr["theta"][-1])], "k|", ms=8)
        ax[1].plot([res.closing_time], [res.impact_theta_dot], "ko")
    ax[2].plot([tr["t"][i]], [res.peak_tip_speed], "kv", ms=5)
    engage = getattr(res, "engage_time", None)
    if engage is not None:
        for a in ax:
            a.axvline(engage, color="C4", ls=":", lw=1.2)
        ax[1].plot([engage], [res.engage_theta_dot], "s", color="C4", ms=5)
    for a in ax:                     # room for the labels above and below the curves
        lo, hi = a.get_ylim()
        a.set_ylim(lo - 0.12 * (hi - lo), hi + 0.22 * (hi - lo))
    fig.tight_layout()
    fig.canvas.draw()                # the limits and the layout, final: labels are placed
    fig.labels = []                  # the placed labels (tests check they touch no curve)
    if res.closed:
        fig.labels.append(place_label(ax[0], f"closed at {res.closing_time:.4f} s",
                                      (res.closing_time, np.degrees(tr["theta"][-1]))))
        fig.labels.append(place_label(ax[1], f"impact {res.impact_theta_dot:.3f} rad/s",
                                      (res.closing_time, res.impact_theta_dot)))
    fig.labels.append(place_label(ax[2], f"peak {res.peak_tip_speed:.3f} m/s",
                                  (tr["t"][i], res.peak_tip_speed)))
    if engage is not None:
        text = (f"end damper on\n{engage:.4f} s, {res.engage_theta_dot:.3f} rad/s"
                if engage > 0 else "end damper engaged\nfrom the release")
        fig.labels.append(place_label(ax[1], text, (engage, res.engage_theta_dot),
                                      avoid=[a for a in fig.labels if a.axes is ax[1]]))
    return fig


def _hinge(model) -> bool:
    return getattr(model.geo, "mechanism", "four_bar") == "hinge"


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
    if _hinge(model):          # a hinge lid: no cranks, the lid on its hinge H (= A)
        if spring:
            ax.plot([p["E"][0], p["D"][0]], [p["E"][1], p["D"][1]], ":", color="C2", lw=1.5,
                    alpha=alpha)
        if label:
            ax.annotate(label, p["T"], xytext=(4, 0), textcoords="offset points", fontsize=8)
        return
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
    pts = linkage_points(model, thetas[0])
    if _hinge(model):
        for a in (a1, a2):
            a.plot(*pts["A"], "ks", ms=7)
            a.plot(*pts["D"], "g^", ms=7)
            a.set_aspect("equal")
            a.set_xlabel("x [m]")
            a.set_ylabel("y [m]")
        a1.set_title(title)
        h = pts["A"]
        a2.set_xlim(h[0] - 0.1, h[0] + 0.15)
        a2.set_ylim(h[1] - 0.12, h[1] + 0.15)
        a2.set_title("zoom: the hinge H, spring E–D (green)", fontsize=9)
        for name, off in (("A", (-12, -10)), ("D", (-4, -13))):
            a2.annotate("H" if name == "A" else name, pts[name], xytext=off,
                        textcoords="offset points", fontsize=9, weight="bold")
        return fig
    for a in (a1, a2):
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


#: the animation's frame rate (frames per second of the GIF)
FPS = 25
#: a stroke's animation shows at least this many frames: the default slow-motion factor is
#: the smallest of :data:`SLOW_MOTION_STEPS` that gives them (the default 0.15 s stroke: x20)
MIN_FRAMES = 60
SLOW_MOTION_STEPS = (1, 2, 5, 10, 20, 50, 100, 200, 500, 1000)
#: an animation plays at most this long (s): a larger factor is lowered to fit
MAX_PLAY_SECONDS = 60.0


def slow_motion_factor(duration: float, factor: float | None = None,
                       fps: int = FPS) -> float:
    """The slow-motion factor of a stroke of ``duration`` seconds: ``factor`` if given, else
    the smallest of :data:`SLOW_MOTION_STEPS` showing at least :data:`MIN_FRAMES` frames;
    either way lowered so that the animation plays at most :data:`MAX_PLAY_SECONDS`."""
    duration = max(float(duration), 1e-9)
    if factor is None:
        factor = next((f for f in SLOW_MOTION_STEPS if duration * f * fps >= MIN_FRAMES - 1),
                      SLOW_MOTION_STEPS[-1])
    return float(max(min(factor, MAX_PLAY_SECONDS / duration), 1e-3))


def animation_frames(t, factor: float, fps: int = FPS) -> np.ndarray:
    """The stroke times of the frames: every 1/(fps x factor) s from the release, and the
    last instant of the trajectory."""
    t = np.asarray(t, float)
    dt = 1.0 / (fps * factor)
    times = np.arange(0.0, t[-1], dt)
    return np.r_[times[times < t[-1] - 1e-9 * dt], t[-1]]


def write_animation(model, traj: dict, path: Path, fps: int = FPS,
                    slow_motion: float | None = None) -> Path | None:
    """A GIF of the stroke (written by Pillow, which matplotlib ships with); None if Pillow
    is not importable.

    It plays ``slow_motion`` times slower than the stroke (default: the factor of
    :func:`slow_motion_factor`, so the default 0.15 s stroke shows 76 frames at x20); the
    lid angle of each frame is interpolated in the trajectory, and the title gives the
    stroke's time, the angle and the factor. The axes are drawn once and each frame only
    moves the linkage over them (a full redraw per frame took 0.07 s: 5 s for the default
    stroke's frames).
    """
    try:
        from PIL import Image
    except ImportError:
        return None
    t = np.asarray(traj["t"], float)
    factor = slow_motion_factor(t[-1], slow_motion, fps)
    times = animation_frames(t, factor, fps)
    thetas = np.interp(times, t, np.asarray(traj["theta"], float))
    speed = "real time" if factor == 1 else f"slow motion x{factor:g}"
    fig, ax = plt.subplots(figsize=(6, 3.2), dpi=100)
    L = model.geo.lid_length
    ax.set_xlim(-0.1, L + 0.05)
    ax.set_ylim(-0.05, 0.25)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    p0 = linkage_points(model, thetas[0])
    ax.plot([0, p0["B"][0]], [0, p0["B"][1]], "ks", ms=6)
    ax.plot(*p0["D"], "g^", ms=6)
    ax.set_title(" ", fontsize=10)              # its room, kept by the layout
    fig.tight_layout()
    moving = dict(animated=True)
    lid = ax.fill([0, 1, 1, 0], [0, 0, 1, 1], color="#c8a26a", alpha=0.5, ec="k", lw=0.8,
                  **moving)[0]
    oa, = ax.plot([], [], "-o", color="C0", lw=2.5, ms=4, **moving)
    bc, = ax.plot([], [], "-o", color="C3", lw=2.5, ms=4, **moving)
    ac, = ax.plot([], [], "-", color="k", lw=1, **moving)
    spring, = ax.plot([], [], ":", color="C2", lw=1.5, **moving)
    title = ax.set_title("", fontsize=10, animated=True)
    canvas = fig.canvas
    canvas.draw()
    background = canvas.copy_from_bbox(fig.bbox)
    hgt = 0.02
    corners = np.array([[0, -hgt / 2], [L, -hgt / 2], [L, hgt / 2], [0, hgt / 2]])
    frames = []
    for th, ti in zip(thetas, times):
        p = linkage_points(model, th)
        R = np.array([[math.cos(th), -math.sin(th)], [math.sin(th), math.cos(th)]])
        lid.set_xy(p["A"] + corners @ R.T)
        oa.set_data([0, p["A"][0]], [0, p["A"][1]])
        bc.set_data([p["B"][0], p["C"][0]], [p["B"][1], p["C"][1]])
        ac.set_data([p["A"][0], p["C"][0]], [p["A"][1], p["C"][1]])
        spring.set_data([p["E"][0], p["D"][0]], [p["E"][1], p["D"][1]])
        title.set_text(f"t = {ti:.3f} s   θ = {math.degrees(th):.2f}°   ({speed})")
        canvas.restore_region(background)
        for artist in (lid, oa, bc, ac, spring, title):
            ax.draw_artist(artist)
        rgb = Image.fromarray(np.asarray(canvas.buffer_rgba())[..., :3].copy())
        # one palette for every frame: the GIF then stores only what changed between frames
        frames.append(rgb.quantize(colors=255, method=Image.Quantize.MEDIANCUT) if not frames
                      else rgb.quantize(palette=frames[0], dither=Image.Dither.NONE))
    plt.close(fig)
    write_with(path, lambda p: frames[0].save(p, save_all=True, append_images=frames[1:],
               duration=int(round(1000 / fps)), loop=0, optimize=False))
    return Path(path)
