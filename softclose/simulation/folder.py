"""A stroke written to a folder: its trajectory (CSV with units), time histories, linkage
drawing and animation (what ``softclose simulate --out`` and ``optimise --out`` write)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..files import write_with

#: trajectory columns: (name in the result, CSV header with unit, scale)
TRAJECTORY_COLUMNS = (("t", "t [s]", 1.0), ("theta", "theta [rad]", 1.0),
                      ("theta", "theta [deg]", 180.0 / np.pi),
                      ("theta_dot", "theta_dot [rad/s]", 1.0),
                      ("theta_ddot", "theta_ddot [rad/s^2]", 1.0), ("phi", "phi [rad]", 1.0),
                      ("gamma", "gamma [rad]", 1.0), ("tip_speed", "tip_speed [m/s]", 1.0),
                      ("spring_length", "spring_length [m]", 1.0), ("energy", "energy [J]", 1.0))


def write_trajectory_csv(traj: dict, path: Path) -> Path:
    """One row per step; the header names each column with its unit (angles in radians,
    theta also in degrees)."""
    cols = [(h, np.asarray(traj[k], float) * s) for k, h, s in TRAJECTORY_COLUMNS if k in traj]
    data = np.column_stack([c for _, c in cols])
    return write_with(path, lambda p: np.savetxt(p, data, delimiter=",", fmt="%.12g",
                      header=",".join(h for h, _ in cols), comments=""))


def write_stroke_outputs(model, res, out: Path, stem: str = "stroke",
                         slow_motion: float | None = None, figure_format: str = "png",
                         figure_style: str | None = None) -> list[Path]:
    """Trajectory CSV, time histories, linkage drawing and animation of one stroke
    (``slow_motion``: the GIF's factor; None: enough for at least 60 frames), the figures
    as ``figure_format`` in ``figure_style``."""
    from ..present.figures import save as save_as
    from ..present.figures.stroke import plot_linkage, plot_time_histories, write_animation
    out = Path(out)

    def save(fig, path):
        return save_as(fig, Path(path).with_suffix("." + figure_format), figure_style)

    tr = res.trajectory
    files = [write_trajectory_csv(tr, out / f"{stem}_trajectory.csv"),
             save(plot_time_histories(res), out / f"{stem}_time.png")]
    idx = np.unique(np.linspace(0, len(tr["t"]) - 1, 5).astype(int))
    labels = [f"t={tr['t'][i]:.3f}s" for i in idx]
    files.append(save(plot_linkage(model, tr["theta"][idx], labels,
                                   title="Lid positions during the stroke"),
                      out / f"{stem}_linkage.png"))
    gif = write_animation(model, tr, out / f"{stem}_animation.gif", slow_motion=slow_motion)
    if gif:
        files.append(gif)
    return files


__all__ = ["write_stroke_outputs", "write_trajectory_csv", "TRAJECTORY_COLUMNS"]
