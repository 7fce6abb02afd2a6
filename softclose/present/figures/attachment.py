"""Where the spring and the dashpot attach: the linkage with the spring's line D–E(θ) and the
dashpot's line F–H(θ) over the stroke, the attachment points, the box each free ground point
may take, and the keep-out regions (``optimise.keep_out``)."""

from __future__ import annotations

import math

import numpy as np

from . import plt
from .stroke import _draw

#: lines drawn over the stroke
LINES_OVER_STROKE = 9


def _lid_point(model, theta: float, p) -> np.ndarray:
    A = np.asarray(model.kin(np.array([theta, 0.0]))[5]).ravel()
    c, s = math.cos(theta), math.sin(theta)
    return A + np.array([c * p[0] - s * p[1], s * p[0] + c * p[1]])


def plot_attachments(model, cfg, title: str = "Attachment points", before=None):
    """The linkage of ``model`` (a :class:`~softclose.model.lid.LidModel` of ``cfg``, its
    points set) at the open and closed angles, the spring and
    dashpot lines at :data:`LINES_OVER_STROKE` angles of the stroke, the paths of the lid
    points E and H, each free ground point's box (``optimise.free``) and the keep-out
    polygons; ``before`` (another model) draws its spring line at the closed angle for comparison."""
    geo, st = model.geo, model.stroke
    fig, ax = plt.subplots(figsize=(7.5, 5.6), layout="constrained")
    for poly in cfg.optimise.keep_out or ():
        P = np.asarray(poly)
        ax.fill(P[:, 0], P[:, 1], color="C3", alpha=0.25, hatch="//", ec="C3", lw=1)
    free = {k: (lo, hi) for k, lo, hi in cfg.optimise.free or ()}
    for name, color in (("spring_anchor", "C2"), ("dashpot_anchor", "C4")):
        bx = free.get(f"geometry.{name}[0]", (geo.__getattribute__(name)[0],) * 2)
        by = free.get(f"geometry.{name}[1]", (geo.__getattribute__(name)[1],) * 2)
        if (bx[0], by[0]) != (bx[1], by[1]):
            ax.add_patch(plt.Rectangle((bx[0], by[0]), bx[1] - bx[0], by[1] - by[0],
                                       fill=False, ls="--", ec=color, lw=1))
    _draw(ax, model, st.theta0, 0.35, None, spring=False)
    _draw(ax, model, st.theta_closed, 1.0, None, spring=False)
    th = np.linspace(st.theta_closed, st.theta0, LINES_OVER_STROKE)
    dense = np.linspace(st.theta_closed, st.theta0, 60)
    D, F = np.asarray(geo.spring_anchor), np.asarray(geo.dashpot_anchor)
    for (ground, lid, color, label) in ((D, geo.lid_e, "C2", "spring D–E"),
                                        (F, geo.dashpot_lid, "C4", "dashpot F–H")):
        for i, t in enumerate(th):
            P = _lid_point(model, t, lid)
            ax.plot([ground[0], P[0]], [ground[1], P[1]], "-", color=color,
                    lw=2.0 if i == 0 else 0.8, alpha=1.0 if i == 0 else 0.45,
                    label=label if i == 0 else None)
        path = np.array([_lid_point(model, t, lid) for t in dense])
        ax.plot(path[:, 0], path[:, 1], ":", color=color, lw=1)
        ax.plot(*ground, "^", color=color, ms=8)
    if before is not None:
        m0 = before
        E0 = _lid_point(m0, st.theta_closed, m0.geo.lid_e)
        D0 = np.asarray(m0.geo.spring_anchor)
        ax.plot([D0[0], E0[0]], [D0[1], E0[1]], "--", color="0.4", lw=1.2,
                label="spring before (closed)")
    for name, q, off in (("D", D, (-6, -14)), ("F", F, (6, -12)),
                         ("E", _lid_point(model, st.theta_closed, geo.lid_e), (6, 6)),
                         ("H", _lid_point(model, st.theta_closed, geo.dashpot_lid), (6, -12))):
        ax.annotate(name, q, xytext=off, textcoords="offset points", fontsize=9, weight="bold")
    ax.plot([0, geo.pivot_b[0]], [0, geo.pivot_b[1]], "ks", ms=6)
    ax.set_aspect("equal")
    ax.set_xlim(-0.11, 0.10)
    ax.set_ylim(-0.04, 0.10)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(f"{title}: lines at {LINES_OVER_STROKE} angles from "
                 f"{math.degrees(st.theta_closed):.0f}° (bold) to "
                 f"{math.degrees(st.theta0):.0f}°", fontsize=10)
    ax.legend(loc="upper left", fontsize=8)
    return fig


__all__ = ["plot_attachments", "LINES_OVER_STROKE"]
