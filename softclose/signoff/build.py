""":func:`report`: the sign-off report of one design (the numbers; :mod:`.html` and
:mod:`.pdf` write them out)."""

from __future__ import annotations

import json
from pathlib import Path

import math
import time

from ..config import Config, check_batch, to_toml
from ..errors import ConfigError
from ..jsonio import jsonable
from ..problem import (METRIC_KEYS, condition_parts, condition_text, resolve,
                       sign_off_conditions, sign_off_states)
from ..simulation.simulator import Simulator
from ..version import __version__
from . import checks, parts
from .result import ReportResult


def _stroke(cfg: Config) -> dict:
    """The fixed-step stroke of cfg (with its trajectory and estimated accuracy), the
    reference's verification and the hand force, at cfg's temperature."""
    sim = Simulator(resolve(cfg), cached=True)
    res = sim.run(trajectory=True)
    ver = checks.check(cfg, hand=True)      # (no hand force where the linkage cannot open)
    return {"simulate": res, "verification": ver, "hand": ver.hand, "model": sim.model}


def _metrics(s: dict) -> dict:
    """The reference's metrics, the fixed-step simulator's with their ± and the differences."""
    ver, res = s["verification"], s["simulate"]
    ref = ver.metrics or {}
    sim = res.to_json()
    diff = {}
    for k in METRIC_KEYS:
        a, b = sim.get(k), ref.get(k)
        if isinstance(a, float) and isinstance(b, float):
            diff[k] = a - b
    out = {"reference": ref, "reference_method": ver.method, "simulate": sim,
           "accuracy": sim.get("accuracy") or {}, "differences": diff,
           "objective": ver.objective}
    if s["hand"] is not None:
        out["hand"] = s["hand"].metrics()
    return out


#: the yield's samples a temperature, unless given, when a toleranced key gives every sample
#: its own model (a geometry or inertia key: ~0.1 s a sample instead of ~20 us)
SLOW_SAMPLES = 100


def _yields(cfg: Config, samples: int | None) -> dict:
    """The Monte Carlo yield at each temperature and jointly (the same samples: a lid
    counts when it passes at every temperature); skipped without a tolerance box."""
    from ..robust.analysis import yield_by_temperature
    from ..robust.box import box_of
    from ..robust.evaluate import slow_keys
    box = box_of(cfg)
    if not box.dim:
        return {"skipped": "No tolerance box is set ([tolerance] spreads none of the keys): "
                           "there is no yield to estimate."}
    note = ""
    slow = slow_keys(box.keys)
    if samples is None and slow and cfg.tolerance.samples > SLOW_SAMPLES:
        samples = SLOW_SAMPLES
        note = (f"{', '.join(slow)} gives every sample its own model (about 0.1 s each): "
                f"{SLOW_SAMPLES} samples a temperature instead of tolerance.samples = "
                f"{cfg.tolerance.samples} (--samples N to choose)")
    t = yield_by_temperature(cfg, samples=samples, reference=0)
    per = [{"temperature_c": condition_parts(T)[0], "state": condition_parts(T)[1] or "new",
            "yield": y.yield_, "yield_ci": list(y.yield_ci),
            "samples": y.samples, "failures": y.failures,
            "meets_required": y.meets_required, "message": y.message}
           for T, y in zip(t.temperatures, t.results)]
    results = t.results
    return {"required_yield": cfg.tolerance.required_yield, "note": note,
            "distribution": cfg.tolerance.distribution, "keys": list(results[0].keys),
            "per_temperature": per, "per_state": t.state_yields(),
            "joint": {"yield": t.yield_, "yield_ci": list(t.yield_ci), "samples": t.samples,
                      "meets_required": t.meets_required}}


def _limits(cfg: Config, matrix: dict, optimiser: dict | None) -> dict:
    """What limits the design: the optimiser's active constraints with dJ when its JSON is
    given, and the row with the smallest relative margin in the matrix."""
    out = {}
    if optimiser and optimiser.get("active"):
        out["active"] = [{k: a.get(k) for k in ("name", "kind", "bound", "value", "unit", "dJ")}
                         for a in optimiser["active"]]
    tight = None
    for r, cells in matrix["cells"].items():
        for col, c in cells.items():
            m = checks.relative_margin(cfg, r, c)
            if tight is None or m < tight[0]:
                tight = (m, r, col, c)
    if tight is not None:
        m, r, col, c = tight
        out["smallest_margin"] = {"constraint": r, "column": col, "value": c["value"],
                                  "limit": c["limit"], "margin": c["margin"],
                                  "relative_margin": m if math.isfinite(m) else None}
    return out


