"""The robust optimiser's result: the robust design, its scenarios, its verification and its
yield beside the nominal optimum's (:class:`RobustResult`), and the box it was designed for
(:func:`box_summary`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from ..present.display import Display, Displayed, Table, interval, num, percent, with_unit
from ..problem import DESIGN_KEYS, ENGAGE_KEYS, ENGAGE_METRICS, METRIC_KEYS, METRICS, UNITS
from .analysis import YieldResult, yield_tables
from .box import Box
from .stats import CI_METHOD
from ..jsonio import jsonable


@dataclass(frozen=True, repr=False)
class RobustResult(Displayed):
    """The robust design, its scenarios, its verification and its yield beside the nominal
    optimum's. A failure is reported in it (``success`` False, ``message``), never raised."""

    success: bool
    message: str
    status: str
    design: dict | None
    objective: float | None
    robust_objective: str
    metrics: dict | None
    scenarios: list
    verification: dict | None
    yield_result: YieldResult | None
    nominal: dict
    nominal_yield: YieldResult | None
    box: dict
    box_scale: float
    rounds: list
    problem: dict
    solver: dict
    infeasibility: dict | None = None
    notes: tuple = ()
    times: dict = field(default_factory=dict)
    #: every corner of the box simulated in the kernel at the design: corners, violating,
    #: worst_margin, breaking (labels of corners outside the NLP that break a constraint),
    #: in_nlp (corners among the scenarios), scenarios (how many the NLP had)
    corner_check: dict | None = None
    #: the spring kind chosen, every kind tried (kind, success, objective, message), the part
    kind: str | None = None
    kinds: tuple = ()
    part: object = None
    #: the bounds and constraints that limit the robust design, with dJ per unit relaxation
    #: (:class:`softclose.optimiser.Active`, ``scenarios`` naming where each holds)
    active: tuple = ()
    #: the sign-off temperatures (°C) every scenario was checked at (SPEC §12), and the one
    #: that limits the design: the temperature of the corner with the smallest constraint
    #: margin (:func:`softclose.robust.stats.margins`) among every corner of the box at every
    #: sign-off temperature, simulated in the kernel at the design (``corner_check``); None
    #: without a design or a box
    temperatures: tuple = ()
    limiting_temperature_c: float | None = None
    #: the states every scenario was checked in (SPEC §17: ``new``, and ``end_of_life`` when
    #: ``[life]`` changes a part) and the state of that limiting corner
    states: tuple = ("new",)
    limiting_state: str | None = None
    #: a compression spring made to order: the EN 15800 box the answer holds for (grade, the
    #: spreads used, their source, the spring d x D x n; :mod:`softclose.robust.spring_box`)
    spring_tolerance: dict | None = None
    #: a co-design: the first stage's screening of the shared variables' box
    #: (:meth:`softclose.optimiser.screening.Screening.to_json`), else None
    screening: dict | None = None
    #: the config it was designed for
    config: object = field(default=None, repr=False, compare=False)

    def design_config(self):
        """The config with the robust design as ``[design]`` (``softclose optimise --robust
        --out D`` writes it as D/design.toml)."""
        if self.design is None or self.config is None:
            raise ValueError("this result has no design")
        kind = {"spring_kind": self.kind} if self.kind else {}
        return self.config.with_design(**kind, **self.design)

    @property
    def yield_(self) -> float | None:
        return None if self.yield_result is None else self.yield_result.yield_

    @property
    def yield_ci(self) -> tuple | None:
        return None if self.yield_result is None else self.yield_result.yield_ci

    def text(self) -> str:
        """What ``softclose optimise --robust`` prints: the verdict, the problem, the box,
        the design, its scenarios, what limits it, the temperatures, the yields."""
        from .text import robust_text
        return robust_text(self)

    def save(self, folder, figure_format: str = "png", figure_style: str | None = None
             ) -> list:
        """The robust design in ``folder`` (what ``softclose optimise --robust --out``
        writes): design.toml, robust.json, the histograms, where it attaches; the paths."""
        from .folder import save_robust
        return save_robust(self, folder, figure_format, figure_style)

    def to_json(self) -> dict:
        out = {"success": self.success, "status": self.status, "message": self.message,
               "design": self.design, "objective": self.objective,
               "robust_objective": self.robust_objective, "kind": self.kind,
               "part": None if self.part is None else self.part.to_json(),
               "kinds": list(self.kinds), "temperatures": list(self.temperatures),
               "limiting_temperature_c": self.limiting_temperature_c,
               "states": list(self.states), "limiting_state": self.limiting_state}
        for k in METRIC_KEYS:
            out[k] = None if self.metrics is None else self.metrics.get(k)
        for k in ENGAGE_KEYS:       # the nominal lid's end damper engages: when, how fast
            if (self.metrics or {}).get(k) is not None:
                out[k] = self.metrics[k]
        y = self.yield_result
        out.update({
            "verification": self.verification,
            "yield": None if y is None else y.yield_,
            "yield_ci": None if y is None else list(y.yield_ci),
            "ci_method": CI_METHOD,
            "required_yield": None if y is None else y.required_yield,
            "samples": None if y is None else y.samples,
            "distribution": None if y is None else y.distribution,
            "percentiles": None if y is None else y.percentiles,
            "failures": None if y is None else y.failures,
            "active": [a.to_json() for a in self.active],
            "scenarios": self.scenarios,
            "nominal": self.nominal,
            "box": self.box, "box_scale": self.box_scale,
            "rounds": self.rounds, "problem": self.problem, "solver": self.solver,
            "times": self.times})
        if self.corner_check is not None:
            out["corner_check"] = self.corner_check
        if self.spring_tolerance is not None:
            out["spring_tolerance"] = self.spring_tolerance
        if self.screening is not None:
            out["screening"] = self.screening
        if self.infeasibility is not None:
            out["infeasibility"] = self.infeasibility
        if self.notes:
            out["notes"] = list(self.notes)
        return jsonable(out)

    def to_frame(self):
        """One row per scenario: the toleranced values, the NLP's metrics, the reference's
        verdict."""
        import pandas as pd
        rows = []
        for s in self.scenarios:
            row = {"scenario": s["label"], "origin": s["origin"], **s["values"]}
            row.update({k: s.get("metrics", {}).get(k) for k in METRIC_KEYS})
            row["objective"] = s.get("objective")
            row["verified"] = s.get("verified")
            rows.append(row)
        return pd.DataFrame(rows)

    def _display(self) -> Display:
        facts = [(k, with_unit(v, UNITS.get(k, "m"))) for k, v in (self.design or {}).items()]
        facts.append((f"objective ({self.robust_objective} case)" if self.robust_objective
                       else "objective", num(self.objective)))
        y, ny = self.yield_result, self.nominal_yield
        if y is not None:
            facts.append(("yield", f"{percent(y.yield_)} (95 % interval "
                                   f"{interval(y.yield_ci)}, {num(y.samples)} samples)"))
        if ny is not None:
            facts.append(("nominal optimum's yield", f"{percent(ny.yield_)} (95 % interval "
                                                     f"{interval(ny.yield_ci)})"))
        facts.append(("scenarios", f"{len(self.scenarios)} (box scale {num(self.box_scale)})"))
        ref = getattr(getattr(self.config, "operating", None), "reference_temperature_c", None)
        if self.temperatures and tuple(self.temperatures) != (ref,):
            lim = self.limiting_temperature_c
            facts.append(("sign-off temperatures",
                          ", ".join(f"{T:g}" for T in self.temperatures) + " °C"
                          + ("" if lim is None else f" (limiting: {lim:g} °C, the corner "
                             "closest to breaking a constraint)")))
        if len(self.states) > 1:
            facts.append(("sign-off states", ", ".join(self.states).replace("_", " ") + (
                "" if self.limiting_state is None else
                f" (limiting: {self.limiting_state.replace('_', ' ')})")))
        tables = []
        if self.design:
            nom = (self.nominal or {}).get("design") or {}
            tables.append(Table("design: robust against the nominal optimum",
                                ("key", "robust", "nominal optimum", "unit"),
                                [(k, num(self.design.get(k), 7), num(nom.get(k), 7), UNITS[k])
                                 for k in DESIGN_KEYS]))
        if self.metrics:
            tables.append(Table("verified metrics of the nominal lid (adaptive reference)",
                                ("metric", "value"),
                                [(m.key, with_unit(self.metrics.get(m.key), m.unit, 7))
                                 for m in METRICS + ENGAGE_METRICS
                                 if m in METRICS or self.metrics.get(m.key) is not None]))
        if self.scenarios:
            tables.append(Table("scenarios", ("scenario", "origin", "objective", "verified"), [
                (s.get("label"), s.get("origin"), num(s.get("objective")),
                 num(s.get("verified"))) for s in self.scenarios]))
        if y is not None:
            tables.extend(yield_tables(y))
        title = "RobustResult: " + ("robust design" if self.success else
                                    f"no robust design ({self.status})")
        return Display(title, self.success, self.message, tuple(facts), tuple(tables),
                       tuple(self.notes))

    def plot(self):
        """Histograms of closing time and impact speed, nominal against robust design, over
        the same samples (a Figure)."""
        from ..present.figures.robust import plot_yield
        if self.yield_result is None:
            raise ValueError("no robust design: nothing to plot")
        ys = [y for y in (self.nominal_yield, self.yield_result) if y is not None]
        labels = (["nominal optimum"] if self.nominal_yield is not None else []) + \
            ["robust design"]
        return plot_yield(ys, labels)


def box_summary(box: Box) -> dict:
    """The box as plain values: each toleranced key's spread and whether it is relative."""
    return {k: {"spread": s, "relative": r} for k, s, r in zip(box.keys, box.spreads, box.relative)}
