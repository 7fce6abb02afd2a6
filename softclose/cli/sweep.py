"""``softclose sweep``: metrics over a grid or a sample of config values, to CSV or Parquet.

    softclose sweep --grid KEY=START:STOP:COUNT[:log] | --grid 'KEY=[v1, v2]' ... --out DIR
    softclose sweep --sample N --range KEY=LO:HI[:log] ... [--sampler sobol|lhs|random]
                    [--seed S] --out DIR
    softclose sweep --resume DIR

Options: ``--format csv|parquet`` (Parquet: one part file per finished chunk, for sweeps
larger than memory), ``--chunk N`` designs per chunk, ``--threads N`` kernel threads,
``--dask ADDRESS|local:N`` and ``--optimise`` (when their modules are installed).

The folder gets ``manifest.json`` (what the sweep is), ``sweep.csv`` or ``sweep.parquet/``,
and the maps (``map_<k1>__<k2>.png`` per pair of keys, ``profile_<k>.png`` for one key).
Ctrl-C keeps every finished chunk, prints the resume command and exits 130; ``--resume DIR``
computes only the missing chunks and refuses a folder of another sweep, naming what differs.

Scale-out: ``--dask`` runs the chunks through ``softclose.sweeps.distributed.mapper(address,
threads)`` (see :mod:`softclose.sweeps.run`); ``--optimise`` calls
``softclose.sweeps.optimal.optimise_grid`` and writes its table and maps.
"""

from __future__ import annotations

import contextlib
import shlex
import signal
import threading
import time
from pathlib import Path

from .common import Outcome, add_common, add_figures, interactive, prepare_out, wrote
from .maps import write_maps


def register(sub) -> None:
    p = sub.add_parser("sweep", help="metrics over a grid or a sample of config values",
                       description="Metrics, objective and feasibility of every design of a "
                                   "grid (--grid) or a sample (--sample N --range ...) of any "
                                   "numeric config keys, as a table (CSV or Parquet) and maps. "
                                   "--optimise instead gives the verified optimum at every point "
                                   "of a grid of non-design keys (one spring and damper per lid "
                                   "of a product range), each also written as "
                                   "DIR/designs/design_<id>.toml, a config every command takes "
                                   "with --config.")
    add_common(p)
    g = p.add_argument_group("designs")
    g.add_argument("--grid", action="append", default=[],
                   metavar="KEY=START:STOP:COUNT[:log] | KEY=[v1, v2, ...]",
                   help="one swept key of a full-factorial grid (repeatable)")
    g.add_argument("--sample", type=int, metavar="N",
                   help="draw N designs in the --range boxes instead of a grid")
    g.add_argument("--range", dest="ranges", action="append", default=[],
                   metavar="KEY=LO:HI[:log]", help="range of one sampled key (repeatable)")
    g.add_argument("--sampler", choices=("sobol", "lhs", "random"),
                   help="how --sample draws: scrambled Sobol (default), Latin hypercube, random")
    g.add_argument("--seed", type=int, help="seed of the sampler (default 0)")
    o = p.add_argument_group("output and execution")
    o.add_argument("--out", metavar="DIR", help="folder for the table, the maps and the manifest")
    o.add_argument("--format", choices=("csv", "parquet"),
                   help="csv (default): sweep.csv; parquet: sweep.parquet/, one part per chunk")
    add_figures(o)
    o.add_argument("--resume", metavar="DIR",
                   help="finish an interrupted sweep in DIR (computes the missing chunks only)")
    o.add_argument("--chunk", type=int, metavar="N",
                   help="designs per chunk (unit of progress, Ctrl-C and resume; default 16384)")
    o.add_argument("--threads", type=int, metavar="N", help="kernel threads (default: all cores)")
    o.add_argument("--dask", metavar="ADDRESS|local:N",
                   help="evaluate the chunks on a Dask cluster (scheduler address or local:N)")
    o.add_argument("--optimise", action="store_true",
                   help="the optimal design at every point of the grid of non-design keys")
    o.add_argument("--robust", action="store_true",
                   help="with --optimise: the robust design (under [tolerance]) at every point")
    p.set_defaults(run=run)


