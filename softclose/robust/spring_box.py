"""The robust design's box of a compression spring made to order: its own EN 15800
tolerances (SPEC §14).

With ``spring.material`` given in the config the spring is made to order: a spring maker
coils it to EN 15800 at ``spring.grade``. EN 15800 states its tolerances from the spring's
wire d, coil diameter D and active coils n (:mod:`softclose.coil_spring.tolerances`)::

    A_L0 = alpha_F k_F Q / R                  the free length (m)
    A_F  = (alpha_F k_F + 1.5 F / 100) Q      a force F at a given length (N)
         = R A_L0 + 0.015 Q F

so a box of the rate ± 1.5 Q % (relative) and of the free length ± A_L0 moves the force at
every working length L by at most R A_L0 + 0.015 Q R (L0 - L) = A_F (to first order): the
standard's own force tolerance. The free length's part enters the robust problem as what it
does to the lid, a force: ``design.spring_preload`` ± R A_L0 = alpha_F k_F Q (absolute, N;
the spring's force is F0 + k (l0 - L), so a free length l0 ± A_L0 at the rate R is a force
± R A_L0 at every length), plus 1.5 Q % of a preload F0 the design has. A spread of the
free length in millimetres would be another box for every rate: a softer spring errs less in
force per millimetre, so the robust optimum runs to the softest spring, whose A_L0 (∝ 1/R)
is then the largest, and the fixed point below never settles; in newtons the box is the
spring maker's, whatever the rate. These are the spreads :func:`spring_rounds` gives
``design.spring_k`` (relative) and ``design.spring_preload`` (absolute) in place of the
config's; a spread of either key the user gave in ``[tolerance]`` wins.

The spring depends on the design (its rate and lengths), the design on the box: an outer
fixed point. Solve with the config's box; design the spring of the answer (of the springs that
meet every check, the one with the smallest EN 15800 free-length tolerance A_L0 -- at the one
rate they all realise, the smallest force tolerance R A_L0 = alpha_F k_F Q --, then the
lightest: :func:`softclose.optimiser.spring_order.spring_order` with ``rank="tolerance"``; or the
``[spring]`` given, checked); solve again with its EN 15800 spreads; design the spring of that
answer, and while its spreads exceed those solved with, solve again with the larger of the
two, at most :data:`MAX_ROUNDS` times. The result says which box the answer holds for
(``spring_tolerance``: the spreads, and the free length's as millimetres at the spring's rate).
"""

from __future__ import annotations

from dataclasses import replace

from ..optimiser.spring_order import spring_order
from ..coil_spring.tolerances import quality_factor
from ..errors import ConfigError
from ..optimiser.made_to_order import made_to_order  # noqa: F401  (re-exported)

#: the most robust solves with the spring's own box
MAX_ROUNDS = 3
#: the keys EN 15800 gives a spread of
RATE, PRELOAD = "design.spring_k", "design.spring_preload"
#: EN 15800's force tolerance: the relative part 1.5 % x Q
FORCE_FRACTION = 0.015


def en15800_spreads(spring_check, grade: int, preload: float = 0.0) -> dict:
    """The EN 15800 spreads of a checked spring (a
    :class:`~softclose.coil_spring.SpringCheck`) of a design with preload ``preload`` (N):
    ``{RATE: 0.015 Q (relative), PRELOAD: alpha_F k_F Q + 0.015 Q |F0| (N, absolute)}``:
    the free length's A_L0 at the spring's rate R is R A_L0 = alpha_F k_F Q."""
    q = quality_factor(grade)
    t = spring_check.tolerance
    return {RATE: FORCE_FRACTION * q,
            PRELOAD: float(t.alpha_f * t.k_f * q + FORCE_FRACTION * q * abs(preload))}


