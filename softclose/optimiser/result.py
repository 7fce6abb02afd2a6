"""The optimiser's answers: immutable, validated, with JSON, table and figure forms.

:class:`OptimiseResult` keeps the two sets of numbers apart: ``metrics`` are the verified
ones (the adaptive reference's simulation of the optimal design) and ``optimiser`` holds
the NLP's own, each compared with the reference in ``verification``. ``objective`` is the
optimiser's J (the quantity minimised), verified against the reference's J to
:data:`softclose.problem.VERIFY_RTOL`. ``active`` names what limits the design.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from ..present.display import Display, Displayed, Table, num, with_unit
from ..problem import (DESIGN_KEYS, ENGAGE_KEYS, ENGAGE_METRICS, METRIC_KEYS, METRICS, UNITS,
                       resolve)
from .verify import Verification
from ..jsonio import jsonable
from ..simulation.simulator import Simulator


@dataclass(frozen=True)
class Active:
    """A bound or constraint that holds with equality at the optimum, and its price.

    ``dJ`` is the change of J per unit relaxation of the limit (per ``unit``; negative:
    relaxing a limiting bound lowers J), from Ipopt's multiplier, unscaled. ``scenarios``
    (robust design only) names the scenarios of the tolerance box where a constraint holds
    with equality; relaxing the limit relaxes it in all of them.
    """

    name: str
    kind: str           # "bound" (a design bound) or "constraint"
    bound: str          # "upper" or "lower"
    value: float        # the limit (SI)
    unit: str
    dJ: float
    scenarios: tuple = ()

    def to_json(self) -> dict:
        out = {"name": self.name, "kind": self.kind, "bound": self.bound,
               "value": self.value, "unit": self.unit, "dJ": self.dJ}
        if self.scenarios:
            out["scenarios"] = list(self.scenarios)
        return out

    def describe(self, J: float | None = None) -> str:
        """'spring_rest_length at its upper bound 0.12 m: dJ = -0.0123 per m of relaxation
        (1 % more lowers J by 0.6 %)'."""
        u = f" {self.unit}" if self.unit else ""
        per = f"per {self.unit}" if self.unit else "per unit"
        what = "bound" if self.kind == "bound" else "limit"
        s = (f"{self.name} at its {self.bound} {what} {self.value:.6g}{u}: dJ = {self.dJ:.3g} "
             f"{per} of relaxation")
        if J and self.value:
            pct = self.dJ * abs(self.value) / J          # % change of J per 1 % relaxation
            s += f" (1 % more room changes J by {pct:+.2g} %)"
        return s


