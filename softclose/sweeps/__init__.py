"""Design-space sweeps: the metrics of every design of a grid or a sample.

>>> from softclose import default_config
>>> from softclose.sweeps import sweep, sample
>>> r = sweep(default_config(), {"design.spring_k": np.linspace(500, 9500, 40),
...                              "design.damper_c": [100, 1000, 4000]})
>>> r.best, r.to_frame(), r.plot()
>>> s = sample(default_config(), {"design.spring_k": (500, 9500),
...                               "design.damper_c": (10, 4000, "log"),
...                               "mass.lid": (0.4, 0.6)}, 4096)

Any numeric config key can be swept (:func:`softclose.config.numeric_keys`): the design
keys, and geometry, mass, stroke, simulate or optimise keys such as
``geometry.spring_anchor[0]`` or ``mass.lid``. Every design gets the stroke metrics of
:data:`softclose.problem.METRICS`, the objective and its feasibility
(:func:`softclose.problem.objective`, :func:`softclose.problem.infeasibility`), and an
integer ``id`` -- its index in the grid (C order over the keys as given) or in the sample
sequence -- so any row can be computed again alone (:func:`recompute`).

- :func:`sweep` -- a full-factorial grid ``{key: values}``;
- :func:`sample` -- ``n`` designs drawn in ranges ``{key: (lo, hi)}`` or ``(lo, hi, "log")``
  with ``scipy.stats.qmc`` (scrambled Sobol by default, Latin hypercube, or random), for
  four or more keys where grids explode;
- :func:`recompute` -- the rows of some ids of a grid or sample.

Neither writes a file nor prints anything unless ``progress=True``. The work is cut into
chunks of :data:`CHUNK` designs, each evaluated by :func:`evaluate_chunk` from plain values
(the config as a dict, the keys, the ids, the swept values), so the same function runs in
this process or in a worker (:mod:`softclose.sweeps.run` describes the mapper interface);
the command line adds Parquet output chunk by chunk, resume, and the maps.
"""

from __future__ import annotations

import numpy as np

from .chunks import CHUNK, columns, evaluate_chunk
from .result import SweepResult
from .space import SAMPLERS, Grid, Range, Sample, make_grid, make_sample, parse_grid, \
    parse_range


def sweep(cfg, axes: dict, *, progress: bool = False, threads: int | None = None,
          chunk: int = CHUNK, dask=None) -> SweepResult:
    """Metrics, objective and feasibility at every point of the full-factorial grid
    ``axes`` = ``{config key: 1-D values}``.

    ``threads``: kernel threads (default: the usable cores, at most 8; on Dask, per task).
    ``dask``: run the chunks on a Dask cluster -- ``"local:N"`` (N worker processes here), a
    scheduler address or a ``distributed.Client`` (the command line's ``--dask``); the rows
    are the same as here. ``progress=True`` draws a progress line on a terminal. Ctrl-C
    returns the finished chunks (``result.interrupted``); so does a cluster that stops
    working (``result.lost`` says why). Bad keys or values, and a scheduler that does not
    answer, raise :class:`~softclose.errors.ConfigError`.
    """
    from .space import check_budget
    grid = make_grid(axes, cfg)
    check_budget(cfg, grid)
    return _run(cfg, grid, progress, threads, chunk, dask)


def _run(cfg, space, progress, threads, chunk, dask) -> SweepResult:
    """Run ``space`` here, or on Dask (a lost cluster: the finished chunks, and why)."""
    import dataclasses

    from .run import run
    if dask is None:
        return run(cfg, space, progress=progress, threads=threads, chunk=chunk)
    from .distributed import mapper
    with mapper(dask, threads) as m:
        res = run(cfg, space, progress=progress, threads=threads, chunk=chunk, mapper=m)
    return dataclasses.replace(res, lost=str(m.lost)) if m.lost is not None else res


def sample(cfg, ranges: dict, n: int, *, sampler: str = "sobol", seed: int = 0,
           progress: bool = False, threads: int | None = None,
           chunk: int = CHUNK, dask=None) -> SweepResult:
    """``n`` designs drawn in ``ranges`` = ``{key: (lo, hi)}`` or ``(lo, hi, "log")``.

    ``sampler``: "sobol" (scrambled; ``n`` a power of 2 keeps its balance), "lhs" (Latin
    hypercube) or "random"; ``seed`` makes the draw reproducible. Otherwise as :func:`sweep`.
    """
    from .space import check_budget
    space = make_sample(ranges, n, sampler, seed, cfg)
    check_budget(cfg, space)
    return _run(cfg, space, progress, threads, chunk, dask)


def recompute(cfg, space, ids, *, threads: int | None = None) -> dict[str, np.ndarray]:
    """The rows of designs ``ids`` of ``space`` (a result's ``space``), computed again."""
    ids = np.asarray(ids, np.int64)
    if ids.size and (ids.min() < 0 or ids.max() >= space.n):
        raise IndexError(f"ids must lie in 0 .. {space.n - 1}")
    return evaluate_chunk(cfg.raw, list(space.keys), ids, space.points(ids), threads=threads)


__all__ = ["sweep", "sample", "recompute", "SweepResult", "Grid", "Sample", "Range",
           "evaluate_chunk", "columns", "CHUNK", "SAMPLERS", "parse_grid", "parse_range",
           "make_grid", "make_sample"]
