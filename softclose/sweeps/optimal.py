"""An optimal design at every point of a grid over non-design config keys.

>>> from softclose import default_config
>>> from softclose.sweeps.optimal import optimise_grid
>>> r = optimise_grid(default_config(), {"mass.lid": [0.4, 0.5, 0.6]})
>>> r.to_frame()       # mass.lid, spring_k, spring_rest_length, damper_c, objective, ...
>>> r.plot()           # the optimal design and objective over the grid

One spring and one damper per lid of a product range: the grid spans keys the optimiser does
not pick (``mass.lid``, ``geometry.lid_length``, ``optimise.closing_time_max``, ...); the
design keys (:data:`softclose.problem.DESIGN_KEYS`) are refused -- the optimiser picks them.

How the points are solved. The grid's points are numbered in C order (the last key varies
fastest) and cut into *segments*: runs of at most :data:`SEGMENT` neighbouring points along
the last key. The first point of a segment is solved by the multistart optimiser
(:func:`softclose.optimiser.optimise`, ``optimise.starts`` starts from a coarse sweep of
the design box); every next point starts from its neighbour's optimum (its design and
states, the continuation of :func:`softclose.optimiser.front`, with the best point of a
coarse sweep of its own problem solved too when that beats the warm answer), and falls back
to the multistart optimiser when the warm solve does not give a verified answer. Every
point is polished and verified by the adaptive reference like ``softclose optimise``'s
answer; ``success`` says so per point.

A segment is a pure function of plain values (the config as a dict, the keys, the points:
:func:`solve_segment`), so the same segments run here one after the other or as Dask tasks
on worker processes with one thread each (``dask="local:N"`` or a scheduler address; Ipopt
and MUMPS are not thread-safe): the table is the same either way, whatever the number of
workers, because the cut into segments depends on the grid only.

``robust=True`` designs each point for its ``[tolerance]`` box instead
(:func:`softclose.robust.optimise_robust`, solved cold at every point) and adds its yield.
"""

from __future__ import annotations

import dataclasses
import math
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from ..present.display import MAX_ROWS, Display, Displayed, Table, num, unit_of
from ..errors import ConfigError, SoftcloseError
from ..problem import DESIGN_KEYS, METRIC_KEYS
from . import distributed
from .distributed import ClusterLost
from .result import readonly_columns
from .space import Grid, make_grid, readonly
from ..jsonio import jsonable
from ..present.progress import Progress
from ..robust import optimise_robust
from ..optimiser import continue_from, optimise
from ..config import from_dict

#: most neighbouring points (along the last key) solved one from the other in one task
SEGMENT = 8
#: most points of one grid (each is an optimisation of a few seconds)
MAX_POINTS = 10_000
#: the table's columns after the grid keys
DESIGN_COLUMNS = DESIGN_KEYS + ("objective",) + METRIC_KEYS + ("success",)
EXTRA_COLUMNS = ("verified_objective", "objective_relative_difference", "active", "start",
                 "iterations", "seconds", "message")
ROBUST_COLUMNS = ("yield", "yield_ci_low", "yield_ci_high")
REFUSED = "--optimise picks the design; sweep only non-design keys"


# -- the grid ------------------------------------------------------------------------------
def check_grid(cfg, axes) -> Any:
    """The :class:`softclose.sweeps.space.Grid` of ``axes`` (a dict ``{key: values}`` or a
    Grid), refusing design keys and oversized grids with a one-line ConfigError."""
    grid = axes if isinstance(axes, Grid) else make_grid(axes, cfg, "axes")
    for key in grid.keys:
        if key.startswith("design.") and key.split(".", 1)[1] in DESIGN_KEYS:
            raise ConfigError(f"--grid {key}: {REFUSED} (e.g. mass.lid, geometry.lid_length)")
    if grid.n > MAX_POINTS:
        raise ConfigError(f"--grid: {grid.n} points is more than {MAX_POINTS} optimisations; "
                          "use fewer points")
    return grid


