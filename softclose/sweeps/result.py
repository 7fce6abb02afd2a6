"""The result of a sweep: immutable, its rows as read-only columns (or a Parquet dataset)."""

from __future__ import annotations

import types
from dataclasses import dataclass, field, fields
from typing import Any, Mapping

import numpy as np

from ..present.display import Display, Displayed, Table, num, percent, unit_of
from .chunks import columns as column_names
from .tally import row_of
from ..jsonio import jsonable
from .store import as_words

#: best rows a sweep shows (of any number of designs)
SHOW_BEST = 5
#: columns of those rows, after id and the swept keys
SHOW_COLUMNS = ("objective", "closing_time", "impact_tip_speed", "peak_tip_speed",
                "holding_moment")


def readonly_columns(columns: Mapping) -> Mapping[str, np.ndarray]:
    """A result's table frozen: a read-only mapping of its columns as read-only arrays."""
    cols = {}
    for k, v in columns.items():
        v = np.asarray(v)
        v.setflags(write=False)
        cols[k] = v
    return types.MappingProxyType(cols)


@dataclass(frozen=True, eq=False, repr=False)
class SweepResult(Displayed):
    """Metrics, objective and feasibility of every design of a grid or sample.

    ``columns`` holds the rows (one per design, sorted by ``id``) as read-only numpy arrays
    named as in :meth:`to_frame`; it is None for a sweep streamed to a Parquet dataset
    (``dataset``, read back by :meth:`to_frame`). ``bins`` is the binned summary the maps of
    any sweep can be drawn from (:class:`softclose.sweeps.tally.Bins`); ``fixed`` the values
    of the design keys that were not swept (from the config). After Ctrl-C
    (``interrupted``) only the finished chunks are present: ``computed < points``; so too
    when a Dask cluster stopped working, and ``lost`` says why.
    """

    space: Any
    points: int
    computed: int
    feasible: int
    reasons: Mapping[str, int]
    best: dict | None
    bins: Any
    seconds: float
    stages: Mapping[str, float]
    chunk: int
    interrupted: bool = False
    columns: Mapping[str, np.ndarray] | None = field(default=None, repr=False)
    dataset: str | None = None
    fixed: Mapping[str, float] = field(default_factory=dict)
    lost: str | None = None

    def __post_init__(self):
        if self.columns is not None:
            object.__setattr__(self, "columns", readonly_columns(self.columns))
        object.__setattr__(self, "reasons", types.MappingProxyType(dict(self.reasons)))
        object.__setattr__(self, "stages", types.MappingProxyType(dict(self.stages)))
        object.__setattr__(self, "fixed", types.MappingProxyType(dict(self.fixed)))
        if self.best is not None:
            object.__setattr__(self, "best", types.MappingProxyType(dict(self.best)))

    def __reduce__(self):
        """Pickled as its fields, the read-only mappings as dicts (frozen again when
        loaded): a result can be sent to another process."""
        state = {f.name: getattr(self, f.name) for f in fields(self)}
        for k in ("columns", "reasons", "stages", "fixed", "best"):
            if state[k] is not None:
                state[k] = dict(state[k])
        return (_from_fields, (state,))

    # -- what it is -------------------------------------------------------------------------
    @property
    def keys(self) -> tuple[str, ...]:
        return tuple(self.space.keys)

    @property
    def kind(self) -> str:
        """"grid" or "sample"."""
        return self.space.kind

    @property
    def success(self) -> bool:
        """Every design was computed (a design that fails is a row with its status and
        reason, not a failure of the sweep)."""
        return self.computed == self.points and not self.interrupted and not self.lost

    @property
    def message(self) -> str:
        if self.lost:
            return (f"{self.lost}; {self.computed} of {self.points} designs computed "
                    "(the finished chunks are kept)")
        if self.interrupted or self.computed < self.points:
            return (f"interrupted: {self.computed} of {self.points} designs computed "
                    "(the finished chunks are kept)")
        if self.best is None:
            return f"no feasible design among the {self.points}"
        return ""

    @property
    def designs_per_second(self) -> float | None:
        ev = self.stages.get("evaluate", self.seconds)
        n = self.stages.get("evaluated", self.computed)
        return n / ev if ev > 0 and n else None

    # -- rows ------------------------------------------------------------------------------
    def row(self, id: int) -> dict:
        """One design's row by its ``id`` (computed again with ``sweep.recompute``)."""
        if self.columns is not None:
            ids = self.columns["id"]
            i = int(np.searchsorted(ids, id))
            if i >= len(ids) or ids[i] != id:
                raise KeyError(f"design {id} was not computed")
            return row_of(self.columns, i, self.keys)
        import pyarrow.dataset as ds
        t = ds.dataset(self.dataset, format="parquet").to_table(
            filter=ds.field("id") == int(id))
        if t.num_rows == 0:
            raise KeyError(f"design {id} was not computed")
        cols = {k: t.column(k).to_numpy(zero_copy_only=False) for k in t.column_names}
        return row_of(cols, 0, self.keys)

    def to_frame(self):
        """One row per design (pandas): ``id``, the swept keys by their config key, the
        metrics, ``objective``, ``feasible``, ``status``, ``reason``; sorted by id."""
        import pandas as pd
        names = column_names(self.keys)
        if self.columns is None:
            df = pd.read_parquet(self.dataset)
            df = df[names].sort_values("id", kind="stable").reset_index(drop=True)
            for k, v in as_words({k: df[k].to_numpy() for k in self.keys}, self.keys).items():
                df[k] = v
            return df
        cols = as_words(self.columns, self.keys)
        return pd.DataFrame({k: np.asarray(cols[k]) for k in names})

    def to_json(self) -> dict:
        """The summary: counts, reasons, the best feasible design, timings."""
        rate = self.designs_per_second
        return jsonable({
            "kind": self.kind, "keys": list(self.keys), "space": self.space.describe(),
            "points": self.points, "computed": self.computed, "feasible": self.feasible,
            "infeasible_reasons": dict(self.reasons), "interrupted": self.interrupted,
            "lost": self.lost,
            "success": self.success, "message": self.message,
            "seconds": self.seconds, "designs_per_second": rate,
            "stages": dict(self.stages), "chunk": self.chunk, "fixed": dict(self.fixed),
            "best": dict(self.best) if self.best is not None else None,
        })

    def best_rows(self, n: int = SHOW_BEST) -> list[dict]:
        """The ``n`` feasible designs of lowest objective, best first (from the rows in
        memory; a sweep streamed to a dataset gives its best design only)."""
        if self.columns is None:
            return [dict(self.best)] if self.best is not None else []
        J = np.asarray(self.columns["objective"], float)
        ok = np.asarray(self.columns["feasible"], bool) & np.isfinite(J)
        idx = np.flatnonzero(ok)
        if len(idx) > n:       # a partial sort: 10^6 rows cost one pass
            idx = idx[np.argpartition(J[idx], n - 1)[:n]]
        idx = idx[np.argsort(J[idx], kind="stable")]
        return [row_of(self.columns, int(i), self.keys) for i in idx]

    def _display(self) -> Display:
        n, ok = self.points, self.feasible
        facts = [("designs", f"{num(n)} ({self.kind} over {', '.join(self.keys)})"),
                 ("computed", num(self.computed)),
                 ("feasible", f"{num(ok)} ({percent(ok / self.computed)})"
                  if self.computed else "—")]
        rate = self.designs_per_second
        facts.append(("time", f"{self.seconds:.2f} s" + (f" ({rate:,.0f} designs/s)"
                                                          if rate else "")))
        if self.fixed:
            facts.append(("not swept", ", ".join(f"{k} = {num(v)} {unit_of(k)}"
                                                 for k, v in self.fixed.items())))
        tables = [Table("space", ("",), [(d,) for d in self.space.describe()])]
        if self.reasons:
            tables.append(Table("why designs are infeasible", ("reason", "designs", "share"), [
                (r, num(c), percent(c / self.computed if self.computed else None))
                for r, c in sorted(self.reasons.items(), key=lambda kv: -kv[1])]))
        best = self.best_rows()
        if best:
            cols = ("id", *self.keys, *SHOW_COLUMNS)
            head = tuple(c if not unit_of(c) else f"{c} [{unit_of(c)}]" for c in cols)
            tables.append(Table(f"best feasible designs (lowest objective; {len(best)} of "
                                f"{num(ok)})", head,
                                [(str(r["id"]), *(num(r.get(c)) for c in cols[1:]))
                                 for r in best],
                                "all rows: .to_frame()"))
        return Display(f"SweepResult: {self.kind} of {num(n)} designs", self.success,
                       self.message, tuple(facts), tuple(tables), short=3)

    def plot(self) -> dict:
        """The maps as matplotlib Figures, by file stem (``map_<k1>__<k2>``, or
        ``profile_<k>`` for one swept key): see :mod:`softclose.present.figures.sweep`."""
        from ..present.figures.sweep import plot_maps
        return plot_maps(self)


def _from_fields(state: dict) -> SweepResult:
    return SweepResult(**state)


__all__ = ["SweepResult"]
