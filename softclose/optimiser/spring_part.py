"""What to buy: the spring of a design as a part, and how precisely it must be made.

A design's spring is a part with a kind, a free length, a rate, a preload, the lengths it
works over (the stroke's), and the largest force it must carry there; a gas strut's with its
extended length, stroke, F1, progression and friction band. How precisely: the largest
deviations of its free length (mm) and rate (relative; a strut's F1) -- each on its own,
every other value nominal -- within which the design still meets every constraint of the
problem and the spring stays valid, found with the C kernel over a fine ladder of deviations
(a design on a constraint's edge has no margin on that side: the report says 0).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..model import elements
from ..model.elements.springs import GAS, strut_stroke
from ..problem import PARAM_KEYS, feasible, params_of, resolve
from ..simulation.simulator import Simulator
from ..simulation.stroke import StrokeStatus

#: the ladders of deviations tried, each side: free length (m), rate (relative)
FREE_LENGTH_STEPS = np.r_[np.arange(1, 101) * 1e-5, np.arange(11, 301) * 1e-4]   # to 30 mm
RATE_STEPS = np.r_[np.arange(1, 101) * 1e-4, np.arange(11, 501) * 1e-3]          # to 50 %


@dataclass(frozen=True)
class SpringPart:
    """The spring to buy. Lengths in m, force in N; ``tolerance``: the free length's (m) and
    the rate's (relative) margins, (below, above), within which the design still works."""

    kind: str
    free_length: float
    rate: float
    preload: float
    working_length: tuple[float, float]
    largest_force: float
    tolerance: dict = field(default_factory=dict)
    #: a gas strut's stroke (m), progression K and friction F_R (N); None for a coil spring
    stroke: float | None = None
    progression: float | None = None
    friction: float | None = None
    #: a coil spring made to order (:mod:`.made_to_order`): SPEC §14's ``spring`` object,
    #: with ``ok`` and its ``checks``; None when none was designed
    coil: dict | None = None

    def to_json(self) -> dict:
        out = {"kind": self.kind, "free_length": self.free_length, "rate": self.rate,
               "preload": self.preload, "working_length": list(self.working_length),
               "largest_force": self.largest_force,
               "tolerance": {k: list(v) for k, v in self.tolerance.items()}}
        if self.kind == "gas_strut":
            out.update(stroke=self.stroke, progression=self.progression,
                       friction=self.friction)
        if self.coil is not None:
            out["coil"] = self.coil
        return out

    def text(self) -> str:
        """Two lines: the part, and how precisely it must be made."""
        lo, hi = self.working_length
        if self.kind == "gas_strut":
            return self._strut_text()
        what = {"compression": "compression spring (pushes)",
                "extension": "extension spring (pulls)",
                "linear": "linear double-acting cartridge (pushes and pulls)"}[self.kind]
        line = (f"{what}: free length {self.free_length * 1e3:.2f} mm, rate "
                f"{self.rate:.6g} N/m, preload {self.preload:.4g} N; works between "
                f"{lo * 1e3:.2f} and {hi * 1e3:.2f} mm, largest force {self.largest_force:.4g} N")
        c = self.coil
        if c is not None:
            line += (f"\n  made to order: wire {c['wire_d'] * 1e3:.3g} mm, coil diameter "
                     f"{c['coil_d'] * 1e3:.4g} mm (outer {c['outer_d'] * 1e3:.4g} mm), "
                     f"{c['active_coils']:g} active coils, {c['material']}, "
                     f"{c['mass'] * 1e3:.3g} g: "
                     + ("every EN 13906 check met" if c["ok"] else "checks FAIL: " + ", ".join(
                         x["name"] for x in c["checks"] if not x["ok"])))
        return line + self._made_to("free length", "rate", "rate",
                                    "the spring leaves its valid range")

    def _made_to(self, length: str, key: str, name: str, beyond: str) -> str:
        """The line of the tolerances the part is made to (none without them): its
        ``length`` in mm and the tolerance ``key`` as ``name`` in per cent."""
        t = self.tolerance
        if not t:
            return ""
        fl, x = t.get("free_length", (0, 0)), t.get(key, (0, 0))
        return (f"\n  made to: {length} -{fl[0] * 1e3:.3f}/+{fl[1] * 1e3:.3f} mm, {name} "
                f"-{x[0] * 100:.2f}/+{x[1] * 100:.2f} % (each alone; beyond, a constraint "
                f"fails or {beyond})")

    def _strut_text(self) -> str:
        lo, hi = self.working_length
        L, s, K = self.free_length, self.stroke, self.progression
        line = (f"gas strut (pushes): extended length {L * 1e3:.2f} mm, stroke {s * 1e3:.2f} "
                f"mm (compressed {(L - s) * 1e3:.2f} mm), F1 {self.preload:.4g} N at the "
                f"reference temperature, progression {K:.3g} (F2 {K * self.preload:.4g} N); "
                f"works between {lo * 1e3:.2f} and {hi * 1e3:.2f} mm, largest force "
                f"{self.largest_force:.4g} N")
        if self.friction:
            line += f"; friction band F3 - F1 = {2 * self.friction:.3g} N"
        return line + self._made_to("extended length", "force", "F1",
                                    "the strut leaves its stroke")


