"""A robust design written to a folder (what ``softclose optimise --robust --out`` writes):
the design as a config file, ``robust.json``, the histograms and where it attaches."""

from __future__ import annotations

import json
from pathlib import Path

from ..config.write import DESIGN_FILE, write_design
from ..files import write_text
from ..jsonio import jsonable
from ..optimiser.text import metrics_line


def save_robust(res, folder, figure_format: str = "png", figure_style: str | None = None
                ) -> list[Path]:
    """``res`` (a :class:`~softclose.robust.RobustResult`) in ``folder``; the paths."""
    from ..present.figures import save as save_as
    out = Path(folder)

    def save(fig, name):
        return save_as(fig, out / f"{name}.{figure_format}", figure_style)

    files = []
    if res.design is not None:
        y = res.yield_result
        files.append(write_design(
            out / DESIGN_FILE, res.design_config(),
            "the robust design of `softclose optimise --robust`"
            + ("" if res.success else " (NOT verified: see robust.json)"),
            [f"nominal lid, verified by the adaptive reference: "
             f"{metrics_line(res.metrics, None)}",
             f"{res.robust_objective}-case J over the tolerance box = {res.objective:.7g}",
             f"yield {100 * y.yield_:.2f} % (95 % interval {100 * y.yield_ci[0]:.2f} – "
             f"{100 * y.yield_ci[1]:.2f} %) over {y.samples} samples"
             if y is not None else ""]))
    files.append(write_text(out / "robust.json",
                            json.dumps(jsonable(res.to_json()), indent=1, allow_nan=False)))
    if res.yield_result is not None:
        files.append(save(res.plot(), "robust_histograms"))
    if res.design and any("[" in k for k in res.design):   # the chosen attachment points
        from ..optimiser.cache import get_model
        from ..present.figures.attachment import plot_attachments
        files.append(save(plot_attachments(get_model(res.design_config()),
                                           res.design_config()), "attachments"))
    return files


__all__ = ["save_robust"]
