"""The optimum with a coil spring one can order (SPEC §14): ``[spring]`` names its wire
(``spring.material``) and not its whole geometry.

A compression spring whose points are fixed is designed inside the NLP
(:mod:`.coil_nlp`): its wire d, coil diameter D and active coils n are variables tied to the
rate, every EN 13906-1 check a constraint, so the optimum's rate and free length are those
of a spring that exists. That spring is then rounded to what a spring maker winds
(:func:`roundings`: the preferred wires of EN 10270 on either side of its d, the coils at its
D rounded down and up to a quarter coil) and the problem solved again with d and n held (D,
the free length, the damper and any free value re-chosen, every check still a constraint),
nearest rounding first; the continuous optimum's J bounds every rounding's from below, so one
within :data:`ROUNDING_GAP` of it ends the search. The best answer is verified by the
reference and its spring checked by :mod:`softclose.coil_spring`; its config names the spring
(``spring.wire_d``, ``coil_d``, ``active_coils``). When no rounding meets every check, the
answer is no design, with the NLP's spring and the roundings tried.

An extension spring, or a spring whose points are free (its working lengths then move with
them), is designed after the optimum instead, as ``softclose spring`` designs one: the
lightest that meets every check at the optimum's rate and free length; the problem is solved
again at that spring's own rate and free length and verified.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ..errors import ConfigError
from .coil_nlp import GEOMETRY, made_to_order

#: the starts of each re-solve with a rounded spring (near the first answer: few suffice)
ROUNDING_STARTS = 2
#: a rounding whose J is within this fraction of the continuous optimum's ends the search
ROUNDING_GAP = 1e-3


def with_spring(cfg, res, solve):
    """``res`` (an optimiser's result) with the coil spring that realises it (module
    docstring): the NLP's spring rounded and re-solved, or the spring designed at its rate and
    free length and the problem re-solved at that spring's own rate (``solve(cfg) ->
    result``), checked again. A result without a coil spring (no design, a gas strut, no
    spring at all) is returned as it is, with a note."""
    from .spring_order import spring_duty, spring_order
    if res.design is None or not res.success:
        return res
    if res.kind not in ("compression", "extension") or not res.design.get("spring_k"):
        return replace(res, notes=res.notes + (
            f"[spring] material: no coil spring to make ({res.kind or 'no'} spring)",))
    nlp_spring = _nlp_spring(cfg, res)
    if nlp_spring is not None:
        return _rounded(cfg, res, solve, nlp_spring)
    first = res.design_config()
    try:
        made = spring_order(first, spring_duty(first))
    except ConfigError as exc:
        return replace(res, success=False, message=f"no coil spring made to order: {exc}")
    if not made.success:
        return replace(res, success=False, message=(
            f"no coil spring made to order realises the optimum (rate "
            f"{res.design['spring_k']:.6g} N/m, free length "
            f"{res.design['spring_rest_length'] * 1e3:.2f} mm): {made.message}; widen "
            "[spring] max_outer_d / min_inner_d, choose another material, or lower "
            "spring.cycles"))
    spring = made.spring
    k, l0 = float(made.best.rate), float(res.design["spring_rest_length"])
    again = solve(cfg.update({"optimise.spring_kinds": [res.kind],
                              "optimise.spring_k": [k, k],
                              "optimise.spring_rest_length": [l0, l0]}))
    if again.design is None:
        return replace(again, success=False, message=(
            f"the spring made to order ({_name(spring)}) has no verified design: "
            f"{again.message}"))
    checked = _checked(again, {f"spring.{g}": getattr(spring, g) for g in GEOMETRY})
    notes = (f"made to order: {_name(spring)} ({spring.material}), its rate {k:.6g} N/m "
             f"against the optimum's {res.design['spring_k']:.6g} N/m: J "
             f"{res.objective:.8g} -> {again.objective:.8g} once wound",)
    return replace(again, **checked, notes=again.notes + notes)


def _checked(again, geometry: dict) -> dict:
    """The spring ``geometry`` (``spring.*`` keys) checked at the re-solved answer
    ``again``: ``success``, ``message`` (the failed checks) and ``part`` (naming the spring
    and its checks), for :func:`dataclasses.replace`."""
    from .spring_order import spring_duty, spring_order
    final = again.design_config()
    check = spring_order(final.update(geometry), spring_duty(final))
    coil = dict(check.spring_json(), ok=bool(check.ok),
                checks=[c.to_json() for c in check.checks])
    return {"success": again.success and check.ok,
            "message": again.message if check.ok else (
                f"the spring made to order fails {', '.join(check.failed)} at the re-solved "
                "design"),
            "part": None if again.part is None else replace(again.part, coil=coil)}


def _nlp_spring(cfg, res) -> dict | None:
    """The NLP's own spring (d, D, n; SI) of ``res``, when its NLP carried one."""
    from .cache import coil_nlp
    from .coil_nlp import spring_of
    if res.run is None or not coil_nlp(cfg.set("design.spring_kind", res.kind)):
        return None
    return spring_of(np.asarray(res.run.x, float)[-3:])