def _column_name(T: float) -> str:
    return condition_text(T)


def _verdict(cfg, matrix: dict, parts_: dict, yields: dict, temps) -> tuple[bool, str, list]:
    """(every requirement met, the one-line verdict, the failures in words)."""
    fails = []
    for col in matrix["columns"]:
        if col == "nominal" and cfg.operating.temperature_c in temps:
            continue                     # the same lid as its temperature's column
        shut = matrix["cells"]["closed"].get(col, {}).get("ok", True)
        for r, cells in matrix["cells"].items():
            what, rel, unit = checks.ROWS[r]
            c = cells.get(col)
            if c is None or c["ok"] or (not shut and r.startswith("closing_time")):
                continue                 # (a lid that does not close: said once)
            where = {"worst corner": "at the worst tolerance corner",
                     "nominal": f"at nominal ({cfg.operating.temperature_c:g} °C)"}.get(
                         col, f"at {col}")
            if col == "worst corner" and c.get("where"):
                where += f" ({c['where']})"
            if r == "closed":
                fails.append(f"the lid does not close {where}")
            elif c["value"] is None or isinstance(c["value"], bool):
                fails.append(f"{r} {where}: {c.get('reason') or 'fails'}")
            else:
                fails.append(f"{r} {where} is {c['value']:.4g} {unit}".rstrip()
                             + f", limit {c['limit']:.4g} {unit}".rstrip())
    for f in parts_.get("failures", ()):
        fails.append(f)
    for y in yields.get("per_temperature", ()):
        if not y["meets_required"]:
            eol = " at the end of life" if y.get("state") == "end_of_life" else ""
            fails.append(f"yield at {y['temperature_c']:g} °C{eol} is "
                         f"{100 * y['yield']:.3g} %, required "
                         f"{100 * yields['required_yield']:.3g} %")
    at = ", ".join(_column_name(T) for T in temps)
    if not fails:
        corner = " and at every corner of the tolerance box" if "worst corner" in \
            matrix["columns"] else ""
        return True, f"This design meets every requirement at {at}{corner}.", fails
    more = f" (and {len(fails) - 3} more)" if len(fails) > 3 else ""
    if all("at the end of life" in f for f in fails):       # (new, it passes)
        return False, ("This design passes new but FAILS at the end of life: "
                       + "; ".join(fails[:3]) + more), fails
    return False, "This design FAILS: " + "; ".join(fails[:3]) + more, fails


