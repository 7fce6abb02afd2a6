"""How the benchmark times things: the median (and least) wall time of repeated calls, the C
kernel's time per stroke, and one row of the speed table with the target it is held to
(:data:`SPEED_TARGETS`).
"""

from __future__ import annotations

import math
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from ..simulation.kernel import binding
from ..problem import as_params
from ..simulation.simulator import Simulator

#: speed targets (from the issues): "max_s" -- at most this many seconds; "min_per_s" --
#: at least this many items per second. Rows without an entry have no target.
SPEED_TARGETS = {
    "model": {"max_s": 1.0},
    "run": {"max_s": 0.5e-3},
    "cli_simulate": {"max_s": 0.3},
    "startup_simulate": {"max_ratio": 1.5},
    "startup_optimise": {"max_ratio": 4.0},
    "kernel_40000": {"min_per_s": 100000.0},
    "kernel_40000_compression": {"min_per_s": 100000.0},
    "kernel_40000_friction_pivot": {"min_per_s": 60000.0},
    "kernel_40000_gas_strut": {"min_per_s": 80000.0},     # with its friction band
    "kernel_40000_hinge": {"max_ratio": 1.0},       # per step as fast as the four-bar's
    "sweep_40000": {"min_per_s": 20000.0},
    "sweep_cli_40000": {"min_per_s": 20000.0},
    "sweep_maps": {"max_s": 1.0},
    "placement_sample_1e6": {"min_per_s": 50000.0},   # issue 23: end to end, the command
    "robust_optimise": {"max_s": 10.0},      # both spring kinds one can buy
    # the optimiser with the spring's wire, coil diameter and coils free (SPEC §14): <= 2x
    # the plain optimiser
    "optimise_made_to_order": {"max_ratio": 2.0},
    # co-design (issue 23), end to end: nominal <= 3 s, robust <= 20 s
    "co_design_points": {"max_s": 3.0},
    "co_design_points_robust": {"max_s": 20.0},
    "co_design_end_damper": {"max_s": 3.0},
    "co_design_end_damper_robust": {"max_s": 20.0},
    "yield_1e5_robust": {"max_s": 1.0},
    "sobol_1024": {"max_s": 2.0},
    "select_1000": {"max_s": 20.0},          # 1,000 catalog pairs, top 10 verified
    "fit_cli_2x1": {"max_s": 2.0},
    "fit_cli_5x3": {"max_s": 10.0},
}


def time_stats(fn, repeats: int, warmup: int = 1) -> tuple[float, float]:
    """(median, min) wall time of ``fn()`` over ``repeats`` calls after ``warmup`` calls, s
    (the other processes' load over the calls: :func:`load_average`)."""
    for _ in range(warmup):
        fn()
    ts = []
    with OtherLoad():
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
    st = sim.stroke
    row = np.r_[binding.kernel_rows(as_params(p)), sim.energy_tol(p[None, :])]

    def call(n):
        d = np.repeat(row[None, :], n, axis=0)
        return lambda: binding.run_strokes(sim.table, sim.method, sim.step, st.t_max, st.theta0,
                                          st.theta_closed, d, threads=1)
    t1 = time_stats(call(1), 3)[1]
    n = int(min(max(1, target / max(t1, 1e-7)), 4000))
    med, low = time_stats(call(n), repeats)
    return med / n, low / n


#: the targets hold on an idle machine: other processes using fewer cores than this on
#: average while a row is measured (2 cores)
IDLE_LOAD = 0.5


def _busy_seconds() -> float | None:
    """CPU seconds every process of the machine has used (Linux /proc/stat), or None."""
    try:
        with open("/proc/stat") as f:
            fields = f.readline().split()[1:]
    except OSError:
        return None
    ticks = [int(x) for x in fields]
    idle = ticks[3] + (ticks[4] if len(ticks) > 4 else 0)          # idle + iowait
    return (sum(ticks[:8]) - idle) / os.sysconf("SC_CLK_TCK")


def _own_seconds() -> float:
    """CPU seconds of this process and its finished children."""
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system


class OtherLoad:
    """The cores other processes used on average while the block ran: the machine's busy CPU
    time minus this process's and its children's, over the wall time. This is the load a
    timing is measured under; the 1-minute load average would count the benchmark's own
    work. ``value`` is None where /proc/stat is not available."""

    def __enter__(self):
        self.value = None
        self._wall, self._busy, self._own = time.perf_counter(), _busy_seconds(), _own_seconds()
        return self

    def __exit__(self, *exc):
        busy = _busy_seconds()
        wall = time.perf_counter() - self._wall
        if busy is not None and self._busy is not None and wall > 0:
            other = (busy - self._busy) - (_own_seconds() - self._own)
            self.value = max(other, 0.0) / wall
        global _LAST_LOAD
        _LAST_LOAD = self.value
        return False


_LAST_LOAD: float | None = None


def load_average() -> float | None:
    """The load other processes put on the machine during the last timing (the cores they
    used on average: :class:`OtherLoad`); None before any or where it cannot be measured."""
    return _LAST_LOAD


def speed_row(key, what, seconds, repeats, note="", count=None, unit="designs",
              ratio=None) -> dict:
    """One speed row: median seconds; ``count`` items per call gives a rate (per second);
    ``ratio``: the time as a multiple of a floor (a start-up against ``import casadi``);
    ``load``: the cores other processes used while it was measured (the targets are an idle
    machine's: :data:`IDLE_LOAD`)."""
    rate = count / seconds if count and seconds > 0 else None
    tgt = SPEED_TARGETS.get(key)
    met = None
    if tgt and "max_s" in tgt:
        met = seconds <= tgt["max_s"]
    elif tgt and "min_per_s" in tgt and rate is not None:
        met = rate >= tgt["min_per_s"]
    elif tgt and "max_ratio" in tgt and ratio is not None:
        met = ratio <= tgt["max_ratio"]
    row = {"key": key, "what": what, "median_s": seconds, "repeats": repeats,
           "rate": rate, "unit": unit if count else "", "target": tgt, "met": met,
           "load": load_average(), "note": note}
    if ratio is not None:
        row["ratio"] = ratio
    return row


def not_measured(key, what, note, repeats=0) -> dict:
    """A row of something not measured, with why (``note``)."""
    return {**speed_row(key, what, math.nan, repeats), "median_s": None, "met": None,
            "note": note}


def fresh_command(*args: str) -> list[str]:
    """A fresh interpreter's command line (``python -P ARGS``; with :func:`fresh_env`): it
    imports this copy of softclose. Without ``-P``, ``python -m``/``-c`` would look first in
    the folder the bench runs in -- a clone's ``softclose/`` beside an installed copy -- and
    time that one, with another build cache."""
    return [sys.executable, "-P", *args]


def fresh_env() -> dict:
    """The environment of a fresh interpreter that imports this copy of softclose."""
    root = str(Path(__file__).resolve().parents[2])
    env = dict(os.environ)
    env["PYTHONPATH"] = root + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    return env


def cli_time(argv: list[str], repeats: int) -> float:
    """Median wall time of ``python -m softclose ARGV`` in a fresh interpreter, in s."""
    cmd = fresh_command("-m", "softclose", *argv)
    env = fresh_env()

    def run():
        r = subprocess.run(cmd, capture_output=True, env=env, text=True)
        if r.returncode != 0:
            raise RuntimeError(f"softclose {' '.join(argv)} failed: {r.stderr.strip()}")
    return median_time(run, repeats)
