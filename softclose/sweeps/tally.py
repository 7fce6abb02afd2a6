"""What a sweep keeps while it runs, whatever its size: counts, the best design, binned maps.

:class:`Tally` counts computed and feasible designs and the reasons of the others, and keeps
the best feasible design (least objective; a tie goes to the smaller id, so the answer does
not depend on the order chunks finish in). :class:`Bins` keeps, for every pair of swept keys
(and every single key), a binned summary: per cell the number of designs, how many are
feasible, why the others are not, and the best feasible design in the cell (its id,
objective, and the mapped metrics). The maps of a streamed sweep are drawn from it, so
they never need the rows in memory; its size depends on the bins, not on the sweep.

Bins: a grid axis of at most :data:`MAX_BINS` values has one bin per value; a longer axis,
or a sampled range, is cut into equal bins (equal in the log for log axes).
"""

from __future__ import annotations

import math

import numpy as np

from ..problem import CATEGORIES, WORD_PARAMS, word_text
from .chunks import columns
from ..jsonio import jsonable

#: metrics kept per cell (what the maps show besides the objective)
MAPPED = ("impact_theta_dot", "peak_tip_speed", "closing_time")
#: most bins per key
MAX_BINS = 120
#: most pairs of keys kept (the first keys' pairs)
MAX_PAIRS = 15


class Tally:
    """Counts and the best feasible design, updated chunk by chunk."""

    def __init__(self, keys, points: int):
        self.keys = list(keys)
        self.points = int(points)
        self.computed = 0
        self.feasible = 0
        self.counts = np.zeros(len(CATEGORIES), np.int64)
        self.best: dict | None = None
        self._best_key = (math.inf, math.inf)

    def update(self, cols: dict, cat: np.ndarray) -> None:
        n = len(cols["id"])
        self.computed += n
        feas = np.asarray(cols["feasible"], bool)
        self.feasible += int(feas.sum())
        self.counts += np.bincount(cat[cat >= 0], minlength=len(CATEGORIES))
        if feas.any():
            J = np.where(feas, cols["objective"], np.inf)
            i = int(np.lexsort((cols["id"], J))[0])
            k = (float(J[i]), int(cols["id"][i]))
            if k < self._best_key:
                self._best_key = k
                self.best = row_of(cols, i, self.keys)

    def reasons(self) -> dict[str, int]:
        return {c: int(n) for c, n in zip(CATEGORIES, self.counts) if n}


def row_of(cols: dict, i: int, keys) -> dict:
    """Row ``i`` of a chunk as plain values (NaN -> None)."""
    row = {k: jsonable(cols[k][i].item() if hasattr(cols[k][i], "item") else cols[k][i])
           for k in columns(keys)}
    for k in keys:                       # a word key (a spring's kind) by its word
        if k in WORD_PARAMS and row[k] is not None:
            row[k] = word_text(k, row[k])
    return row


class Axis:
    """The bins of one swept key: centres, and how a value finds its bin."""

    def __init__(self, key: str, lo: float, hi: float, log: bool, values=None, nbins=None):
        self.key, self.log = key, bool(log)
        if values is not None and len(values) <= MAX_BINS:
            self.exact = np.sort(np.asarray(values, float))
            self.centres = self.exact
            self.n = len(self.exact)
            self.edges = None
        else:
            self.exact = None
            self.n = int(nbins or MAX_BINS)
            f = np.log if self.log else (lambda x: x)
            self.edges = np.linspace(f(lo), f(hi), self.n + 1)
            c = 0.5 * (self.edges[:-1] + self.edges[1:])
            self.centres = np.exp(c) if self.log else c
            self.edges = np.exp(self.edges) if self.log else self.edges
        self.lo, self.hi = float(lo), float(hi)

    def index(self, x: np.ndarray) -> np.ndarray:
        if self.exact is not None:
            return np.clip(np.searchsorted(self.exact, x), 0, self.n - 1)
        return np.clip(np.searchsorted(self.edges, x, side="right") - 1, 0, self.n - 1)