@dataclass(frozen=True, repr=False)
class OptimiseResult(Displayed):
    """The optimiser's answer; a failure is reported in it (``success`` False), never raised.

    ``success``: Ipopt converged and (when verified) the adaptive reference confirms every
    constraint and every number; ``message`` says otherwise why and what to change.
    """

    success: bool
    message: str
    status: str
    design: dict | None
    objective: float | None
    metrics: dict | None = None
    optimiser: dict | None = None
    verification: Verification | None = None
    active: tuple = ()
    starts: tuple = ()
    nodes: int = 0
    substeps: int = 0
    #: a two-phase stroke (an end damper engaging inside it): phase 2's sub-steps (each
    #: phase has ``nodes`` intervals); None for one phase
    substeps_engaged: int | None = None
    hessian: str = ""
    iterations: int = 0
    solve_time: float = 0.0
    build_time: float = 0.0
    total_time: float = 0.0
    problem: dict = field(default_factory=dict)
    sweep: dict | None = None
    infeasibility: dict | None = None
    #: free attachment points: the kernel's screening of their box
    #: (:meth:`softclose.optimiser.screening.Screening.to_json`), else None
    screening: dict | None = None
    notes: tuple = ()
    config: object = field(default=None, repr=False, compare=False)
    run: object = field(default=None, repr=False, compare=False)    # the final Ipopt run
    nlp_key: tuple | None = field(default=None, repr=False, compare=False)
    #: the spring kind chosen, every kind tried (kind, success, objective, message), the part
    kind: str | None = None
    kinds: tuple = ()
    part: object = None

    @property
    def verified(self) -> bool:
        return self.verification is not None and self.verification.ok

    @property
    def verified_objective(self) -> float | None:
        """J of the verified metrics (the reference's)."""
        return None if self.verification is None else self.verification.objective

    def save(self, folder, slow_motion: float | None = None, figure_format: str = "png",
             figure_style: str | None = None) -> list:
        """The optimum in ``folder`` (what ``softclose optimise --out`` writes): design.toml,
        optimise.json, its figures and its stroke; the paths."""
        from .folder import save_optimum
        return save_optimum(self, folder, slow_motion, figure_format, figure_style)

    def to_json(self) -> dict:
        """success, design, objective, the verified §4 metrics, the optimiser's own numbers,
        verification, active limits, problem, starts, the coarse sweep, solver, notes."""
        out = {"success": self.success, "message": self.message, "status": self.status,
               "design": self.design, "objective": self.objective, "kind": self.kind,
               "part": None if self.part is None else self.part.to_json(),
               "kinds": list(self.kinds)}
        for k in METRIC_KEYS:
            out[k] = None if self.metrics is None else self.metrics.get(k)
        for k in ENGAGE_KEYS:       # an end damper that engages: when, and how fast
            if (self.metrics or self.optimiser or {}).get(k) is not None:
                out[k] = None if self.metrics is None else self.metrics.get(k)
        hand = None if self.verification is None else self.verification.hand
        if hand is not None:        # the §13 hand-force metrics (the opening force is §9's)
            out.update({k: v for k, v in hand.metrics().items() if k != "opening_force"})
        out["optimiser"] = self.optimiser
        out["verification"] = None if self.verification is None else self.verification.to_json()
        out["active"] = [a.to_json() for a in self.active]
        out["problem"] = self.problem
        out["starts"] = list(self.starts)
        out["sweep"] = self.sweep
        if self.screening is not None:
            out["screening"] = self.screening
        out["solver"] = {"method": "direct multiple shooting, RK4, Ipopt" + (
                             ", two phases (switched at the end damper's engagement angle, "
                             "its time free)" if self.substeps_engaged else ""),
                         "nodes": self.nodes, "substeps": self.substeps,
                         **({"phases": [{"nodes": self.nodes, "substeps": self.substeps},
                                        {"nodes": self.nodes, "substeps": self.substeps_engaged}]}
                            if self.substeps_engaged else {}),
                         "hessian": self.hessian, "iterations": self.iterations,
                         "solve_time": self.solve_time, "build_time": self.build_time,
                         "total_time": self.total_time}
        if self.infeasibility is not None:
            out["infeasibility"] = self.infeasibility
        out["notes"] = list(self.notes)
        return jsonable(out)

    def row(self) -> dict:
        """The one-row table form (:meth:`to_frame`) as a dict."""
        row = {k: (self.design or {}).get(k) for k in DESIGN_KEYS}
        row.update({k: v for k, v in (self.design or {}).items() if k not in row})  # free
        row["spring_kind"] = self.kind
        row["objective"] = self.objective
        row.update({k: (self.metrics or {}).get(k) for k in METRIC_KEYS})
        row.update({k: (self.metrics or {}).get(k) for k in ENGAGE_KEYS
                    if (self.metrics or self.optimiser or {}).get(k) is not None})
        ver = self.verification.to_json() if self.verification is not None else {}
        row.update({"success": self.success, "verified_objective": self.verified_objective,
                    "objective_relative_difference": ver.get("objective_relative_difference"),
                    "active": ", ".join(f"{a.name} ({a.bound})" for a in self.active),
                    "status": self.status, "iterations": self.iterations,
                    "total_time": self.total_time})
        return row

    def to_frame(self):
        """One row (pandas DataFrame): design, objective, the verified metrics, success,
        verified_objective and objective_relative_difference, active limits, status."""
        import pandas as pd
        return pd.DataFrame([self.row()])

    def design_config(self):
        """The config this result solved, with its optimal design as ``[design]``: what
        every function takes to analyse the optimum (``softclose.tolerance_analysis(
        res.design_config())``); ``softclose optimise --out D`` writes it as D/design.toml."""
        if self.design is None or self.config is None:
            raise ValueError("this result has no design")
        return self.config.with_design(**self.design)

    def simulate(self, trajectory: bool = True):
        """The optimal design's stroke by the fixed-step simulator (with its trajectory)."""
        if self.design is None or self.config is None:
            raise ValueError("this result has no design to simulate")
        return Simulator(resolve(self.config.with_design(**self.design)),
                         cached=True).run(trajectory=trajectory)

    def text(self) -> str:
        """What ``softclose optimise`` prints: the verdict, the problem, the design, J, the
        verified metrics beside the optimiser's own, the limits, the starts, the notes."""
        from .text import optimum_text
        return optimum_text(self)

    def _display(self) -> Display:
        bounds = self.problem.get("bounds", {})
        facts = [(k, with_unit((self.design or {}).get(k), UNITS[k])) for k in DESIGN_KEYS
                 if self.design]
        facts.append(("objective J", num(self.objective)))
        if self.verification is not None and self.verification.objective is not None:
            facts.append(("verified J", f"{num(self.verification.objective)} (adaptive "
                          "reference)"))
        eng = self.metrics if (self.metrics or {}).get("engage_time") is not None else \
            self.optimiser if (self.optimiser or {}).get("engage_time") is not None else None
        if eng is not None:
            facts.append(("end damper engages", f"at t = {num(eng['engage_time'])} s, theta' = "
                          f"{num(eng['engage_theta_dot'])} rad/s"
                          + (" (verified)" if eng is self.metrics else " (the optimiser's)")))
        tables = []
        if self.design:
            free = {k.split(".", 1)[1]: (lo, hi)
                    for k, lo, hi in (getattr(self.config, "optimise", None) and
                                      self.config.optimise.free or ())}
            tables.append(Table("design", ("key", "value", "unit", "bounds"), [
                (k, num(self.design[k], 7), UNITS.get(k, "m"),
                 " … ".join(num(b) for b in (bounds.get(k) or free.get(k) or ())))
                for k in self.design]))
        if self.metrics is not None or self.optimiser is not None:
            ver = self.verification
            agree = ver.agreement if ver is not None else {}
            rows = []
            engage = [m for m in ENGAGE_METRICS
                      if (self.metrics or self.optimiser or {}).get(m.key) is not None]
            for m in METRICS + tuple(engage):
                ref = (self.metrics or {}).get(m.key)
                own = (self.optimiser or {}).get(m.key)
                a = agree.get(m.key, {})
                rows.append((m.key, with_unit(ref, m.unit, 7) if self.metrics else "—",
                             with_unit(own, m.unit, 7),
                             "" if a.get("difference") is None else
                             f"{a['difference']:.1e} (allowed {a['tolerance']:.1e})"))
            heading = ("verified metrics (adaptive reference) beside the optimiser's own"
                       if self.metrics is not None else "the optimiser's own metrics "
                       "(not verified)")
            tables.append(Table(heading, ("metric", "verified", "optimiser", "difference"),
                                rows))
        if self.active:
            tables.append(Table("what limits the design", ("limit", "at", "dJ per unit relaxed",
                                                             "in words"),
                                [(a.name, with_unit(a.value, a.unit), f"{a.dJ:.3g}",
                                  a.describe(self.objective)) for a in self.active]))
        if self.starts:
            conv = sum(1 for r in self.starts if r.get("success"))
            facts.append(("starts", f"{conv} of {len(self.starts)} converged"))
        facts.append(("solver", f"{self.nodes} x {self.substeps} RK4 steps, {self.hessian} "
                      f"Hessian, {self.iterations} iterations, {self.total_time:.2f} s"))
        title = "OptimiseResult: " + ("verified optimum" if self.success and self.verified
                                      else "optimum (not verified)" if self.success
                                      else f"no verified optimum ({self.status})")
        return Display(title, self.success, self.message, tuple(facts), tuple(tables),
                       tuple(self.notes), short=4)

    def plot(self):
        """The optimal stroke's time histories with the verified metrics marked, and where
        the design sits within its bounds: a matplotlib Figure."""
        from ..present.figures.optimise import plot_optimum
        return plot_optimum(self)


