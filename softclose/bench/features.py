"""The features' entries of the benchmark, each through its public function: sweep
throughput on the 40,000-design grid (the kernel, the in-process sweep, the command line end
to end), robust optimisation, the co-design commands, Monte Carlo yield, Sobol indices and the calibration's fits
(:mod:`.fitting`) (:func:`feature_entries`);
and the optimiser's shooting intervals N and sub-steps against the error of the optimal
objective and the solve time (:func:`optimiser_study`).
"""

from __future__ import annotations

import json
import statistics
import subprocess
import time
from pathlib import Path

import numpy as np

from ..config import Config, default_config, to_dict
from ..model.lid import LidModel
from ..problem import PARAM_COLUMNS, objective, params_of, resolve
from ..simulation.reference import Reference
from ..simulation.simulator import Simulator
from .precision import TRUTH_TOL
from .timing import (SPEED_TARGETS, cli_time, fresh_command, fresh_env, not_measured, OtherLoad,
                     speed_row)
from ..optimiser import optimise, solve
from ..catalog.illustrative import dampers, springs
from ..catalog import select
from ..sweeps.space import make_grid, make_sample
from ..optimiser.kinds import kind_config
from ..optimiser.cache import prepare
from ..config.free import parse_free_option
from .fitting import fit_entries
from ..robust import optimise_robust, sensitivity as sens, tolerance_analysis as ta
from ..sweeps import sweep

#: a feature entry is repeated (up to its repeat count) only while its runs took less than this
FEATURE_BUDGET_S = 30.0
#: the 40,000-design grid of the sweep throughput entry
SWEEP_GRID = {"design.spring_k": (500.0, 9500.0, 40),
              "design.spring_rest_length": (0.05, 0.09, 40),
              "design.damper_c": (100.0, 4000.0, 25)}

#: the gas strut's 40,000-design grid on the default lid (its extended length from the
#: stroke's longest length to where its stroke still reaches the shortest) and the hinge
#: lid's (the chest lid of examples/lids with a linear spring)
GAS_STRUT_GRID = {"design.spring_preload": (5.0, 50.0, 40),
                  "design.spring_rest_length": (0.0585, 0.087, 40),
                  "design.damper_c": (100.0, 4000.0, 25)}
HINGE_GRID = {"design.spring_k": (0.0, 3000.0, 40),
              "design.spring_rest_length": (0.05, 0.2, 40),
              "design.damper_c": (20.0, 800.0, 25)}
#: the hinge row's lid: examples/lids/chest_lid.toml's geometry, mass and stroke (here, not
#: read from the checkout: an installed package has no examples/), with a linear spring
HINGE_LID = {"geometry.mechanism": "hinge", "geometry.hinge": [0.0, 0.0],
             "geometry.lid_length": 0.6, "geometry.lid_g": [0.3, 0.02],
             "geometry.lid_tip": [0.6, 0.0], "geometry.spring_anchor": [0.0, -0.08],
             "geometry.lid_e": [0.06, -0.01], "geometry.dashpot_anchor": [0.06, -0.20],
             "geometry.dashpot_lid": [0.12, -0.01], "mass.lid": 3.0,
             "stroke.theta0_deg": 60.0, "stroke.theta_closed_deg": 0.0,
             "design.spring_kind": "linear", "design.spring_preload": 0.0,
             "design.damper_c": 285.0}

#: the placement sample (issue 23): the co-design's box of the spring's points, at the
#: README's robust design (a compression spring)
PLACEMENT_BOX = {"geometry.spring_anchor[0]": (-0.09, -0.03),
                 "geometry.spring_anchor[1]": (-0.01, 0.05),
                 "geometry.lid_e[0]": (-0.006, 0.044), "geometry.lid_e[1]": (0.004, 0.024)}
PLACEMENT_DESIGN = {"design.spring_kind": "compression", "design.spring_k": 4920.026,
                    "design.spring_rest_length": 0.05843374, "design.damper_c": 4932.998}
#: rows of the placement sample (the command end to end; --quick leaves it out) and of its
#: kernel row (Simulator.run_batch with per-row points, in-process)
PLACEMENT_ROWS = 1 << 20
PLACEMENT_KERNEL_ROWS = 1 << 16

#: optimiser settings of the N / sub-steps study
OPT_NODES = (5, 10, 20, 40)
OPT_SUBSTEPS = (1, 2, 4)


