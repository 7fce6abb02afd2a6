"""Sweep maps: the metrics and the objective over pairs of swept keys.

For each pair of swept keys a 2 x 2 figure shows impact_theta_dot, peak_tip_speed,
closing_time and the objective, feasible designs coloured (discrete levels at round
values, labelled contour lines), infeasible ones grey or hatched by reason, the best
feasible design starred. Which designs a map shows is stated in its title:

- a grid held in memory: the slice through the best feasible design -- every other key
  fixed at that design's value (named, with its unit);
- a sampled or streamed sweep: its binned summary, each cell showing the best feasible
  design among those that fell in it (the other keys free within their ranges).

One swept key gives profiles (the four quantities against the key). Drawing does not
depend on the size of the sweep: a slice longer than :data:`MAX_CELLS` per axis is
thinned, and the binned summary has at most :data:`softclose.sweeps.tally.MAX_BINS` bins
per key; there are no per-cell Python loops.
"""

from __future__ import annotations

import re

import numpy as np

from ...problem import CATEGORIES, categorise, word_code, WORD_PARAMS, word_text
from . import current_style, DPI, plt, save
from ...files import write_with
from ...config.schema import BY_NAME
from ..display import num

#: the quantities of a map, their labels and units
QUANTITIES = {
    "impact_theta_dot": ("impact angular velocity θ'", "rad/s"),
    "peak_tip_speed": ("peak tip speed", "m/s"),
    "closing_time": ("closing time", "s"),
    "objective": ("objective J = w_i θ'² + w_p v_peak²", "-"),
}
#: names and units of the config keys a sweep may vary (geometry lengths are in metres,
#: the assembly angles in degrees)
LABELS = {
    "design.spring_k": ("spring stiffness k", "N/m"),
    "design.spring_rest_length": ("spring rest length l0", "m"),
    "design.damper_c": ("damper c", "N s/m"),
    "design.rotary_damper_c": ("rotary damper c_rot", "N m s/rad"),
    "mass.lid": ("lid mass", "kg"), "mass.crank_oa": ("crank OA mass", "kg"),
    "mass.crank_bc": ("crank BC mass", "kg"), "mass.inertia_lid": ("lid inertia", "kg m²"),
    "mass.inertia_oa": ("crank OA inertia", "kg m²"),
    "mass.inertia_bc": ("crank BC inertia", "kg m²"), "mass.gravity": ("gravity g", "m/s²"),
    "stroke.theta0_deg": ("release angle θ0", "deg"),
    "stroke.theta_closed_deg": ("closed angle", "deg"), "stroke.t_max": ("t_max", "s"),
    "simulate.step": ("integrator step", "s"), "simulate.reference_tol": ("reference tol", "-"),
    "optimise.closing_time_max": ("closing_time_max", "s"),
    "optimise.closing_time_min": ("closing_time_min", "s"),
    "optimise.holding_moment_min": ("holding_moment_min", "N m"),
    "optimise.weight_impact": ("weight_impact", "s²"),
    "optimise.weight_peak_tip": ("weight_peak_tip", "s²/m²"),
}
#: how infeasible cells are drawn, by category (fill colour, hatch)
STYLE = {"not closed": ("0.62", None), "too slow": ("0.88", "//"),
         "too fast": ("0.88", "\\\\"), "not held shut": ("0.88", "xx"),
         "rebound": ("0.88", ".."), "too heavy to open": ("0.88", "--"),
         "invalid": ("0.35", None),
         "not integrated": ("0.88", "++")}
#: most cells per axis drawn from a slice held in memory (longer axes are thinned)
MAX_CELLS = 300


def unit(key: str) -> str:
    """The unit of a config key (or vector component): its label's, else its record's."""
    if key in LABELS:
        return LABELS[key][1]
    record = BY_NAME.get(key.split("[", 1)[0])
    if record is not None and record.unit:
        return record.unit
    return "-"


