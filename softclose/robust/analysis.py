"""Tolerance analysis of one design: Monte Carlo yield, percentiles, reference checks.

``tolerance_analysis(cfg)`` draws ``[tolerance] samples`` points of the configured
distribution over the tolerance box of cfg's design, runs every stroke in the C kernel
(:mod:`softclose.robust.evaluate`), and reports

- the **yield**: the fraction of samples that meet every constraint of the problem
  (closed, closing time within the window, held shut, no rebound), with a 95 % Wilson score
  interval (:func:`softclose.robust.stats.wilson`);
- the 1st / 50th / 99th **percentiles** of closing time (a lid that did not close counts as
  +inf, so a percentile beyond t_max reads "not closed"), of the impact speeds, the peak tip
  speed and the objective J (over the samples that closed);
- the **nominal lid**: the design with every toleranced key at its nominal value, its
  metrics (the same kernel as the samples), J and whether it meets every constraint, and
  whether the design has a spring or a damper at all (``nominal["bare"]``: the default
  config's design has neither, and its "yield" is that of a lid slamming shut);
- why the others failed (counts by reason);
- the **adaptive reference** at the worst sample and at the samples nearest the boundary of
  the feasible set (distinct points: two samples whose labels read the same are one check),
  with the kernel's numbers beside it: that the verdicts agree shows the kernel's step error
  does not move samples across the boundary.
"""

from __future__ import annotations

import time
from collections import Counter
from dataclasses import dataclass, field

import numpy as np

from ..config import Config, check_batch
from ..present.display import Display, Displayed, Table, interval, num, percent, unit_of, with_unit
from ..problem import (BARE_LID, LID_MASS, METRIC_KEYS, bare_lid, design_of,
                       params_of)
from .box import Box, box_of
from .evaluate import evaluate
from .stats import CI_METHOD, margins, percentiles, wilson
from .verify import reference_check
from ..problem import (UNITS, at_state, at_temperature, condition_parts, condition_text,
                       sign_off_conditions, sign_off_states)
from ..jsonio import jsonable
from ..simulation.stroke import StrokeStatus

#: metrics whose percentiles are reported (closing time over every sample, the others over
#: the samples that closed)
PERCENTILE_KEYS = ("closing_time", "impact_theta_dot", "impact_tip_speed", "peak_tip_speed",
                   "objective")


@dataclass(frozen=True, repr=False)
class YieldResult(Displayed):
    """Monte Carlo yield of one design over its tolerance box (see the module docstring).

    ``success`` means the analysis ran (every stroke integrated); whether the design is good
    enough is ``meets_required`` (yield >= required_yield).
    """

    success: bool
    message: str
    design: dict
    keys: tuple
    distribution: str
    samples: int
    seed: int
    yield_: float
    yield_ci: tuple
    required_yield: float
    failures: dict
    percentiles: dict
    box: dict
    reference: list = field(default_factory=list)
    numerical_failures: int = 0
    time: float = 0.0
    data: dict = field(default_factory=dict, repr=False, compare=False)
    #: the nominal lid (:func:`nominal_stroke`): metrics, objective, feasible, reason, bare
    nominal: dict = field(default_factory=dict)

    @property
    def meets_required(self) -> bool:
        return self.yield_ >= self.required_yield

    @property
    def warnings(self) -> tuple[str, ...]:
        """What a reader must know to read the yield: the design has no spring and no
        damper (:data:`softclose.problem.BARE_LID`)."""
        return (BARE_LID,) if self.nominal.get("bare") else ()

    def text(self, source: str = "design") -> str:
        """What ``softclose yield`` prints (``source``: where the design comes from)."""
        from .text import yield_text
        return yield_text(self, source)

    def to_json(self) -> dict:
        return jsonable({
            "success": self.success, "message": self.message, "design": self.design,
            "yield": self.yield_, "yield_ci": list(self.yield_ci), "ci_method": CI_METHOD,
            "required_yield": self.required_yield, "meets_required": self.meets_required,
            "samples": self.samples, "distribution": self.distribution, "seed": self.seed,
            "box": self.box, "nominal": self.nominal, "warnings": list(self.warnings),
            "failures": self.failures,
            "numerical_failures": self.numerical_failures, "percentiles": self.percentiles,
            "reference": self.reference, "time": self.time})

    def to_frame(self):
        """One row per sample: the toleranced keys, the metrics, objective, feasible, reason."""
        import pandas as pd
        d = self.data
        cols = {k: d["X"][:, j] for j, k in enumerate(self.keys)}
        cols.update({k: v for k, v in d["cols"].items() if k != "status"})
        return pd.DataFrame(cols)

    def save(self, folder, figure_format: str = "png", figure_style: str | None = None,
             tag: str = "") -> list:
        """The samples (``yield_samples.csv``) and their histograms
        (``yield_histograms``) in ``folder`` (what ``softclose yield --out`` writes; ``tag``
        ends both names, e.g. ``_20C``); the paths."""
        from ..present.figures import save_with_table
        return save_with_table(folder, f"yield_samples{tag}.csv", self.to_frame(),
                               f"yield_histograms{tag}", self.plot, figure_format,
                               figure_style)

    def _display(self) -> Display:
        return Display("YieldResult: Monte Carlo yield over the tolerance box",
                       self.success, self.message, yield_facts(self), yield_tables(self))

    def plot(self):
        """Histograms of closing time and impact speed over the samples (a Figure)."""
        from ..present.figures.robust import plot_yield
        return plot_yield([self], ["design"])


