"""Work precision of the closing stroke: for every fixed-step method and a range of steps, the
error of the metrics that carry an accuracy target against a tight adaptive reference, and
the C kernel's run time per stroke (:func:`work_precision`); the cheapest setting that meets
the targets (:func:`cheapest_setting`) and whether the configured default is it
(:func:`assess_default`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..config import Config
from ..numerics.integrators import METHODS, SEED
from ..model.lid import LidModel
from ..problem import as_params, PARAM_DEFAULTS, params_of, RELATIVE, resolve, TARGETS
from ..simulation.reference import Reference
from ..simulation.simulator import Simulator
from .timing import kernel_times, time_stats
from ..jsonio import jsonable
from ..model.elements import PARAMS

#: the metrics with an accuracy target, in table order
METRICS = tuple(TARGETS)
#: tolerance of the adaptive reference that is taken as the truth
TRUTH_TOL = 1e-14
#: the adaptive reference's own line in the work-precision table
REFERENCE_TOLS = (1e-6, 1e-8, 1e-10, 1e-12)

_HIGH = (2e-2, 1e-2, 5e-3, 2e-3, 1e-3, 5e-4, 2e-4, 1e-4)
#: steps of each method (the configured default step is always added to its method)
STEPS = {"rk4": _HIGH, "gauss4": _HIGH, "radau5": _HIGH,
         "euler_cromer": (2e-3, 1e-3, 5e-4, 2e-4, 1e-4, 5e-5, 2e-5, 1e-5, 5e-6, 2e-6, 1e-6)}
QUICK_STEPS = {"rk4": (1e-2, 5e-3, 2e-3, 1e-3, 5e-4), "gauss4": (1e-2, 5e-3, 2e-3, 1e-3),
               "radau5": (1e-2, 5e-3, 2e-3, 1e-3), "euler_cromer": (1e-3, 1e-4, 1e-5)}

#: spring + dashpot designs of the benchmark (k N/m, l0 m, c N s/m, c_rot N m s/rad)
SPRING_DASHPOT = {
    "soft_close": (500.0, 0.05, 3000.0, 0.0),       # closes in 0.32 s at -0.76 rad/s
    "strong_spring": (5000.0, 0.06, 2000.0, 0.0),   # nearly balanced: 0.36 s, -0.40 rad/s
    "stiff_corner": (10000.0, 0.02, 5000.0, 0.0),   # corner of the design box: 0.10 s, -3.2 rad/s
}
#: how many of the spring + dashpot designs a quick run takes (in the order above)
QUICK_DESIGNS = 1
#: designs with the real elements (full runs only), by their parameters (the others at their
#: defaults): a preloaded compression spring (its force jumps by the preload at the free
#: length, which this stroke never reaches: 0.45 s, -0.40 rad/s); a one-way dashpot with
#: Coulomb friction (0.33 s, -0.73 rad/s); a torsion spring with friction (0.35 s, -0.72 rad/s)
ELEMENT_DESIGNS = {
    "compression_preload": {"spring_k": 1500.0, "spring_rest_length": 0.07,
                            "damper_c": 2000.0, "spring_kind": "compression",
                            "spring_preload": 10.0},
    "friction_one_way": {"spring_k": 500.0, "spring_rest_length": 0.05, "damper_c": 3000.0,
                         "damper_one_way": True, "friction_torque": 0.05},
    "torsion_friction": {"damper_c": 2500.0, "torsion_k": 0.2, "torsion_free_angle_deg": 30.0,
                         "friction_torque": 0.03},
}


def element_params(values: dict) -> np.ndarray:
    """The parameter vector p of a design given by some of its parameters (words by their
    codes), the others at their defaults (absent)."""
    p = PARAM_DEFAULTS.copy()
    for i, q in enumerate(PARAMS):
        if q.name in values:
            p[i] = q.number(values[q.name])
    return p


def designs_for(cfg: Config, quick: bool = False) -> dict[str, np.ndarray]:
    """The benchmark's designs: the config's own (named "spec8" when it is the SPEC §8 case:
    no spring, no damper), the spring + dashpot designs (the first only when ``quick``) and,
    in a full run, the real elements' (:data:`ELEMENT_DESIGNS`)."""
    own = params_of(cfg)
    name = "spec8" if own[0] == 0 and own[2] == 0 and own[3] == 0 else "config"
    out = {name: own}
    for i, (k, v) in enumerate(SPRING_DASHPOT.items()):
        if quick and i >= QUICK_DESIGNS:
            break
        out[k] = as_params(v)
    if not quick:
        out.update({k: element_params(v) for k, v in ELEMENT_DESIGNS.items()})
    return out

