"""The optimiser's answers: immutable, validated, with JSON, table and figure forms.

:class:`OptimiseResult` keeps the two sets of numbers apart: ``metrics`` are the verified
ones (the adaptive reference's simulation of the optimal design) and ``optimiser`` holds
the NLP's own, each compared with the reference in ``verification``. ``objective`` is the
optimiser's J (the quantity minimised), verified against the reference's J to
:data:`softclose.problem.VERIFY_RTOL`. ``active`` names what limits the design.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from ..problem import DESIGN_KEYS, METRIC_KEYS
from .verify import Verification


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


@dataclass(frozen=True)
class OptimiseResult:
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
    hessian: str = ""
    iterations: int = 0
    solve_time: float = 0.0
    build_time: float = 0.0
    total_time: float = 0.0
    problem: dict = field(default_factory=dict)
    sweep: dict | None = None
    infeasibility: dict | None = None
    notes: tuple = ()
    config: object = field(default=None, repr=False, compare=False)
    run: object = field(default=None, repr=False, compare=False)    # the final Ipopt run
    nlp_key: tuple | None = field(default=None, repr=False, compare=False)

    @property
    def verified(self) -> bool:
        return self.verification is not None and self.verification.ok

    @property
    def verified_objective(self) -> float | None:
        """J of the verified metrics (the reference's)."""
        return None if self.verification is None else self.verification.objective

    def to_json(self) -> dict:
        """success, design, objective, the verified §4 metrics, the optimiser's own numbers,
        verification, active limits, problem, starts, the coarse sweep, solver, notes."""
        from ..jsonio import jsonable
        out = {"success": self.success, "message": self.message, "status": self.status,
               "design": self.design, "objective": self.objective}
        for k in METRIC_KEYS:
            out[k] = None if self.metrics is None else self.metrics.get(k)
        out["optimiser"] = self.optimiser
        out["verification"] = None if self.verification is None else self.verification.to_json()
        out["active"] = [a.to_json() for a in self.active]
        out["problem"] = self.problem
        out["starts"] = list(self.starts)
        out["sweep"] = self.sweep
        out["solver"] = {"method": "direct multiple shooting, RK4, Ipopt",
                         "nodes": self.nodes, "substeps": self.substeps,
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
        row["objective"] = self.objective
        row.update({k: (self.metrics or {}).get(k) for k in METRIC_KEYS})
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
        from ..simulate import Simulator
        if self.design is None or self.config is None:
            raise ValueError("this result has no design to simulate")
        return Simulator(self.config.with_design(**self.design)).run(trajectory=trajectory)

    def plot(self):
        """The optimal stroke's time histories with the verified metrics marked, and where
        the design sits within its bounds: a matplotlib Figure."""
        from ..figures.optimise import plot_optimum
        return plot_optimum(self)


@dataclass(frozen=True)
class FrontResult:
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

    def to_json(self) -> dict:
        """{"success", "message", "points": [{closing_time_max, success, design, objective,
        the §4 metrics, verification, active, message}], "total_time"}."""
        from ..jsonio import jsonable
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

    def plot(self):
        """Objective, speeds and design against closing_time_max: a matplotlib Figure."""
        from ..figures.optimise import plot_front
        return plot_front(self)