def sweep_axes() -> dict[str, np.ndarray]:
    """The 40,000-design grid of the sweep throughput entry (:data:`SWEEP_GRID`)."""
    return {k: np.linspace(a, b, n) for k, (a, b, n) in SWEEP_GRID.items()}


def grid_rows(cfg: Config, grid: dict) -> np.ndarray:
    """The parameter vectors of ``cfg`` over a full grid {key: (lo, hi, n)}."""
    g = make_grid({k: np.linspace(a, b, n) for k, (a, b, n) in grid.items()})
    n = int(np.prod([n for _, _, n in grid.values()]))
    P = np.tile(params_of(cfg), (n, 1))
    P[:, [PARAM_COLUMNS[k] for k in g.keys]] = g.points(np.arange(n))
    return P


def _hinge_row(rows: list, timed, rep: int, per_step: float | None) -> None:
    """The kernel on a hinge lid (the chest lid of examples/lids with the four-bar row's
    linear spring and dashpot: k x l0 x c), held to the four-bar's time per integration step
    (its strokes are longer: the row's ratio is its time per step over the four-bar's)."""
    key = "kernel_40000_hinge"
    what = ("Simulator.run_batch: 40,000 strokes of the chest lid on its hinge "
            "(examples/lids), a linear spring and a dashpot, k x l0 x c")
    c = default_config().update(HINGE_LID)
    P = grid_rows(c, HINGE_GRID)
    sim = Simulator(resolve(c))
    sim.run_batch(P[:1000])
    r = timed(key, what, lambda: sim.run_batch(P), rep, count=len(P))
    if r is None or per_step is None:
        return
    row = rows[-1]
    row["ratio"] = row["median_s"] / float(np.sum(r["steps"])) / per_step
    row["target"] = SPEED_TARGETS[key]
    row["met"] = row["ratio"] <= row["target"]["max_ratio"]
    row["note"] = (f"{np.mean(r['steps']):.0f} steps a stroke; time per step "
                   f"{row['ratio']:.2f} x the four-bar's (kernel_40000)")


