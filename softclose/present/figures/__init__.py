"""Every figure softclose draws. The only modules that import matplotlib (Agg backend).

Each ``plot_*`` function returns a :class:`matplotlib.figure.Figure`; :func:`save` writes it
(PNG, PDF or SVG by the suffix) and closes it. Every axis carries its unit. Two styles: the
screen's (as drawn) and a report's (:func:`restyle`: a 3.5 in column, 8-pt text, vector);
``with style("report"):`` or :func:`set_style` picks one for what is drawn and saved.
"""

from __future__ import annotations

import os
from pathlib import Path

import matplotlib
import numpy as np

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from ...errors import ConfigError
from ...files import write_with

plt.rcParams.update({"font.size": 10, "axes.grid": True, "grid.alpha": 0.3,
                     "figure.dpi": 110, "savefig.bbox": "tight"})

DPI = 120
#: the file formats a figure is written in (by the path's suffix)
FORMATS = ("png", "pdf", "svg")
#: the styles: "screen" (as drawn) and "report" (a column of a paper: see :func:`restyle`)
STYLES = ("screen", "report")
#: a report's column width and the width of a figure across both columns (in)
COLUMN_WIDTH = 3.5
TEXT_WIDTH = 7.16
#: a report's base font size (pt); a screen figure's text is scaled from 10 pt to it
REPORT_FONT = 8.0
#: the smallest font of a report figure (pt)
REPORT_MIN_FONT = 5.5
#: the least a figure is shrunk to fit the report's width with its text at 8 pt (below it,
#: the panels would crowd their labels: the figure shrinks as the text, 0.8)
MIN_SCALE = 0.55
#: resolution of the raster parts (colour meshes) of a vector report figure
VECTOR_DPI = 300

#: environment variables that set the defaults of a process (``studies/report_figures.py
#: --format pdf`` runs every study with them): the format every figure is saved in (the
#: path's suffix replaced), and the style
ENV_FORMAT = "SOFTCLOSE_FIGURE_FORMAT"
ENV_STYLE = "SOFTCLOSE_FIGURE_STYLE"

_current = {"style": os.environ.get(ENV_STYLE) or "screen"}


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


def check_style(name: str) -> str:
    if name not in STYLES:
        raise ConfigError(f"figure style {name!r}: expected one of {', '.join(STYLES)}")
    return name


def set_style(name: str) -> None:
    """The style of the figures drawn and saved from now on: "screen" or "report"."""
    _current["style"] = check_style(name)


def current_style() -> str:
    return _current["style"]


class style:
    """``with softclose.present.figures.style("report"): fig = res.plot()`` -- figures drawn
    (through a result's ``.plot()``) and saved (:func:`save`) in the block take the style."""

    def __init__(self, name: str):
        self.name = check_style(name)

    def __enter__(self):
        self._old = _current["style"]
        _current["style"] = self.name
        return self

    def __exit__(self, *exc):
        _current["style"] = self._old
        return False