def yield_facts(y: YieldResult) -> tuple:
    """The one-line facts of a yield: the design, the yield with its interval, the samples."""
    ok = "meets" if y.meets_required else "below"
    facts = [("yield", f"{percent(y.yield_)} (95 % interval {interval(y.yield_ci)}; "
                       f"{ok} the required {percent(y.required_yield)})"),
             ("samples", f"{num(y.samples)} ({y.distribution}, seed {y.seed})")]
    facts += [(k, with_unit(v, UNITS.get(k, ""))) for k, v in y.design.items()]
    if y.numerical_failures:
        facts.append(("not integrated", f"{y.numerical_failures} strokes"))
    return tuple(facts)


def yield_tables(y: YieldResult) -> tuple:
    """The box, why samples failed and the percentiles, as tables."""
    box = Table("tolerance box", ("key", "nominal", "low", "high", "spread"), [
        (k, with_unit(b["nominal"], unit_of(k)), num(b["low"]), num(b["high"]),
         f"±{100 * b['spread']:.3g} %" if b["relative"] else f"±{num(b['spread'])} "
         f"{unit_of(k)}") for k, b in y.box.items()])
    fail = Table("why samples fail", ("reason", "samples", "share"), [
        (r, num(n), percent(n / y.samples if y.samples else None))
        for r, n in sorted(y.failures.items(), key=lambda kv: -kv[1])]) if y.failures else None
    def cell(k, v):   # a lid that did not close has an infinite closing time
        return "not closed" if k == "closing_time" and v is not None and v == float("inf") \
            else num(v)
    qs = tuple(next(iter(y.percentiles.values()), {}).keys())
    pct = Table("percentiles", ("metric", *(f"{q[1:]} %" for q in qs)), [
        (f"{k} [{unit_of(k)}]", *(cell(k, p.get(q)) for q in qs))
        for k, p in y.percentiles.items()])
    return tuple(t for t in (box, fail, pct) if t is not None)


def _box_json(box: Box) -> dict:
    return {k: {"nominal": float(v), "low": float(lo), "high": float(hi),
                "spread": s, "relative": r}
            for k, v, lo, hi, s, r in zip(box.keys, box.nominal, box.lo, box.hi, box.spreads,
                                          box.relative)}