def segments(shape: tuple[int, ...], length: int = SEGMENT) -> list[np.ndarray]:
    """The ids of each segment: runs of at most ``length`` neighbours along the last axis,
    each line cut into near-equal pieces. Depends on the grid's shape only."""
    n = math.prod(shape)
    if n == 0:
        return []
    last = shape[-1] if shape else 1
    pieces = -(-last // length)
    out = []
    for start in range(0, n, last):
        out += [a for a in np.array_split(np.arange(start, start + last), pieces) if a.size]
    return out


# -- one segment (runs anywhere: plain values in, plain values out) -------------------------
def solve_segment(cfg_dict: dict, keys: list[str], ids, X, robust: bool = False) -> list[dict]:
    """The optimum at each point ``X[i]`` (values of ``keys``) of one segment, each from its
    predecessor's (see the module docstring). ``cfg_dict`` is the config as plain values
    (``cfg.raw``). Returns one row dict per point (plain values): design, objective, the
    verified metrics, success, verification, how it was started, time and message."""
    with _SOLVING:
        return list(_segment(cfg_dict, keys, ids, X, robust))


#: one optimisation at a time per process: Ipopt and MUMPS are not thread-safe, and a Dask
#: worker with several threads would otherwise run segments side by side
_SOLVING = threading.Lock()


def _segment(cfg_dict: dict, keys: list[str], ids, X, robust: bool):
    """The rows of :func:`solve_segment`, yielded as each point is finished."""
    base = from_dict(cfg_dict)
    keys = list(keys)
    X = np.asarray(X, float).reshape(len(ids), len(keys))
    rows, prev = [], None
    for i, x in zip(np.asarray(ids, np.int64), X):
        values = {k: float(v) for k, v in zip(keys, x)}
        t0 = time.perf_counter()
        try:
            cfg = base.update(values)
            if robust:
                res, start = _robust(cfg), "robust (cold)"
            else:
                res, start = _optimum(cfg, prev)
        except SoftcloseError as exc:
            row = _row(int(i), values, None, "", str(exc).splitlines()[0])
            row["seconds"] = time.perf_counter() - t0
            rows.append(row)
            prev = None
            yield row
            continue
        if start.startswith("warm"):
            start = f"warm from id {rows[-1]['id']}"
        row = _row(int(i), values, res, start, res.message or "")
        row["seconds"] = time.perf_counter() - t0
        rows.append(row)
        prev = res if (not robust and getattr(res, "run", None) is not None
                       and res.design is not None) else None
        yield row


def _optimum(cfg, prev) -> tuple[Any, str]:
    """cfg's verified optimum: warm from ``prev`` (a neighbour's result) when there is one,
    with the multistart optimiser as the fallback; (result, how it was started)."""
    if prev is not None:
        warm = continue_from(cfg, prev)
        if warm.success:
            return warm, "warm"
        cold = optimise(cfg, verify=True)
        if cold.success or warm.design is None:
            return cold, "multistart (the warm start failed)"
        return warm, "warm"
    return optimise(cfg, verify=True), "multistart"


def _robust(cfg):
    return optimise_robust(cfg, verify=True)


def _row(i: int, values: dict, res, start: str, message: str) -> dict:
    row: dict[str, Any] = {"id": i, **values}
    design = getattr(res, "design", None) or {}
    metrics = getattr(res, "metrics", None) or {}
    for k in DESIGN_KEYS:
        row[k] = _num(design.get(k))
    row["objective"] = _num(getattr(res, "objective", None))
    for k in METRIC_KEYS:
        v = metrics.get(k)
        row[k] = bool(v) if k == "closed" else _num(v)
    row["success"] = bool(getattr(res, "success", False))
    ver = getattr(res, "verification", None)
    if ver is not None and hasattr(ver, "to_json"):
        ver = ver.to_json()
    ver = ver or {}
    row["verified_objective"] = _num(ver.get("objective"))
    row["objective_relative_difference"] = _num(ver.get("objective_relative_difference"))
    if "worst_objective_relative_difference" in ver:     # a robust design: its worst scenario
        worst = [s for s in getattr(res, "scenarios", ()) if s.get("worst")]
        ref = (worst[0].get("reference") or {}) if worst else {}
        row["verified_objective"] = _num(ref.get("objective"))
        row["objective_relative_difference"] = _num(ver["worst_objective_relative_difference"])
    row["active"] = ", ".join(f"{a.name} ({a.bound})" for a in getattr(res, "active", ()) or ())
    row["start"] = start
    row["iterations"] = int(getattr(res, "iterations", 0) or 0)
    row["message"] = message
    if hasattr(res, "yield_result"):
        y = res.yield_result
        ci = getattr(y, "yield_ci", None) or (None, None)
        row["yield"] = _num(getattr(y, "yield_", None))
        row["yield_ci_low"], row["yield_ci_high"] = _num(ci[0]), _num(ci[1])
    return row


def _num(v) -> float:
    try:
        return float(v) if v is not None else math.nan
    except (TypeError, ValueError):
        return math.nan


# -- the whole grid ------------------------------------------------------------------------
def optimise_grid(cfg, axes, *, dask=None, robust: bool = False, progress: bool = False,
                  segment: int = SEGMENT) -> "OptimalGridResult":
    """The verified optimal design at every point of the grid ``axes`` = ``{config key:
    values}`` of non-design keys (a design key is a ConfigError).

    ``dask``: None (here, one segment after the other), ``"local:N"`` (N worker processes)
    or a Dask scheduler address; the table is the same either way. ``robust=True``: the
    robust design of each point (:func:`softclose.robust.optimise_robust`). ``progress``
    draws a progress line on a terminal. ``segment``: most neighbours solved one from the
    other in one task (:func:`segments`). Ctrl-C returns the points finished so far
    (``interrupted``). A point that cannot be solved is reported in the table
    (``success`` False, ``message``), never raised.
    """
    grid = check_grid(cfg, axes)
    if isinstance(segment, bool) or not isinstance(segment, (int, np.integer)) or segment < 1:
        raise ConfigError(f"segment: expected a whole number >= 1, got {segment!r}")
    keys = list(grid.keys)
    # robust designs start cold at every point: one point per task parallelises them fully
    segs = segments(grid.shape, 1 if robust else int(segment))
    points = grid.points(np.arange(grid.n))
    tasks = ((ids, (cfg.raw, keys, ids, points[ids], bool(robust))) for ids in segs)
    rows: dict[int, dict] = {}
    t0 = time.perf_counter()
    where = "local"
    interrupted = False
    lost = ""
    bar = Progress(grid.n, "optimal grid", enabled=progress, unit="")
    try:
        if dask is None:
            with _SOLVING:
                for ids, args in tasks:
                    for r in _segment(*args):       # each point kept as soon as it is done
                        rows[r["id"]] = r
                        bar.update(len(rows), f"id {r['id']}: "
                                   f"{'verified' if r['success'] else 'NOT verified'}",
                                   force=True)
        else:
            where = dask if isinstance(dask, str) else "client"
            with distributed.connect(dask) as client:
                for _, out in distributed.map_tasks(client, solve_segment, tasks, label="segment"):
                    for r in out:
                        rows.setdefault(r["id"], r)
                    bar.update(len(rows), force=True)
    except KeyboardInterrupt:
        interrupted = True
    except ClusterLost as exc:           # the Dask cluster stopped: keep the rows
        lost = str(exc) if len(rows) < grid.n else ""   # (lost after the last point: no harm)
    finally:
        bar.close()
    res = OptimalGridResult.from_rows(grid, rows, time.perf_counter() - t0, where,
                                      bool(robust), interrupted)
    return dataclasses.replace(res, lost=lost, config=cfg)


@dataclass(frozen=True, eq=False, repr=False)
class OptimalGridResult(Displayed):
    """The optimal design over a grid of non-design keys: one row per grid point.

    ``columns`` (read-only numpy arrays, rows in id order = C order over ``keys``): ``id``,
    the grid keys, spring_k, spring_rest_length, damper_c, objective (the optimiser's J),
    the verified metrics of :data:`softclose.problem.METRIC_KEYS`, success (optimal and
    confirmed by the adaptive reference), verified_objective (the reference's J) and
    objective_relative_difference, active (the bounds and constraints that limit the optimum),
    start (multistart or warm from which id), iterations,
    seconds, message (why a point failed); with ``robust``, its yield and interval too, and
    the verification columns are those of the worst scenario.
    A point not computed (Ctrl-C) has success False and message "not computed".
    """

    keys: tuple[str, ...]
    axes: tuple[np.ndarray, ...]
    columns: Mapping[str, np.ndarray] = field(repr=False)
    seconds: float = 0.0
    where: str = "local"
    robust: bool = False
    interrupted: bool = False
    #: why the Dask cluster stopped before every point was done ("" if it did not)
    lost: str = ""
    #: the config the grid was solved over (its keys set per point)
    config: Any = field(default=None, repr=False)

    def __post_init__(self):
        object.__setattr__(self, "columns", readonly_columns(self.columns))
        object.__setattr__(self, "axes", tuple(readonly(a) for a in self.axes))
        object.__setattr__(self, "keys", tuple(self.keys))

    @classmethod
    def from_rows(cls, grid, rows: dict, seconds: float, where: str, robust: bool,
                  interrupted: bool) -> "OptimalGridResult":
        keys = list(grid.keys)
        X = grid.points(np.arange(grid.n))
        names = cls.column_names(keys, robust)
        cols: dict[str, list] = {k: [] for k in names}
        for i in range(grid.n):
            r = rows.get(i)
            if r is None:
                r = _row(i, dict(zip(keys, map(float, X[i]))), None, "", "not computed")
                r["seconds"] = math.nan
            for k in names:
                cols[k].append(r.get(k, math.nan))
        out = {}
        for k, v in cols.items():
            if k == "id":
                out[k] = np.array(v, np.int64)
            elif k in ("success", "closed"):
                out[k] = np.array(v, bool)
            elif k in ("active", "start", "message"):
                out[k] = np.array(v, dtype=object)
            elif k == "iterations":
                out[k] = np.array(v, np.int64)
            else:
                out[k] = np.array(v, float)
        return cls(tuple(keys), tuple(grid.values), out, seconds, where, robust,
                   interrupted or len(rows) < grid.n)

    @staticmethod
    def column_names(keys, robust: bool = False) -> list[str]:
        return ["id", *keys, *DESIGN_COLUMNS, *EXTRA_COLUMNS,
                *(ROBUST_COLUMNS if robust else ())]

    # -- what it is ----------------------------------------------------------------------
    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(len(a) for a in self.axes)

    @property
    def points(self) -> int:
        return len(self.columns["id"])

    @property
    def verified(self) -> int:
        """Points whose optimum was found and confirmed by the adaptive reference."""
        return int(self.columns["success"].sum())

    @property
    def success(self) -> bool:
        """Every point optimal and verified (and nothing interrupted)."""
        return self.verified == self.points and not self.interrupted

    @property
    def message(self) -> str:
        if self.success:
            return ""
        if self.lost:
            done = self.points - int(np.sum(self.columns["message"] == "not computed"))
            return f"{self.lost}; the {done} finished points of {self.points} are kept"
        bad = np.nonzero(~self.columns["success"])[0]
        i = int(bad[0])
        where = ", ".join(f"{k} = {self.columns[k][i]:.6g}" for k in self.keys)
        more = f" (and {len(bad) - 1} more)" if len(bad) > 1 else ""
        return (f"{len(bad)} of {self.points} points have no verified optimum; first at "
                f"{where}: {self.columns['message'][i]}{more}")

    def row(self, i: int) -> dict:
        """The row of grid point ``i`` (plain values; NaN as None)."""
        return jsonable({k: v[i] for k, v in self.columns.items()})

    def design_config(self, i: int):
        """The config of grid point ``i`` (its keys set) with its optimal design as
        ``[design]`` (``softclose sweep --optimise --out D`` writes it as
        D/designs/design_<i>.toml); ValueError when the point has no design."""
        if self.config is None:
            raise ValueError("this result does not carry its config")
        c = self.columns
        design = {k: float(c[k][i]) for k in DESIGN_KEYS}
        if not all(math.isfinite(v) for v in design.values()):
            raise ValueError(f"grid point {i} has no design ({c['message'][i]})")
        return self.config.update({k: float(c[k][i]) for k in self.keys}).with_design(**design)

    def grid(self, name: str) -> np.ndarray:
        """Column ``name`` shaped as the grid (axes in the order of ``keys``)."""
        return np.reshape(self.columns[name], self.shape)

    # -- forms -----------------------------------------------------------------------------
    def to_frame(self):
        """One row per grid point (pandas DataFrame): the grid keys by config key, then
        spring_k, spring_rest_length, damper_c, objective, the metrics, success, then the
        verification and solve columns."""
        import pandas as pd
        names = self.column_names(self.keys, self.robust)[1:]
        return pd.DataFrame({k: self.columns[k] for k in names})

    def text(self) -> str:
        """What ``softclose sweep --optimise`` prints: a line per point (up to 40), else
        the ranges of the design and J."""
        from .text import optimal_grid_text
        return optimal_grid_text(self)

    def save_designs(self, folder) -> list:
        """Each point with a design as ``folder/designs/design_<id>.toml`` (what ``softclose
        sweep --optimise --out`` writes): its config with the optimum as [design]."""
        return write_grid_designs(self, folder)

    def to_json(self) -> dict:
        return jsonable({
            "success": self.success, "message": self.message, "keys": list(self.keys),
            "axes": {k: a for k, a in zip(self.keys, self.axes)}, "points": self.points,
            "verified": self.verified, "robust": self.robust, "where": self.where,
            "seconds": self.seconds, "interrupted": self.interrupted, "lost": self.lost or None,
            "rows": [self.row(i) for i in range(self.points)]})

    def _display(self) -> Display:
        facts = [("points", f"{num(self.points)} ({' x '.join(map(str, self.shape))} over "
                            f"{', '.join(self.keys)})"),
                 ("verified", num(self.verified)),
                 ("robust", "yes" if self.robust else "no"),
                 ("time", f"{self.seconds:.2f} s ({self.where})")]
        cols = ("id", *self.keys, *DESIGN_COLUMNS[:4], "closing_time", "impact_tip_speed",
                *(("yield",) if self.robust and "yield" in self.columns else ()), "success")
        head = tuple(c if not unit_of(c) else f"{c} [{unit_of(c)}]" for c in cols)
        rows = [(str(int(self.columns["id"][i])),
                 *(num(self.columns[c][i]) for c in cols[1:])) for i in
                range(min(self.points, MAX_ROWS))]
        table = Table("optimal designs by grid point", head, rows,
                      f"first {len(rows)} of {num(self.points)}; all: .to_frame()"
                      if self.points > len(rows) else "")
        return Display("OptimalGridResult: the optimum at every grid point", self.success,
                       self.message, tuple(facts), (table,), short=2)

    def plot(self):
        """Maps (two or more keys) or profiles (one key) of the optimal spring_k,
        spring_rest_length, damper_c and objective: a matplotlib Figure."""
        from ..present.figures.sweep_optimal import plot_optimal_grid
        return plot_optimal_grid(self)


# -- files and the command line ------------------------------------------------------------
TABLE = "optimal"
FIGURE = "optimal.png"


def write_grid_designs(res, out) -> list:
    """Each grid point with a design as ``out/designs/design_<id>.toml``: its config (the grid
    keys set) with its optimum (robust design) as [design]."""
    import math

    from ..config.write import write_design
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


def write_table(res: OptimalGridResult, out, fmt: str = "csv") -> Path:
    """``optimal.csv`` (empty cells for NaN, true/false) or ``optimal.parquet`` in ``out``:
    the columns of :meth:`OptimalGridResult.to_frame`."""
    import pyarrow as pa
    names = res.column_names(res.keys, res.robust)[1:]
    table = pa.table({k: pa.array(res.columns[k].tolist() if res.columns[k].dtype == object
                                  else res.columns[k], from_pandas=True) for k in names})
    out = Path(out)
    path = out / f"{TABLE}.{'parquet' if fmt == 'parquet' else 'csv'}"
    tmp = path.with_name(f".{path.name}.tmp")
    if fmt == "parquet":
        import pyarrow.parquet as pq
        pq.write_table(table, tmp)
    else:
        import pyarrow.csv as pcsv
        pcsv.write_csv(table, tmp, pcsv.WriteOptions(quoting_style="needed"))
    tmp.replace(path)
    return path
