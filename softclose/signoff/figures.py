"""The report's figures: the lid open and closed, its spring and dashpot over the stroke
(the attachment figure), the stroke at each operating temperature, and the hand force with
its zones at each."""

from __future__ import annotations

import io

import numpy as np

from ..present.figures import plt
from ..present.figures.attachment import plot_attachments
from ..present.figures.handforce import plot_hand_force
from ..present.figures.stroke import plot_linkage


def plot_strokes(strokes: dict, limit: float | None = None):
    """theta and the tip speed against time, one line per temperature ({T: StrokeResult}
    with trajectories), the closing-time limit dashed."""
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(6.5, 5.2), sharex=True)
    for i, (T, res) in enumerate(sorted(strokes.items())):
        tr = res.trajectory
        if not tr:
            continue
        label = f"{T:g} °C" + (f": closes at {res.closing_time:.4g} s" if res.closed
                               else ": does not close")
        a1.plot(tr["t"], np.degrees(tr["theta"]), color=f"C{i}", lw=2, label=label)
        a2.plot(tr["t"], tr["tip_speed"], color=f"C{i}", lw=2)
    if limit is not None:
        for a in (a1, a2):
            a.axvline(limit, color="k", ls="--", lw=1)
        a1.annotate("closing_time_max", (limit, a1.get_ylim()[1]), xytext=(-3, -12),
                    textcoords="offset points", fontsize=8, ha="right")
    a1.set_ylabel(r"$\theta$ [deg]")
    a2.set_ylabel(r"tip speed $|v_T|$ [m/s]")
    a2.set_xlabel("time t [s]")
    a1.set_title("The closing stroke at each operating temperature")
    a1.legend(fontsize=8, loc="best")
    fig.tight_layout()
    return fig


class Figures(dict):
    """The report's figures (matplotlib Figures) by name, in the order the report shows
    them; each one's SVG (:func:`figure_svg`) is drawn once and kept, for the HTML page and
    the PDF alike (a figure changed after its first SVG keeps that SVG)."""

    def __init__(self, *args, **kw):
        super().__init__(*args, **kw)
        self.svgs = {}


def figure_svg(figs: dict, name: str) -> str:
    """Figure ``name`` of ``figs`` as SVG, its text as SVG text (light, searchable, set in
    the reader's fonts), cropped to what is drawn, without a date: drawn once for a
    :class:`Figures`."""
    from matplotlib import rc_context
    memo = getattr(figs, "svgs", {})
    if name not in memo:
        buf = io.StringIO()
        with rc_context({"svg.fonttype": "none"}):
            figs[name].savefig(buf, format="svg", bbox_inches="tight", metadata={"Date": None})
        memo[name] = buf.getvalue()
    return memo[name]


def report_figures(result) -> Figures:
    """The figures of a :class:`~softclose.signoff.ReportResult`, by name, in the order the
    report shows them (a :class:`Figures`)."""
    d = result.drawing
    model, st = d["model"], d["cfg"].stroke
    figs = {"linkage": plot_linkage(model, [st.theta0, st.theta_closed], ["open", "closed"],
                                    title="The lid open and closed"),
            "attachments": plot_attachments(model, d["cfg"], title="The spring and the "
                                                                   "dashpot over the stroke"),
            "strokes": plot_strokes(d["strokes"], result.problem["closing_time_max"])}
    for T, hf in d["hands"].items():
        if hf is not None:
            figs[f"hand_force_{T:g}C"] = plot_hand_force(hf, title=f"Hand force at {T:g} °C")
    return Figures(figs)


def close(figs: dict) -> None:
    for f in figs.values():
        plt.close(f)


__all__ = ["plot_strokes", "report_figures", "close", "Figures", "figure_svg"]