def label(key: str) -> str:
    """Axis label of a config key, with its unit."""
    name = LABELS.get(key, (key, None))[0]
    return f"{name} [{unit(key)}]"


def stem(key: str) -> str:
    return re.sub(r"[^A-Za-z0-9_]+", "_", key).strip("_")


def _fmt(v, key: str | None = None) -> str:
    if key in WORD_PARAMS and not isinstance(v, str):
        return word_text(key, v)
    return num(v, spec=".4g")


def _number(key: str, v) -> float:
    """A best design's value on a map axis (a word key's word as p's number)."""
    return word_code(key, v) if key in WORD_PARAMS and isinstance(v, str) else float(v)


def _is_word(key: str) -> bool:
    return key in WORD_PARAMS


def _setting(key: str, value) -> str:
    """``key = value unit`` (a word key: ``key = word``)."""
    if _is_word(key):
        return f"{key} = {_fmt(value, key)}"
    return f"{key} = {_fmt(value)} {unit(key)}"


def _mapped(keys) -> list[int]:
    """The axes a map may show: not a word key (a spring's kind is sliced, not drawn)."""
    return [j for j, k in enumerate(keys) if k not in WORD_PARAMS]


# -- what a map shows ------------------------------------------------------------------------
class _View:
    """One map or profile: centres per axis, the quantities and the category of each cell."""

    def __init__(self, keys, centres, logs, Z, cat, best, note, contours=True, extent=None):
        self.keys, self.centres, self.logs = keys, centres, logs
        self.Z, self.cat, self.best, self.note = Z, cat, best, note
        self.contours = contours      # not over the scatter of a random sample's cells
        # per axis, the range the axis shows: the grid's own values (a cell around the first
        # and last value is cut at them), or a sampled key's range; None: the cells' edges
        self.extent = extent or [None] * len(keys)