def with_spreads(cfg, spreads: dict):
    """``cfg`` with ``[tolerance]`` spreads of the rate (relative) and the preload
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
        order = spring_order(result.design_config(), rank="tolerance")
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
    given = {k for k in (cfg.raw.get("tolerance") or {}) if k in (RATE, PRELOAD)}
    # the config's spreads of the two keys: the rate's relative, the preload's in newtons (a
    # relative one is of a nominal the design moves: not comparable)
    config_box = {s.key: s.value for s in cfg.tolerance.spreads
                  if s.key not in given and ((s.key == RATE and s.relative)
                                             or (s.key == PRELOAD and not s.relative))}
    notes, rounds, used = [], [], None
    for i in range(MAX_ROUNDS + 1):
        spring, why = _spring_of(res)
        box = {k: (config_box.get(k, 0.0) if used is None else used[k])
               for k in (RATE, PRELOAD) if k not in given}
        if spring is None:
            notes.append(f"EN 15800 box, round {i + 1}: the answer "
                         + ("for the config's box" if used is None else
                            "for the spring's box of the round before") + f" has no spring ({why})")
            rounds.append({"result": res, "box": box, "spring": None, "holds": False})
            break
        preload = float((res.design or {}).get("spring_preload", 0.0) or 0.0)
        own = {k: v for k, v in en15800_spreads(spring, grade, preload).items()
               if k not in given}
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
    absolute = {s.key: not s.relative for s in cfg.tolerance.spreads if s.key in given}
    rate = float(spring.rate)
    info = {"grade": grade,
            "spreads": {k: {("absolute" if absolute.get(k, k == PRELOAD) else "relative"):
                            spreads.get(k, 0.0)} for k in (RATE, PRELOAD)},
            "free_length": (None if PRELOAD in given or not absolute.get(PRELOAD, True)
                            else spreads.get(PRELOAD, 0.0) / rate),
            "source": {k: ("[tolerance]" if k in given else "EN 15800" if pick["box"] is not
                           rounds[0]["box"] else "the config's box") for k in (RATE, PRELOAD)},
            "spring": _spring_json(spring), "own": pick.get("own"), "holds": holds,
            "round": rounds.index(pick) + 1,
            "rounds": [{"box": r["box"], "own": r.get("own"), "holds": r["holds"],
                        "spring": None if r["spring"] is None else _spring_json(r["spring"]),
                        "objective": r["result"].objective, "success": r["result"].success}
                       for r in rounds]}

    def say(values: dict, mark_given: bool) -> str:
        out = []
        for k in (RATE, PRELOAD):
            v = values.get(k)
            if v is None:
                continue
            if k == RATE:
                out.append(f"spring_k ±{100 * v:.3g} %")
            else:
                out.append(f"spring_preload ±{v:.4g} N (free length ±{v / rate * 1e3:.4g} mm "
                           f"at {rate:.5g} N/m)")
            if mark_given and k in given:
                out[-1] += " ([tolerance]: wins over EN 15800)"
        return ", ".join(out)

    txt, own = say(spreads, True), say(pick.get("own") or {}, False)
    notes.append(f"EN 15800 grade {grade}: the spring made to order {_name(spring)} "
                 f"(round {rounds.index(pick) + 1} of {len(rounds)}); the answer holds for "
                 f"{txt}" + ("; the spring's own EN 15800 spreads lie within" if holds else
                             f"; the spring's own EN 15800 spreads ({own}) do NOT all lie "
                             "within: choose spring.grade = 1, a stiffer wire "
                             "(spring.material) or give the space (spring.max_outer_d), and "
                             "run again"))
    if not holds:        # not a robust design of the spring one can order
        return replace(res, success=False, message=(
            f"the robust design does not hold for its own spring's EN 15800 box ({own}; "
            f"solved for {txt}): choose spring.grade = 1 or give the space "
            "(spring.max_outer_d)"), notes=res.notes + tuple(notes),
            spring_tolerance=info)
    # the design's config names its spring (design.toml: softclose spring and the report
    # check that one): its rate lies within the box's ±1.5 Q % of the design's
    sp = spring.spring
    config = None if res.config is None else res.config.update(
        {"spring.wire_d": sp.wire_d, "spring.coil_d": sp.coil_d,
         "spring.active_coils": sp.active_coils})
    return replace(res, notes=res.notes + tuple(notes), spring_tolerance=info, config=config)


__all__ = ["made_to_order", "en15800_spreads", "RATE", "PRELOAD", "with_spreads",
           "spring_rounds", "MAX_ROUNDS"]
