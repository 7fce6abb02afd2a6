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
writes the files, :mod:`softclose.present.figures.bench` draws it.

The modules: :mod:`.precision` (work precision, the cheapest setting, the default),
:mod:`.calls` (the speed rows, start-up), :mod:`.features` (the sweep, robust, yield, Sobol and
optimiser entries), :mod:`.seed` (the seed's drop), :mod:`.timing` (how things are timed, a
speed row), :mod:`.benchmark` (:func:`run` and its result, machine and commit).
"""

from ..numerics.integrators import SEED
from .benchmark import BenchResult, commit, machine, run
from .features import (FEATURE_BUDGET_S, OPT_NODES, OPT_SUBSTEPS, SWEEP_GRID, feature_entries,
                    optimiser_study, sweep_axes)
from .precision import (METRICS, QUICK_DESIGNS, QUICK_STEPS, REFERENCE_TOLS, SPRING_DASHPOT,
                        STEPS, TRUTH_TOL, WorkPrecision, assess_default, cheapest_setting,
                        designs_for, errors, fit_order, meets, work_precision)
from .seed import SEED_KEYS, SEED_STEP, seed_reading, seed_reproduction
from .calls import HEAVY_MODULES, cli_time, speed, startup_imports
from .timing import SPEED_TARGETS, kernel_times, median_time, speed_row, time_stats

__all__ = ["run", "work_precision", "speed", "optimiser_study", "feature_entries",
           "assess_default", "cheapest_setting", "errors", "meets", "fit_order",
           "designs_for", "kernel_times", "time_stats", "median_time", "cli_time",
           "startup_imports", "machine", "commit", "sweep_axes", "BenchResult",
           "WorkPrecision", "TRUTH_TOL", "REFERENCE_TOLS", "SEED", "STEPS", "QUICK_STEPS",
           "SPRING_DASHPOT", "SPEED_TARGETS", "HEAVY_MODULES", "SWEEP_GRID", "METRICS",
           "QUICK_DESIGNS", "FEATURE_BUDGET_S", "OPT_NODES", "OPT_SUBSTEPS", "speed_row",
           "seed_reading", "seed_reproduction", "SEED_STEP", "SEED_KEYS"]
