"""Run time against error, for every integrator and step size, and the speed of the calls.

What it measures (in-process, ``time.perf_counter``, several repeats, the median):

- **Work precision of the closing stroke** (:func:`work_precision`). For every fixed-step
  method (rk4, euler_cromer, gauss4, radau5) and a range of steps, the error of the
  metrics that carry an accuracy target (:data:`softclose.problem.TARGETS`) against a tight
  adaptive reference (CVODES at :data:`TRUTH_TOL`), and the C kernel's run time per stroke.
  The designs are the config's own (the SPEC §8 case by default) and the spring + dashpot
  designs :data:`SPRING_DASHPOT`. The adaptive reference is a line of its own (tolerance
  against run time); the seed's method (Euler-Cromer at 1 kHz) is marked.
- **The configured default** (:func:`assess_default`): does ``cfg.simulate.integrator`` at
  ``cfg.simulate.step`` meet the targets on every design, and is it the cheapest setting
  that does? The cheapest setting on the designs of a run is reported separately: a quick
  run (fewer designs) cannot confirm a default that a design it omits rules out.
- **Speed** (:func:`speed`): model build, one stroke (with and without its error estimate),
  the raw kernel, a batch, the reference, ``softclose simulate`` end to end in a fresh
  interpreter (and which heavy modules its start-up imports), and -- when their public
  functions exist -- sweep throughput, robust optimisation, Monte Carlo yield and Sobol
  indices. Rows carry the speed target they are held to (:data:`SPEED_TARGETS`).
- **Optimiser** (:func:`optimiser_study`): shooting intervals N and sub-steps against the
  error of the optimal objective and the solve time.

Everything is returned as data (:class:`BenchResult`); ``softclose bench`` formats it and
writes the files, :mod:`softclose.figures.bench` draws it.
"""

from __future__ import annotations

import datetime
import json
import math
import os
import platform
import statistics
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from . import native
from .config import Config
from .integrators import METHODS, SEED
from .model import LidModel
from .problem import PARAM_COLUMNS, RELATIVE, TARGETS, objective, params_of
from .reference import Reference
from .simulate import Simulator

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

#: speed targets (from the issues): "max_s" -- at most this many seconds; "min_per_s" --
#: at least this many items per second. Rows without an entry have no target.
SPEED_TARGETS = {
    "model": {"max_s": 1.0},
    "run": {"max_s": 0.5e-3},
    "cli_simulate": {"max_s": 0.3},
    "kernel_40000": {"min_per_s": 100000.0},
    "sweep_40000": {"min_per_s": 20000.0},
    "sweep_cli_40000": {"min_per_s": 20000.0},
    "sweep_maps": {"max_s": 1.0},
    "robust_optimise": {"max_s": 5.0},
    "yield_1e5_robust": {"max_s": 1.0},
    "sobol_1024": {"max_s": 2.0},
}
#: modules that ``softclose simulate`` must not import at start-up (they are imported lazily)
HEAVY_MODULES = ("pandas", "pyarrow", "scipy", "SALib", "dask", "matplotlib")
#: a later entry is repeated (up to its repeat count) only while its runs took less than this
LATER_BUDGET_S = 30.0
#: the 40,000-design grid of the sweep throughput entry
SWEEP_GRID = {"design.spring_k": (500.0, 9500.0, 40),
              "design.spring_rest_length": (0.05, 0.09, 40),
              "design.damper_c": (100.0, 4000.0, 25)}

#: optimiser settings of the N / sub-steps study
OPT_NODES = (5, 10, 20, 40)
OPT_SUBSTEPS = (1, 2, 4)


def designs_for(cfg: Config, quick: bool = False) -> dict[str, np.ndarray]:
    """The benchmark's designs: the config's own (named "spec8" when it is the SPEC §8 case:
    no spring, no damper) and the spring + dashpot designs (the first only when ``quick``)."""
    own = params_of(cfg)
    name = "spec8" if own[0] == 0 and own[2] == 0 and own[3] == 0 else "config"
    out = {name: own}
    for i, (k, v) in enumerate(SPRING_DASHPOT.items()):
        if quick and i >= QUICK_DESIGNS:
            break
        out[k] = np.array(v, float)
    return out


