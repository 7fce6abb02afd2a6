"""An interactive explorer of one lid: sliders for the spring, its rest length, the damper and
the lid's mass; the stroke, the tip speed and the spring's length redrawn as a slider moves,
with a map of the objective over the neighbourhood of the springs and dampers.

The kernel answers in microseconds, so every move re-runs the stroke and the whole map
(:meth:`Explorer.update`, ~5 ms for a 21 x 21 map): no figure is precomputed. The lid's mass
is a column of the kernel's rows (the coefficients are affine in it), so moving it rebuilds
nothing. :meth:`Explorer.update` is plain numbers in, arrays out (tested without a browser);
:meth:`Explorer.widget` wraps it in ipywidgets sliders and a matplotlib figure
(:mod:`softclose.present.figures.explorer`) for a notebook.
"""

from __future__ import annotations

import numpy as np

from ..simulation.kernel import binding
from ..config import Config
from ..problem import DESIGN_KEYS, feasible, objective, params_of, resolve
from ..simulation.simulator import Simulator
from ..simulation.stroke import StrokeStatus

#: the sliders: key, label, unit
SLIDERS = (("spring_k", "spring k", "N/m"), ("spring_rest_length", "rest length l0", "m"),
           ("damper_c", "damper c", "N s/m"), ("lid_mass", "lid mass", "kg"))


class Explorer:
    """Strokes of one geometry at any spring, damper and lid mass (see the module doc).

    ``span``: the map covers the current spring_k and damper_c times (1 - span .. 1 + span)
    (clipped to the design bounds), ``n`` x ``n`` designs.
    """

    def __init__(self, cfg: Config, span: float = 0.5, n: int = 21):
        self.cfg = cfg
        self.sim = Simulator(resolve(cfg), cached=True)
        self.span, self.n = float(span), int(n)

    def bounds(self) -> dict:
        """Each slider's range: the design bounds of [optimise], the lid mass ±50 %."""
        o = self.cfg.optimise
        out = {k: tuple(getattr(o, k)) for k in DESIGN_KEYS}
        m = self.cfg.mass.lid
        out["lid_mass"] = (0.5 * m, 1.5 * m)
        return out

    def start(self) -> dict:
        """The sliders' first values: the config's design and lid mass."""
        d = self.cfg.design
        return {"spring_k": d.spring_k, "spring_rest_length": d.spring_rest_length,
                "damper_c": d.damper_c, "lid_mass": self.cfg.mass.lid}

    def update(self, spring_k: float, spring_rest_length: float, damper_c: float,
               lid_mass: float) -> dict:
        """The stroke of this design and lid mass, and the map around it.

        Returns ``t``, ``theta`` (rad), ``tip_speed`` (m/s), ``spring_length`` (m) along the
        stroke; ``metrics`` (closed, closing_time, impact_theta_dot, impact_tip_speed,
        peak_tip_speed, holding_moment, objective, feasible, status); and the map: ``k``,
        ``c`` (its axes), ``J`` (objective, NaN where the lid does not close) and
        ``feasible`` (n x n, rows along c).
        """
        sim, st = self.sim, self.cfg.stroke
        design = {"spring_k": spring_k, "spring_rest_length": spring_rest_length,
                  "damper_c": damper_c}
        p = params_of(self.cfg, design)
        m = float(lid_mass)
        row = np.r_[binding.kernel_rows(p), sim.energy_tol(p[None, :], m), m]
        out, traj = binding.run_stroke_trajectory(sim.table, sim.method, sim.step, st.t_max,
                                                 st.theta0, st.theta_closed, row)
        status = StrokeStatus(int(out[0]))
        tr = sim.derive_trajectory(traj, p, ("tip_speed", "spring_length")) if status.ok \
            else {"t": traj[:, 0], "theta": traj[:, 1], "tip_speed": np.zeros(len(traj)),
                  "spring_length": np.zeros(len(traj))}
        col = dict(zip(binding.OUT_FIELDS, out))
        closed = status is StrokeStatus.CLOSED
        hm = float(sim.holding_moments(p[None, :], m)[0])
        J = objective(self.cfg.optimise, col["impact_theta_dot"], col["peak_tip_speed"]) \
            if closed else None
        ok = bool(feasible(self.cfg.optimise, closed, col["closing_time"], hm,
                           col["theta_dot_max"])[0])
        metrics = {"closed": closed, "status": status.text,
                   "closing_time": col["closing_time"] if closed else None,
                   "impact_theta_dot": col["impact_theta_dot"] if closed else None,
                   "impact_tip_speed": col["impact_tip_speed"] if closed else None,
                   "peak_tip_speed": col["peak_tip_speed"] if status.ok else None,
                   "holding_moment": hm, "objective": J, "feasible": ok}
        return {"t": tr["t"], "theta": tr["theta"], "tip_speed": tr["tip_speed"],
                "spring_length": tr["spring_length"], "metrics": metrics,
                **self.neighbourhood(design, m)}

    def neighbourhood(self, design: dict, lid_mass: float) -> dict:
        """The objective and feasibility over spring_k x damper_c around ``design``."""
        b = self.bounds()
        axes = []
        for key in ("spring_k", "damper_c"):
            lo, hi = b[key]
            v = design[key]
            axes.append(np.linspace(max(lo, v * (1 - self.span)),
                                    min(hi, max(v * (1 + self.span), lo + 1e-9)), self.n))
        K, C = np.meshgrid(*axes)                      # rows along c, columns along k
        P = np.tile(params_of(self.cfg, design), (K.size, 1))
        P[:, 0], P[:, 2] = K.ravel(), C.ravel()
        r = self.sim.run_batch(P, lid_mass=lid_mass)
        o = self.cfg.optimise
        J = np.where(r["closed"], objective(o, r["impact_theta_dot"], r["peak_tip_speed"]),
                     np.nan)
        ok = feasible(o, r["closed"], r["closing_time"], r["holding_moment"],
                      r["theta_dot_max"])
        return {"k": axes[0], "c": axes[1], "J": J.reshape(K.shape),
                "feasible": ok.reshape(K.shape)}

    def widget(self):
        """Sliders and a live figure (ipywidgets, matplotlib) for a notebook; moving a
        slider calls :meth:`update` and redraws. Returns the widget box."""
        import ipywidgets as w

        from ..present.figures.explorer import ExplorerFigure
        b, start = self.bounds(), self.start()
        sliders = {}
        for key, label, unit in SLIDERS:
            lo, hi = b[key]
            value = float(np.clip(start[key], lo, hi))
            sliders[key] = w.FloatSlider(value=value, min=lo, max=hi, step=(hi - lo) / 200,
                                         description=f"{label} [{unit}]", readout_format=".4g",
                                         continuous_update=True,
                                         style={"description_width": "9em"},
                                         layout=w.Layout(width="32em"))
        out = w.Output()
        view = ExplorerFigure()

        def redraw(_=None):
            from IPython.display import clear_output, display
            values = {k: s.value for k, s in sliders.items()}
            data = self.update(**values)
            fig = view.draw(data, values)
            with out:
                clear_output(wait=True)
                display(fig)
            return data
        redraw()
        for s in sliders.values():
            s.observe(redraw, names="value")
        box = w.VBox([*sliders.values(), out])
        box.explorer, box.sliders, box.view, box.redraw = self, sliders, view, redraw
        return box


__all__ = ["Explorer", "SLIDERS"]
