"""Robust design under manufacturing tolerances (config section ``[tolerance]``).

- :func:`tolerance_analysis` -- Monte Carlo yield of a design over its tolerance box, with a
  Wilson confidence interval, percentiles and adaptive-reference checks (``softclose yield``);
- :func:`sensitivity` -- Sobol first-order and total indices of closing time and impact speed
  with respect to each toleranced key, by SALib (``softclose sensitivity``);
- :func:`optimise_robust` -- the design that meets every constraint in every scenario of the
  box, by a scenario multiple-shooting NLP with interior worst cases added by Monte Carlo
  (``softclose optimise --robust``, ``softclose.optimise(cfg, robust=True)``);
- :func:`bench_numbers` -- the timings the benchmark reports.

The modules: :mod:`.box` (the box and its samples), :mod:`.evaluate` (samples -> strokes in the
C kernel), :mod:`.stats`, :mod:`.analysis`, :mod:`.sensitivity`, :mod:`.nlp` (the scenario
NLP), :mod:`.verify` (adaptive reference checks); the robust optimiser: :mod:`.design` (its
procedure, step by step), :mod:`.policy` (its limits and tolerances), :mod:`.scenarios` (the
points of the box the NLP holds), :mod:`.solve` (the NLP solved over one box),
:mod:`.worst_cases` (interior search and corner check), :mod:`.infeasible` (why no design),
:mod:`.result`.
"""

from .analysis import TemperatureYield, YieldResult, tolerance_analysis, yield_by_temperature
from .design import optimise_robust
from .result import RobustResult
from .sensitivity import SensitivityResult, sensitivity
from ..config import default_config

__all__ = ["tolerance_analysis", "yield_by_temperature", "TemperatureYield", "sensitivity", "optimise_robust", "YieldResult",
           "SensitivityResult", "RobustResult", "bench_numbers"]


def bench_numbers(cfg=None, *, repeats: int = 1) -> dict:
    """Wall-clock seconds of the three robust-design workloads on ``cfg`` (default config):
    ``robust_optimise`` (end to end, the three default tolerances), ``monte_carlo_1e5``
    (10^5 strokes of the robust design over its box), ``sobol_1024`` (N = 1024 base samples).
    Each is the best of ``repeats`` runs after one warm-up (kernel compiled, imports done)."""
    import time

    from .box import box_of
    from .evaluate import evaluate
    cfg = cfg or default_config()

    def best(f):
        ts = []
        for _ in range(max(1, repeats)):
            t0 = time.perf_counter()
            out = f()
            ts.append(time.perf_counter() - t0)
        return min(ts), out

    t_rob, res = best(lambda: optimise_robust(cfg))
    design = res.design or {}
    c = cfg.with_design(**design) if design else cfg
    box = box_of(c)
    z = box.draw(100_000, 0)
    X = box.values(z)
    evaluate(c, box.keys, X[:1000])                     # warm-up: tables built, threads up
    t_mc, _ = best(lambda: evaluate(c, box.keys, X))
    sensitivity(c, samples=8)                            # warm-up: SALib imported
    t_sob, _ = best(lambda: sensitivity(c, samples=1024))
    return {"robust_optimise": t_rob, "monte_carlo_1e5": t_mc, "sobol_1024": t_sob,
            "robust_success": res.success, "robust_yield": res.yield_,
            "scenarios": len(res.scenarios)}
