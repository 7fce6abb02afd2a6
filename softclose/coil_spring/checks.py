"""A spring judged against its duty: one check (value, limit, relation: :class:`Check`) and
the whole verdict with the spring's EN 13906 / EN 15800 values (:class:`SpringCheck`), as
:func:`softclose.coil_spring.design.check` returns it."""

from __future__ import annotations

import math
from dataclasses import dataclass

from . import extension as en13906_2
from . import tolerances as en15800


@dataclass(frozen=True)
class Check:
    """One check: ``value <relation> limit`` (``ok``), in ``unit``. ``limit`` None: no
    limit applies (e.g. a spring that cannot buckle), and the check is met."""

    name: str
    value: float
    limit: float | None
    ok: bool
    relation: str = "<="
    unit: str = ""

    @property
    def ratio(self) -> float:
        """How far the value is from its limit (> 1: failed), for ranking near misses."""
        return 0.0 if self.limit is None else _ratio(self.value, self.limit, self.relation)

    def to_json(self) -> dict:
        return {"name": self.name, "value": self.value, "limit": self.limit, "ok": self.ok,
                "relation": self.relation, "unit": self.unit}


def _ratio(value, limit, relation) -> float:
    a, b = (value, limit) if relation in ("<=", "<") else (limit, value)
    if b > 0:
        return a / b
    return math.inf if a > b else 0.0


def _check(name, value, limit, relation="<=", unit="") -> Check:
    if limit is None:
        ok = True
    elif relation == "<=":
        ok = value <= limit
    elif relation == "<":
        ok = value < limit
    else:
        ok = value >= limit
    return Check(name, float(value), None if limit is None else float(limit), bool(ok),
                 relation, unit)