def restyle(fig, name: str | None = None):
    """``fig`` in the style ``name`` (default: the current one), changed in place and
    returned.

    "report": a figure drawn at most 7 in wide (one panel, or a column of them) becomes one
    column of a paper, :data:`COLUMN_WIDTH` = 3.5 in wide; a wider one (panels side by
    side) the width of both columns, :data:`TEXT_WIDTH`, unless that shrinks it below
    :data:`MIN_SCALE` (then the figure shrinks as its text does); the height keeps the aspect. The
    text goes from the screen's 10 pt to :data:`REPORT_FONT` = 8 pt (every size scaled alike,
    none below :data:`REPORT_MIN_FONT`), lines and markers thin in proportion; colour meshes
    are rasterised inside a vector file (the axes, text and lines stay vector). A figure is
    restyled once.
    """
    name = check_style(name or _current["style"])
    if name == "screen" or getattr(fig, "_softclose_style", None) == name:
        return fig
    from matplotlib.collections import QuadMesh
    from matplotlib.lines import Line2D
    from matplotlib.text import Text
    w, h = fig.get_size_inches()
    width = COLUMN_WIDTH if w <= 7.0 else TEXT_WIDTH
    k = REPORT_FONT / 10.0
    fixed = getattr(fig, "_softclose_fixed_layout", False)
    # a figure laid out by fractions (the sweep maps) keeps its text's share of the height:
    # its height shrinks as the text does; the others keep their aspect
    if width / w < MIN_SCALE:
        # many panels side by side (a 15 in grid of six) cannot shrink to the page with
        # their text: the whole figure shrinks as its text does, to be scaled in the report
        fig.set_size_inches(w * k, h * k)
    else:
        fig.set_size_inches(width, h * (k if fixed else width / w))
    for t in fig.findobj(Text):
        t.set_fontsize(max(REPORT_MIN_FONT, round(t.get_fontsize() * k, 1)))
    for ln in fig.findobj(Line2D):
        ln.set_linewidth(ln.get_linewidth() * 0.75)
        ln.set_markersize(ln.get_markersize() * 0.7)
    for ax in fig.axes:
        ax.tick_params(width=0.6, length=2.5, pad=2)
        for sp in ax.spines.values():
            sp.set_linewidth(0.6)
        leg = ax.get_legend()
        if leg is not None:
            leg.get_frame().set_linewidth(0.5)
    for m in fig.findobj(QuadMesh):
        m.set_rasterized(True)
    if fig.get_layout_engine() is None and not fixed:
        try:
            fig.tight_layout(pad=0.3)
        except (ValueError, RuntimeError):
            pass
    fig._softclose_style = name
    return fig


def figure_format(path) -> str:
    """The format of a figure file by its suffix (png, pdf, svg); anything else is refused
    with one line naming the path."""
    fmt = Path(path).suffix.lower().lstrip(".")
    if fmt not in FORMATS:
        raise ConfigError(f"{path}: a figure is written as {', '.join('.' + f for f in FORMATS)}"
                          f" (by the suffix), not {Path(path).suffix or 'without one'}")
    return fmt


def save(fig, path, style: str | None = None) -> Path:
    """Write ``fig`` to ``path`` -- PNG, PDF or SVG by its suffix -- in ``style`` (default
    the current one: :func:`set_style`), and close it. Vector files keep their text as text
    (PDF: TrueType fonts; SVG: text elements)."""
    path = Path(path)
    if os.environ.get(ENV_FORMAT):
        path = path.with_suffix("." + os.environ[ENV_FORMAT].lstrip("."))
    fmt = figure_format(path)
    restyle(fig, style)
    rc = {"pdf.fonttype": 42, "svg.fonttype": "none"}
    with matplotlib.rc_context(rc):
        write_with(path, lambda p: fig.savefig(p, dpi=DPI if fmt == "png" else VECTOR_DPI,
                                               format=fmt))
    plt.close(fig)
    return path


def save_with_table(folder, table: str, frame, figure: str, plot, figure_format: str = "png",
                    style: str | None = None) -> list[Path]:
    """A result's table and figure in ``folder``: ``frame`` (a pandas DataFrame) as
    ``table`` without the index, then the figure ``plot()`` draws as ``figure`` (its stem)
    in ``figure_format`` and ``style``; the two paths, table first. The figure is drawn only
    once the table is on disk: a failure or a Ctrl-C while matplotlib draws still leaves
    the numbers."""
    path = Path(folder) / table
    write_with(path, lambda p: frame.to_csv(p, index=False))
    return [path, save(plot(), Path(folder) / f"{figure}.{figure_format}", style)]


__all__ = ["plt", "save", "save_with_table", "DPI", "FORMATS", "STYLES", "set_style",
           "current_style", "style",
           "restyle", "figure_format", "place_label"]
