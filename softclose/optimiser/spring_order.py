"""The coil spring of a config's design, made to order (SPEC §14).

The lid asks of its compression spring (between E on the lid and the anchor D) a rate
``design.spring_k``, a free length, and the lengths it works at over the stroke: the longest
and shortest |D - E| as the lid turns between ``stroke.theta_closed_deg`` and
``stroke.theta0_deg`` (purely kinematic, so the same at every operating temperature). With a
preload F0 the coil spring's free length is ``spring_rest_length + F0 / spring_k`` (its force
at the model's l0 is then F0). :func:`spring_duty` states that duty
(:class:`softclose.coil_spring.Duty`); :func:`spring_order` checks the ``[spring]`` given
(wire, coil diameter and active coils all set) or designs one
(:func:`softclose.coil_spring.design`).

An extension spring (``design.spring_kind = "extension"``, EN 13906-2) is asked for its rate,
its free length ``spring_rest_length`` (its body closed: the model's l0), its initial tension
``spring_preload`` and the same working lengths, all at or above the free length.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import ConfigError
from ..model.lid import shared_model
from ..coil_spring import PREFERRED_WIRE_D, CoilSpring, Duty, check, design
from ..coil_spring import standard
from ..coil_spring.materials import material
from ..problem import resolve

#: angles of the grid on which the spring's extremes over the stroke are bracketed
GRID = 801


def working_lengths(cfg) -> tuple[float, float]:
    """(longest, shortest) length |D - E| of the spring (m) over theta in
    [theta_closed, theta0]: the best of a grid of angles, refined by a bounded scalar search
    in the cells about it."""
    from scipy.optimize import minimize_scalar

    q = shared_model(resolve(cfg)).coordinate_fns["spring"]
    a, b = cfg.stroke.theta_closed, cfg.stroke.theta0
    grid = np.linspace(a, b, GRID)
    lv = np.asarray(q.map(GRID)(grid)[0], float).ravel()
    out = []
    for sign in (-1.0, 1.0):                      # the longest, then the shortest
        i = int(np.argmin(sign * lv))
        lo, hi = grid[max(i - 1, 0)], grid[min(i + 1, GRID - 1)]
        best = float(lv[i])
        r = minimize_scalar(lambda t: sign * float(q(t)[0]), bounds=(lo, hi),
                            method="bounded", options={"xatol": 1e-12})
        if r.success and sign * float(r.fun) < sign * best:
            best = sign * float(r.fun)
        out.append(best)
    return out[0], out[1]


def spring_duty(cfg) -> Duty:
    """What the config's lid asks of its compression or extension spring (see the module
    docstring).

    Raises
    ------
    softclose.errors.ConfigError
        In one line naming the key: the design's spring is not a coil spring
        (``design.spring_kind``), has no rate (``design.spring_k``), or leaves its side of
        its free length somewhere over the stroke (``design.spring_rest_length``).
    """
    d = cfg.design
    if d.spring_kind not in ("compression", "extension"):
        raise ConfigError(f"design.spring_kind: softclose spring makes a compression or an "
                          f"extension spring to order; the design's spring is "
                          f"{d.spring_kind!r} (set design.spring_kind = \"compression\" or "
                          "\"extension\")")
    if not d.spring_k > 0:
        raise ConfigError(f"design.spring_k: the {d.spring_kind} spring has no rate (0 N/m); "
                          "a coil spring to order needs a rate above 0")
    l0, F0 = relaxed(cfg)
    if d.spring_kind == "extension":
        return _extension_duty(cfg, l0, F0)
    free = l0 + F0 / d.spring_k
    longest, shortest = working_lengths(cfg)
    if longest > free * (1 + 1e-12):
        raise ConfigError(f"design.spring_rest_length: the compression spring's free length "
                          f"{free * 1e3:.4g} mm is shorter than its longest length over the "
                          f"stroke, {longest * 1e3:.4g} mm: it would come loose (a longer "
                          "free length or a preload keeps it in place)")
    return Duty(rate=d.spring_k, free_length=free, longest_length=min(longest, free),
                shortest_length=shortest, cycles=cfg.spring.cycles,
                seating=cfg.spring.seating)


def relaxed(cfg) -> tuple[float, float]:
    """(l0, F0) of the design's coil spring: the new spring's (``design.spring_rest_length``,
    ``design.spring_preload``), or at the end of its life when ``life.state`` says so
    (relaxed: SPEC §17, :func:`softclose.model.life.at_end_of_life`; its preload and free
    length lose the force it held shut, and its checks are at the new length)."""
    from ..model.elements import PARAM_NAMES
    from ..model.life import aged, at_end_of_life, shut_coordinates
    d, case = cfg.design, resolve(cfg)
    if not aged(case.life):
        return d.spring_rest_length, d.spring_preload
    p = at_end_of_life(case.p, case.life, shut_coordinates(shared_model(case)))
    return (float(p[PARAM_NAMES.index("spring_rest_length")]),
            float(p[PARAM_NAMES.index("spring_preload")]))


def _extension_duty(cfg, l0, F0) -> Duty:
    d = cfg.design
    free = l0
    longest, shortest = working_lengths(cfg)
    if shortest < free * (1 - 1e-12):
        raise ConfigError(f"design.spring_rest_length: the extension spring's free length "
                          f"{free * 1e3:.4g} mm is longer than its shortest length over the "
                          f"stroke, {shortest * 1e3:.4g} mm: it would go slack (a shorter "
                          "free length keeps it pulling)")
    return Duty(rate=d.spring_k, free_length=free, longest_length=longest,
                shortest_length=max(shortest, free), cycles=cfg.spring.cycles,
                seating=cfg.spring.seating, kind="extension",
                initial_tension=F0)


def spring_order(cfg, duty: Duty | None = None, rank: str = "mass"):
    """The ``[spring]`` of ``cfg`` checked against its duty (a
    :class:`~softclose.coil_spring.SpringCheck`, when ``wire_d``, ``coil_d`` and
    ``active_coils`` are all given), else designed (a
    :class:`~softclose.coil_spring.SpringDesign`: the given ``wire_d`` or ``coil_d`` held
    -- ``wire_d`` and ``active_coils`` given, D is the one of the rate --, the rest chosen,
    ranked by ``rank``: ``"mass"`` or ``"tolerance"``, see
    :func:`~softclose.coil_spring.designer.design`)."""
    duty = spring_duty(cfg) if duty is None else duty
    sp = cfg.spring
    space = dict(max_outer_d=sp.max_outer_d, min_inner_d=sp.min_inner_d, grade=sp.grade)
    if None not in (sp.wire_d, sp.coil_d, sp.active_coils):
        spring = CoilSpring(sp.wire_d, sp.coil_d, sp.active_coils, sp.material, sp.ends)
        return check(spring, duty, **space)
    wires = PREFERRED_WIRE_D if sp.wire_d is None else (sp.wire_d,)
    coils = None if sp.coil_d is None else (sp.coil_d,)
    if sp.active_coils is not None and coils is None:    # d and n held: D gives the rate
        coils = (standard.coil_d_for_rate(material(sp.material).G, sp.wire_d,
                                          sp.active_coils, duty.rate),)
    return design(duty, sp.material, ends=sp.ends, wires=wires, coil_ds=coils, rank=rank,
                  **space)


@dataclass(frozen=True)
class SpringOrder:
    """The design's spring made to order (``softclose spring``): the spring checked (a
    :class:`~softclose.coil_spring.SpringCheck`, when the config gives its wire, coil diameter
    and coils) or designed (a :class:`~softclose.coil_spring.SpringDesign`), for ``duty``."""

    result: object
    duty: object

    @property
    def checked(self) -> bool:
        from ..coil_spring import SpringCheck
        return isinstance(self.result, SpringCheck)

    @property
    def success(self) -> bool:
        return bool(self.result.ok if self.checked else self.result.success)

    @property
    def best(self):
        """The spring's checks: the one checked, or the best design (None: none found)."""
        return self.result if self.checked else self.result.best

    @property
    def message(self) -> str:
        return self._json["message"]

    def to_json(self) -> dict:
        """The checks or the design, ``mode``, ``success``, ``message`` and the duty (a
        copy: made once, :meth:`text` and :attr:`message` read it too)."""
        import copy
        return copy.deepcopy(self._json)

    @functools.cached_property
    def _json(self) -> dict:
        from ..jsonio import jsonable
        payload = self.result.to_json()
        if self.checked:
            payload.update(mode="check", success=self.success, message=(
                "the spring meets every check" if self.success else
                "the spring fails " + "; ".join(_failed(c) for c in payload["checks"]
                                                if not c["ok"])))
        else:
            payload["mode"] = "design"
            if not self.success:
                payload["message"] += MORE_ROOM[self.duty.kind == "extension"]
        payload["duty"] = self.duty.to_json()
        return jsonable(payload)

    def text(self) -> str:
        """What ``softclose spring`` prints."""
        from .spring_text import spring_text
        return spring_text(self._json)

    def save(self, folder, figure_format: str = "png", figure_style: str | None = None
             ) -> list[Path]:
        """``spring.json``, the checks and the candidates as CSV and the figure of the
        spring's force and stress over its length in ``folder``; the paths."""
        import json

        from ..files import write_text, write_with
        from ..present.figures import save
        out = Path(folder)
        files = [write_text(out / "spring.json",
                            json.dumps(self._json, indent=1, allow_nan=False) + "\n")]
        best = self.best
        if best is not None:
            files.append(write_with(out / "spring_checks.csv",
                                    lambda p: best.to_frame().to_csv(p, index=False)))
        if not self.checked:
            files.append(write_with(out / "spring_candidates.csv",
                                    lambda p: self.result.to_frame().to_csv(p, index=False)))
        if best is not None:
            from ..present.figures.spring import plot_spring
            files.append(save(plot_spring(best), out / f"spring.{figure_format}", figure_style))
        return files