def analyse_samples(cfg: Config, box: Box, z: np.ndarray, *, seed: int = 0,
                    reference: int = 3, t0: float | None = None) -> YieldResult:
    """The yield analysis of cfg's design on the given unit-coordinate samples ``z``."""
    t0 = time.perf_counter() if t0 is None else t0
    X = box.values(z)
    cols = evaluate(cfg, box.keys, X)
    n = len(z)
    ok = np.asarray(cols["feasible"], bool)
    k = int(ok.sum())
    status = np.asarray(cols["status"], int)
    numerical = int(np.sum(~np.isin(status, (StrokeStatus.CLOSED, StrokeStatus.NOT_CLOSED))))
    reasons = Counter(r for r in cols["reason"] if r)
    ct = np.where(cols["closed"], cols["closing_time"], np.inf)
    closed = np.asarray(cols["closed"], bool)
    pct = {"closing_time": percentiles(ct)}
    for key in PERCENTILE_KEYS[1:]:
        pct[key] = percentiles(np.asarray(cols[key], float)[closed])
    m = margins(cols, cfg.optimise)
    checks = []
    if reference and n:
        picks, labels = [], set()

        def pick(i, why):
            label = box.label(z[i])
            if label not in labels:        # the same point as far as a reader can tell
                labels.add(label)
                picks.append((i, why))
        if (~ok).any():
            pick(int(np.argmin(m)), "worst sample")
        near = np.argsort(np.abs(np.where(np.isfinite(m), m, np.inf)))
        for i in near[:max(64, 4 * reference)]:
            if len(picks) >= reference or not np.isfinite(m[i]):
                break
            nth = sum(1 for _, w in picks if w.endswith("nearest the boundary"))
            pick(int(i), ("sample" if not nth else f"{_ORDINAL[min(nth, 3)]} sample")
                 + " nearest the boundary")
        for i, why in picks:
            kern = {c: (None if isinstance(v := cols[c][i], float) and not np.isfinite(v)
                        else v) for c in cols}
            kern = {c: (v.item() if hasattr(v, "item") else v) for c, v in kern.items()}
            chk = reference_check(cfg, box.keys, X[i], f"{why}: {box.label(z[i])}", kern,
                                  kern.get("objective"))
            chk["sample"] = i
            chk["margin"] = float(m[i]) if np.isfinite(m[i]) else None
            checks.append(chk)
    msg = ""
    if numerical:
        msg = (f"{numerical} of {n} strokes could not be integrated at simulate.step = "
               f"{cfg.simulate.step:g} s and count as failing; use a smaller simulate.step")
    disagree = [c for c in checks if c.get("verdicts_agree") is False]
    if disagree:
        msg = (msg + "; " if msg else "") + (
            f"the adaptive reference disagrees with the kernel's verdict at {len(disagree)} of "
            f"{len(checks)} checked samples (margins below the kernel's accuracy)")
    y = k / n if n else float("nan")
    nominal = nominal_stroke(cfg)
    return YieldResult(
        success=numerical == 0, message=msg, design=design_of(params_of(cfg)),
        keys=box.keys, distribution=box.distribution, samples=n, seed=seed, yield_=y,
        yield_ci=wilson(k, n), required_yield=cfg.tolerance.required_yield,
        failures=dict(reasons), percentiles=pct, box=_box_json(box), reference=checks,
        numerical_failures=numerical, time=time.perf_counter() - t0,
        data={"z": z, "X": X, "cols": cols, "margin": m,
              "closing_time_max": cfg.optimise.closing_time_max}, nominal=nominal)


_ORDINAL = {1: "2nd", 2: "3rd", 3: "next"}


def nominal_stroke(cfg: Config) -> dict:
    """The design's own lid, every toleranced key at its nominal value: its §4 metrics from
    the C kernel (as the samples'), ``objective`` (J; None when it does not close),
    ``feasible`` and ``reason`` (the first constraint it breaks, "" if none), and ``bare``
    (no spring and no damper: :func:`softclose.problem.bare_lid`)."""
    cols = evaluate(cfg, [LID_MASS], [[cfg.mass.lid]])   # the lid-mass column: exact
    out = {}
    for k in METRIC_KEYS + ("objective",):
        v = cols[k][0]
        v = v.item() if hasattr(v, "item") else v
        out[k] = None if isinstance(v, float) and not np.isfinite(v) else v
    out["closed"] = bool(out["closed"])
    out["feasible"] = bool(cols["feasible"][0])
    out["reason"] = str(cols["reason"][0])
    out["bare"] = bare_lid(cfg)
    return out