# -- errors --------------------------------------------------------------------------------
def errors(res, truth) -> dict:
    """Error of each targeted metric of ``res`` against ``truth`` (both
    :class:`~softclose.simulation.stroke.StrokeResult`): absolute, or relative for
    :data:`softclose.problem.RELATIVE`, absolute where the truth is 0 (a lid that never
    moves has no tip speed to be relative to); None where either value is missing."""
    out = {}
    for k in METRICS:
        a, b = getattr(res, k), getattr(truth, k)
        if a is None or b is None or not (math.isfinite(a) and math.isfinite(b)):
            out[k] = None
        else:
            out[k] = abs(a - b) / (abs(b) if k in RELATIVE and b != 0 else 1.0)
    return out


def meets(err: dict) -> bool:
    """Every error of :func:`errors` within its target."""
    return all(err.get(k) is not None and err[k] <= TARGETS[k] for k in METRICS)


def fit_order(hs, errs, truth_scale: float, floor: float = 0.0, hi: float = 1e-2):
    """Slope of log(err) against log(x) over the asymptotic points.

    Points count when err lies above 30 x ``floor`` (the truth's own uncertainty) and
    1e-12 x truth_scale, and err/truth_scale is at most ``hi`` (below the pre-asymptotic
    range). Returns None with fewer than 3 such points.
    """
    lo = max(30 * floor, 1e-12 * truth_scale)
    pts = [(math.log(h), math.log(e)) for h, e in zip(hs, errs)
           if e is not None and e > lo and e / truth_scale <= hi]
    if len(pts) < 3:
        return None
    x, y = np.array(pts).T
    return float(np.polyfit(x, y, 1)[0])


# -- the work-precision study ---------------------------------------------------------------
@dataclass(frozen=True)
class WorkPrecision:
    """Errors and run times of every method and step on the benchmark's designs.

    ``rows``: one dict per (design, method, step) and per reference tolerance (errors
    ``err_<metric>``, the stroke's own estimates ``est_<metric>``, ``time_per_stroke`` in s,
    ``meets_targets``, ``seed``). ``truths``: the reference at :data:`TRUTH_TOL` per design;
    ``truth_floor``: the errors of the reference at 10 x TRUTH_TOL against it (the truth's
    own uncertainty). ``orders`` / ``slopes``: fitted slopes of error against step / run
    time, keyed (design, method, metric). ``default``: :func:`assess_default`.
    """

    rows: tuple
    truths: dict
    truth_floor: dict
    orders: dict
    slopes: dict
    default: dict
    designs: tuple
    quick: bool = False

    def rows_of(self, design: str, method: str) -> list[dict]:
        return [r for r in self.rows if r["design"] == design and r["method"] == method]

    def to_json(self) -> dict:
        return jsonable({
            "designs": list(self.designs), "quick": self.quick, "truth_tol": TRUTH_TOL,
            "default": self.default, "rows": list(self.rows),
            "truths": {d: t.to_json() for d, t in self.truths.items()},
            "truth_floor": self.truth_floor,
            "orders": [{"design": d, "method": m, "metric": k, "order": o,
                        "slope_vs_time": self.slopes.get((d, m, k))}
                       for (d, m, k), o in self.orders.items()]})