def _space(cfg, args):
    from ..errors import ConfigError
    from ..sweeps.space import make_sample, parse_grid, parse_range
    if args.grid and args.sample is not None:
        raise ConfigError("--grid and --sample: give one of them (a grid or a sample)")
    if args.ranges and args.sample is None:
        raise ConfigError("--range: only with --sample N (a grid takes --grid)")
    if args.sample is None and (args.sampler or args.seed is not None):
        raise ConfigError("--sampler/--seed: only with --sample N")
    if args.grid:
        return parse_grid(args.grid, cfg)
    if args.sample is not None:
        if args.sample <= 0:
            raise ConfigError(f"--sample: N must be positive, got {args.sample}")
        if not args.ranges:
            raise ConfigError("--sample: give the range of each sampled key with "
                              "--range KEY=LO:HI (repeatable)")
        ranges = [parse_range(r, cfg) for r in args.ranges]
        return make_sample(ranges, args.sample, args.sampler or "sobol",
                           0 if args.seed is None else args.seed, cfg, "--sample")
    return None


def _resume_spec(cfg, args):
    """The sweep to finish: the folder's manifest, checked against what was asked."""
    from ..config import from_dict
    from ..errors import ConfigError
    from ..sweeps import store
    from ..sweeps.space import space_from_spec
    folder = Path(args.resume)
    if args.out is not None and Path(args.out).resolve() != folder.resolve():
        raise ConfigError(f"--out {args.out} and --resume {args.resume}: a sweep is resumed "
                          "in its own folder; give only --resume DIR")
    if not folder.is_dir():
        raise ConfigError(f"--resume {args.resume}: no such folder")
    old = store.read_manifest(folder)
    if old is None:
        raise ConfigError(f"--resume {args.resume}: no sweep there ({store.MANIFEST} missing)")
    asked = _space(cfg, args)
    space = asked if asked is not None else space_from_spec(old["space"])
    if not (args.config or args.overrides):
        cfg = from_dict(old["raw"])      # the folder's config unless one is given
    fmt = args.format or old["format"]
    chunk = args.chunk or old["chunk"]
    new = store.manifest(cfg, space, chunk, fmt)
    diff = store.differences(old, new)
    if diff:
        more = f" (and {len(diff) - 2} more)" if len(diff) > 2 else ""
        raise ConfigError(f"--resume {args.resume}: the folder holds a different sweep: "
                          f"{'; '.join(diff[:2])}{more}")
    return cfg, space, fmt, chunk, folder, old


def run(cfg, args) -> Outcome:
    from ..errors import ConfigError
    from ..sweeps import store
    from ..sweeps.chunks import CHUNK
    if args.chunk is not None and args.chunk < 1:
        raise ConfigError(f"--chunk: must be a positive number of designs, got {args.chunk}")
    if args.threads is not None and args.threads < 1:
        raise ConfigError(f"--threads: must be at least 1, got {args.threads}")
    from ..sweeps import optimal as optimal_grid
    from ..sweeps import distributed
    dask = distributed if args.dask else None
    if args.robust and not args.optimise:
        raise ConfigError("--robust: only with --optimise (the robust design at every point)")
    optimal = optimal_grid if args.optimise else None
    if args.resume:
        cfg, space, fmt, chunk, out, old = _resume_spec(cfg, args)
        m = store.manifest(cfg, space, chunk, fmt)
    else:
        if args.out is None:
            raise ConfigError("--out: give the output folder (or --resume DIR)")
        space = _space(cfg, args)
        if space is None:
            raise ConfigError("--grid: give at least one KEY=START:STOP:COUNT "
                              "(or --sample N with --range)")
        if not args.optimise:
            from ..sweeps.space import check_budget
            check_budget(cfg, space, "--sample" if space.kind == "sample" else "--grid")
        fmt, chunk = args.format or "csv", args.chunk or CHUNK
        fresh = not Path(args.out).exists()
        out = prepare_out(args.out, [store.MANIFEST,
                                     store.CSV if fmt == "csv" else store.DATASET + "/"])
        old = store.read_manifest(out)
        if old is not None and not old.get("complete"):
            raise ConfigError(f"--out {args.out}: holds an unfinished sweep; finish it with "
                              f"--resume {args.out}, or choose another folder")
        m = store.manifest(cfg, space, chunk, fmt)
    if optimal is not None:
        return _optimal_grid(cfg, args, space, out)
    # the folder is written (an earlier finished sweep cleared, the manifest) once a --dask
    # cluster answers: a scheduler that does not leaves --out as it was
    try:
        return _sweep(cfg, args, space, fmt, chunk, out, m, dask,
                      replace=not args.resume and old is not None)
    except BaseException:
        if not args.resume and fresh:    # nothing came of it: no empty folder left behind
            with contextlib.suppress(OSError):
                out.rmdir()
        raise