class Bins:
    """Binned summary of a sweep per key and per pair of keys (see the module docstring)."""

    def __init__(self, space):
        self.keys = list(space.keys)
        self.kind = space.kind
        self.axes: list[Axis] = []
        if space.kind == "grid":
            for k, v, lg in zip(space.keys, space.values,
                                space.log or (False,) * len(space.keys)):
                self.axes.append(Axis(k, float(v.min()), float(v.max()), lg, values=v))
        else:
            # about 16 designs a cell in each 2-D map (a cell shows its best: fewer is noise)
            nb = int(np.clip(round(math.sqrt(space.n / 16)), 6, 60))
            for r in space.ranges:
                self.axes.append(Axis(r.key, r.lo, r.hi, r.log, nbins=nb))
        multi = [j for j, a in enumerate(self.axes) if a.n >= 2]
        self.groups: list[tuple[int, ...]] = [(j,) for j in multi]
        self.groups += [(a, b) for i, a in enumerate(multi) for b in multi[i + 1:]][:MAX_PAIRS]
        self.cells = {}
        for g in self.groups:
            shape = tuple(self.axes[j].n for j in g)
            m = math.prod(shape)
            self.cells[g] = {
                "shape": shape,
                "count": np.zeros(m, np.int64),
                "feasible": np.zeros(m, np.int64),
                "categories": np.zeros((m, len(CATEGORIES)), np.int64),
                "objective": np.full(m, np.inf),
                "id": np.full(m, -1, np.int64),
                **{q: np.full(m, np.nan) for q in MAPPED},
            }

    def update(self, cols: dict, cat: np.ndarray) -> None:
        if not self.groups or len(cols["id"]) == 0:
            return
        idx = [a.index(np.asarray(cols[a.key], float)) for a in self.axes]
        ids = np.asarray(cols["id"], np.int64)
        feas = np.asarray(cols["feasible"], bool)
        J = np.where(feas, np.asarray(cols["objective"], float), np.inf)
        ncat = len(CATEGORIES)
        for g in self.groups:
            c = self.cells[g]
            m = len(c["count"])
            cell = idx[g[0]] if len(g) == 1 else idx[g[0]] * self.axes[g[1]].n + idx[g[1]]
            c["count"] += np.bincount(cell, minlength=m)
            c["feasible"] += np.bincount(cell[feas], minlength=m)
            bad = cat >= 0
            c["categories"] += np.bincount(cell[bad] * ncat + cat[bad],
                                           minlength=m * ncat).reshape(m, ncat)
            if not feas.any():
                continue
            f = np.nonzero(feas)[0]
            order = f[np.lexsort((ids[f], J[f], cell[f]))]
            best = order[np.unique(cell[order], return_index=True)[1]]
            cf = cell[best]
            better = (J[best] < c["objective"][cf]) | \
                ((J[best] == c["objective"][cf]) & (ids[best] < c["id"][cf]))
            sel, cs = best[better], cf[better]
            c["objective"][cs] = J[sel]
            c["id"][cs] = ids[sel]
            for q in MAPPED:
                c[q][cs] = np.asarray(cols[q], float)[sel]

    def freeze(self) -> "Bins":
        for c in self.cells.values():
            for v in c.values():
                if isinstance(v, np.ndarray):
                    v.setflags(write=False)
        return self

    def grid(self, group: tuple[int, ...], name: str) -> np.ndarray:
        """One kept quantity of a group as an array over its bins (NaN where no feasible
        design fell in a cell, for the objective and the metrics)."""
        c = self.cells[group]
        v = c[name]
        if name == "objective":
            v = np.where(np.isfinite(v), v, np.nan)
        return np.asarray(v).reshape(c["shape"] + v.shape[1:])


__all__ = ["Tally", "Bins", "CATEGORIES", "MAPPED", "row_of"]