def work_precision(cfg: Config, quick: bool = False, repeats: int | None = None,
                   methods=None, log=None) -> WorkPrecision:
    """Errors and run times of every method and step on the benchmark designs."""
    log = log or (lambda *a: None)
    repeats = repeats or (3 if quick else 7)
    steps = {m: set(s) for m, s in (QUICK_STEPS if quick else STEPS).items()}
    steps.setdefault(cfg.simulate.integrator, set()).add(cfg.simulate.step)
    methods = list(methods or METHODS)
    case = resolve(cfg)
    model = LidModel(case)
    designs = designs_for(cfg, quick)
    truth_ref = Reference(model, TRUTH_TOL)
    check_ref = Reference(model, 10 * TRUTH_TOL)
    rows, truths, floor = [], {}, {}
    table = None  # one coefficient table for every method (it depends on the model only)
    for dname, p in designs.items():
        truths[dname] = truth_ref.simulate(p, case)
        floor[dname] = errors(check_ref.simulate(p, case), truths[dname])
        log(f"  truth for {dname}: closing_time {truths[dname].closing_time}")
        for mname in methods:
            sim = Simulator(case, model=model, integrator=mname)
            if table is not None:
                sim.table = table
            table = sim.table
            for h in sorted(steps.get(mname, ()), reverse=True):
                sim.step = h
                res = sim.run(p)
                err = errors(res, truths[dname]) if res.ok else {k: None for k in METRICS}
                t_kernel, t_min = kernel_times(sim, p, repeats)
                rows.append({
                    "design": dname, "method": mname, "step": h, "status": res.status.text,
                    "steps": res.steps, "time_per_stroke": t_kernel, "time_min": t_min,
                    **{f"err_{k}": err[k] for k in METRICS},
                    **{f"est_{k}": (res.accuracy or {}).get(k) for k in METRICS},
                    "meets_targets": res.ok and meets(err),
                    "seed": (mname, h) == SEED,
                    "message": res.message or "",
                })
        for tol in REFERENCE_TOLS if not quick else REFERENCE_TOLS[1::2]:
            ref = Reference(model, tol)
            r = ref.simulate(p, case)
            t, t_min = time_stats(lambda: ref.simulate(p, case), max(1, repeats // 2), warmup=0)
            err = errors(r, truths[dname])
            rows.append({"design": dname, "method": "reference", "step": tol,
                         "status": r.status.text, "steps": 0, "time_per_stroke": t,
                         "time_min": t_min, **{f"err_{k}": err[k] for k in METRICS},
                         **{f"est_{k}": None for k in METRICS},
                         "meets_targets": meets(err), "seed": False, "message": ""})
        log(f"  {dname}: done")
    orders, slopes = {}, {}
    for dname in designs:
        for mname in methods:
            rs = [r for r in rows if r["design"] == dname and r["method"] == mname
                  and r["status"] in ("closed", "not closed")]
            for k in METRICS:
                scale = 1.0 if k in RELATIVE else abs(getattr(truths[dname], k) or 1.0)
                es = [r[f"err_{k}"] for r in rs]
                fl = floor[dname].get(k) or 0.0
                orders[(dname, mname, k)] = fit_order([r["step"] for r in rs], es, scale, fl)
                slopes[(dname, mname, k)] = fit_order([r["time_per_stroke"] for r in rs], es,
                                                      scale, fl)
    default = assess_default(cfg, rows, list(designs))
    return WorkPrecision(tuple(rows), truths, floor, orders, slopes, default,
                         tuple(designs), quick)


def cheapest_setting(rows: list, designs: list) -> dict:
    """The cheapest (method, step) that meets the targets on every design of ``designs``.

    Within a method the cheapest is its largest passing step (a fixed-step stroke's work is
    its step count times the method's stages: no timing noise decides between two steps of
    one method); between methods, the total kernel run time over the designs at those steps,
    each the fastest of its repeats (``time_min``: the least disturbed by other load on the
    machine). ``per_method`` gives the cheapest passing step of each method. ``method`` and
    ``step`` are None when nothing passes.
    """
    per = {}
    for r in rows:
        if r["method"] == "reference" or r["design"] not in designs:
            continue
        e = per.setdefault((r["method"], r["step"]), {"method": r["method"], "step": r["step"],
                                                      "ok": True, "time": 0.0, "designs": 0})
        e["ok"] &= bool(r["meets_targets"])
        e["time"] += r.get("time_min", r["time_per_stroke"])
        e["designs"] += 1
    best: dict = {}
    for e in per.values():
        if e["ok"] and e["designs"] == len(designs) and \
                e["step"] > best.get(e["method"], {"step": -1.0})["step"]:
            best[e["method"]] = e
    good = sorted(best.values(), key=lambda e: e["time"])
    per_method = {e["method"]: {"step": e["step"],
                                "mean_time_per_stroke": e["time"] / len(designs)}
                  for e in good}
    if not good:
        return {"method": None, "step": None, "mean_time_per_stroke": None,
                "per_method": per_method}
    return {"method": good[0]["method"], "step": good[0]["step"],
            "mean_time_per_stroke": good[0]["time"] / len(designs), "per_method": per_method}


def assess_default(cfg: Config, rows: list, designs: list) -> dict:
    """The configured default (``cfg.simulate.integrator`` at ``cfg.simulate.step``) against
    the designs of this run.

    Returns ``method``, ``step`` (the configured setting), ``meets_targets`` (on every
    design), ``failing_designs``, ``cheapest`` (:func:`cheapest_setting` on these designs),
    ``confirmed`` (the default meets the targets and nothing cheaper does), and
    ``omitted_designs``: designs of the full benchmark this run left out. When the default
    is not confirmed and designs were omitted, this run cannot tell whether one of them is
    what rules the cheaper setting out.
    """
    method, step = cfg.simulate.integrator, cfg.simulate.step
    mine = [r for r in rows if r["method"] == method and r["step"] == step]
    failing = [r["design"] for r in mine if not r["meets_targets"]]
    ok = len(mine) == len(designs) and not failing
    cheapest = cheapest_setting(rows, designs)
    mean = (sum(r["time_per_stroke"] for r in mine) / len(mine)) if mine else None
    confirmed = ok and (cheapest["method"], cheapest["step"]) == (method, step)
    full = list(designs_for(cfg, quick=False))
    return {"method": method, "step": step, "meets_targets": ok, "failing_designs": failing,
            "mean_time_per_stroke": mean, "confirmed": confirmed, "cheapest": cheapest,
            "designs": list(designs), "omitted_designs": [d for d in full if d not in designs]}