def feature_entries(cfg: Config, quick: bool = False, log=None) -> list[dict]:
    """Sweep throughput on the 40,000-design grid (the kernel, the in-process sweep, and
    the command line end to end with its CSV and maps), robust optimisation, the co-design
    commands end to end (the attachment points, the end damper; nominal and robust:
    :func:`_co_design_rows`), Monte Carlo yield of 1e5 samples and Sobol indices at
    N = 1024, each through its public function.

    Yield and Sobol indices are measured at the nominal optimum (``softclose.optimise``'s
    design): the default config's own design has no spring and no damper, so relative
    spreads of spring_k and damper_c would be zero there. A function that does not exist
    yet gives a row with a note; ``quick`` skips the longest (robust optimisation, the
    Monte Carlo run, catalog selection) with a note. Each entry is the median of up to 3 runs (1 with
    ``quick``), fewer when the runs so far took :data:`FEATURE_BUDGET_S` or more.
    """
    log = log or (lambda *a: None)
    rows = []

    def timed(key, what, fn, repeats, count=None, unit="designs", note=""):
        out, ts = [], []
        try:
            with OtherLoad():
                while len(ts) < repeats and (not ts or sum(ts) < FEATURE_BUDGET_S):
                    t = time.perf_counter()
                    out.append(fn())
                    ts.append(time.perf_counter() - t)
        except Exception as exc:  # reported in the table, the bench goes on
            rows.append(not_measured(key, what, f"failed: {type(exc).__name__}: "
                                                f"{str(exc).splitlines()[0]}", repeats))
            log(f"  {what}: failed ({exc})")
            return None
        t = statistics.median(ts)
        rows.append(speed_row(key, what, t, len(ts), note, count=count, unit=unit))
        log(f"  {what}: {t:.3f} s")
        return out[-1]

    rep = 1 if quick else 3
    n_grid = int(np.prod([n for _, _, n in SWEEP_GRID.values()]))
    axes = sweep_axes()
    sim = Simulator(resolve(cfg))
    grid = make_grid(axes)            # the sweep's own designs, in its order
    P = np.tile(params_of(cfg), (n_grid, 1))
    P[:, [PARAM_COLUMNS[k] for k in grid.keys]] = grid.points(np.arange(n_grid))
    sim.run_batch(P[:1000])                             # warm-up: threads up
    base = timed("kernel_40000", f"Simulator.run_batch: the {n_grid:,} strokes of that grid, "
                 "all cores", lambda: sim.run_batch(P), rep, count=n_grid,
                 note="closing and not closing alike; a lid that creeps open runs to t_max")
    # its time per integration step: what the hinge lid's row is held to
    per_step = None if base is None else rows[-1]["median_s"] / float(np.sum(base["steps"]))
    # the same grid with the real elements: a preloaded compression spring (rows whose free
    # length is below the stroke's lengths are invalid designs, found and reported as such),
    # then friction with a rotary damper at pivot O (its psi'^2 from the element table)
    for key, what, extra, cols in (
            ("kernel_40000_compression", "a compression spring with 20 N preload",
             {"design.spring_kind": "compression", "design.spring_preload": 20.0}, {}),
            ("kernel_40000_friction_pivot", "friction 0.05 N m and a rotary damper at pivot O",
             {"friction.torque": 0.05, "design.rotary_damper_pivot": "O"},
             {"design.rotary_damper_c": 0.01})):
        c_el = cfg.update({**extra, **cols})
        sim_el = Simulator(resolve(c_el))
        P_el = np.tile(params_of(c_el), (n_grid, 1))
        P_el[:, [PARAM_COLUMNS[k] for k in grid.keys]] = grid.points(np.arange(n_grid))
        sim_el.run_batch(P_el[:1000])
        timed(key, f"Simulator.run_batch: the same {n_grid:,} strokes with {what}",
              lambda: sim_el.run_batch(P_el), rep, count=n_grid,
              note="invalid designs and their reasons included")
    # a gas strut with its friction band (F1 x extended length x c over the strut's valid
    # lengths) on the default lid
    c_gas = cfg.update({"design.spring_kind": "gas_strut", "design.strut_friction": 2.0})
    P_gas = grid_rows(c_gas, GAS_STRUT_GRID)
    sim_gas = Simulator(resolve(c_gas))
    sim_gas.run_batch(P_gas[:1000])
    timed("kernel_40000_gas_strut", f"Simulator.run_batch: {len(P_gas):,} strokes of a gas "
          "strut (F1 x extended length x c) with a 4 N friction band",
          lambda: sim_gas.run_batch(P_gas), rep, count=len(P_gas),
          note="closing, sticking and not closing alike")
    _hinge_row(rows, timed, rep, per_step)
    _placement_rows(cfg, rows, timed, quick)
    what = f"sweep(cfg, axes): the {n_grid:,}-design grid k × l0 × c, in-process"
    res = timed("sweep_40000", what, lambda: sweep(cfg, axes), rep, count=n_grid)
    if res is not None:
        rows[-1]["note"] = (f"the result's own designs_per_second (evaluation only): "
                            f"{res.designs_per_second or 0:,.0f}")
    _cli_sweep_rows(cfg, rows, n_grid, timed, 1 if quick else 5)
    what = "robust optimisation over the [tolerance] box"
    rob = None
    if quick:
        rows.append(not_measured("robust_optimise", what, "not run with --quick"))
    else:
        rob = timed("robust_optimise", what + ": softclose.optimise(cfg, robust=True), "
                    "one problem per spring kind (compression, extension)",
                    lambda: optimise_robust(cfg), 1)
    _co_design_rows(cfg, rows, quick, log)
    _made_to_order_row(cfg, rows, quick, log)
    what_mc = "Monte Carlo yield: tolerance_analysis(cfg, samples=100000)"
    what_s = "Sobol indices: sensitivity(cfg, samples=1024)"
    at, note = _nominal_optimum(cfg)
    # the Monte Carlo pass of the robust design (what `optimise --robust` checks), then the
    # nominal optimum's on its box: 12 % of its lids creep open and run to t_max (their
    # metrics change until then), which is why it takes longer
    if rob is None or not getattr(rob, "design", None):
        rows.append(not_measured("yield_1e5_robust", what_mc + ", the robust design",
                                 "not run with --quick" if quick else "no robust design"))
    else:
        c_rob = rob.design_config()
        ta(c_rob, samples=1000)                         # warm-up: its tables built
        timed("yield_1e5_robust", what_mc + ", the robust design",
              lambda: ta(c_rob, samples=100000, reference=0), rep, count=100000,
              unit="samples", note="the Monte Carlo pass (kernel, yield, interval, "
              "percentiles); the adaptive reference checks of the report are not in it")
    if quick:
        rows.append(not_measured("yield_1e5", what_mc, "not run with --quick"))
    elif at is None:
        rows.append(not_measured("yield_1e5", what_mc, note))
    else:
        timed("yield_1e5", what_mc + ", the nominal optimum", lambda: ta(at, samples=100000),
              rep, count=100000, unit="samples", note=note + "; with its 3 adaptive "
              "reference checks; no target of its own (see the robust design's row)")
    if at is None:
        rows.append(not_measured("sobol_1024", what_s, note))
    else:
        timed("sobol_1024", what_s, lambda: sens(at, samples=1024), rep, note=note)
    _select_row(cfg, timed, rows, quick)
    fit_entries(rows, timed, 1 if quick else 5)
    return rows