def report(cfg: Config, *, optimiser: dict | None = None, samples: int | None = None,
           progress: bool = False) -> ReportResult:
    """The sign-off report of cfg's design (SPEC §16): an immutable
    :class:`~softclose.signoff.ReportResult` whose ``success`` says whether the design meets
    every requirement and ``message`` says so in one line.

    ``optimiser``: the optimiser's JSON (``optimise.json`` or ``robust.json`` next to a
    design file), whose active constraints and their dJ say what limits the design; ``samples``: Monte Carlo
    samples of each yield (default ``[tolerance] samples``).
    """
    t0 = time.perf_counter()
    timings = {}
    temps = checks.temperatures(cfg)
    if samples is not None and samples < 1:
        raise ConfigError(f"samples: {samples}; expected a whole number >= 1")
    # each yield samples this many strokes at each temperature: refused before any work
    check_batch(cfg, int(samples or cfg.tolerance.samples),
                "--samples" if samples else "tolerance.samples")
    nominal = _stroke(cfg)
    strokes = {}
    # the end of life a sign-off state (SPEC §17): each temperature's column at it too
    states = sign_off_states(cfg)
    conditions = sign_off_conditions(cfg)
    for T in conditions:
        strokes[T] = (nominal if T == cfg.operating.temperature_c and cfg.life.state == "new"
                      else _stroke(checks.at_temperature(cfg, T)))
    timings["strokes"] = time.perf_counter() - t0
    if progress:
        print(f"report: strokes at {len(temps)} temperatures", flush=True)
    columns = ["nominal"] + [_column_name(T) for T in conditions]
    cells = {r: {} for r in checks.constraint_rows(cfg)}
    for col, s in [("nominal", nominal)] + [(_column_name(T), strokes[T]) for T in conditions]:
        for r, c in checks.column(cfg, s["verification"]).items():
            cells[r][col] = c
    t1 = time.perf_counter()
    corners, corner_facts = checks.worst_corners(cfg, conditions)
    if corners:
        columns.append("worst corner")
        for r, c in corners.items():
            cells[r]["worst corner"] = c
    timings["corners"] = time.perf_counter() - t1
    matrix = {"rows": [{"name": r, "what": checks.ROWS[r][0], "relation": checks.ROWS[r][1],
                        "unit": checks.ROWS[r][2]} for r in cells],
              "columns": columns, "cells": cells, "corners": corner_facts}
    t1 = time.perf_counter()
    parts_ = parts.parts(cfg, nominal["verification"].stroke, temps)
    timings["parts"] = time.perf_counter() - t1
    t1 = time.perf_counter()
    yields = _yields(cfg, samples)
    timings["yield"] = time.perf_counter() - t1
    ok, verdict, fails = _verdict(cfg, matrix, parts_, yields, temps)
    by_t = {_column_name(T): {"temperature_c": condition_parts(T)[0],
                              **({"state": condition_parts(T)[1] or "new"}
                                 if len(states) > 1 else {}),
                              **_metrics(strokes[T])} for T in conditions}
    design = {"mechanism": cfg.geometry.mechanism, "spring_kind": cfg.design.spring_kind,
              **checks.design_values(cfg),
              "rotary_damper_c": cfg.design.rotary_damper_c,
              "end_damper_c": cfg.design.end_damper_c,
              "damper_temperature_coeff": cfg.design.damper_temperature_coeff,
              "reference_temperature_c": cfg.operating.reference_temperature_c,
              "temperature_c": cfg.operating.temperature_c}
    limits = _limits(cfg, matrix, optimiser)
    timings["total"] = time.perf_counter() - t0
    return ReportResult(
        success=ok, message=verdict, failures=tuple(fails), version=__version__,
        temperatures=temps, design=jsonable(design), parts=jsonable(parts_),
        metrics=jsonable(_metrics(nominal)), strokes=jsonable(by_t),
        matrix=jsonable(matrix), yields=jsonable(yields),
        limits=jsonable(limits), config_toml=to_toml(cfg),
        problem={"closing_time_max": cfg.optimise.closing_time_max,
                 "closing_time_min": cfg.optimise.closing_time_min,
                 "holding_moment_min": cfg.optimise.holding_moment_min,
                 "opening_force_max": cfg.optimise.opening_force_max,
                 "self_close_min_deg": cfg.optimise.self_close_min_deg},
        time=timings["total"], timings=timings,
        drawing={"cfg": cfg, "model": nominal["model"],
                 "strokes": {T: strokes[T]["simulate"] for T in temps},
                 "hands": {T: strokes[T]["hand"] for T in temps}},
        states=states, limiting_state=_limiting_state(limits, fails, states))


def _limiting_state(limits: dict, fails, states) -> str | None:
    """The state that limits the design: the end of life when every failure is there, the
    new lid when one is new; without failures the state of the column with the smallest
    relative margin (None with the new lid alone)."""
    if len(states) == 1:
        return None
    if fails:
        return "end_of_life" if all("at the end of life" in f for f in fails) else "new"
    col = (limits.get("smallest_margin") or {}).get("column", "")
    return "end_of_life" if "at the end of life" in col else "new"


#: the optimisers' JSON files that `--out D` writes next to D/design.toml
OPTIMISER_FILES = ("robust.json", "optimise.json")


def optimiser_json(config: str | None, cfg) -> dict | None:
    """The optimiser's JSON next to a design file (``robust.json`` or ``optimise.json``) whose
    design is cfg's, if there is one; it says which constraints are active and their dJ. A
    file of another design (a folder written twice, a design edited since) is not used."""
    if not config:
        return None
    for name in OPTIMISER_FILES:
        try:
            payload = json.loads((Path(config).parent / name).read_text())
            design = payload["design"]
            same = all(abs(float(v) - float(getattr(cfg.design, k))) <= 1e-12 * max(1.0, abs(v))
                       for k, v in design.items())
        except (OSError, ValueError, KeyError, TypeError, AttributeError):
            continue
        if same:
            return payload
    return None


__all__ = ["report", "optimiser_json"]
