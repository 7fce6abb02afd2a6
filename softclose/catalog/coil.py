"""Catalog coil springs checked at their working lengths (``select``).

A catalog row that gives its coil (``wire_d_m, coil_d_m, active_coils[, material]``,
:mod:`.files`) is judged as :func:`softclose.coil_spring.check` judges a spring made to
order (EN 13906-1 for a compression spring, EN 13906-2's body for an extension spring), for
the duty the lid asks of it:

- the rate the coil's own, ``G d^4 / (8 D^3 n)``;
- the free length the row's, moved by its tolerance to the end that deflects the spring more
  (compression: ``free_length + free_length_tolerance``, plus ``preload / rate`` as for a
  spring to order; extension: ``free_length - free_length_tolerance``), the initial tension
  the row's preload (extension);
- the working lengths: the longest and shortest |D - E| over the stroke
  (:func:`softclose.optimiser.spring_order.working_lengths`, the pair's own attachment points);
- ``spring.cycles``, ``spring.seating``, the sign-off temperatures of ``[operating]``.

A pair is not feasible when its spring fails one of :data:`DECIDING`: ``static`` (it would be
overstressed: a compression spring's tau_c at solid length above 0.56 R_m -- EN 13906-1's
static check, as ``softclose spring`` makes it: the spring must survive being pressed solid,
in assembly or abuse; an extension spring's tau at its largest working force above
0.45 R_m), ``fatigue`` (its stroke stress above the Goodman line at
``spring.cycles``) or ``buckling`` (compression: the largest deflection reaches s_K). The
other checks (the rate's rounding, the coil gaps, the body length, the initial tension, the
temperatures) are reported, not deciding: the part exists. A spring that leaves its valid
range over the stroke has no duty (the screening refuses it already).
"""

from __future__ import annotations

from ..coil_spring import Duty, check
from ..errors import ConfigError
from ..problem import sign_off_temperatures

#: the checks that make a pair infeasible
DECIDING = ("static", "fatigue", "buckling")
#: the words of a failed deciding check in a ranking row's reason
WORDS = {"static": "overstressed", "fatigue": "fails fatigue", "buckling": "buckles"}


def working_lengths(cfg) -> tuple[float, float]:
    """(longest, shortest) spring length over the stroke of ``cfg`` (m), cached per
    geometry and stroke."""
    from ..optimiser.spring_order import working_lengths as lengths
    from ..model.lid import model_key
    from ..problem import resolve
    key = (model_key(resolve(cfg)), cfg.stroke.theta_closed, cfg.stroke.theta0)
    if key not in _LENGTHS:
        if len(_LENGTHS) > 256:
            _LENGTHS.clear()
        _LENGTHS[key] = lengths(cfg)
    return _LENGTHS[key]


_LENGTHS: dict = {}


def duty(cfg, spring, lengths=None) -> Duty:
    """The duty of catalog spring ``spring`` (a :class:`.files.SpringEntry` with a coil) in
    ``cfg`` (module docstring); ``lengths``: (longest, shortest) when known. Raises
    :class:`ConfigError` when the spring leaves its valid range over the stroke."""
    longest, shortest = working_lengths(cfg) if lengths is None else lengths
    sp = cfg.spring
    common = dict(rate=spring.coil.rate, cycles=sp.cycles, seating=sp.seating,
                  temperatures_c=sign_off_temperatures(cfg),
                  reference_temperature_c=cfg.operating.reference_temperature_c)
    if spring.kind == "extension":
        free = spring.free_length - spring.free_length_tolerance
        return Duty(free_length=free, longest_length=longest,
                    shortest_length=max(shortest, free), kind="extension",
                    initial_tension=spring.preload, **common)
    free = spring.free_length + spring.free_length_tolerance + spring.preload / spring.rate
    return Duty(free_length=free, longest_length=min(longest, free), shortest_length=shortest,
                **common)


def _margin(c) -> float:
    """How far a check is from its limit, as a share of the limit (< 0: failed)."""
    if c.limit is None or c.limit == 0:
        return 1.0
    return ((c.limit - c.value) if c.relation in ("<=", "<") else
            (c.value - c.limit)) / abs(c.limit)


def _unit(c) -> tuple[float, str]:
    return {"m": (1e3, "mm"), "Pa": (1e-6, "MPa")}.get(c.unit, (1.0, c.unit))


def _words(c, res) -> str:
    scale, unit = _unit(c)
    static = ("stress at the longest working length" if res.kind == "extension" else
              "stress at solid length")
    what = {"static": static, "fatigue": "stroke stress", "buckling": "deflection"}[c.name]
    limit = {"static": "0.45 R_m =" if res.kind == "extension" else "0.56 R_m =",
             "fatigue": f"Goodman's for {res.duty.cycles:.3g} strokes",
             "buckling": "s_K"}[c.name]
    return (f"spring {WORDS[c.name]}: {what} {c.value * scale:.4g} {unit} against {limit} "
            f"{c.limit * scale:.4g} {unit}, margin {100 * _margin(c):+.1f} %")


def spring_checks(cfg, spring, lengths=None) -> dict | None:
    """The checks of a catalog spring with a coil in ``cfg`` (None without a coil):
    ``{"ok", "reason", "standard", "free_length", "working_lengths", "life", "checks": [{name,
    value, relation, limit, unit, ok, margin, deciding}], ...}``; ``ok`` is whether every
    check of :data:`DECIDING` is met, ``reason`` names each failed one with its margin."""
    coil = spring.coil
    if coil is None:
        return None
    std = "EN 13906-2 (the body; hooks not covered)" if spring.kind == "extension" else \
        "EN 13906-1"
    try:
        d = duty(cfg, spring, lengths)
    except ConfigError as exc:            # out of its valid range: the screen refuses it
        return {"ok": True, "reason": "", "standard": std, "checked": False,
                "message": f"not checked: {exc}", "checks": []}
    res = check(coil, d)
    failed = [c for c in res.checks if c.name in DECIDING and not c.ok]
    reason = "; ".join(_words(c, res) for c in failed)
    if reason:
        reason += f" ({std})"
    return {"ok": not failed, "reason": reason, "standard": std, "checked": True,
            "free_length": d.free_length,
            "working_lengths": [d.shortest_length, d.longest_length]
            if d.kind == "extension" else [d.longest_length, d.shortest_length],
            "rate": res.rate, "life": res.life, "mass": res.mass,
            "natural_frequency": res.natural_frequency, "stresses": dict(res.stresses),
            "buckling": dict(res.buckling),
            "checks": [{**c.to_json(), "margin": _margin(c), "deciding": c.name in DECIDING}
                       for c in res.checks]}


def apply(entry: dict, checks: dict | None) -> dict:
    """A ranking row with its spring's checks: ``spring_checks`` set; a failed deciding
    check makes the pair infeasible, its words first in ``reason``."""
    entry["spring_checks"] = checks
    if checks is not None and not checks["ok"]:
        entry["feasible"] = False
        entry["reason"] = checks["reason"] + (f"; {entry['reason']}" if entry["reason"] else "")
    return entry


__all__ = ["DECIDING", "duty", "spring_checks", "apply", "working_lengths"]