#: the co-design commands (issue 23): the attachment points' four keys, the end damper's two
CO_DESIGN = {
    "points": ["--free", "geometry.spring_anchor[0]=-0.09:-0.03",
               "--free", "geometry.spring_anchor[1]=-0.01:0.05",
               "--free", "geometry.lid_e[0]=-0.006:0.044", "--free", "geometry.lid_e[1]=0.004:0.024"],
    "end_damper": ["--free", "design.end_damper_c=0:2",
                   "--free", "design.end_damper_angle_deg=1:10"],
}


def _co_design_rows(cfg: Config, rows: list, quick: bool = False, log=None) -> None:
    """The co-design commands end to end in a fresh interpreter (``softclose optimise
    [--robust] --free ... --json``), after one run of each and with each spring kind's
    nominal NLP compiled (:func:`softclose.optimiser.cache.prepare`): what a user's second
    and later runs take. Nominal: the median of 3 runs; robust: one run, after
    ``softclose prepare`` compiled its scenario NLPs (:func:`_settle`)."""
    log = log or (lambda *a: None)
    for lever, free in CO_DESIGN.items():
        for robust in (False, True):
            key = f"co_design_{lever}" + ("_robust" if robust else "")
            what = (f"`softclose optimise{' --robust' if robust else ''} "
                    f"{' '.join(free)} --json` end to end (fresh interpreter, NLPs compiled)")
            if quick or cfg != _default():
                rows.append(not_measured(key, what, "not run with --quick" if quick else
                                         "measured on the default config only"))
                continue
            argv = ["optimise", *(["--robust"] if robust else []), *free, "--json"]
            try:
                if not robust:
                    _prepare(cfg, free)
                else:
                    _settle(argv, log)
                with OtherLoad():
                    t = cli_time(argv, 1 if robust else 3)
            except Exception as exc:    # reported in the table, the bench goes on
                rows.append(not_measured(key, what, f"failed: {type(exc).__name__}: "
                                                    f"{str(exc).splitlines()[0][:200]}"))
                continue
            rows.append(speed_row(key, what, t, 1 if robust else 3))
            log(f"  {what}: {t:.2f} s")


#: the optimiser with a spring made to order (SPEC §14): the wire named, the geometry not
MADE_TO_ORDER = ["--set", 'spring.material="EN10270-1-SH"']


def _made_to_order_row(cfg: Config, rows: list, quick: bool = False, log=None) -> None:
    """``softclose optimise --set spring.material=... --json`` end to end against the plain
    ``softclose optimise --json`` (fresh interpreters, each after ``softclose prepare`` of
    its own options): the spring's d, D and n as NLP variables, its roundings re-solved,
    as a multiple of the plain optimiser's time (target: at most 2)."""
    log = log or (lambda *a: None)
    key = "optimise_made_to_order"
    what = (f"`softclose optimise {' '.join(MADE_TO_ORDER)} --json` end to end against "
            "`softclose optimise --json` (fresh interpreters, NLPs compiled)")
    if quick or cfg != _default():
        rows.append(not_measured(key, what, "not run with --quick" if quick else
                                 "measured on the default config only"))
        return
    try:
        plain, made = ["optimise", "--json"], ["optimise", *MADE_TO_ORDER, "--json"]
        _settle(plain, log)
        _settle(made, log)
        with OtherLoad():
            t0, t1 = cli_time(plain, 3), cli_time(made, 3)
    except Exception as exc:    # reported in the table, the bench goes on
        rows.append(not_measured(key, what, f"failed: {type(exc).__name__}: "
                                            f"{str(exc).splitlines()[0][:200]}"))
        return
    rows.append(speed_row(key, what, t1, 3, ratio=t1 / t0,
                          note=f"the plain optimiser: {t0:.2f} s"))
    log(f"  {what}: {t1:.2f} s, {t1 / t0:.2f} x the plain optimiser's {t0:.2f} s")