def spring_part(cfg, design: dict | None, metrics: dict | None,
                tolerance: bool = True, model=None) -> SpringPart | None:
    """The part of ``design`` (``cfg``'s spring kind and preload) over the stroke whose
    ``metrics`` give its working lengths; None without a spring. ``tolerance``: find how
    precisely it must be made (:func:`margins`; ``model``: cfg's model, when at hand)."""
    p = params_of(cfg, design)
    P = dict(zip(PARAM_KEYS, p))
    if P["spring_k"] == 0 and P["spring_preload"] == 0 or metrics is None \
            or metrics.get("min_spring_length") is None:
        return None
    kind = cfg.design.spring_kind if design is None or "spring_kind" not in design \
        else design["spring_kind"]
    lo, hi = float(metrics["min_spring_length"]), float(metrics["max_spring_length"])
    spring = elements.BY_NAME["spring"]
    forces = [float(spring.tension(x, elements.params(p))) for x in (lo, hi)]
    strut = {}
    if kind == "gas_strut":
        strut = {"stroke": float(strut_stroke(elements.params(p))),
                 "progression": float(P["strut_progression"]),
                 "friction": float(P["strut_friction"])}
    return SpringPart(kind, float(P["spring_rest_length"]), float(P["spring_k"]),
                      float(P["spring_preload"]), (lo, hi), float(max(abs(f) for f in forces)),
                      margins(cfg, p, model) if tolerance else {}, **strut)


def margins(cfg, p, model=None) -> dict:
    """How far the free length (m) and the rate (relative) may each move, below and above,
    with the design still feasible and valid (the kernel at cfg's step, every other value
    nominal): the first deviation of the ladder that fails, less one step (found on every
    :data:`LADDER_STRIDE`-th step, then step by step below the first that fails)."""
    # the model at hand (else built), its table from the build cache when it has been built
    # before: a whole model and table cost ~20 ms against ~10 ms for the strokes
    sim = Simulator(resolve(cfg), model=model, cached=model is not None)
    p = np.asarray(p, float)
    ladders = []                  # (name, steps, column, relative, sign), each side
    gas = p[PARAM_KEYS.index("spring_kind")] == GAS        # (a strut's force: its F1)
    for key, steps, relative in (("spring_rest_length", FREE_LENGTH_STEPS, False),
                                 ("spring_preload" if gas else "spring_k", RATE_STEPS, True)):
        for sign in (-1.0, 1.0):
            ladders.append(("free_length" if key == "spring_rest_length" else
                            "force" if gas else "rate", steps,
                            PARAM_KEYS.index(key), relative, sign))

    def ok_at(which: list) -> list:
        """Feasible and valid at the ladder indices ``which[l]`` of each ladder l: one batch."""
        rows = []
        for (_, steps, j, relative, sign), idx in zip(ladders, which):
            d = sign * steps[idx]
            P = np.tile(p, (len(d), 1))
            P[:, j] = p[j] * (1 + d) if relative else p[j] + d
            P[:, j] = np.maximum(P[:, j], 0.0 if relative else 1e-4)
            rows.append(P)
        r = sim.run_batch(np.vstack(rows))
        ok = feasible(cfg.optimise, r["closed"], r["closing_time"], r["holding_moment"],
                      r["theta_dot_max"]) & (r["status"] == StrokeStatus.CLOSED)
        return np.split(ok, np.cumsum([len(x) for x in which])[:-1])

    # every LADDER_STRIDE-th step first, then the steps below the first that fails
    coarse = [np.arange(LADDER_STRIDE - 1, len(steps), LADDER_STRIDE)
              for _, steps, _, _, _ in ladders]
    first = []
    for idx, ok in zip(coarse, ok_at(coarse)):
        bad = np.flatnonzero(~ok)
        first.append(int(idx[bad[0]]) if len(bad) else None)
    fine = [np.arange(max(f - LADDER_STRIDE + 1, 0), f) if f is not None else
            np.arange(coarse_idx[-1] + 1, len(lad[1]))
            for f, coarse_idx, lad in zip(first, coarse, ladders)]
    out = {}
    for (name, steps, _, _, _), f, idx, ok in zip(ladders, first, fine, ok_at(fine)):
        bad = np.flatnonzero(~ok)
        fail = int(idx[bad[0]]) if len(bad) else f          # the first step that fails
        side = float(steps[-1]) if fail is None else \
            (float(steps[fail - 1]) if fail > 0 else 0.0)
        out[name] = out.get(name, ()) + (side,)
    return out


#: the margins' ladders are tried every LADDER_STRIDE-th step, then step by step below the
#: first that fails (the constraints change monotonically over so short a span)
LADDER_STRIDE = 10
