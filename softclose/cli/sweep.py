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
import signal
from pathlib import Path

from .common import Outcome, add_common, add_figures, interactive, prepare_out, wrote


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
    from ..errors import ConfigError
    from ..sweeps.store import resume_spec
    if args.out is not None and Path(args.out).resolve() != Path(args.resume).resolve():
        raise ConfigError(f"--out {args.out} and --resume {args.resume}: a sweep is resumed "
                          "in its own folder; give only --resume DIR")
    return resume_spec(args.resume, cfg, _space(cfg, args), bool(args.config or args.overrides),
                       args.format, args.chunk)


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
    from .common import FIGURES
    from ..sweeps.folder import sweep_to_folder
    with _plain_ctrl_c():
        s = sweep_to_folder(cfg, space, out, fmt, chunk, m, resume=bool(args.resume),
                            replace=replace, threads=args.threads, progress=interactive(args),
                            mapper_context=(dask.mapper(args.dask, args.threads)
                                            if dask is not None else None),
                            figure_format=FIGURES["format"], figure_style=FIGURES["style"])
    code = s.lost.exit_code if s.lost is not None else 130 if s.interrupted else 0
    return Outcome(s.to_json(), s.text(), code, s.files, error=s.error)


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
    designs = res.save_designs(out)
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