def _settle(argv: list[str], log) -> None:
    """Compile the NLPs of ``softclose ARGV`` before it is timed: ``softclose prepare`` with
    its options, in the foreground (minutes for the robust co-design's nominal NLPs; its
    first stage's scenario NLP stays in the virtual machine), so that the timed run loads
    them, as a user's runs after a prepare do."""
    t = cli_time(["prepare", *[a for a in argv[1:] if a != "--json"]], 1)
    log(f"  (`softclose prepare {' '.join(argv[1:3])} ...`: {t:.0f} s)")


def _default() -> Config:
    return default_config()


def _prepare(cfg: Config, free: list) -> None:
    """Compile the nominal NLP of each spring kind of ``cfg`` with the ``--free`` options
    ``free`` (one run before first, so the compiled library is what the timed runs load)."""
    table = dict(parse_free_option(free[i + 1]) for i in range(0, len(free), 2))
    c = cfg.set("optimise.free", table)
    for kind in c.optimise.spring_kinds:
        ck, why = kind_config(c, kind)
        if why is None:
            prepare(ck)


def _placement_rows(cfg: Config, rows: list, timed, quick: bool) -> None:
    """Placements at kernel speed (issue 23): Simulator.run_batch over PLACEMENT_KERNEL_ROWS
    Sobol points of the spring's attachment points (per-row point columns, in-process), and
    ``softclose sweep --sample 1048576`` over the same box end to end (a fresh interpreter,
    Parquet and maps; not with ``quick``)."""
    import tempfile

    c = cfg.update(PLACEMENT_DESIGN)
    n = PLACEMENT_KERNEL_ROWS
    space = make_sample(PLACEMENT_BOX, n, "sobol", 0, c)
    X = space.points(np.arange(n))
    pts = {k: X[:, j] for j, k in enumerate(space.keys)}
    sim = Simulator(resolve(c))
    P = np.tile(params_of(c), (n, 1))
    sim.run_batch(P[:1000], points={k: v[:1000] for k, v in pts.items()})    # warm-up
    timed("kernel_placements", f"Simulator.run_batch(P, points=...): {n:,} Sobol placements "
          "of the spring's anchor and lid point (the co-design's box), the README's robust "
          "design, all cores", lambda: sim.run_batch(P, points=pts), 1 if quick else 3,
          count=n, note="per-row point columns: no model per placement; most rows take the "
          "compression spring past its free length (invalid, reasons located)")
    what = (f"softclose sweep --sample {PLACEMENT_ROWS:,} over the spring's four placement "
            "keys (the co-design's box), the README's robust design, --format parquet, fresh "
            "interpreter, end to end")
    if quick:
        rows.append(not_measured("placement_sample_1e6", what, "not run with --quick"))
        return
    args = [f"--range={k}={lo:g}:{hi:g}" for k, (lo, hi) in PLACEMENT_BOX.items()]
    args += [f"--set={k}={json.dumps(v)}" for k, v in PLACEMENT_DESIGN.items()]
    with tempfile.TemporaryDirectory() as tmp:
        def run():
            r = subprocess.run([*fresh_command("-m", "softclose"), "sweep", "--sample",
                                str(PLACEMENT_ROWS), *args, "--format", "parquet", "--out",
                                str(Path(tmp) / "placements"), "--json"], capture_output=True,
                               text=True, env=fresh_env())
            if r.returncode != 0:
                raise RuntimeError(f"exit {r.returncode}: {r.stderr.strip()[-300:]}")
            return json.loads(r.stdout)
        res = timed("placement_sample_1e6", what, run, 1, count=PLACEMENT_ROWS,
                    note="Parquet parts and six maps")
    if res is not None:
        st = res.get("stages", {})
        rows[-1]["note"] = (f"evaluation {st.get('evaluate', 0):.1f} s "
                            f"({res.get('designs_per_second') or 0:,.0f} designs/s), maps "
                            f"{st.get('maps', 0):.1f} s; {res.get('feasible', 0):,} feasible, "
                            f"{res.get('infeasible_reasons', {})}")


