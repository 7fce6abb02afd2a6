"""A calibration written to a folder (what ``softclose fit --out`` writes): the calibrated
config with its header, the estimates, every sample with the model beside it, the figure."""

from __future__ import annotations

from pathlib import Path

from ..files import write_text, write_with


def save_fit(res, folder, data=None, figure_format: str = "png",
             figure_style: str | None = None) -> list[Path]:
    """The hand-over of a fit in ``folder``: calibrated.toml (its header names ``data``, by
    default the strokes' files), fit.csv, samples.csv, the figure; the paths."""
    from ..present.figures import save
    out = Path(folder)
    data = [s.path for s in res.strokes] if data is None else data
    import numpy as np
    import pandas as pd
    from ..config import to_toml
    from ..version import __version__
    files = []
    cfg = res.calibrated_config()
    tol = res.tolerance()
    head = [f"softclose {__version__}: the config calibrated to measured strokes",
            "data: " + ", ".join(str(d) for d in data),
            "fitted: " + ", ".join(f"{k} = {res.values[k]!r} ± {res.std[k]:.3g} (95 %: "
                                   f"{res.ci95[k][0]:.6g} .. {res.ci95[k][1]:.6g})"
                                   for k in res.keys),
            ("[tolerance] proposal from the 95 % intervals (the lid's keys; the design "
             "variables keep the spreads of the parts to buy): " + ", ".join(
                 f"{k} = {v}" for k, v in tol.items())) if tol else
            "no [tolerance] proposal (no key of the lid determined; the design variables "
            "keep the spreads of the parts to buy)",
            "design for what is known of the lid: softclose optimise --robust --config "
            "calibrated.toml"]
    if not res.identifiable:
        head.insert(1, "WARNING: not identifiable: " + res.message)
    path = out / "calibrated.toml"
    write_text(path, to_toml(cfg, "\n".join(head)))
    files.append(path)
    table = out / "fit.csv"
    write_with(table, lambda p: res.to_frame().to_csv(p, index=False))
    files.append(table)
    rows = []
    for s in res.strokes:
        rows.append(pd.DataFrame({"file": s.path, "time_s": s.t, "measured": s.y,
                                  "model": s.model, "residual": s.y - s.model,
                                  "unit": s.unit, "fitted": np.isfinite(s.model)}))
    samples = out / "samples.csv"
    write_with(samples, lambda p: pd.concat(rows).to_csv(p, index=False))
    files.append(samples)
    files.append(save(res.plot(), out / f"fit.{figure_format}", figure_style))
    return files


__all__ = ["save_fit"]
