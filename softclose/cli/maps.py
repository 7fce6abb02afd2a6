"""The maps of ``softclose sweep`` as files, drawn by this process after the sweep.

matplotlib takes about a third of a second of CPU to import (the command imports it in a
thread while the kernel runs: :func:`softclose.cli.sweep._import_outputs`), and each map
about as much to draw. They are drawn here, one after the other, once the table is written:
no other process is started, and nothing is left running when the command ends. An
interrupted sweep draws no maps (resuming it does).
"""

from __future__ import annotations

from pathlib import Path


def write_maps(res, out: Path) -> list[Path]:
    """Draw and save the maps of ``res`` in ``out`` (this process, one after the other);
    their paths."""
    from ..present.figures.sweep import map_names, plot_maps, save_maps
    from .common import FIGURES, figure_path
    names = map_names(res)
    if names:
        figs = plot_maps(res, only=names)
        if FIGURES["format"] == "png" and FIGURES["style"] is None:
            save_maps(figs, out)
        else:
            save_maps(figs, out, FIGURES["format"], FIGURES["style"])
    return [figure_path(Path(out) / f"{n}.png") for n in names]


__all__ = ["write_maps"]
