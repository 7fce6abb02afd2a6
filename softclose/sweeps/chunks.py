"""The unit of work of a sweep: one chunk of designs, evaluated from plain values.

:func:`evaluate_chunk` takes only plain values -- the config as a dict (``cfg.raw``), the
swept keys, the design ids and their swept values -- and returns a dict of numpy columns.
It builds (and caches, per process) its own :class:`~softclose.simulation.simulator.Simulator`, because
CasADi objects do not pickle; so the same function runs in this process (the local runner)
or in any worker process that can import softclose (a Dask worker, a job array), and its
result depends on nothing but its arguments.

How a chunk is evaluated (metric only, batched):

- rows are grouped by their values of the keys that change the model (neither design keys,
  ``mass.lid`` nor an attachment point's component); each group gets the config with those
  values (validated as if from a file) and a simulator (model + coefficient table, about
  0.1 s, cached: groups that differ only in ``optimise.*`` keys share one);
- a group whose values the config or the model refuse (a loop that cannot close, a toggle
  on the stroke) gets status ``invalid`` and the one-line reason -- the sweep goes on;
- the design keys (``design.spring_k``, ``design.spring_rest_length``, ``design.damper_c``,
  ``design.rotary_damper_c``) go into the kernel's parameter rows, a swept ``mass.lid``
  into its per-stroke lid-mass column (the tabulated coefficients are affine in the lid
  mass, :mod:`softclose.simulation.kernel.binding`: one table serves every mass, and a row at the table's own
  mass gives the same bits as without the column), swept attachment points
  (``geometry.spring_anchor[i]``, ``lid_e[i]``, ``dashpot_anchor[i]``, ``dashpot_lid[i]``)
  into its per-stroke point columns (the lengths from the table's pose pieces, as a table
  built at those points would give them: one model serves every placement), and the group's
  strokes run as one batch in the C kernel (threads, nothing kept per step); a lid mass or
  a point the config refuses makes that row ``invalid`` with the config's one-line reason;
- the objective and the feasibility come from :mod:`softclose.problem` (never restated);
  a stroke the method cannot integrate carries the simulator's diagnosis as its reason.
"""

from __future__ import annotations

import json
import threading
from collections import OrderedDict

import numpy as np

from ..config.free import PLACEMENT_KEYS, point_refusals
from ..problem import (LID_MASS, METRIC_KEYS, PARAM_COLUMNS, WORD_PARAMS, infeasibility,
                       objective, params_of, resolve)
from ..simulation.stroke import StrokeStatus
from ..errors import SoftcloseError
from ..config import from_dict, RANGES, to_dict
from ..simulation.simulator import Simulator

#: designs per chunk: the unit of progress, of Ctrl-C and resume, and of a Parquet part file
CHUNK = 16384
#: status of a design whose config values were refused
INVALID = "invalid"
#: the columns of a chunk (and of every sweep table) around the swept keys
HEAD = ("id",)
TAIL = METRIC_KEYS + ("objective", "feasible", "status", "reason")
#: simulators kept per process
_CACHE_SIZE = 16
_sims: OrderedDict = OrderedDict()
_cfgs: OrderedDict = OrderedDict()
_cache_lock = threading.RLock()


def columns(keys) -> list[str]:
    """Column names of a sweep table: id, the swept keys, the metrics, objective,
    feasible, status, reason."""
    return [*HEAD, *keys, *TAIL]


def _lru(cache: OrderedDict, key, make):
    with _cache_lock:        # (chunks are evaluated in threads: one of them builds it)
        if key in cache:
            cache.move_to_end(key)
            return cache[key]
        value = make()
        cache[key] = value
        if len(cache) > _CACHE_SIZE:
            cache.popitem(last=False)
        return value


def _config(cfg_dict: dict):
    return _lru(_cfgs, json.dumps(cfg_dict, sort_keys=True, default=float),
                lambda: from_dict(cfg_dict))


def _simulator(cfg):
    """The simulator of ``cfg``'s model and method (the [optimise] and [tolerance] sections
    do not change a stroke, so configs differing only there share one)."""
    d = to_dict(cfg)
    d.pop("optimise", None)
    d.pop("tolerance", None)
    return _lru(_sims, json.dumps(d, sort_keys=True), lambda: Simulator(resolve(cfg)))


