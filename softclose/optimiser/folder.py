"""An optimum and a front written to a folder (what ``softclose optimise --out`` and
``softclose pareto --out`` write): the design as a config file every command takes, the JSON,
the figures and the optimum's stroke."""

from __future__ import annotations

from pathlib import Path

from ..config.write import DESIGN_FILE, write_design
from ..files import write_text
from .text import metrics_line

def save_optimum(res, folder, slow_motion: float | None = None, figure_format: str = "png",
                 figure_style: str | None = None) -> list[Path]:
    """The optimum ``res`` as a config file (``design.toml``), ``optimise.json``, its figure,
    where it attaches (co-design or a keep-out zone) and its stroke (trajectory CSV, figures,
    animation) in ``folder``; the paths."""
    from ..jsonio import dumps
    from ..present.figures import save as save_as
    from ..problem import resolve
    from ..simulation.folder import write_stroke_outputs
    from ..simulation.simulator import Simulator
    out = Path(folder)

    def save(fig, name):
        return save_as(fig, out / f"{name}.{figure_format}", figure_style)

    files = [write_design(out / DESIGN_FILE, res.design_config(),
                          "the optimum of `softclose optimise`"
                          + ("" if res.success else " (NOT verified: see optimise.json)"),
                          [f"verified by the adaptive reference: "
                           f"{metrics_line(res.metrics, res.verified_objective)}"
                           if res.verification is not None else ""])]
    sim = Simulator(resolve(res.design_config()))   # its model carries the design
    stroke = sim.run(trajectory=True)
    files.append(write_text(out / "optimise.json", dumps(res.to_json(), indent=1)))
    files.append(save(res.plot(), "optimum"))
    cfg = res.design_config()
    if any("[" in k for k in res.design) or cfg.optimise.keep_out:   # where it attaches
        from ..present.figures.attachment import plot_attachments
        from .cache import get_model
        files.append(save(plot_attachments(get_model(cfg), cfg), "attachments"))
    files += write_stroke_outputs(sim.model, stroke, out, stem="optimum",
                                  slow_motion=slow_motion, figure_format=figure_format,
                                  figure_style=figure_style)
    return files


def save_front_designs(fr, folder) -> dict:
    """Each point of the front ``fr`` with a design as ``folder/designs/design_<i>.toml`` (its
    config: closing_time_max the point's); {point index: path}."""
    designs = Path(folder) / "designs"
    paths = {}
    for i, (t, p) in enumerate(zip(fr.closing_times, fr.points)):
        if p.design is None or p.config is None:
            continue
        designs.mkdir(exist_ok=True)
        paths[i] = write_design(
            designs / f"design_{i:02d}.toml", p.design_config(),
            f"point {i} of `softclose pareto`: the optimum for closing_time_max = {t:g} s"
            + ("" if p.success else " (NOT verified)"),
            [f"verified by the adaptive reference: "
             f"{metrics_line(p.metrics, p.verified_objective)}"
             if p.verification is not None else ""])
    return paths


__all__ = ["save_optimum", "save_front_designs"]