#: what to change when no spring meets every check: (a compression spring, an extension one)
MORE_ROOM = (" (more room: spring.max_outer_d, spring.min_inner_d; fewer spring.cycles; "
             "shot-peened wire; another free length or rate of the design)",
             " (more room: spring.max_outer_d, spring.min_inner_d; fewer spring.cycles; a "
             "longer free length, a stiffer rate or a lower initial tension of the design)")


def _failed(c: dict) -> str:
    """A failed check in words: 'buckling: 26.99 mm, limit < 13.62 mm'."""
    scale, shown = {"m": (1e3, "mm"), "Pa": (1e-6, "MPa"), "1": (100.0, "%")}.get(
        c["unit"], (1.0, c["unit"]))
    return (f"{c['name']}: {c['value'] * scale:.4g} {shown}, limit {c['relation']} "
            f"{c['limit'] * scale:.4g} {shown}")


def order_spring(cfg) -> SpringOrder:
    """The spring of ``cfg``'s design made to order: checked when the config gives its
    wire, coil diameter and coils, else designed (:func:`spring_order`), for its duty
    (:func:`spring_duty`)."""
    duty = spring_duty(cfg)
    return SpringOrder(spring_order(cfg, duty), duty)


__all__ = ["working_lengths", "spring_duty", "relaxed", "spring_order", "order_spring", "SpringOrder", "GRID"]
