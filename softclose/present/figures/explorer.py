"""The explorer's figure (:mod:`softclose.notebook.explorer`): the stroke, the tip speed and the
spring's length against time, and the objective over the neighbourhood of springs and
dampers with the current design marked; redrawn in place as a slider moves."""

from __future__ import annotations

import numpy as np

from . import plt


class ExplorerFigure:
    """One figure of four panels, drawn again by :meth:`draw` (the same Figure object)."""

    def __init__(self):
        self.fig, ax = plt.subplots(2, 2, figsize=(10, 6.4), layout="constrained")
        self.ax = ax.ravel()
        self.colorbar = None

    def draw(self, data: dict, values: dict):
        """Draw the explorer's ``data`` (:meth:`softclose.notebook.explorer.Explorer.update`) for the
        slider ``values``; returns the Figure."""
        a_th, a_v, a_l, a_map = self.ax
        for a in self.ax:
            a.clear()
        t = data["t"]
        m = data["metrics"]
        a_th.plot(t, np.degrees(data["theta"]), color="C0")
        a_th.set_ylabel("lid angle θ [deg]")
        state = (f"closes in {m['closing_time']:.3f} s" if m["closed"] else m["status"]) + \
            ("" if m["feasible"] else "  (infeasible)")
        a_th.set_title(state, fontsize=10)
        a_v.plot(t, data["tip_speed"], color="C2")
        a_v.set_ylabel("tip speed |v_T| [m/s]")
        if m["peak_tip_speed"] is not None:
            a_v.set_title(f"peak {m['peak_tip_speed']:.3f} m/s"
                          + (f", impact {m['impact_tip_speed']:.3f} m/s" if m["closed"] else ""),
                          fontsize=10)
        a_l.plot(t, 1e3 * np.asarray(data["spring_length"]), color="C3")
        a_l.set_ylabel("spring length [mm]")
        for a in (a_th, a_v, a_l):
            a.set_xlabel("time t [s]")
            a.grid(alpha=0.3)
        J = np.ma.masked_invalid(data["J"])
        mesh = a_map.pcolormesh(data["k"], data["c"], J, shading="nearest", cmap="viridis")
        if (~data["feasible"]).any():
            a_map.contourf(data["k"], data["c"], (~data["feasible"]).astype(float),
                           levels=[0.5, 1.5], colors="none", hatches=["///"])
        a_map.plot(values["spring_k"], values["damper_c"], "r*", ms=12, mec="w")
        a_map.set_xlabel("spring k [N/m]")
        a_map.set_ylabel("damper c [N s/m]")
        a_map.set_title(f"objective J [-] around the design (hatched: infeasible; "
                        f"l0 = {1e3 * values['spring_rest_length']:.1f} mm, "
                        f"m = {values['lid_mass']:.3g} kg)", fontsize=9)
        if self.colorbar is None:
            self.colorbar = self.fig.colorbar(mesh, ax=a_map, label="objective J [-]")
        else:
            self.colorbar.update_normal(mesh)
        return self.fig


__all__ = ["ExplorerFigure"]
