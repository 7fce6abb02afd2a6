"""Speed of the user-facing calls: model build, one stroke (with and without its error
estimate), the raw kernel, a batch, the reference, ``softclose simulate`` end to end in a
fresh interpreter and which heavy modules its start-up imports (:func:`speed`), and the
features' entries (:mod:`softclose.bench.features`).
"""

from __future__ import annotations

import json
import os
import subprocess

import numpy as np

from ..simulation.kernel import binding
from ..config import Config, default_config
from ..model.lid import LidModel
from ..simulation.reference import Reference
from ..simulation.simulator import Simulator
from .features import feature_entries
from .timing import (cli_time, fresh_command, fresh_env, kernel_times, median_time,
                     not_measured, speed_row)
from ..optimiser import cache as optimiser_cache
from ..problem import resolve

#: modules that ``softclose simulate`` must not import at start-up (they are imported lazily)
HEAVY_MODULES = ("pandas", "pyarrow", "scipy", "SALib", "dask", "matplotlib")


def speed(cfg: Config, quick: bool = False, cli: bool = True, features: bool = True,
          log=None) -> list[dict]:
    """Run times (median of repeats) of model build, one stroke, the kernel, the reference,
    the CLI start-up, and (``features``) the sweep / robust / yield / Sobol entries."""
    log = log or (lambda *a: None)
    rows = []

    def add(row):
        rows.append(row)
        log(f"  {row['what']}: {row['median_s'] * 1e3:.3f} ms")
    r = 3 if quick else 9
    case = resolve(cfg)
    add(speed_row("model", "LidModel(cfg) (symbolic model, CasADi)",
                  median_time(lambda: LidModel(case), r), r))
    model = LidModel(case)
    add(speed_row("table", "Simulator(cfg, model) (coefficient table)",
                  median_time(lambda: Simulator(case, model=model), r), r))
    sim = Simulator(case, model=model)
    p = model.params()
    n = 50 if quick else 300
    add(speed_row("run", "Simulator.run(p, estimate_error=False)",
                  median_time(lambda: sim.run(p, estimate_error=False), n, warmup=5), n,
                  f"{sim.method.name}, step {sim.step:g} s"))
    add(speed_row("run_estimate", "Simulator.run(p) (with the h/2 error estimate)",
                  median_time(lambda: sim.run(p), n // 3, warmup=3), n // 3))
    st = cfg.stroke
    d1 = np.r_[p, sim.energy_tol(p[None, :])][None, :]
    add(speed_row("kernel_call", "raw kernel call binding.run_strokes (1 design, 1 thread)",
                  median_time(lambda: binding.run_strokes(sim.table, sim.method, sim.step,
                                                         st.t_max, st.theta0,
                                                         st.theta_closed, d1, threads=1),
                              n, warmup=5), n))
    add(speed_row("kernel_stroke", "kernel time per stroke (batch, 1 thread)",
                  kernel_times(sim, p, 7)[0], 7))
    rng = np.random.default_rng(0)
    B = 2000
    lo = [getattr(cfg.optimise, k)[0] for k in ("spring_k", "spring_rest_length", "damper_c")]
    hi = [getattr(cfg.optimise, k)[1] for k in ("spring_k", "spring_rest_length", "damper_c")]
    P = np.column_stack([rng.uniform(lo, hi, (B, 3)), np.zeros(B)])
    rb = 3 if quick else 5
    tb = median_time(lambda: sim.run_batch(P), rb)
    add(speed_row("batch", f"Simulator.run_batch, {B} random designs of the design box, "
                  "all cores", tb, rb, f"{os.cpu_count()} threads", count=B))
    ref = Reference(model, case.solver.reference_tol)
    rr = 2 if quick else 5
    add(speed_row("reference", f"Reference(model).simulate(p) (CVODES, tol {ref.tol:g})",
                  median_time(lambda: ref.simulate(p, case), rr), rr))
    if cli:
        rc = 5 if quick else 9
        heavy = startup_imports(["simulate", "--json"])
        note = ("imports none of " + ", ".join(HEAVY_MODULES) if not heavy else
                "imports " + ", ".join(heavy) + " at start-up")
        add(speed_row("cli_simulate", "`python -m softclose simulate --json` end to end "
                      "(fresh interpreter)", cli_time(["simulate", "--json"], rc), rc, note))
        if quick:
            rows.extend(not_measured(key, f"{what} end to end / `python -c \"import casadi\"`",
                                     f"not measured with --quick ({3 * (STARTUP_REPEATS + 1)} "
                                     "fresh interpreters): run softclose bench")
                        for key, _, what in STARTUP)
        else:
            rows.extend(startup_rows(STARTUP_REPEATS, log))
    if features:
        rows.extend(feature_entries(cfg, quick=quick, log=log))
    return rows


#: the start-up targets: a command end to end in a fresh interpreter, as a multiple of the
#: interpreter's own ``python -c "import casadi"`` (its floor): key, command, what
STARTUP = (("startup_simulate", ["simulate", "--json"], "`softclose simulate --json`"),
           ("startup_optimise", ["optimise", "--json"], "`softclose optimise --json` (the "
            "main job: 6 starts, verification)"))
#: fresh interpreters of each command of :data:`STARTUP` and of ``import casadi`` (after one
#: round that warms the caches): the rows are medians of this many
STARTUP_REPEATS = 5


def _children_cpu() -> float | None:
    """CPU seconds (user + system) of this process's finished children, None where the OS
    does not count them."""
    try:
        import resource
    except ImportError:             # pragma: no cover  (not a POSIX system)
        return None
    ru = resource.getrusage(resource.RUSAGE_CHILDREN)
    return ru.ru_utime + ru.ru_stime


def timed_process(cmd: list[str], env: dict) -> tuple[float, float | None]:
    """(wall seconds, CPU seconds or None) of one fresh process running ``cmd`` to its end;
    a RuntimeError with its last words when it fails."""
    import time
    c0, t0 = _children_cpu(), time.perf_counter()
    r = subprocess.run(cmd, capture_output=True, env=env, text=True)
    wall, c1 = time.perf_counter() - t0, _children_cpu()
    if r.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd[2:])} failed: {r.stderr.strip()[-300:]}")
    return wall, None if c0 is None or c1 is None else c1 - c0


def startup_rows(repeats: int = STARTUP_REPEATS, log=None) -> list[dict]:
    """The start-up ratios of :data:`STARTUP` on the default config: each command's median
    wall time over ``repeats`` fresh interpreters, divided by the median of as many of
    ``python -c "import casadi"``, the two run in turn (``import casadi``, then each
    command, round after round: a change of the host's speed touches all alike), after one
    round that warms the caches and with the optimiser's NLP compiled
    (:func:`softclose.optimiser.cache.prepare`): what a user's second and later runs take.
    Each row also has the ratio taken pair by pair (each command against the ``import
    casadi`` of its round; ``paired_ratio``, the median) and the ratio of the CPU times'
    medians (``cpu_ratio``: on a busy host the steadier of the three)."""
    import statistics
    log = log or (lambda *a: None)
    lib = optimiser_cache.prepare(default_config())
    how = ("the NLP compiled" if lib is not None else
           "the NLP interpreted (no C compiler, or the cache is off)")
    import importlib.util
    from pathlib import Path
    pyc = Path(importlib.util.cache_from_source(str(Path(__file__).with_name("calls.py"))))
    if not pyc.exists():          # a checkout run with PYTHONDONTWRITEBYTECODE, say
        how += "; no .pyc files: every module is compiled from source at each start " \
               "(measure an installed package)"
    env = fresh_env()
    cmds = {"casadi": fresh_command("-c", "import casadi")}
    cmds.update({k: fresh_command("-m", "softclose", *argv) for k, argv, _ in STARTUP})
    wall: dict = {k: [] for k in cmds}
    cpu: dict = {k: [] for k in cmds}
    for i in range(repeats + 1):
        for k, cmd in cmds.items():
            w, c = timed_process(cmd, env)
            if i:                                    # the first round warms the caches
                wall[k].append(w)
                cpu[k].append(c)
    floor = statistics.median(wall["casadi"])
    cpu_floor = None if None in cpu["casadi"] else statistics.median(cpu["casadi"])
    rows = []
    for key, _, what in STARTUP:
        t = statistics.median(wall[key])
        paired = statistics.median(a / b for a, b in zip(wall[key], wall["casadi"]))
        cpu_ratio = None if cpu_floor is None or None in cpu[key] or cpu_floor <= 0 else \
            statistics.median(cpu[key]) / cpu_floor
        row = speed_row(key, f"{what} end to end / `python -c \"import casadi\"`", t, repeats,
                        f"{t * 1e3:.0f} ms against {floor * 1e3:.0f} ms (medians of {repeats}, "
                        f"alternated); pair by pair {paired:.2f}x"
                        + (f"; CPU {cpu_ratio:.2f}x" if cpu_ratio is not None else "")
                        + f"; {how}", ratio=t / floor)
        row.update(floor_s=floor, paired_ratio=paired, cpu_ratio=cpu_ratio)
        rows.append(row)
        log(f"  {what}: {t / floor:.2f} x import casadi (pair by pair {paired:.2f} x)")
    return rows


def startup_imports(argv: list[str], modules=HEAVY_MODULES) -> list[str]:
    """Which of ``modules`` a fresh interpreter has imported after
    ``softclose.cli.main(argv)`` (the command's own start-up and run)."""
    code = ("import io, json, sys, contextlib\n"
            "from softclose.cli import main\n"
            "with contextlib.redirect_stdout(io.StringIO()):\n"
            f"    main({list(argv)!r})\n"
            f"print(json.dumps([m for m in {list(modules)!r} if m in sys.modules]))\n")
    r = subprocess.run(fresh_command("-c", code), capture_output=True, text=True,
                       env=fresh_env())
    if r.returncode != 0:
        raise RuntimeError(f"softclose {' '.join(argv)} failed: {r.stderr.strip()[-300:]}")
    return json.loads(r.stdout.strip().splitlines()[-1])