@dataclass(frozen=True)
class TemperatureYield:
    """The yield at each sign-off temperature and jointly (the same samples at every
    temperature: a lid counts when it meets every constraint at all of them)."""

    temperatures: tuple            # the temperatures (°C)
    results: tuple                 # a YieldResult at each
    yield_: float                  # jointly
    yield_ci: tuple
    samples: int
    required_yield: float

    @property
    def meets_required(self) -> bool:
        return self.yield_ >= self.required_yield

    @property
    def success(self) -> bool:
        return self.meets_required and all(r.success or r.meets_required for r in self.results)

    @property
    def limiting(self) -> float:
        """The temperature with the lowest yield."""
        return min(zip(self.results, self.temperatures), key=lambda x: x[0].yield_)[1]

    def text(self, source: str = "design") -> str:
        """What ``softclose yield`` prints at several sign-off temperatures."""
        from .text import yield_by_temperature_text
        return yield_by_temperature_text(self, source)

    @property
    def message(self) -> str:
        """Why the joint yield falls short ("" when it meets the required yield)."""
        if self.meets_required:
            return ""
        return (f"the yield at every temperature is {100 * self.yield_:.2f} %, below the "
                f"required {100 * self.required_yield:g} % (lowest at "
                f"{condition_text(self.limiting)})")

    def state_yields(self) -> list[dict]:
        """With the end of life a sign-off state (SPEC §17): each state's yield over its
        temperatures (the same samples), [] with the new lid alone."""
        states: dict = {}
        for T, r in zip(self.temperatures, self.results):
            st = condition_parts(T)[1] or "new"
            ok = np.asarray(r.data["cols"]["feasible"], bool)
            states[st] = ok if st not in states else states[st] & ok
        if len(states) <= 1:
            return []
        return [{"state": st, "yield": float(ok.mean()),
                 "yield_ci": list(wilson(int(ok.sum()), len(ok)))} for st, ok in states.items()]

    def save(self, folder, figure_format: str = "png", figure_style: str | None = None
             ) -> list:
        """Each sign-off condition's samples and histograms in ``folder``
        (``yield_samples_<T>C.csv``, ``yield_histograms_<T>C``, with ``_end_of_life`` at the
        end of life: what ``softclose yield --out`` writes); the paths."""
        from ..problem import condition_tag
        return [f for T, r in zip(self.temperatures, self.results)
                for f in r.save(folder, figure_format, figure_style, f"_{condition_tag(T)}")]

    def to_json(self) -> dict:
        """The joint yield's keys, the design and its box (the same at each temperature),
        ``success`` (the joint yield meets the required one) and ``temperatures``: each
        temperature's yield."""
        first, states = self.results[0], self.state_yields()
        return jsonable({
            "design": first.design, "box": first.box, "distribution": first.distribution,
            "seed": first.seed, "success": self.meets_required, "message": self.message,
            "yield": self.yield_, "yield_ci": list(self.yield_ci), "ci_method": CI_METHOD,
            "samples": self.samples, "required_yield": self.required_yield,
            "meets_required": self.meets_required,
            "limiting_temperature_c": condition_parts(self.limiting)[0],
            "temperatures": [dict(r.to_json(), temperature_c=condition_parts(T)[0],
                                  **({"state": condition_parts(T)[1] or "new"} if states
                                     else {}))
                             for T, r in zip(self.temperatures, self.results)],
            **({"states": states,
                "limiting_state": condition_parts(self.limiting)[1] or "new"}
               if states else {})})


def yield_by_temperature(cfg: Config, *, samples: int | None = None, seed: int = 0,
                         reference: int = 3, progress: bool = False) -> TemperatureYield:
    """:func:`tolerance_analysis` at each sign-off temperature
    (:func:`sign_off_temperatures`), with the same samples, and the joint yield."""
    temps = sign_off_conditions(cfg)          # (each temperature new, and at the end of life)
    if len(sign_off_states(cfg)) > 1:
        cfg = at_state(cfg, "new")
    results, joint = [], None
    for T in temps:
        y = tolerance_analysis(at_temperature(cfg, T), samples=samples, seed=seed,
                               reference=reference, progress=progress)
        results.append(y)
        ok = np.asarray(y.data["cols"]["feasible"], bool)
        joint = ok if joint is None else joint & ok
    n, k = len(joint), int(joint.sum())
    return TemperatureYield(temps, tuple(results), k / n, wilson(k, n), n,
                            cfg.tolerance.required_yield)


def tolerance_analysis(cfg: Config, *, samples: int | None = None, seed: int = 0,
                       design: dict | None = None, reference: int = 3,
                       progress: bool = False) -> YieldResult:
    """Monte Carlo yield of cfg's design (or ``design``: {name: value} as a result's
    ``design`` gives it, a co-design's attachment points and end damper included) over the
    ``[tolerance]`` box.

    ``samples`` defaults to ``[tolerance] samples``; ``seed`` fixes the draw; ``reference``
    samples (the worst one and those nearest the feasibility boundary) are re-simulated by
    the adaptive reference.
    """
    t0 = time.perf_counter()
    if design:
        cfg = cfg.with_design(**design)     # (a co-design's points and end damper too)
    box = box_of(cfg)
    n = int(samples or cfg.tolerance.samples)
    check_batch(cfg, n, "--samples" if samples else "tolerance.samples")
    z = box.draw(n, seed)
    return analyse_samples(cfg, box, z, seed=seed, reference=reference, t0=t0)