def _views_from_columns(res) -> list[_View]:
    """Slices through the best feasible design of a grid held in memory."""
    space, cols = res.space, res.columns
    shape = space.shape
    full = {q: np.asarray(cols[q], float).reshape(shape) for q in QUANTITIES}
    cat = categorise(cols["status"], cols["reason"]).reshape(shape)
    if res.best is not None:
        bidx = np.unravel_index(int(res.best["id"]), shape)
    else:
        bidx = tuple(n // 2 for n in shape)
    multi = [j for j, n in enumerate(shape) if n >= 2 and j in _mapped(space.keys)]
    groups = [(multi[0],)] if len(multi) == 1 else \
        [(a, b) for i, a in enumerate(multi) for b in multi[i + 1:]][:15]
    views = []
    for g in groups:
        sl = tuple(slice(None) if j in g else bidx[j] for j in range(len(shape)))
        take = []
        centres = []
        for j in g:  # sorted values, thinned to MAX_CELLS
            order = np.argsort(space.values[j], kind="stable")
            order = order[::int(np.ceil(len(order) / MAX_CELLS))]
            take.append(order)
            centres.append(space.values[j][order])
        ix = np.ix_(*take)

        def pick(a, ix=ix, sl=sl):
            return a[sl][ix]
        fixed = [_setting(space.keys[j], space.values[j][bidx[j]])
                 for j in range(len(shape)) if j not in g and shape[j] >= 1]
        why = "the best feasible design's values" if res.best is not None else \
            "the middle of each axis (no feasible design)"
        note = (f"slice at {', '.join(fixed)} ({why})" if fixed else "every design of the grid")
        best = None
        if res.best is not None:
            best = tuple(_number(space.keys[j], res.best[space.keys[j]]) for j in g)
        views.append(_View([space.keys[j] for j in g], centres,
                           [space.log[j] if space.log else False for j in g],
                           {q: pick(full[q]) for q in QUANTITIES}, pick(cat), best, note,
                           extent=[_span(space.values[j]) for j in g]))
    return views


def _views_from_bins(res) -> list[_View]:
    """Maps from the binned summary (sampled or streamed sweeps)."""
    b = res.bins
    keys = [a.key for a in b.axes]
    shown = [g for g in b.groups if all(j in _mapped(keys) for j in g)]
    multi = [g for g in shown if len(g) == 1]
    groups = multi if len(multi) == 1 else [g for g in shown if len(g) == 2]
    views = []
    for g in groups:
        c = b.cells[g]
        count = np.asarray(c["count"]).reshape(c["shape"])
        feas = np.asarray(c["feasible"]).reshape(c["shape"])
        cats = np.asarray(c["categories"]).reshape(c["shape"] + (-1,))
        cat = np.where(feas > 0, -1, np.argmax(cats, axis=-1))
        cat = np.where(count == 0, -2, cat)
        Z = {q: b.grid(g, q) for q in QUANTITIES}
        others = [a for j, a in enumerate(b.axes) if j not in g and a.n >= 2]
        if res.kind == "sample":
            what = (f"{res.points:,} designs ({res.space.sampler}) in "
                    f"{' x '.join(str(b.axes[j].n) for j in g)} bins")
        else:
            what = f"{res.points:,} designs in {' x '.join(str(b.axes[j].n) for j in g)} bins"
        free = ", ".join(f"{a.key} {_fmt(a.lo, a.key)}..{_fmt(a.hi, a.key)}"
                         + ("" if _is_word(a.key) else f" {unit(a.key)}") for a in others)
        exact = all(b.axes[j].exact is not None for j in g)
        if exact and not free:
            note = f"every design of the grid ({res.points:,})"
        elif exact:
            note = f"{res.points:,} designs; each point: the best feasible design over {free}"
        else:
            note = f"{what}; each cell: its best feasible design" + \
                (f" over {free}" if free else "")
        best = None
        if res.best is not None:
            best = tuple(_number(b.axes[j].key, res.best[b.axes[j].key]) for j in g)
        views.append(_View([b.axes[j].key for j in g], [b.axes[j].centres for j in g],
                           [b.axes[j].log for j in g], Z, cat, best, note,
                           contours=res.kind == "grid",
                           extent=[_span(b.axes[j].exact) if b.axes[j].exact is not None
                                   else (b.axes[j].lo, b.axes[j].hi) for j in g]))
    return views


def _span(values):
    """(lowest, highest) of a grid axis' values; None for a single value (its cell stays)."""
    v = np.asarray(values, float)
    return (float(v.min()), float(v.max())) if len(v) > 1 and v.min() < v.max() else None


# -- drawing --------------------------------------------------------------------------------
def _levels(z: np.ndarray, log: bool):
    """Round boundaries of the colour levels (and whether they are logarithmic)."""
    from matplotlib.ticker import LogLocator, MaxNLocator
    lo, hi = float(np.min(z)), float(np.max(z))
    if hi <= lo:
        pad = abs(lo) * 0.01 or 1e-12
        lo, hi = lo - pad, hi + pad
    if log and lo > 0 and hi / lo > 30:
        lv = LogLocator(base=10, subs=(1.0, 2.0, 5.0)).tick_values(lo, hi)
        lv = lv[(lv >= lo / 10) & (lv <= hi * 10)]
        i0 = max(np.searchsorted(lv, lo, side="right") - 1, 0)
        i1 = min(np.searchsorted(lv, hi, side="left"), len(lv) - 1)
        return lv[i0:i1 + 1], True
    lv = MaxNLocator(nbins=10, steps=[1, 2, 2.5, 5, 10]).tick_values(lo, hi)
    i0 = max(np.searchsorted(lv, lo, side="right") - 1, 0)
    i1 = min(np.searchsorted(lv, hi, side="left"), len(lv) - 1)
    return lv[i0:i1 + 1], False


def _ticks(levels: np.ndarray, log: bool) -> np.ndarray:
    """Colour-bar ticks: round numbers among the level boundaries (at most about 7)."""
    from matplotlib.ticker import MaxNLocator
    if log or len(levels) <= 7:
        return levels if len(levels) <= 8 else levels[::2]
    t = MaxNLocator(nbins=6, steps=[1, 2, 2.5, 5, 10]).tick_values(levels[0], levels[-1])
    t = t[(t >= levels[0] - 1e-9 * abs(levels[0])) & (t <= levels[-1] + 1e-9 * abs(levels[-1]))]
    return t if len(t) >= 2 else levels[::max(1, len(levels) // 6)]


def _edges(c: np.ndarray, log: bool) -> np.ndarray:
    """Cell edges around centres ``c`` (midpoints, in the log for log axes)."""
    x = np.log(c) if log else np.asarray(c, float)
    if len(x) == 1:
        e = np.array([x[0] - 0.5, x[0] + 0.5]) if not log else np.array([x[0] - 0.05, x[0] + 0.05])
    else:
        m = 0.5 * (x[1:] + x[:-1])
        e = np.r_[2 * x[0] - m[0], m, 2 * x[-1] - m[-1]]
    return np.exp(e) if log else e


def _panel(fig, ax, v: _View, q: str, feas: np.ndarray, cax) -> None:
    from matplotlib.colors import BoundaryNorm
    name, u = QUANTITIES[q]
    Z = np.asarray(v.Z[q], float)
    ok = feas & np.isfinite(Z)
    xe, ye = _edges(v.centres[0], v.logs[0]), _edges(v.centres[1], v.logs[1])
    if ok.any():
        levels, logl = _levels(Z[ok], q == "objective")
        norm = BoundaryNorm(levels, 256, extend="neither")
        Zm = np.ma.masked_where(~ok, np.clip(Z, levels[0], levels[-1]))
        pm = ax.pcolormesh(xe, ye, Zm.T, cmap="viridis", norm=norm)
        cb = fig.colorbar(pm, cax=cax, spacing="uniform")
        ticks = _ticks(levels, logl)
        cb.set_ticks(ticks)
        cb.set_ticklabels([f"{t:g}" for t in ticks])
        cb.set_label(f"{name} [{u}]")
        if v.contours and ok.sum() >= 6 and min(Z.shape) >= 3:
            lines = [t for t in ticks if levels[0] < t < levels[-1]]
            if len(lines):
                X, Y = np.meshgrid(v.centres[0], v.centres[1], indexing="ij")
                cs = ax.contour(X.T, Y.T, Zm.T, levels=lines, colors="k", linewidths=0.6,
                                linestyles="solid")
                if cs.allsegs and any(len(s) for s in cs.allsegs):
                    ax.clabel(cs, inline=True, fontsize=7, fmt=lambda t: f"{t:g}")
    else:
        cax.set_visible(False)                      # nothing feasible to colour
    ax.set_title(name, fontsize=10, y=1.0, pad=4)  # a fixed place: no overlap search


def _infeasible(ax, v: _View, present: list) -> None:
    """Infeasible cells: whole cells filled by category (one mesh), hatched by reason (the
    hatch lines of one contourf per hatched category present, on the cell grid padded by
    half a cell); cells with no design (binned summaries) stay white."""
    from matplotlib.colors import ListedColormap
    xe, ye = _edges(v.centres[0], v.logs[0]), _edges(v.centres[1], v.logs[1])
    cat = np.asarray(v.cat)
    bad = cat >= 0
    if bad.any():
        cmap = ListedColormap([STYLE[c][0] for c in CATEGORIES])
        ax.pcolormesh(xe, ye, np.ma.masked_where(~bad, cat).T, cmap=cmap, vmin=-0.5,
                      vmax=len(CATEGORIES) - 0.5)
    xn = np.r_[xe[0], v.centres[0], xe[-1]]
    yn = np.r_[ye[0], v.centres[1], ye[-1]]
    padded = np.pad(cat, 1, mode="edge")
    for code, name in enumerate(CATEGORIES):
        m = padded == code
        if not m.any():
            continue
        if name not in present:
            present.append(name)
        hatch = STYLE[name][1]
        if hatch:
            ax.contourf(xn, yn, m.T.astype(float), levels=[0.5, 1.5], colors="none",
                        hatches=[hatch])
    if (cat == -2).any() and "no design" not in present:
        present.append("no design")


def _legend(fig, present, best_label):
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch
    handles = [Patch(facecolor=STYLE.get(r, ("white", None))[0], edgecolor="0.3",
                     hatch=STYLE.get(r, (None, None))[1], label=r) for r in present]
    if best_label:
        handles.append(Line2D([], [], marker="*", color="red", mec="white", ms=14, ls="none",
                              label=best_label))
    if handles:
        fig.legend(handles=handles, loc="lower center", ncol=min(len(handles), 5), fontsize=9,
                   frameon=False)


def _title(head: str, note: str, width: int) -> tuple[str, int]:
    """The figure's title: ``head`` and the note, each line of it wrapped at ``width``
    characters (a sample's note names every free key's range); and how many lines wrapping
    added."""
    import textwrap
    lines = [head] + [w for line in note.split("\n") for w in textwrap.wrap(line, width)]
    return "\n".join(lines), len(lines) - 1 - len(note.split("\n"))


def _map(v: _View, res):
    from matplotlib.ticker import MaxNLocator
    # a fixed grid of panels and colour bars (no axes stealing room for a colour bar); the
    # axes are not shared (sharing costs a tick-label search per draw): the same edges anyway
    title, extra = _title("Sweep maps; infeasible designs grey or hatched by reason", v.note,
                          140)
    fig = plt.figure(figsize=(11, 8.6))
    gs = fig.add_gridspec(2, 5, width_ratios=[1, 0.045, 0.3, 1, 0.045], left=0.08,
                          right=0.93, bottom=0.12, top=0.89 - 0.017 * extra, wspace=0.05,
                          hspace=0.14)
    axs = np.array([[fig.add_subplot(gs[i, 3 * j]) for j in range(2)] for i in range(2)])
    caxs = [fig.add_subplot(gs[i, 3 * j + 1]) for i in range(2) for j in range(2)]
    feas = v.cat == -1
    present: list[str] = []
    for ax, cax, q in zip(axs.ravel(), caxs, QUANTITIES):
        _panel(fig, ax, v, q, feas, cax)
        _infeasible(ax, v, present)
        if v.best is not None:
            ax.plot(*v.best, marker="*", color="red", mec="white", ms=16, ls="none",
                    clip_on=False, zorder=5)       # whole, also on the grid's edge
        ax.grid(False)
        if v.logs[0]:
            ax.set_xscale("log")
        else:
            ax.xaxis.set_major_locator(MaxNLocator(nbins=5, steps=[1, 2, 2.5, 5, 10]))
        if v.logs[1]:
            ax.set_yscale("log")
        else:
            ax.yaxis.set_major_locator(MaxNLocator(nbins=6, steps=[1, 2, 2.5, 5, 10]))
        _within(ax, v)
    for ax in axs[0]:
        ax.tick_params(labelbottom=False)
    for ax in axs[:, 1]:
        ax.tick_params(labelleft=False)
    for ax in axs[1]:
        ax.set_xlabel(label(v.keys[0]))
        ax.xaxis.set_label_coords(0.5, -0.1)  # fixed: tick labels have one height
    for ax in axs[:, 0]:
        ax.set_ylabel(label(v.keys[1]))
    best_label = (f"best feasible design (J = {res.best['objective']:.4g})"
                  if res.best is not None else None)
    _legend(fig, present, best_label)
    fig.suptitle(title, fontsize=10)
    return fig


def _within(ax, v: _View) -> None:
    """The axes show the grid's range, not beyond: a grid from 100 to 4000 N s/m is drawn
    from 100 to 4000 (its first and last cells cut at those values), never from -350."""
    for span, set_lim in zip(v.extent, (ax.set_xlim, ax.set_ylim)):
        if span is not None:
            set_lim(*span)


def _profile(v: _View, res):
    key = v.keys[0]
    x = np.asarray(v.centres[0])
    feas = v.cat == -1
    fig, axs = plt.subplots(2, 2, figsize=(10, 7), sharex=True)
    for ax, q in zip(axs.ravel(), QUANTITIES):
        y = np.asarray(v.Z[q], float)
        ax.plot(x, y, color="0.7", lw=1, marker=".", ms=3, label="infeasible")
        ax.plot(x, np.where(feas, y, np.nan), color="C0", lw=2, label="feasible")
        if v.best is not None:
            i = int(np.argmin(np.abs(x - v.best[0])))
            ax.plot(x[i], y[i], "r*", ms=14, label="best feasible", clip_on=False, zorder=5)
        name, u = QUANTITIES[q]
        ax.set_ylabel(f"{name} [{u}]")
        if v.logs[0]:
            ax.set_xscale("log")
        if v.extent[0] is not None:
            ax.set_xlim(*v.extent[0])
    for ax in axs[1]:
        ax.set_xlabel(label(key))
    axs[0, 0].legend(fontsize=8)
    title, extra = _title(f"Sweep over {key}", v.note, 125)
    fig.suptitle(title, fontsize=10)
    fig.subplots_adjust(left=0.08, right=0.97, bottom=0.09, top=0.87 - 0.02 * extra,
                        wspace=0.25, hspace=0.12)
    return fig


def save_maps(figs: dict, out, fmt: str = "png", style: str | None = None) -> list:
    """Write the maps as ``<stem>.<fmt>`` in ``out`` and close them. PNG on the screen
    (their layout is fixed: no tight-bbox pass, which would draw each figure twice); other
    formats and styles through :func:`softclose.present.figures.save`."""
    from pathlib import Path

    import matplotlib

    paths = []
    if fmt != "png" or (style or current_style()) != "screen":
        for name, fig in figs.items():
            fig._softclose_fixed_layout = True
            paths.append(save(fig, Path(out) / f"{name}.{fmt}", style=style))
        return paths
    with matplotlib.rc_context({"savefig.bbox": "standard"}):
        for name, fig in figs.items():
            path = Path(out) / f"{name}.png"
            write_with(path, lambda p: fig.savefig(p, dpi=DPI, pil_kwargs={"compress_level": 1}))
            plt.close(fig)
            paths.append(path)
    return paths


def _views(res) -> list[_View]:
    if res.computed == 0:
        return []
    in_memory = res.columns is not None and res.kind == "grid" and res.computed == res.points
    views = _views_from_columns(res) if in_memory else _views_from_bins(res)
    if res.fixed:       # the design keys not swept, at the config's values
        fixed = ", ".join(f"{k.split('.')[1]} = {_fmt(v)}"
                          + ("" if isinstance(v, str) else f" {unit(k)}")   # (a word: none)
                          for k, v in res.fixed.items())
        for v in views:
            v.note += f"\nnot swept: {fixed}"
    return views


def _name(v: _View) -> str:
    if len(v.keys) == 1:
        return f"profile_{stem(v.keys[0])}"
    return f"map_{stem(v.keys[0])}__{stem(v.keys[1])}"


def map_names(res) -> list[str]:
    """The file stems :func:`plot_maps` would draw, without drawing them."""
    return [_name(v) for v in _views(res)]


def plot_maps(res, only=None) -> dict:
    """The maps of a sweep result, by file stem: ``map_<k1>__<k2>`` for each pair of swept
    keys, or ``profile_<k>`` when one key is swept (``only``: these stems). Empty when
    nothing can be drawn."""
    out = {}
    for v in _views(res):
        name = _name(v)
        if only is not None and name not in only:
            continue
        out[name] = _profile(v, res) if len(v.keys) == 1 else _map(v, res)
    return out


__all__ = ["plot_maps", "save_maps", "map_names", "label", "QUANTITIES", "LABELS"]