# -- timing ------------------------------------------------------------------------------
def time_stats(fn, repeats: int, warmup: int = 1) -> tuple[float, float]:
    """(median, min) wall time of ``fn()`` over ``repeats`` calls after ``warmup`` calls, s."""
    for _ in range(warmup):
        fn()
    ts = []
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        ts.append(time.perf_counter() - t)
    return statistics.median(ts), min(ts)


def median_time(fn, repeats: int, warmup: int = 1) -> float:
    """Median wall time of ``fn()`` over ``repeats`` calls (after ``warmup`` calls), in s."""
    return time_stats(fn, repeats, warmup)[0]


def kernel_times(sim: Simulator, p: np.ndarray, repeats: int = 5,
                 target: float = 3e-3) -> tuple[float, float]:
    """(median, min) run time of one stroke in the C kernel (one thread), in s.

    A batch of identical strokes is sized so one call takes about ``target`` seconds, which
    makes the Python call overhead negligible; the times of ``repeats`` calls are divided
    by the batch size.
    """
    st = sim.cfg.stroke
    row = np.r_[p, sim.energy_tol(p[None, :])]

    def call(n):
        d = np.repeat(row[None, :], n, axis=0)
        return lambda: native.run_strokes(sim.table, sim.method, sim.step, st.t_max, st.theta0,
                                          st.theta_closed, d, threads=1)
    t1 = time_stats(call(1), 3)[1]
    n = int(min(max(1, target / max(t1, 1e-7)), 4000))
    med, low = time_stats(call(n), repeats)
    return med / n, low / n


