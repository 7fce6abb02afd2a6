"""The robust design's box of a compression spring made to order: its own EN 15800
tolerances (SPEC §14).

With ``spring.material`` given in the config the spring is made to order: a spring maker
coils it to EN 15800 at ``spring.grade``. EN 15800 states its tolerances from the spring's
wire d, coil diameter D and active coils n (:mod:`softclose.coil_spring.tolerances`)::

    A_L0 = alpha_F k_F Q / R                  the free length (m)
    A_F  = (alpha_F k_F + 1.5 F / 100) Q      a force F at a given length (N)
         = R A_L0 + 0.015 Q F

so a box of the free length ± A_L0 and of the rate ± 1.5 Q % (relative) moves the force at
every working length L by at most R A_L0 + 0.015 Q R (L0 - L) = A_F (to first order): the
standard's own force tolerance. These are the spreads :func:`spring_rounds` gives
``design.spring_rest_length`` (absolute; with a preload the free length is
``spring_rest_length + F0 / k`` and moves with it) and ``design.spring_k`` (relative) in place
of the config's defaults; a spread of either key the user gave in ``[tolerance]`` wins.

The spring depends on the design (its rate and lengths), the design on the box: an outer
fixed point. Solve with the config's box; design the spring of the answer (the lightest that
passes, :func:`softclose.coil_spring.order.spring_order`; or the ``[spring]`` given, checked);
solve again with its EN 15800 spreads; design the spring of that answer, and while its spreads
exceed those solved with, solve again with the larger of the two, at most :data:`MAX_ROUNDS`
times. The result says which box the answer holds for (``spring_tolerance``).
"""

from __future__ import annotations

from dataclasses import replace

from ..coil_spring.order import spring_order
from ..coil_spring.tolerances import quality_factor
from ..errors import ConfigError
from ..optimiser.made_to_order import made_to_order  # noqa: F401  (re-exported)

#: the most robust solves with the spring's own box
MAX_ROUNDS = 3
#: the keys EN 15800 gives a spread of
RATE, FREE_LENGTH = "design.spring_k", "design.spring_rest_length"
#: EN 15800's force tolerance: the relative part 1.5 % x Q
FORCE_FRACTION = 0.015


def en15800_spreads(spring_check, grade: int) -> dict:
    """The EN 15800 spreads of a checked spring (a
    :class:`~softclose.coil_spring.SpringCheck`): ``{RATE: 0.015 Q (relative),
    FREE_LENGTH: A_L0 (m, absolute)}``."""
    return {RATE: FORCE_FRACTION * quality_factor(grade),
            FREE_LENGTH: float(spring_check.tolerance.free_length)}


def with_spreads(cfg, spreads: dict):
    """``cfg`` with ``[tolerance]`` spreads of the rate (relative) and the free length
    (absolute) set, and the compression spring the only kind."""
    values = {f"tolerance.{k}": (v if k == RATE else {"absolute": v})
              for k, v in spreads.items()}
    values["optimise.spring_kinds"] = ["compression"]
    return cfg.update(values)


def _spring_of(result):
    """The checked spring of a robust result's design (None with the reason)."""
    if result.design is None:
        return None, "the robust solve found no design"
    if result.kind != "compression":
        return None, (f"the design's spring is {'an' if result.kind == 'extension' else 'a'} "
                      f"{result.kind} spring; EN 15800 states compression springs' tolerances")
    try:
        order = spring_order(result.design_config())
    except ConfigError as e:
        return None, str(e)
    best = getattr(order, "best", order)      # a SpringDesign's best, or the SpringCheck
    if best is None or not best.ok:
        return None, (f"no compression spring made to order meets every check "
                      f"({getattr(order, 'message', 'the [spring] given fails')})")
    return best, None


def _spring_json(c) -> dict:
    s = c.spring
    return {"material": s.material, "wire_d": s.wire_d, "coil_d": s.coil_d,
            "active_coils": s.active_coils, "rate": c.rate,
            "rate_deviation": c.rate_deviation, "free_length": c.duty.free_length,
            "tolerance": {"force": dict(c.tolerance.force),
                          "free_length": c.tolerance.free_length}}


def _name(c) -> str:
    s = c.spring
    return (f"d {s.wire_d * 1e3:g} mm x D {s.coil_d * 1e3:g} mm x n {s.active_coils:g} "
            f"({s.material})")


