"""Every figure softclose draws. The only modules that import matplotlib (Agg backend).

Each ``plot_*`` function returns a :class:`matplotlib.figure.Figure`; :func:`save` writes it
and closes it. Every axis carries its unit.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

plt.rcParams.update({"font.size": 10, "axes.grid": True, "grid.alpha": 0.3,
                     "figure.dpi": 110, "savefig.bbox": "tight"})

DPI = 120


def save(fig, path) -> Path:
    """Write ``fig`` to ``path`` (PNG by its suffix) and close it."""
    path = Path(path)
    fig.savefig(path, dpi=DPI)
    plt.close(fig)
    return path


__all__ = ["plt", "save", "DPI"]