def empty(keys, n: int) -> dict[str, np.ndarray]:
    """A chunk of ``n`` rows with nothing computed yet."""
    out: dict[str, np.ndarray] = {"id": np.zeros(n, np.int64)}
    for k in keys:
        out[k] = np.full(n, np.nan)
    for k in METRIC_KEYS + ("objective",):
        out[k] = np.full(n, np.nan)
    out["closed"] = np.zeros(n, bool)
    out["feasible"] = np.zeros(n, bool)
    out["status"] = np.full(n, "", dtype=object)
    out["reason"] = np.full(n, "", dtype=object)
    return out


def evaluate_chunk(cfg_dict: dict, keys: list[str], ids: np.ndarray, X: np.ndarray,
                   threads: int | None = None) -> dict[str, np.ndarray]:
    """Metrics, objective and feasibility of designs ``ids`` with swept values ``X``.

    ``cfg_dict`` is a config as plain values (``cfg.raw``: what a TOML file and ``--set``
    gave); ``keys`` the swept config keys; ``X`` an array (len(ids), len(keys)). Returns the
    columns of :func:`columns` (``status``/``reason`` as str objects, ``closed``/
    ``feasible`` as bool, ``id`` as int64), rows in the order of ``ids``.
    """
    keys = list(keys)
    ids = np.asarray(ids, np.int64)
    X = np.asarray(X, float).reshape(len(ids), len(keys))
    n = len(ids)
    out = empty(keys, n)
    out["id"][:] = ids
    for j, k in enumerate(keys):
        out[k][:] = X[:, j]
    if n == 0:
        return out
    base = _config(cfg_dict)
    P = np.tile(params_of(base), (n, 1))
    for j, k in enumerate(keys):
        if k in PARAM_COLUMNS:
            P[:, PARAM_COLUMNS[k]] = X[:, j]
    jm = keys.index(LID_MASS) if LID_MASS in keys else None
    jp = [j for j, k in enumerate(keys) if k in PLACEMENT_KEYS]
    other = [j for j, k in enumerate(keys) if k not in PARAM_COLUMNS and j != jm
             and k not in PLACEMENT_KEYS]
    if other:
        uniq, inv = np.unique(X[:, other], axis=0, return_inverse=True)
        inv = np.asarray(inv).ravel()
    else:
        uniq, inv = np.zeros((1, 0)), np.zeros(n, np.int64)
    order = np.argsort(inv, kind="stable")
    bounds = np.searchsorted(inv[order], np.arange(len(uniq) + 1))
    for g in range(len(uniq)):
        rows = order[bounds[g]:bounds[g + 1]]
        values = {keys[j]: WORD_PARAMS[keys[j]].word(float(uniq[g, i]))
                  if keys[j] in WORD_PARAMS else float(uniq[g, i])       # (life.state)
                  for i, j in enumerate(other)}
        try:
            cfg = base.update(values) if values else base
            sim = _simulator(cfg)
        except SoftcloseError as exc:
            out["status"][rows] = INVALID
            out["reason"][rows] = str(exc).splitlines()[0]
            continue
        masses = points = None
        if jm is not None or jp:
            refused = lid_mass_refusals(cfg, X[rows, jm]) if jm is not None else \
                np.full(len(rows), "", dtype=object)
            if jp:
                why = point_refusals(cfg, {keys[j]: X[rows, j] for j in jp}, len(rows))
                refused = np.where(refused == "", why, refused)
            bad = refused != ""
            out["status"][rows[bad]] = INVALID
            out["reason"][rows[bad]] = refused[bad]
            rows = rows[~bad]
            masses = X[rows, jm] if jm is not None else None
            points = {keys[j]: X[rows, j] for j in jp} or None
            if len(rows) == 0:
                continue
        kw = {k: v for k, v in (("lid_mass", masses), ("points", points)) if v is not None}
        res = sim.run_batch(P[rows], threads=threads, opening=True, **kw)
        _store(out, rows, res, cfg, sim, P[rows], masses, res.get("points"))
    return out