def _select_row(cfg: Config, timed, rows: list, quick: bool = False) -> None:
    """``select``: 1,000 spring x damper pairs of the illustrative catalog (its first 100
    springs x its first 10 dampers), each over its own tolerance box at 16 corners and 256
    samples, ranked, the best 10 verified at every corner by the adaptive reference."""
    what = ("select(cfg, springs, dampers): 1,000 catalog pairs (100 springs x 10 dampers) "
            "over their tolerance boxes, top 10 verified")
    if quick:
        rows.append(not_measured("select_1000", what, "not run with --quick"))
        return
    s, d = springs()[:100], dampers()[:10]
    select(cfg, s[:2], d[:2], samples=16, verify=0)     # warm-up: its tables built
    res = timed("select_1000", what, lambda: select(cfg, s, d), 1, count=1000, unit="pairs")
    if res is not None:
        t = res.times
        rows[-1]["note"] = (f"screen {t.get('screen', 0):.2f} s (16 corners + nominal + 256 samples a "
                f"pair: {res.evaluated * 273:,} strokes), reference at the best "
                f"{res.verified_count} pairs' 16 corners {t.get('verify', 0):.2f} s")


def _cli_sweep_rows(cfg: Config, rows: list, n_grid: int, timed, repeats: int) -> None:
    """``softclose sweep`` over :data:`SWEEP_GRID` end to end (a fresh interpreter, the CSV
    and the three maps, start-up included; the default config), and its maps stage (from
    the command's ``--json`` stages: after the table is evaluated until every map is
    saved)."""
    import tempfile

    what = (f"softclose sweep --grid ... --out DIR: the {n_grid:,}-design grid with its CSV "
            "and maps, fresh interpreter, end to end")
    what_maps = "the maps of that command (3 maps; its `maps` stage)"
    if to_dict(cfg) != to_dict(default_config()):
        for key, w in (("sweep_cli_40000", what), ("sweep_maps", what_maps)):
            rows.append(not_measured(key, w, "the command line runs the default config"))
        return
    grid = [f"--grid={k}={a:g}:{b:g}:{n}" for k, (a, b, n) in SWEEP_GRID.items()]
    maps: list[float] = []
    with tempfile.TemporaryDirectory() as tmp:
        def run():
            out = Path(tmp) / f"run{len(maps)}"
            r = subprocess.run([*fresh_command("-m", "softclose"), "sweep", *grid, "--out",
                                str(out), "--json"], capture_output=True, text=True,
                               env=fresh_env())
            if r.returncode != 0:
                raise RuntimeError(f"exit {r.returncode}: {r.stderr.strip()[-300:]}")
            maps.append(json.loads(r.stdout)["stages"]["maps"])
        timed("sweep_cli_40000", what, run, repeats, count=n_grid,
              note="CSV and 3 maps")
    if maps:
        rows.append(speed_row("sweep_maps", what_maps, statistics.median(maps), len(maps),
                              note=f"{min(maps):.2f}–{max(maps):.2f} s; drawn from the "
                                   "slices through the best design: no larger for a "
                                   "larger sweep"))


def _nominal_optimum(cfg: Config):
    """(cfg with the nominal optimum's design, note), or (None, why not)."""
    try:
        r = optimise(cfg)
    except Exception as exc:  # reported in the table
        return None, f"not measured: optimise(cfg) failed ({type(exc).__name__}: {exc})"
    if not getattr(r, "success", False) or not getattr(r, "design", None):
        return None, "not measured: optimise(cfg) found no design to analyse"
    d = r.design
    return cfg.with_design(**{k: d[k] for k in ("spring_k", "spring_rest_length",
                                                 "damper_c")}), \
        (f"at the nominal optimum k = {d['spring_k']:.7g} N/m, l0 = "
         f"{d['spring_rest_length']:.7g} m, c = {d['damper_c']:.7g} N s/m")


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
    nodes = (5, 10, 20) if quick else OPT_NODES
    subs = (1, 4) if quick else OPT_SUBSTEPS
    case = resolve(cfg)
    ref = Reference(LidModel(case), TRUTH_TOL)
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
            rr = ref.simulate(params_of(cfg, d), case)
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