def _plain_ctrl_c():
    """Ctrl-C as Python's plain KeyboardInterrupt while the sweep runs: the runner catches
    it between chunks, keeps what is finished and the command reports it (exit 130). (The
    command line's own handler notes it for the solvers; the sweep calls none.)"""
    from ..interrupt import sigint_handler
    return sigint_handler(signal.default_int_handler)


def _sweep(cfg, args, space, fmt, chunk, out: Path, m: dict, dask,
           replace: bool = False) -> Outcome:
    with _plain_ctrl_c():
        return _sweep_run(cfg, args, space, fmt, chunk, out, m, dask, replace)


def _sweep_run(cfg, args, space, fmt, chunk, out: Path, m: dict, dask,
               replace: bool = False) -> Outcome:
    from ..sweeps import store
    from ..sweeps.run import _no_interrupt
    from ..sweeps.run import run as run_sweep
    t0 = time.perf_counter()
    parquet = fmt == "parquet"
    keys = list(space.keys)
    if args.resume:
        if parquet:
            done = store.parquet_chunks(out, keys, space.n, chunk)
        elif (out / store.CSV).exists():
            done = store.chunks_of(store.read_csv(out / store.CSV, keys), space.n, chunk)
        else:
            done = ()
    else:
        done = ()
    # the table's library and matplotlib are imported while the kernel runs (its threads
    # leave the interpreter free); the maps are drawn here once the table is written
    prefetch = threading.Thread(target=_import_outputs, args=(parquet, True),
                                name="softclose-imports", daemon=True)
    prefetch.start()
    ctx = dask.mapper(args.dask, args.threads) if dask is not None else \
        contextlib.nullcontext(None)
    try:
        with ctx as mapper:              # connected: only now is the folder written
            if replace:
                store.clear(out)         # a finished earlier sweep is replaced
            store.write_manifest(out, m, complete=False)
            sink = store.ParquetSink(out, keys) if parquet else None
            res = run_sweep(cfg, space, progress=interactive(args), threads=args.threads,
                            chunk=chunk, keep=not parquet, sink=sink, done=done,
                            mapper=mapper,
                            dataset=str(out / store.DATASET) if parquet else None)
    finally:
        prefetch.join()                  # no import half done
    stages = dict(res.stages)
    files: list[Path] = []
    interrupted = res.interrupted
    maps = not interrupted and res.computed > 0
    try:
        if parquet:
            files.append(out / store.DATASET)
        else:
            tw = time.perf_counter()
            # the finished chunks are written whatever happens (a second Ctrl-C waits)
            with _no_interrupt(reraise=not interrupted):
                files.append(store.write_csv(res.columns, keys, out / store.CSV))
            stages["csv"] = time.perf_counter() - tw
        if not interrupted:
            tm = time.perf_counter()
            if maps:
                files += write_maps(res, out)
            store.write_manifest(out, m, complete=True)
            stages["maps"] = time.perf_counter() - tm
    except KeyboardInterrupt:            # the table is whole; resuming draws the maps
        interrupted = True
    resume = f"softclose sweep --resume {shlex.quote(str(out))}" if interrupted else None
    stages["total"] = time.perf_counter() - t0
    files.append(out / store.MANIFEST)
    payload = res.to_json()
    payload.update(stages=stages, format=fmt, out=str(out), resume=resume,
                   files=[str(f) for f in files])
    payload["interrupted"] = interrupted
    from ..sweeps.text import sweep_text
    text = sweep_text(res, payload, files, resume)
    lost = getattr(mapper, "lost", None)     # the Dask cluster stopped working mid-sweep
    if lost is not None:
        error = f"{lost}; the finished chunks are kept, resume with: {resume}"
        payload["error"] = error
        return Outcome(payload, text, lost.exit_code, tuple(files), error=error)
    return Outcome(payload, text, 130 if interrupted else 0, tuple(files))


