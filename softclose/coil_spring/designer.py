"""Designing a coil spring to a duty (:func:`design`): preferred EN 10270 wire diameters,
coil diameters on a grid within the space, active coils rounded to a quarter coil, every
check of :func:`softclose.coil_spring.design.check` met, the candidates ranked by mass."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from ..errors import ConfigError
from . import extension as en13906_2
from . import standard as en13906
from . import tolerances as en15800
from .materials import DEFAULT_MATERIAL, PREFERRED_WIRE_D, material as get_material
from .design import COIL_ROUNDING, COIL_STEP, CoilSpring, Duty, SpringCheck, _evaluate, _positive, _space


@dataclass(frozen=True, repr=False)
class SpringDesign:
    """The result of :func:`design`: the lightest spring meeting every check (``best``)
    and the candidates, the lightest passing spring of each wire diameter, by mass.

    ``success`` False: no spring meets every check; ``best`` is then the nearest miss
    (smallest largest value/limit among its failed checks) and ``message`` says which
    checks failed how often.
    """

    success: bool
    message: str
    best: SpringCheck | None
    candidates: tuple
    evaluated: int
    duty: Duty
    material: str
    failures: dict = field(default_factory=dict)

    @property
    def spring(self) -> CoilSpring | None:
        return None if self.best is None else self.best.spring

    def to_json(self) -> dict:
        """``{"spring", "checks", "candidates": [...], "success", "message", ...}`` (SPEC
        §14; a candidate is its ``spring`` object)."""
        b = self.best
        return {"spring": None if b is None else b.spring_json(),
                "checks": [] if b is None else [c.to_json() for c in b.checks],
                "candidates": [c.spring_json() for c in self.candidates],
                "success": self.success, "message": self.message,
                "evaluated": self.evaluated, "failures": dict(self.failures),
                "duty": self.duty.to_json()}

    def to_frame(self):
        """The candidates, lightest first: d, D, n, rate and its deviation, mass, L_c,
        tau_kh / tau_kH, life, s_2 / s_K, f_e."""
        import pandas as pd
        rows = []
        for r, c in enumerate(self.candidates, 1):
            s = c.spring
            row = {
                "rank": r, "material": s.material, "wire_d": s.wire_d, "coil_d": s.coil_d,
                "outer_d": s.outer_d, "active_coils": s.active_coils, "rate": c.rate,
                "rate_deviation": c.rate_deviation, "mass": c.mass}
            if c.kind == "extension":          # EN 13906-2: the body, no buckling
                row.update({
                    "body_length": en13906_2.body_length(s.active_coils, s.wire_d),
                    "tau_kh": c.stresses["tau_kh"],
                    "tau_kh_allowed": c.stresses["tau_kh_allowed"],
                    "tau_2": c.stresses["tau_2"], "tau_2_allowed": c.stresses["tau_2_allowed"],
                    "life": c.life})
            else:
                row.update({
                    "solid_length": s.solid_length, "min_working_length": s.min_working_length,
                    "tau_kh": c.stresses["tau_kh"],
                    "tau_kh_allowed": c.stresses["tau_kh_allowed"],
                    "tau_c": c.stresses["tau_c"], "tau_c_allowed": c.stresses["tau_c_allowed"],
                    "life": c.life, "s_2": c.buckling["s_2"], "s_k": c.buckling["s_k"]})
            row.update(natural_frequency=c.natural_frequency, ok=c.ok)
            rows.append(row)
        return pd.DataFrame(rows)

    def __repr__(self) -> str:
        return (f"SpringDesign({'ok' if self.success else 'no spring'}: "
                f"{self.best!r}, {len(self.candidates)} candidates)")


#: how :func:`design` ranks the springs that meet every check
RANKS = {"mass": lambda c: c.mass,
         "tolerance": lambda c: (c.tolerance.free_length, c.mass)}


def _coil_grid(lo: float, hi: float, step: float) -> list[float]:
    i0, i1 = math.ceil(lo / step - 1e-9), math.floor(hi / step + 1e-9)
    return [round(i * step, 10) for i in range(i0, i1 + 1)]


def design(duty: Duty, material: str = DEFAULT_MATERIAL, *, ends: str = "closed_ground",
           max_outer_d: float | None = None, min_inner_d: float | None = None,
           grade: int = en15800.DEFAULT_GRADE, wires=PREFERRED_WIRE_D,
           coil_step: float = COIL_STEP, coil_ds=None, rank: str = "mass") -> SpringDesign:
    """Design the lightest compression spring (or extension spring, ``duty.kind``) of
    ``material`` for ``duty``.

    For every preferred wire diameter d of EN 10270 (``wires``) the material covers, and
    every mean coil diameter D on a ``coil_step`` grid with ``4 <= D/d <= 20`` and the
    space (``D + d <= max_outer_d``, ``D - d >= min_inner_d``), the active coils are
    ``n = G d^4 / (8 D^3 R)`` rounded to a quarter coil (n >= 2), so the achieved rate
    ``R = G d^4 / (8 D^3 n)`` lies within ``0.125/n`` (relative) of the request (an
    extension spring: n >= 3, EN 13906-2, and its closed body ``(n + 1) d`` within the free
    length is one of the checks). Each spring is judged by :func:`check`; those meeting
    every check are ranked by mass.

    Parameters
    ----------
    duty : Duty
    material : str
        ``spring.material``.
    ends : str
        ``"closed_ground"`` or ``"closed"``.
    max_outer_d, min_inner_d : float, optional
        The space (m).
    grade : int
        EN 15800 grade of the tolerances reported.
    wires : sequence of float
        The wire diameters to try (m).
    coil_step : float
        The grid of D (m).
    coil_ds : sequence of float, optional
        The mean coil diameters to try instead of the grid (m), e.g. one given D.
    rank : str
        ``"mass"`` (the lightest first) or ``"tolerance"``: the smallest EN 15800 free
        length tolerance A_L0 first, then the lightest (a robust design's spring, whose
        own tolerance box must lie within the box the design holds for).

    Returns
    -------
    SpringDesign
        ``best`` the lightest spring meeting every check; ``candidates`` the lightest
        passing spring of each wire diameter, lightest first.
    """
    if not isinstance(duty, Duty):
        raise ConfigError(f"duty: expected a Duty, got {type(duty).__name__}")
    mat = get_material(material)
    min_coils = en13906.MIN_ACTIVE_COILS
    if duty.kind == "extension":
        en13906_2.check_material(mat.name)
        min_coils = en13906_2.MIN_ACTIVE_COILS
    if ends not in en13906.ENDS:
        raise ConfigError(f"spring.ends: unknown end form {ends!r} (one of "
                          f"{', '.join(en13906.ENDS)})")
    en15800.quality_factor(grade)
    max_outer_d = _space("spring.max_outer_d", max_outer_d)
    min_inner_d = _space("spring.min_inner_d", min_inner_d)
    if max_outer_d is not None and min_inner_d is not None and min_inner_d >= max_outer_d:
        raise ConfigError(f"spring.min_inner_d: {min_inner_d:.6g} m leaves no room below "
                          f"spring.max_outer_d = {max_outer_d:.6g} m")
    _positive("coil_step", coil_step, "m")
    if coil_ds is not None:
        coil_ds = [_positive("spring.coil_d", D, "m") for D in coil_ds]
    wires = [_positive("spring.wire_d", d, "m") for d in wires]
    if rank not in RANKS:
        raise ValueError(f"rank: one of {', '.join(RANKS)}, got {rank!r}")
    order = RANKS[rank]
    lo_w, hi_w = en13906.INDEX_RANGE
    best_per_wire: dict[float, SpringCheck] = {}
    nearest: SpringCheck | None = None
    failures: dict[str, int] = {}
    evaluated = 0
    for d in wires:
        if not mat.d_min < d <= mat.d_max or d > en13906.MAX_WIRE_D:
            continue
        lo, hi = lo_w * d, hi_w * d
        if min_inner_d is not None:
            lo = max(lo, min_inner_d + d)
        if max_outer_d is not None:
            hi = min(hi, max_outer_d - d)
        grid = _coil_grid(lo, hi, coil_step) if coil_ds is None else \
            sorted(D for D in coil_ds if lo * (1 - 1e-12) <= D <= hi * (1 + 1e-12))
        for D in grid:
            if not lo_w <= D / d <= hi_w:
                continue
            n_exact = en13906.active_coils_for_rate(mat.G, d, D, duty.rate)
            n = round(n_exact / COIL_ROUNDING) * COIL_ROUNDING
            if n < min_coils:
                break                           # a larger D gives still fewer coils
            spring = CoilSpring(d, D, n, mat.name, ends)
            res = _evaluate(spring, duty, grade, max_outer_d, min_inner_d)
            evaluated += 1
            if res.ok:
                cur = best_per_wire.get(d)
                if cur is None or order(res) < order(cur):
                    best_per_wire[d] = res
            else:
                for name in res.failed:
                    failures[name] = failures.get(name, 0) + 1
                if nearest is None or (res.worst_ratio, res.mass) < (nearest.worst_ratio,
                                                                      nearest.mass):
                    nearest = res
    candidates = tuple(sorted(best_per_wire.values(), key=order))
    if candidates:
        b = candidates[0]
        s = b.spring
        msg = (f"{s.material}, d = {s.wire_d * 1e3:g} mm, D = {s.coil_d * 1e3:g} mm, "
               f"n = {s.active_coils:g}: rate {b.rate:.5g} N/m ({b.rate_deviation:+.2%}), "
               f"mass {b.mass * 1e3:.3g} g; {len(candidates)} wire diameters meet every check")
        return SpringDesign(True, msg, b, candidates, evaluated, duty, mat.name, failures)
    if evaluated == 0:
        msg = ("no spring to try: no preferred wire diameter and coil diameter within "
               f"4 <= D/d <= 20, the space and n >= {min_coils:g} give the rate")
    else:
        counts = ", ".join(f"{k} {v}" for k, v in sorted(failures.items(),
                                                           key=lambda kv: -kv[1]))
        msg = (f"no spring of {mat.name} meets every check ({evaluated} tried; failures: "
               f"{counts}); nearest: {nearest!r}")
    return SpringDesign(False, msg, nearest, (), evaluated, duty, mat.name, failures)