# -- errors --------------------------------------------------------------------------------
def errors(res, truth) -> dict:
    """Error of each targeted metric of ``res`` against ``truth`` (both
    :class:`~softclose.stroke.StrokeResult`): absolute, or relative for
    :data:`softclose.problem.RELATIVE`; None where either value is missing."""
    out = {}
    for k in METRICS:
        a, b = getattr(res, k), getattr(truth, k)
        if a is None or b is None or not (math.isfinite(a) and math.isfinite(b)):
            out[k] = None
        else:
            out[k] = abs(a - b) / (abs(b) if k in RELATIVE else 1.0)
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
        from .jsonio import jsonable
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
    model = LidModel(cfg)
    designs = designs_for(cfg, quick)
    truth_ref = Reference(model, TRUTH_TOL)
    check_ref = Reference(model, 10 * TRUTH_TOL)
    rows, truths, floor = [], {}, {}
    table = None  # one coefficient table for every method (it depends on the model only)
    for dname, p in designs.items():
        truths[dname] = truth_ref.simulate(p)
        floor[dname] = errors(check_ref.simulate(p), truths[dname])
        log(f"  truth for {dname}: closing_time {truths[dname].closing_time}")
        for mname in methods:
            sim = Simulator(cfg, model=model, integrator=mname)
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
            r = ref.simulate(p)
            t, t_min = time_stats(lambda: ref.simulate(p), max(1, repeats // 2), warmup=0)
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

    Cost is the total kernel run time over the designs, each the fastest of its repeats
    (``time_min``: the least disturbed by other load on the machine). ``per_method`` gives
    the cheapest passing step of each method. ``method`` and ``step`` are None when nothing
    passes.
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
    good = sorted((e for e in per.values() if e["ok"] and e["designs"] == len(designs)),
                  key=lambda e: e["time"])
    per_method = {}
    for e in good:
        per_method.setdefault(e["method"], {"step": e["step"],
                                            "mean_time_per_stroke": e["time"] / len(designs)})
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


# -- speed of the user-facing calls --------------------------------------------------------
def _speed_row(key, what, seconds, repeats, note="", count=None, unit="designs") -> dict:
    """One speed row: median seconds; ``count`` items per call gives a rate (per second)."""
    rate = count / seconds if count and seconds > 0 else None
    tgt = SPEED_TARGETS.get(key)
    met = None
    if tgt and "max_s" in tgt:
        met = seconds <= tgt["max_s"]
    elif tgt and "min_per_s" in tgt and rate is not None:
        met = rate >= tgt["min_per_s"]
    return {"key": key, "what": what, "median_s": seconds, "repeats": repeats,
            "rate": rate, "unit": unit if count else "", "target": tgt, "met": met,
            "note": note}


def speed(cfg: Config, quick: bool = False, cli: bool = True, later: bool = True,
          log=None) -> list[dict]:
    """Run times (median of repeats) of model build, one stroke, the kernel, the reference,
    the CLI start-up, and (``later``) the sweep / robust / yield / Sobol entries."""
    log = log or (lambda *a: None)
    rows = []

    def add(row):
        rows.append(row)
        log(f"  {row['what']}: {row['median_s'] * 1e3:.3f} ms")
    r = 3 if quick else 9
    add(_speed_row("model", "LidModel(cfg) (symbolic model, CasADi)",
                   median_time(lambda: LidModel(cfg), r), r))
    model = LidModel(cfg)
    add(_speed_row("table", "Simulator(cfg, model) (coefficient table)",
                   median_time(lambda: Simulator(cfg, model=model), r), r))
    sim = Simulator(cfg, model=model)
    p = model.params()
    n = 50 if quick else 300
    add(_speed_row("run", "Simulator.run(p, estimate_error=False)",
                   median_time(lambda: sim.run(p, estimate_error=False), n, warmup=5), n,
                   f"{sim.method.name}, step {sim.step:g} s"))
    add(_speed_row("run_estimate", "Simulator.run(p) (with the h/2 error estimate)",
                   median_time(lambda: sim.run(p), n // 3, warmup=3), n // 3))
    st = cfg.stroke
    d1 = np.r_[p, sim.energy_tol(p[None, :])][None, :]
    add(_speed_row("kernel_call", "raw kernel call native.run_strokes (1 design, 1 thread)",
                   median_time(lambda: native.run_strokes(sim.table, sim.method, sim.step,
                                                          st.t_max, st.theta0,
                                                          st.theta_closed, d1, threads=1),
                               n, warmup=5), n))
    add(_speed_row("kernel_stroke", "kernel time per stroke (batch, 1 thread)",
                   kernel_times(sim, p, 7)[0], 7))
    rng = np.random.default_rng(0)
    B = 2000
    lo = [getattr(cfg.optimise, k)[0] for k in ("spring_k", "spring_rest_length", "damper_c")]
    hi = [getattr(cfg.optimise, k)[1] for k in ("spring_k", "spring_rest_length", "damper_c")]
    P = np.column_stack([rng.uniform(lo, hi, (B, 3)), np.zeros(B)])
    rb = 3 if quick else 5
    tb = median_time(lambda: sim.run_batch(P), rb)
    add(_speed_row("batch", f"Simulator.run_batch, {B} random designs of the design box, "
                   "all cores", tb, rb, f"{os.cpu_count()} threads", count=B))
    ref = Reference(model)
    rr = 2 if quick else 5
    add(_speed_row("reference", f"Reference(model).simulate(p) (CVODES, tol {ref.tol:g})",
                   median_time(lambda: ref.simulate(p), rr), rr))
    if cli:
        rc = 5 if quick else 9
        heavy = startup_imports(["simulate", "--json"])
        note = ("imports none of " + ", ".join(HEAVY_MODULES) if not heavy else
                "imports " + ", ".join(heavy) + " at start-up")
        add(_speed_row("cli_simulate", "`python -m softclose simulate --json` end to end "
                       "(fresh interpreter)", cli_time(["simulate", "--json"], rc), rc, note))
    if later:
        rows.extend(later_entries(cfg, quick=quick, log=log))
    return rows


def cli_time(argv: list[str], repeats: int) -> float:
    """Median wall time of ``python -m softclose ARGV`` in a fresh interpreter, in s."""
    cmd = [sys.executable, "-m", "softclose", *argv]
    env = _env()

    def run():
        r = subprocess.run(cmd, capture_output=True, env=env, text=True)
        if r.returncode != 0:
            raise RuntimeError(f"softclose {' '.join(argv)} failed: {r.stderr.strip()}")
    return median_time(run, repeats)


def startup_imports(argv: list[str], modules=HEAVY_MODULES) -> list[str]:
    """Which of ``modules`` a fresh interpreter has imported after
    ``softclose.cli.main(argv)`` (the command's own start-up and run)."""
    code = ("import io, json, sys, contextlib\n"
            "from softclose.cli import main\n"
            "with contextlib.redirect_stdout(io.StringIO()):\n"
            f"    main({list(argv)!r})\n"
            f"print(json.dumps([m for m in {list(modules)!r} if m in sys.modules]))\n")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                       env=_env())
    if r.returncode != 0:
        raise RuntimeError(f"softclose {' '.join(argv)} failed: {r.stderr.strip()[-300:]}")
    return json.loads(r.stdout.strip().splitlines()[-1])


def _env() -> dict:
    """The environment of a fresh interpreter that imports this copy of softclose."""
    root = str(Path(__file__).resolve().parents[1])
    env = dict(os.environ)
    env["PYTHONPATH"] = root + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    return env


def sweep_axes() -> dict[str, np.ndarray]:
    """The 40,000-design grid of the sweep throughput entry (:data:`SWEEP_GRID`)."""
    return {k: np.linspace(a, b, n) for k, (a, b, n) in SWEEP_GRID.items()}


def later_entries(cfg: Config, quick: bool = False, log=None) -> list[dict]:
    """Sweep throughput on the 40,000-design grid (the kernel, the in-process sweep, and
    the command line end to end with its CSV and maps), robust optimisation, Monte Carlo
    yield of 1e5 samples and Sobol indices at N = 1024, each through its public function.

    Yield and Sobol indices are measured at the nominal optimum (``softclose.optimise``'s
    design): the default config's own design has no spring and no damper, so relative
    spreads of spring_k and damper_c would be zero there. A function that does not exist
    yet gives a row with a note; ``quick`` skips the two longest (robust optimisation and
    the Monte Carlo run) with a note. Each entry is the median of up to 3 runs (1 with
    ``quick``), fewer when the runs so far took :data:`LATER_BUDGET_S` or more.
    """
    log = log or (lambda *a: None)
    rows = []

    def timed(key, what, fn, repeats, count=None, unit="designs", note=""):
        out, ts = [], []
        try:
            while len(ts) < repeats and (not ts or sum(ts) < LATER_BUDGET_S):
                t = time.perf_counter()
                out.append(fn())
                ts.append(time.perf_counter() - t)
        except Exception as exc:  # reported in the table, the bench goes on
            rows.append(_not_measured(key, what, f"failed: {type(exc).__name__}: "
                                                 f"{str(exc).splitlines()[0]}", repeats))
            log(f"  {what}: failed ({exc})")
            return None
        t = statistics.median(ts)
        rows.append(_speed_row(key, what, t, len(ts), note, count=count, unit=unit))
        log(f"  {what}: {t:.3f} s")
        return out[-1]

    rep = 1 if quick else 3
    from .sweeps import sweep
    from .sweeps.space import make_grid
    n_grid = int(np.prod([n for _, _, n in SWEEP_GRID.values()]))
    axes = sweep_axes()
    sim = Simulator(cfg)
    grid = make_grid(axes)            # the sweep's own designs, in its order
    P = np.tile(params_of(cfg), (n_grid, 1))
    P[:, [PARAM_COLUMNS[k] for k in grid.keys]] = grid.points(np.arange(n_grid))
    sim.run_batch(P[:1000])                             # warm-up: threads up
    timed("kernel_40000", f"Simulator.run_batch: the {n_grid:,} strokes of that grid, "
          "all cores", lambda: sim.run_batch(P), rep, count=n_grid,
          note="closing and not closing alike; a lid that creeps open runs to t_max")
    what = f"sweep(cfg, axes): the {n_grid:,}-design grid k × l0 × c, in-process"
    res = timed("sweep_40000", what, lambda: sweep(cfg, axes), rep, count=n_grid)
    if res is not None:
        rows[-1]["note"] = (f"the result's own designs_per_second (evaluation only): "
                            f"{res.designs_per_second or 0:,.0f}")
    _cli_sweep_rows(cfg, rows, n_grid, timed, 1 if quick else 5)
    from .robust import optimise_robust
    from .robust import sensitivity as sens
    from .robust import tolerance_analysis as ta
    what = "robust optimisation over the [tolerance] box"
    rob = None
    if quick:
        rows.append(_not_measured("robust_optimise", what, "not run with --quick"))
    else:
        rob = timed("robust_optimise", what + ": softclose.optimise(cfg, robust=True)",
                    lambda: optimise_robust(cfg), 1)
    what_mc = "Monte Carlo yield: tolerance_analysis(cfg, samples=100000)"
    what_s = "Sobol indices: sensitivity(cfg, samples=1024)"
    at, note = _nominal_optimum(cfg)
    # the Monte Carlo pass of the robust design (what `optimise --robust` checks), then the
    # nominal optimum's on its box: 12 % of its lids creep open and run to t_max (their
    # metrics change until then), which is why it takes longer
    if rob is None or not getattr(rob, "design", None):
        rows.append(_not_measured("yield_1e5_robust", what_mc + ", the robust design",
                                  "not run with --quick" if quick else "no robust design"))
    else:
        c_rob = cfg.with_design(**rob.design)
        ta(c_rob, samples=1000)                         # warm-up: its tables built
        timed("yield_1e5_robust", what_mc + ", the robust design",
              lambda: ta(c_rob, samples=100000, reference=0), rep, count=100000,
              unit="samples", note="the Monte Carlo pass (kernel, yield, interval, "
              "percentiles); the adaptive reference checks of the report are not in it")
    if quick:
        rows.append(_not_measured("yield_1e5", what_mc, "not run with --quick"))
    elif at is None:
        rows.append(_not_measured("yield_1e5", what_mc, note))
    else:
        timed("yield_1e5", what_mc + ", the nominal optimum", lambda: ta(at, samples=100000),
              rep, count=100000, unit="samples", note=note + "; with its 3 adaptive "
              "reference checks; no target of its own (see the robust design's row)")
    if at is None:
        rows.append(_not_measured("sobol_1024", what_s, note))
    else:
        timed("sobol_1024", what_s, lambda: sens(at, samples=1024), rep, note=note)
    return rows


def _cli_sweep_rows(cfg: Config, rows: list, n_grid: int, timed, repeats: int) -> None:
    """``softclose sweep`` over :data:`SWEEP_GRID` end to end (a fresh interpreter, the CSV
    and the three maps, start-up included; the default config), and its maps stage (from
    the command's ``--json`` stages: after the table is evaluated until every map is
    saved)."""
    import tempfile

    from .config import default_config, to_dict
    what = (f"softclose sweep --grid ... --out DIR: the {n_grid:,}-design grid with its CSV "
            "and maps, fresh interpreter, end to end")
    what_maps = "the maps of that command (3 maps; its `maps` stage)"
    if to_dict(cfg) != to_dict(default_config()):
        for key, w in (("sweep_cli_40000", what), ("sweep_maps", what_maps)):
            rows.append(_not_measured(key, w, "the command line runs the default config"))
        return
    grid = [f"--grid={k}={a:g}:{b:g}:{n}" for k, (a, b, n) in SWEEP_GRID.items()]
    maps: list[float] = []
    with tempfile.TemporaryDirectory() as tmp:
        def run():
            out = Path(tmp) / f"run{len(maps)}"
            r = subprocess.run([sys.executable, "-m", "softclose", "sweep", *grid, "--out",
                                str(out), "--json"], capture_output=True, text=True,
                               env=_env())
            if r.returncode != 0:
                raise RuntimeError(f"exit {r.returncode}: {r.stderr.strip()[-300:]}")
            maps.append(json.loads(r.stdout)["stages"]["maps"])
        timed("sweep_cli_40000", what, run, repeats, count=n_grid,
              note="CSV and 3 maps; the maps are drawn by processes forked at start-up")
    if maps:
        rows.append(_speed_row("sweep_maps", what_maps, statistics.median(maps), len(maps),
                               note=f"{min(maps):.2f}–{max(maps):.2f} s; drawn from the "
                                    "slices through the best design: no larger for a "
                                    "larger sweep"))


def _not_measured(key, what, note, repeats=0) -> dict:
    return {**_speed_row(key, what, math.nan, repeats), "median_s": None, "met": None,
            "note": note}


def _nominal_optimum(cfg: Config):
    """(cfg with the nominal optimum's design, note), or (None, why not)."""
    from .optimiser import optimise
    try:
        r = optimise(cfg)
    except Exception as exc:  # reported in the table
        return None, f"not measured: optimise(cfg) failed ({type(exc).__name__}: {exc})"
    if not getattr(r, "success", False) or not getattr(r, "design", None):
        return None, "not measured: optimise(cfg) found no design to analyse"
    d = r.design
    return cfg.with_design(**{k: d[k] for k in ("spring_k", "spring_rest_length",
                                                 "damper_c")}), \
        (f"at the nominal optimum k = {d['spring_k']:.5g} N/m, l0 = "
         f"{d['spring_rest_length']:.5g} m, c = {d['damper_c']:.5g} N s/m")


# -- optimiser ---------------------------------------------------------------------------
def optimiser_study(cfg: Config, quick: bool = False, log=None) -> tuple[list, str]:
    """N and sub-steps against the error of the optimal objective and the solve time.

    The error is measured against the best estimate of the continuous optimum: the
    objective that the adaptive reference gives at the design of the finest setting.
    Each row also carries the discretisation error at its own design,
    |J_N - J_reference(design_N)|. Returns (rows, note); rows is empty with a note
    when the optimiser's ``solve`` is not available.
    """
    log = log or (lambda *a: None)
    from .optimiser import solve
    nodes = (5, 10, 20) if quick else OPT_NODES
    subs = (1, 4) if quick else OPT_SUBSTEPS
    ref = Reference(LidModel(cfg), TRUTH_TOL)
    rows = []
    for n in nodes:
        for s in subs:
            try:
                t = time.perf_counter()
                r = solve(cfg, nodes=n, substeps=s)
                wall = time.perf_counter() - t
            except Exception as exc:  # reported in the table, the bench goes on
                rows.append({"nodes": n, "substeps": s, "success": False,
                             "message": f"{type(exc).__name__}: {str(exc).splitlines()[0]}"})
                continue
            if not r.success or r.design is None or r.objective is None:
                rows.append({"nodes": n, "substeps": s, "success": False,
                             "message": str(getattr(r, "message", "") or "not solved")})
                continue
            d = r.design
            rr = ref.simulate(params_of(cfg, d))
            J_ref = objective(cfg.optimise, rr.impact_theta_dot, rr.peak_tip_speed)
            rows.append({"nodes": n, "substeps": s, "success": True,
                         "objective": float(r.objective), "objective_reference": J_ref,
                         "discretisation_error": None if J_ref is None else
                         abs(float(r.objective) - J_ref),
                         "solve_time": float(getattr(r, "solve_time", 0.0) or wall),
                         "build_time": float(getattr(r, "build_time", 0.0) or 0.0),
                         "wall_time": wall,
                         "spring_k": d["spring_k"], "spring_rest_length": d["spring_rest_length"],
                         "damper_c": d["damper_c"], "message": ""})
            log(f"  N={n} substeps={s}: J={r.objective:.6g} in {wall:.2f} s")
    ok = [r for r in rows if r.get("success") and r.get("objective_reference") is not None]
    if ok:
        finest = max(ok, key=lambda r: (r["nodes"] * r["substeps"], r["nodes"]))
        J_star = finest["objective_reference"]
        for r in rows:
            r["J_star"] = J_star
            r["objective_error"] = abs(r["objective"] - J_star) if "objective" in r else None
    return rows, ""


# -- the seed's computation ----------------------------------------------------------------
#: the seed notebook's step (1000 samples per second)
SEED_STEP = SEED[1]
#: the metrics the seed reads off its drop
SEED_KEYS = ("closing_time", "impact_theta_dot", "impact_tip_speed")


def seed_reading(sim: Simulator) -> dict:
    """The seed's numbers: ``sim`` (Euler-Cromer at 1 ms) with the impact read at the first
    sample at or below theta_closed, as the seed notebook does, instead of located in the
    step. Also returns the same stroke with the event located (``located_event``) and the
    trajectory."""
    res = sim.run(trajectory=True, estimate_error=False)
    tr = res.trajectory
    # the kernel stops at the located event; the sample the seed reads is one full step on
    # from the last node before it
    t, th, thd = tr["t"][-2], tr["theta"][-2], tr["theta_dot"][-2]
    x1 = native.kernel_step(sim.table, sim.method, sim.model.params(), sim.step,
                            np.array([th, thd]))
    v_T = np.asarray(sim.model.kin(np.array([x1[0], x1[1]]))[4]).ravel()
    return {"closing_time": t + sim.step, "impact_theta_dot": float(x1[1]),
            "impact_tip_speed": float(np.hypot(v_T[0], v_T[1])),
            "theta_at_sample_deg": math.degrees(x1[0]), "located_event": res.metrics(),
            "trajectory": tr}


def _slope(hs, errs, above: float = 1e-8):
    """Slope of log error against log step over the errors above ``above`` (NaN if < 2)."""
    e, h = np.asarray(errs, float), np.asarray(hs, float)
    ok = e > above
    if ok.sum() < 2:
        return math.nan
    return float(np.polyfit(np.log(h[ok]), np.log(e[ok]), 1)[0])


def seed_reproduction(cfg: Config, fast: bool = False) -> dict:
    """The seed notebook's gravity-only drop (Euler-Cromer at 1 kHz, impact read off the
    sample grid) against the adaptive reference (tolerance ``simulate.reference_tol``) and
    the configured default (``simulate.integrator`` at ``simulate.step``, event located).

    Returns the metrics and errors of each, the errors of Euler-Cromer and rk4 against the
    step (``convergence``), their observed orders, and the trajectories of the seed's drop
    and of the default (``trajectories``, for the figure).
    """
    ec = Simulator(cfg, integrator=SEED[0], step=SEED_STEP)
    seed = seed_reading(ec)
    default = Simulator(cfg, model=ec.model).run(trajectory=True)
    ref = Reference(ec.model).simulate()
    steps = SEED_STEP * 2.0 ** -np.arange(0, 4 if fast else 8)
    steps = np.r_[SEED_STEP * np.array([8, 4, 2]), steps]
    conv = {"step": steps.tolist()}
    for name in ("euler_cromer", "rk4"):
        for k in SEED_KEYS[:2]:
            conv[f"{name}_{k}_error"] = []
        for h in steps:
            r = Simulator(cfg, model=ec.model, integrator=name, step=float(h)).run(
                estimate_error=False)
            for k in SEED_KEYS[:2]:
                conv[f"{name}_{k}_error"].append(abs(getattr(r, k) - getattr(ref, k)))
    order = {n: _slope(steps, conv[f"{n}_impact_theta_dot_error"])
             for n in ("euler_cromer", "rk4")}
    refv = {k: getattr(ref, k) for k in SEED_KEYS}
    loc = seed["located_event"]
    return {
        "reference": refv, "reference_tol": ref.tolerance,
        "seed_grid_reading": {k: seed[k] for k in SEED_KEYS},
        "seed_theta_at_sample_deg": seed["theta_at_sample_deg"],
        "seed_errors": {k: seed[k] - refv[k] for k in SEED_KEYS},
        "euler_cromer_located_event": {k: loc[k] for k in SEED_KEYS},
        "euler_cromer_located_errors": {k: loc[k] - refv[k] for k in SEED_KEYS},
        "default": {"method": default.method, "step": default.step,
                    **{k: getattr(default, k) for k in SEED_KEYS}},
        "default_errors": {k: getattr(default, k) - refv[k] for k in SEED_KEYS},
        "default_accuracy": {k: (default.accuracy or {}).get(k) for k in SEED_KEYS},
        "observed_order": order, "convergence": conv,
        "trajectories": {"seed": seed["trajectory"], "default": default.trajectory},
    }


# -- the whole benchmark ---------------------------------------------------------------------
def machine() -> str:
    """CPU, cores, OS, Python, NumPy and CasADi versions of this machine."""
    cpu = platform.processor() or ""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    import casadi
    return (f"{cpu}, {os.cpu_count()} cores; {platform.system()} {platform.release()}; "
            f"Python {platform.python_version()}, NumPy {np.__version__}, "
            f"CasADi {casadi.__version__}")


def commit() -> str | None:
    """The git commit of this source tree (with "+dirty" if it has changes), if known."""
    root = Path(__file__).resolve().parents[1]
    try:
        h = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=root, text=True,
                           capture_output=True, timeout=10)
        if h.returncode != 0:
            return None
        d = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=root,
                           text=True, capture_output=True, timeout=10)
        return h.stdout.strip() + ("+dirty" if d.stdout.strip() else "")
    except (OSError, subprocess.SubprocessError):
        return None


@dataclass(frozen=True)
class BenchResult:
    """Everything one benchmark run measured (see the module docstring)."""

    machine: str
    date: str
    commit: str | None
    quick: bool
    work_precision: WorkPrecision
    speed: tuple
    optimiser: tuple
    optimiser_note: str
    elapsed: float
    config: dict = field(default_factory=dict)
    load: tuple = ()  # 1-minute load average at the start and at the end of the run

    @property
    def default(self) -> dict:
        return self.work_precision.default

    @property
    def success(self) -> bool:
        return True

    def to_json(self) -> dict:
        from .jsonio import jsonable
        return jsonable({"machine": self.machine, "date": self.date, "commit": self.commit,
                         "quick": self.quick, "targets": dict(TARGETS),
                         "relative": list(RELATIVE), "speed_targets": SPEED_TARGETS,
                         "default": self.default,
                         "work_precision": self.work_precision.to_json(),
                         "speed": list(self.speed), "optimiser": list(self.optimiser),
                         "optimiser_note": self.optimiser_note, "elapsed": self.elapsed,
                         "load": list(self.load), "config": self.config})


def run(cfg: Config, quick: bool = False, log=None, cli: bool = True,
        optimiser: bool = True, later: bool = True) -> BenchResult:
    """The whole benchmark: work precision, speed, optimiser (see the module docstring)."""
    log = log or (lambda *a: None)
    t0 = time.perf_counter()
    load0 = _load()
    log("work precision ...")
    wp = work_precision(cfg, quick=quick, log=log)
    log("speed ...")
    sp = speed(cfg, quick=quick, cli=cli, later=later, log=log)
    log("optimiser ...")
    opt, note = optimiser_study(cfg, quick=quick, log=log) if optimiser else \
        ([], "optimiser section not run")
    return BenchResult(machine=machine(),
                       date=datetime.datetime.now().astimezone().isoformat(timespec="seconds"),
                       commit=commit(), quick=quick, work_precision=wp, speed=tuple(sp),
                       optimiser=tuple(opt), optimiser_note=note,
                       elapsed=time.perf_counter() - t0,
                       config={"integrator": cfg.simulate.integrator,
                               "step": cfg.simulate.step,
                               "nodes": cfg.optimise.nodes,
                               "substeps": cfg.optimise.substeps},
                       load=(load0, _load()))


def _load() -> float | None:
    """The 1-minute load average (None where the OS does not give it)."""
    try:
        return os.getloadavg()[0]
    except (AttributeError, OSError):
        return None


__all__ = ["run", "work_precision", "speed", "optimiser_study", "later_entries",
           "assess_default", "cheapest_setting", "errors", "meets", "fit_order",
           "designs_for", "kernel_times", "time_stats", "median_time", "cli_time",
           "startup_imports", "machine", "commit", "sweep_axes", "BenchResult",
           "WorkPrecision", "TRUTH_TOL", "REFERENCE_TOLS", "SEED", "STEPS", "QUICK_STEPS",
           "SPRING_DASHPOT", "SPEED_TARGETS", "HEAVY_MODULES", "SWEEP_GRID", "METRICS"]