def _import_outputs(parquet: bool, plotting: bool) -> None:
    with contextlib.suppress(Exception):
        if parquet:
            import pyarrow.parquet  # noqa: F401
        else:
            import pyarrow.csv  # noqa: F401
        if plotting:
            from ..present.figures import sweep  # noqa: F401  (matplotlib)


def write_grid_designs(res, out) -> list:
    """Each grid point with a design as ``out/designs/design_<id>.toml``: its config (the grid
    keys set) with its optimum (robust design) as [design]."""
    import math

    from .common import write_design
    c = res.columns
    folder = Path(out) / "designs"
    paths = []
    for i in range(res.points):
        if not all(math.isfinite(c[k][i]) for k in ("spring_k", "spring_rest_length",
                                                     "damper_c")):
            continue
        folder.mkdir(exist_ok=True)
        where = ", ".join(f"{k} = {c[k][i]:.7g}" for k in res.keys)
        kind = "robust design" if res.robust else "optimum"
        J = c["verified_objective"][i]
        paths.append(write_design(
            folder / f"design_{i}.toml", res.design_config(i),
            f"row {i} of `softclose sweep --optimise`: the {kind} at {where}"
            + ("" if c["success"][i] else " (NOT verified)"),
            [f"J = {c['objective'][i]:.7g} (the optimiser's)"
             + (f", {J:.7g} (the adaptive reference's)" if math.isfinite(J) else "")]))
    return paths


def _optimal_grid(cfg, args, space, out):
    """``softclose sweep --optimise --grid KEY=... [--dask ADDRESS|local:N] [--robust]
    --out DIR``: the table (``optimal.csv`` or, with ``--format parquet``,
    ``optimal.parquet``) and the maps (``optimal.png``) in DIR. Exit 0 when every point is
    verified, 3 when some point has no verified optimum (the table says which and why),
    130 after Ctrl-C (the finished points are written)."""
    from ..errors import ConfigError
    from ..sweeps.optimal import FIGURE, optimise_grid, write_table
    if getattr(args, "resume", None):
        raise ConfigError("--resume: not with --optimise (an optimal grid is not resumed; "
                          "run it again)")
    if getattr(space, "kind", "grid") != "grid":
        raise ConfigError("--optimise: needs a grid of non-design keys (--grid KEY=...), "
                          "not --sample")
    robust = bool(getattr(args, "robust", False))
    res = optimise_grid(cfg, space, dask=getattr(args, "dask", None), robust=robust,
                        progress=interactive(args))
    files = [write_table(res, out, getattr(args, "format", None) or "csv")]
    designs = write_grid_designs(res, out)
    if not res.interrupted and res.verified:
        from .common import save_figure as save
        files.append(save(res.plot(), Path(out) / FIGURE))
    payload = res.to_json()
    payload["files"] = [str(f) for f in files + designs]
    code = 3 if res.lost else 130 if res.interrupted else 0 if res.success else 3
    text = res.text() + wrote(files)
    if designs:
        text += (f"\n  wrote {len(designs)} design files {Path(out) / 'designs'}/design_<id>"
                 ".toml (id: the row of the table, from 0); each is a config every command "
                 "takes with --config")
    if res.interrupted and not res.lost:
        text += "\n  interrupted: the finished points are in the table"
    return Outcome(payload, text, code, tuple(files), error=res.message if code == 3 else None)
