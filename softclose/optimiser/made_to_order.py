"""The optimum with a coil spring one can order (SPEC §14): ``[spring]`` names its wire
(``spring.material``) and not its geometry.

The optimiser's rate and free length are not yet a part. The spring that realises them is
designed as ``softclose spring`` designs one (:mod:`softclose.coil_spring`: preferred wires
of EN 10270, coil diameters within the space, a quarter coil; every EN 13906 check met over
the stroke's working lengths and at every sign-off temperature; the lightest), so its wire,
coil diameter and coils are rounded to what a spring maker winds. Its own rate R = G d^4 /
(8 D^3 n) then differs from the optimum's by up to a quarter coil's worth; the problem is
solved again with the spring's rate and free length fixed (the damper and any other free
value re-chosen) and that answer is verified by the reference and checked again. When no
spring in the space meets every check at the optimum, the answer is no design, with the
checks that fail.

The wire, the coil diameter and the coils are chosen after the continuous optimum, not as
variables of the NLP: the checks depend on the rate and the free length alone (the stroke's
working lengths are the geometry's), so the spring found at the optimum is the one the NLP's
region allows at that rate; a design whose rate no spring can carry is reported as such.
"""

from __future__ import annotations

from dataclasses import replace

from ..errors import ConfigError

#: the keys of a spring's geometry in ``[spring]``: all three given, the spring is checked
GEOMETRY = ("wire_d", "coil_d", "active_coils")


def made_to_order(cfg) -> bool:
    """Does ``cfg`` ask for a coil spring made to order (``spring.material`` given, its
    geometry not)?"""
    raw = cfg.raw.get("spring", {}) if isinstance(cfg.raw, dict) else {}
    return "material" in raw and not all(k in raw for k in GEOMETRY)


def with_spring(cfg, res, solve):
    """``res`` (an optimiser's result) with the coil spring that realises it: the spring
    designed at its rate and free length, the problem solved again at the spring's own rate
    (``solve(cfg) -> result``), checked again. A result without a coil spring (no design, a
    gas strut, no spring at all) is returned as it is, with a note."""
    from ..coil_spring.order import spring_duty, spring_order
    if res.design is None or not res.success:
        return res
    if res.kind not in ("compression", "extension") or not res.design.get("spring_k"):
        return replace(res, notes=res.notes + (
            f"[spring] material: no coil spring to make ({res.kind or 'no'} spring)",))
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
    final = again.design_config()
    check = spring_order(final.update({f"spring.{g}": getattr(spring, g) for g in GEOMETRY}),
                         spring_duty(final))
    coil = dict(check.spring_json(), ok=bool(check.ok),
                checks=[c.to_json() for c in check.checks])
    part = None if again.part is None else replace(again.part, coil=coil)
    notes = (f"made to order: {_name(spring)} ({spring.material}), its rate {k:.6g} N/m "
             f"against the optimum's {res.design['spring_k']:.6g} N/m: J "
             f"{res.objective:.8g} -> {again.objective:.8g} once wound",)
    ok = again.success and check.ok
    message = again.message if check.ok else (
        f"the spring made to order fails {', '.join(check.failed)} at the re-solved design")
    return replace(again, success=ok, message=message, part=part,
                   notes=again.notes + notes)


def _name(spring) -> str:
    """d x D x n of a coil spring, in mm."""
    return (f"wire {spring.wire_d * 1e3:.3g} mm x coil {spring.coil_d * 1e3:.4g} mm x "
            f"{spring.active_coils:g} active coils")


__all__ = ["made_to_order", "with_spring", "GEOMETRY"]