@dataclass(frozen=True, repr=False)
class FrontResult(Displayed):
    """The verified optima for a series of closing_time_max values (the Pareto front of the
    objective against the allowed closing time)."""

    closing_times: tuple
    points: tuple          # OptimiseResult, one per closing time
    total_time: float = 0.0

    @property
    def success(self) -> bool:
        """Every point found and verified."""
        return all(p.success for p in self.points)

    @property
    def message(self) -> str:
        bad = [f"{t:g} s ({p.message or p.status})" for t, p in zip(self.closing_times, self.points)
               if not p.success]
        if not bad:
            return ""
        return (f"{len(bad)} of {len(self.points)} points have no verified optimum: "
                + "; ".join(bad))

    def save_designs(self, folder) -> dict:
        """Each point with a design as ``folder/designs/design_<i>.toml``; {index: path}."""
        from .folder import save_front_designs
        return save_front_designs(self, folder)

    def to_json(self) -> dict:
        """{"success", "message", "points": [{closing_time_max, success, design, objective,
        the §4 metrics, verification, active, message}], "total_time"}."""
        pts = []
        for t, p in zip(self.closing_times, self.points):
            j = p.to_json()
            pts.append({"closing_time_max": t, "success": p.success, "message": p.message,
                        "design": j["design"], "objective": j["objective"],
                        **{k: j[k] for k in METRIC_KEYS}, "verification": j["verification"],
                        "active": j["active"], "optimiser": j["optimiser"],
                        "iterations": p.iterations, "time": p.total_time})
        return jsonable({"success": self.success, "message": self.message, "points": pts,
                         "total_time": self.total_time})

    def to_frame(self):
        """One row per point: closing_time_max, then the columns of
        :meth:`OptimiseResult.to_frame`."""
        import pandas as pd
        return pd.DataFrame([{"closing_time_max": t, **p.row()}
                             for t, p in zip(self.closing_times, self.points)])

    def text(self) -> str:
        """What ``softclose pareto`` prints: one row per closing_time_max."""
        from .text import front_text
        return front_text(self)

    def _display(self) -> Display:
        ok = sum(1 for p in self.points if p.success)
        rows = []
        for t, p in zip(self.closing_times, self.points):
            d, m = p.design or {}, p.metrics or {}
            rows.append((num(t), "yes" if p.success else "no", num(d.get("spring_k")),
                         num(d.get("spring_rest_length")), num(d.get("damper_c")),
                         num(p.objective), num(m.get("closing_time")),
                         num(m.get("impact_tip_speed")), num(m.get("peak_tip_speed"))))
        u = UNITS
        table = Table("the front", (
            "closing_time_max [s]", "verified", f"spring_k [{u['spring_k']}]",
            f"spring_rest_length [{u['spring_rest_length']}]", f"damper_c [{u['damper_c']}]",
            "J", "closing_time [s]", "impact_tip_speed [m/s]", "peak_tip_speed [m/s]"), rows)
        facts = (("points", f"{len(self.points)}, {ok} verified"),
                 ("closing_time_max", f"{num(min(self.closing_times))} … "
                  f"{num(max(self.closing_times))} s" if self.closing_times else "—"),
                 ("time", f"{self.total_time:.2f} s"))
        return Display("FrontResult: the objective against closing_time_max", self.success,
                       self.message, facts, (table,))

    def plot(self):
        """Objective, speeds and design against closing_time_max: a matplotlib Figure."""
        from ..present.figures.optimise import plot_front
        return plot_front(self)
