"""Every figure softclose draws. The only modules that import matplotlib (Agg backend).

Each ``plot_*`` function returns a :class:`matplotlib.figure.Figure`; :func:`save` writes it
and closes it. Every axis carries its unit.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib
import numpy as np

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

plt.rcParams.update({"font.size": 10, "axes.grid": True, "grid.alpha": 0.3,
                     "figure.dpi": 110, "savefig.bbox": "tight"})

DPI = 120


def _curve_points(ax, exclude=()):
    """Every line of ``ax`` (but ``exclude``) as display coordinates, densely resampled so
    that a label box between two vertices of a segment still contains a point of it."""
    pts = []
    for line in ax.get_lines():
        if line in exclude or not line.get_visible():
            continue
        xy = line.get_transform().transform(np.column_stack(line.get_data()).astype(float))
        xy = xy[np.all(np.isfinite(xy), axis=1)]
        if len(xy) == 1 or line.get_linestyle() in ("None", "none", "", " "):
            pts.append(xy)
            continue
        for a, b in zip(xy[:-1], xy[1:]):
            n = max(2, int(np.hypot(*(b - a)) / 2.0) + 2)      # a point every 2 pixels
            pts.append(a + (b - a) * np.linspace(0, 1, n)[:, None])
    return np.concatenate(pts) if pts else np.zeros((0, 2))


#: offsets (points) tried for a label, nearest first; a far one gets a leader line
LABEL_OFFSETS = tuple(sorted(((dx, dy) for dx in (-10, 10, -40, 40, -90, 90, -160, 160, 0)
                              for dy in (14, -14, 35, -35, 60, -60, 90, -90, 0)
                              if (dx, dy) != (0, 0)),
                             key=lambda o: (o[0] ** 2 + o[1] ** 2, o[1] < 0, o[0] > 0)))


def label_extent(ann, renderer=None):
    """The display box of an annotation's text (without its leader line)."""
    from matplotlib.text import Text
    renderer = renderer or ann.figure.canvas.get_renderer()
    ann.update_positions(renderer)
    return Text.get_window_extent(ann, renderer)


def place_label(ax, text: str, xy, avoid=(), pad: float = 3.0, twins=(), **kwargs):
    """Annotate the data point ``xy`` of ``ax`` with ``text`` where its box touches no line
    of the axes, no earlier label in ``avoid`` and stays inside the axes: the nearest of
    :data:`LABEL_OFFSETS` that does (a leader line when it is not next to the point);
    ``twins``: axes sharing the area (a twinx) whose lines count too.
    Returns the annotation (its window extent can be checked: tests do). The axes' limits
    and layout must be final: call it after ``fig.canvas.draw()``."""
    fig = ax.figure
    renderer = fig.canvas.get_renderer()
    pts = np.concatenate([_curve_points(a) for a in (ax, *twins)])
    frame = ax.get_window_extent(renderer)
    boxes = [label_extent(a, renderer) for a in avoid]
    style = {"bbox": {"boxstyle": "round,pad=0.2", "fc": "white", "ec": "none", "alpha": 0.9},
             **kwargs}
    best = None
    for dx, dy in LABEL_OFFSETS:
        ha = "right" if dx < 0 else "left" if dx > 0 else "center"
        va = "bottom" if dy > 0 else "top" if dy < 0 else "center"
        far = abs(dx) > 20 or abs(dy) > 20
        ann = ax.annotate(text, xy, xytext=(dx, dy), textcoords="offset points", ha=ha, va=va,
                          arrowprops={"arrowstyle": "-", "color": "0.45", "lw": 0.7,
                                      "shrinkA": 0, "shrinkB": 3} if far else None, **style)
        bb = label_extent(ann, renderer)
        x0, y0, x1, y1 = bb.x0 - pad, bb.y0 - pad, bb.x1 + pad, bb.y1 + pad
        inside = (x0 >= frame.x0 and x1 <= frame.x1 and y0 >= frame.y0 and y1 <= frame.y1)
        hit = bool(len(pts)) and bool(np.any((pts[:, 0] >= x0) & (pts[:, 0] <= x1)
                                             & (pts[:, 1] >= y0) & (pts[:, 1] <= y1)))
        clash = any(bb.overlaps(b) for b in boxes)
        if inside and not hit and not clash:
            if best is not None:
                best.remove()
            return ann
        if best is None:
            best = ann                    # kept if no place is free: the nearest one
        else:
            ann.remove()
    return best


def save(fig, path) -> Path:
    """Write ``fig`` to ``path`` (PNG by its suffix) and close it."""
    path = Path(path)
    fig.savefig(path, dpi=DPI)
    plt.close(fig)
    return path


__all__ = ["plt", "save", "DPI", "place_label"]