def spring_rounds(cfg, solve, first=None):
    """The robust design over the box of its own spring made to order (module docstring).

    ``solve(cfg)`` is one robust solve (a :class:`~softclose.robust.result.RobustResult`);
    ``first`` its answer on ``cfg`` if already solved. Returns the last answer whose spring's
    own EN 15800 spreads lie within those it was solved with (``holds``), else the last
    answer that has a spring made to order, with ``spring_tolerance``: the grade, the spreads
    used and where each comes from, the spring d x D x n, its own spreads, every round."""
    res = solve(cfg) if first is None else first
    grade = cfg.spring.grade
    given = {k for k in (cfg.raw.get("tolerance") or {}) if k in (RATE, FREE_LENGTH)}
    config_box = {s.key: s.value for s in cfg.tolerance.spreads
                  if s.key in (RATE, FREE_LENGTH) and s.key not in given}
    if config_box.get(FREE_LENGTH) is not None:      # (a relative one: not comparable)
        config_box.pop(FREE_LENGTH)
    notes, rounds, used = [], [], None
    for i in range(MAX_ROUNDS + 1):
        spring, why = _spring_of(res)
        box = {k: (config_box.get(k, 0.0) if used is None else used[k])
               for k in (RATE, FREE_LENGTH) if k not in given}
        if spring is None:
            notes.append(f"EN 15800 box, round {i + 1}: the answer "
                         + ("for the config's box" if used is None else
                            "for the spring's box of the round before") + f" has no spring ({why})")
            rounds.append({"result": res, "box": box, "spring": None, "holds": False})
            break
        own = {k: v for k, v in en15800_spreads(spring, grade).items() if k not in given}
        holds = all(own[k] <= box[k] * (1 + 1e-9) for k in own)
        rounds.append({"result": res, "box": box, "spring": spring, "own": own,
                       "holds": holds})
        if holds or i == MAX_ROUNDS:
            break
        used = dict(own) if used is None else {k: max(used[k], own[k]) for k in own}
        res = solve(with_spreads(cfg, used))
    pick = next((r for r in reversed(rounds) if r["holds"]), None) or next(
        (r for r in reversed(rounds) if r["spring"] is not None), None)
    if pick is None:
        return replace(res, notes=res.notes + tuple(notes))
    res, spring, holds = pick["result"], pick["spring"], pick["holds"]
    spreads = dict(pick["box"])
    for s in cfg.tolerance.spreads:
        if s.key in given:
            spreads[s.key] = s.value
    absolute = {k: not s.relative for s in cfg.tolerance.spreads for k in (s.key,)
                if k in given}
    info = {"grade": grade,
            "spreads": {k: {("absolute" if absolute.get(k, k == FREE_LENGTH) else "relative"):
                            spreads.get(k, 0.0)} for k in (RATE, FREE_LENGTH)},
            "source": {k: ("[tolerance]" if k in given else "EN 15800" if pick["box"] is not
                           rounds[0]["box"] else "the config's box") for k in (RATE, FREE_LENGTH)},
            "spring": _spring_json(spring), "own": pick.get("own"), "holds": holds,
            "round": rounds.index(pick) + 1,
            "rounds": [{"box": r["box"], "own": r.get("own"), "holds": r["holds"],
                        "spring": None if r["spring"] is None else _spring_json(r["spring"]),
                        "objective": r["result"].objective, "success": r["result"].success}
                       for r in rounds]}
    txt = ", ".join(f"{k.removeprefix('design.')} ±" + (
        f"{100 * spreads[k]:.3g} %" if k == RATE else f"{spreads[k] * 1e3:.4g} mm")
        + (" ([tolerance]: wins over EN 15800)" if k in given else "")
        for k in (RATE, FREE_LENGTH) if spreads.get(k) is not None)
    own = ", ".join(f"{k.removeprefix('design.')} ±" + (
        f"{100 * v:.3g} %" if k == RATE else f"{v * 1e3:.4g} mm")
        for k, v in (pick.get("own") or {}).items())
    notes.append(f"EN 15800 grade {grade}: the spring made to order {_name(spring)} "
                 f"(round {rounds.index(pick) + 1} of {len(rounds)}); the answer holds for "
                 f"{txt}" + ("; the spring's own EN 15800 spreads lie within" if holds else
                             f"; the spring's own EN 15800 spreads ({own}) do NOT all lie "
                             "within: narrow optimise.spring_k / spring_rest_length bounds or "
                             "give the space (spring.max_outer_d) and run again"))
    if not holds:        # not a robust design of the spring one can order
        return replace(res, success=False, message=(
            f"the robust design does not hold for its own spring's EN 15800 box ({own}; "
            f"solved for {txt}): narrow optimise.spring_k / spring_rest_length or give the "
            "space (spring.max_outer_d)"), notes=res.notes + tuple(notes),
            spring_tolerance=info)
    return replace(res, notes=res.notes + tuple(notes), spring_tolerance=info)


__all__ = ["made_to_order", "en15800_spreads", "with_spreads", "spring_rounds", "MAX_ROUNDS"]