def roundings(cfg, spring: dict, rate: float) -> list[tuple[float, float]]:
    """(d, n) to try for the NLP's ``spring`` of ``rate``: the preferred wires on either side
    of its d (those the material covers, or the ``spring.wire_d`` given), each with its
    active coils at the spring's D rounded down and up to a quarter coil (n >= 2)."""
    from ..coil_spring import PREFERRED_WIRE_D
    from ..coil_spring import standard as en13906
    from ..coil_spring.design import COIL_ROUNDING
    from ..coil_spring.materials import material
    sp = cfg.spring
    m = material(sp.material)
    d0, D0 = spring["wire_d"], spring["coil_d"]
    if sp.wire_d is not None:
        wires = [float(sp.wire_d)]
    else:
        ok = [d for d in PREFERRED_WIRE_D if m.d_min < d <= m.d_max]
        below = [d for d in ok if d <= d0 * (1 + 1e-9)]
        above = [d for d in ok if d > d0 * (1 + 1e-9)]
        wires = below[-1:] + above[:1]
    out = []
    for d in wires:
        if sp.active_coils is not None:
            out.append((d, float(sp.active_coils)))
            continue
        n = en13906.active_coils_for_rate(m.G, d, D0, rate)
        for nr in (math.floor(n / COIL_ROUNDING) * COIL_ROUNDING,
                   math.ceil(n / COIL_ROUNDING) * COIL_ROUNDING):
            if nr >= en13906.MIN_ACTIVE_COILS and (d, nr) not in out:
                out.append((d, nr))
    return out


def _rounded(cfg, res, solve, spring: dict):
    """The NLP's spring rounded to a preferred wire and a quarter coil: the problem solved
    again with d and n held (D and the rest free, every check a constraint) for the
    roundings of :func:`roundings`, nearest first, the best verified answer kept, its spring
    checked. Holding d and n restricts the problem, so the continuous optimum's J bounds
    every rounding's from below: a rounding within :data:`ROUNDING_GAP` of it ends the
    search (no other can be better by more)."""
    tried, best = [], None
    d0, n0 = spring["wire_d"], spring["active_coils"]
    for d, n in sorted(roundings(cfg, spring, res.design["spring_k"]),
                       key=lambda dn: (abs(math.log(dn[0] / d0)), abs(dn[1] - n0))):
        if best is not None and best[0].objective <= res.objective * (1 + ROUNDING_GAP):
            tried.append(f"d {d * 1e3:g} mm, n {n:g}: not needed")
            continue
        again = solve(cfg.update({"optimise.spring_kinds": ["compression"],
                                  "optimise.starts": ROUNDING_STARTS,
                                  "spring.wire_d": d, "spring.active_coils": n}))
        tried.append(f"d {d * 1e3:g} mm, n {n:g}: " + (
            f"J = {again.objective:.8g}" if again.success else "no design"))
        if again.success and again.design is not None and (
                best is None or again.objective < best[0].objective):
            best = (again, d, n)
    if best is None:
        return replace(res, success=False, message=(
            f"no coil spring made to order of a preferred wire and a quarter coil realises "
            f"the optimum (the NLP's spring: {_name_of(spring)}; tried " + "; ".join(tried)
            + "): widen [spring] max_outer_d / min_inner_d, choose another material, or "
            "lower spring.cycles"))
    again, d, n = best
    wound = _nlp_spring(cfg, again) or dict(spring, wire_d=d, active_coils=n)
    geometry = {"spring.wire_d": d, "spring.coil_d": round(wound["coil_d"], 9),
                "spring.active_coils": n}
    notes = (f"made to order: the NLP's spring {_name_of(spring)} at J {res.objective:.8g}; "
             f"wound as {_name_of(dict(wound, wire_d=d, active_coils=n))} "
             f"({cfg.spring.material}), rate {again.design['spring_k']:.6g} N/m: J "
             f"{again.objective:.8g} (the roundings tried: " + "; ".join(tried) + ")",)
    return replace(again, **_checked(again, geometry), notes=again.notes + notes,
                   config=again.config.update(geometry) if again.config is not None else None)


def _name_of(spring: dict) -> str:
    return (f"wire {spring['wire_d'] * 1e3:.4g} mm x coil {spring['coil_d'] * 1e3:.4g} mm x "
            f"{spring['active_coils']:.4g} active coils")


def _name(spring) -> str:
    """d x D x n of a coil spring, in mm."""
    return (f"wire {spring.wire_d * 1e3:.3g} mm x coil {spring.coil_d * 1e3:.4g} mm x "
            f"{spring.active_coils:g} active coils")


__all__ = ["made_to_order", "with_spring", "GEOMETRY"]