def lid_mass_refusals(cfg, masses: np.ndarray) -> np.ndarray:
    """Why ``cfg`` refuses each lid mass in ``masses`` (its one-line message; "" where
    ``cfg.update({"mass.lid": m})`` accepts it), without a config per value.

    The config's checks that involve ``mass.lid`` -- a positive number within
    ``RANGES["mass.lid"]``, and the ``[tolerance]`` spreads of ``mass.lid`` and of the
    ``mass.inertia_lid`` derived from it, which refuse masses below a bound -- each accept
    an interval of masses. So the masses inside the range are accepted when the smallest and
    the largest of them are; otherwise (never for the default [tolerance]) each distinct
    value is tried. Each refused value is tried for its message, exactly as the config
    words it.
    """

    def refusal(m: float) -> str:
        try:
            cfg.update({LID_MASS: float(m)})
        except SoftcloseError as exc:
            return str(exc).splitlines()[0]
        return ""

    m = np.asarray(masses, float)
    lo, hi, _ = RANGES[LID_MASS]
    with np.errstate(invalid="ignore"):
        inside = np.isfinite(m) & (m > 0) & (m >= lo) & (m <= hi)
    try_each = ~inside
    if inside.any() and (refusal(m[inside].min()) or refusal(m[inside].max())):
        try_each[:] = True
    out = np.full(len(m), "", dtype=object)
    if try_each.any():
        u, inv = np.unique(m[try_each], return_inverse=True)
        out[try_each] = np.array([refusal(v) for v in u], dtype=object)[np.asarray(inv).ravel()]
    return out


_STATUS_TEXT = np.array([StrokeStatus(s).text for s in range(len(StrokeStatus))], dtype=object)


def _store(out: dict, rows: np.ndarray, res: dict, cfg, sim, P: np.ndarray,
           masses: np.ndarray | None = None, points: np.ndarray | None = None) -> None:
    """Fill ``rows`` of ``out`` from a kernel batch ``res`` of the group's config ``cfg``
    (``masses``: the rows' lid masses, None for the config's own; ``points``: the rows'
    own attachment points, the kernel's convention, or None)."""
    status = np.asarray(res["status"], int)
    ok = (status == StrokeStatus.CLOSED) | (status == StrokeStatus.NOT_CLOSED)
    closed = status == StrokeStatus.CLOSED
    for k in METRIC_KEYS[1:]:
        v = np.asarray(res[k], float).copy()
        if k not in ("holding_moment", "opening_force"):     # (statics: every design has them)
            v[~ok] = np.nan
        out[k][rows] = v
    out["closed"][rows] = closed
    J = objective(cfg.optimise, res["impact_theta_dot"], res["peak_tip_speed"])
    out["objective"][rows] = np.where(closed, J, np.nan)
    reason = infeasibility(cfg.optimise, closed, res["closing_time"], res["holding_moment"],
                           res["theta_dot_max"], res["opening_force"])
    why = np.asarray(res["reason"], dtype=object)   # why an open stroke stays open
    nc = (status == StrokeStatus.NOT_CLOSED) & (why != "")
    reason[nc] = "not closed (" + why[nc] + ")"     # "not closed (held open at ...)"
    invalid = status == StrokeStatus.OUT_OF_RANGE    # a part left its valid range
    reason[invalid] = np.asarray(res["reason"], dtype=object)[invalid]
    for k in ("min_spring_length", "max_spring_length"):        # they say why
        out[k][rows[invalid]] = np.asarray(res[k], float)[invalid]
    for i in np.nonzero(~ok & ~invalid)[0]:  # the method could not integrate it: say why
        s = StrokeStatus(int(status[i]))
        reason[i] = ("not closed (the lid swung beyond the stroke range)"
                     if s is StrokeStatus.LEFT_RANGE else
                     sim.diagnose(s, P[i], None if masses is None else float(masses[i]),
                                  None if points is None else points[i]))
    out["status"][rows] = _STATUS_TEXT[np.clip(status, 0, len(_STATUS_TEXT) - 1)]
    out["status"][rows[invalid]] = INVALID
    out["reason"][rows] = reason
    out["feasible"][rows] = reason == ""


__all__ = ["evaluate_chunk", "columns", "CHUNK", "INVALID", "PARAM_COLUMNS", "LID_MASS",
           "empty", "lid_mass_refusals"]