@dataclass(frozen=True, repr=False)
class SpringCheck:
    """A spring judged against its duty (:func:`check`): EN 13906-1 and EN 15800 values
    in SI, and every check. ``ok``: all checks met; ``failed``: the names of those not.

    Attributes
    ----------
    forces : dict
        ``F1``, ``F2`` at L1 and L2, ``Fn`` at L_n, ``Fc`` at L_c (N), reference temperature;
        an extension spring: ``F0`` (the initial tension), ``F1``, ``F2``.
    stresses : dict
        ``tau_k1``, ``tau_k2``, ``tau_kh`` (corrected, at the governing temperature),
        ``tau_c`` (uncorrected at solid length), ``tau_c_allowed`` = 0.56 R_m,
        ``tau_kh_allowed`` = the Goodman stroke at tau_k1 and ``cycles`` (Pa); an extension
        spring: ``tau_0`` (initial tension, as wound) and ``tau_0_allowed`` (the upper end of
        its preferred range), ``tau_2`` (uncorrected at F2) and
        ``tau_2_allowed`` = 0.45 R_m instead of tau_c and its limit.
    life : float
        Cycles the stroke stress endures (1e7: 10^7 or more; 0: fewer than 10^3).
    buckling : dict
        ``s_k`` (m, None: never buckles), ``s_2`` (m), ``safe``; an extension spring:
        ``{"s_k": None, "s_2": None, "safe": True}`` (it does not buckle).
    tolerance : Tolerances or None
        EN 15800's (compression springs); None for an extension spring.
    temperatures : tuple
        Per operating temperature: its rate and working forces.
    """

    spring: object      # the CoilSpring judged (softclose.coil_spring.design)
    duty: object        # its Duty
    grade: int
    max_outer_d: float | None
    min_inner_d: float | None
    rate: float
    rate_deviation: float
    forces: dict
    stresses: dict
    life: float
    buckling: dict
    natural_frequency: float
    mass: float
    tolerance: en15800.Tolerances | None
    governing_temperature_c: float
    temperatures: tuple
    checks: tuple

    @property
    def kind(self) -> str:
        """``"compression"`` or ``"extension"`` (the duty's)."""
        return self.duty.kind

    @property
    def ok(self) -> bool:
        return all(c.ok for c in self.checks)

    @property
    def failed(self) -> tuple:
        """Names of the checks not met."""
        return tuple(c.name for c in self.checks if not c.ok)

    def check_named(self, name: str) -> Check:
        for c in self.checks:
            if c.name == name:
                return c
        raise KeyError(name)

    @property
    def worst_ratio(self) -> float:
        """The largest value/limit of the failed checks (0 when all are met)."""
        return max((c.ratio for c in self.checks if not c.ok), default=0.0)

    def spring_json(self) -> dict:
        """SPEC §14's ``spring`` object (SI), then the details (an extension spring:
        ``kind``, ``initial_tension``, ``body_length``, ``length_for_hooks`` (L0 - L_K, for both
        hooks), ``hooks`` (what is not covered); ``solid_length``, ``min_working_length``
        and ``tolerance`` are None)."""
        s, d = self.spring, self.duty
        if self.kind == "extension":
            Lk = en13906_2.body_length(s.active_coils, s.wire_d)
            return {
                "kind": "extension", "material": s.material, "wire_d": s.wire_d,
                "coil_d": s.coil_d, "outer_d": s.outer_d, "inner_d": s.inner_d,
                "active_coils": s.active_coils, "total_coils": s.active_coils,
                "free_length": d.free_length, "solid_length": None,
                "min_working_length": None, "body_length": Lk,
                "length_for_hooks": d.free_length - Lk, "initial_tension": d.initial_tension,
                "rate": self.rate, "forces": dict(self.forces),
                "stresses": dict(self.stresses), "life": self.life,
                "buckling": dict(self.buckling), "natural_frequency": self.natural_frequency,
                "mass": self.mass, "tolerance": None, "hooks": en13906_2.HOOKS_NOTE,
                "index": s.index, "stress_correction": s.stress_correction,
                "tensile_strength": s.tensile_strength, "rate_required": d.rate,
                "rate_deviation": self.rate_deviation,
                "working_lengths": [d.shortest_length, d.longest_length],
                "wire_length": en13906_2.wire_length(s.coil_d, s.active_coils),
                "cycles": d.cycles,
                "governing_temperature_c": self.governing_temperature_c,
                "temperatures": [dict(t) for t in self.temperatures],
                "ok": self.ok, "failed": list(self.failed)}
        return {"kind": "compression",
            "material": s.material, "wire_d": s.wire_d, "coil_d": s.coil_d,
            "outer_d": s.outer_d, "inner_d": s.inner_d, "active_coils": s.active_coils,
            "total_coils": s.total_coils, "free_length": d.free_length,
            "solid_length": s.solid_length, "min_working_length": s.min_working_length,
            "rate": self.rate, "forces": dict(self.forces), "stresses": dict(self.stresses),
            "life": self.life, "buckling": dict(self.buckling),
            "natural_frequency": self.natural_frequency, "mass": self.mass,
            "tolerance": {"grade": self.tolerance.grade, "force": dict(self.tolerance.force),
                          "free_length": self.tolerance.free_length},
            "ends": s.ends, "index": s.index, "stress_correction": s.stress_correction,
            "tensile_strength": s.tensile_strength, "rate_required": d.rate,
            "rate_deviation": self.rate_deviation,
            "working_lengths": [d.longest_length, d.shortest_length],
            "min_gap_sum": s.min_gap_sum, "wire_length": s.wire_length,
            "cycles": d.cycles, "seating": d.seating,
            "governing_temperature_c": self.governing_temperature_c,
            "temperatures": [dict(t) for t in self.temperatures],
            "ok": self.ok, "failed": list(self.failed)}

    def to_json(self) -> dict:
        """``{"spring": ..., "checks": [...], "candidates": [], "ok", "failed"}`` (SPEC §14)."""
        return {"spring": self.spring_json(), "checks": [c.to_json() for c in self.checks],
                "candidates": [], "ok": self.ok, "failed": list(self.failed)}

    def to_frame(self):
        """The checks, one row each: name, value, relation, limit, unit, ok."""
        import pandas as pd
        return pd.DataFrame([{"name": c.name, "value": c.value, "relation": c.relation,
                              "limit": c.limit, "unit": c.unit, "ok": c.ok}
                             for c in self.checks])

    def __repr__(self) -> str:
        s = self.spring
        return (f"SpringCheck({s.material}, d={s.wire_d * 1e3:g} mm, "
                f"D={s.coil_d * 1e3:g} mm, n={s.active_coils:g}: "
                f"{'ok' if self.ok else 'fails ' + ', '.join(self.failed)})")
