"""Strokes at sampled config values: toleranced key values per sample -> metric columns.

How each kind of key reaches the C kernel (fastest first):

- design keys (``design.spring_k`` ...) are columns of the kernel's parameter rows
  ``p = (k, l0, c, c_rot)``: one batch call for all samples;
- ``mass.lid`` is the kernel's per-stroke lid-mass column when the kernel has one
  (``Simulator.run_batch(P, lid_mass=...)``). Without it, the coefficient table of each
  sampled mass is formed exactly from two tables: every tabulated coefficient (M, M', Vg,
  Vg', and the mass-free ones) is affine in the lid mass (the lid inertia too, derived or
  fixed), and so are their cubic Hermite pieces; then one kernel call per sample (correct,
  about 10x slower);
- any other key (geometry, crank masses, stroke angles ...) changes the model: samples are
  grouped by their values and each group gets its own model, table and simulator (about
  0.03 s each; correct, slow when every sample has its own value).

Every sample gets the metrics of :data:`softclose.problem.METRIC_KEYS`, ``theta_dot_max``,
the kernel status, the objective and the reason it is infeasible ("" if feasible), from
:mod:`softclose.problem`.
"""

from __future__ import annotations

import copy
import inspect
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from ..config import Config
from ..errors import SoftcloseError
from ..problem import METRIC_KEYS, infeasibility, objective, params_of
from .box import PARAM_COLUMNS

#: the kernel's output columns kept per sample
COLUMNS = METRIC_KEYS + ("theta_dot_max", "status", "objective", "reason", "feasible")
_SIMS: dict = {}


def with_values(cfg: Config, values: dict[str, float]) -> Config:
    """``cfg`` with numeric keys (``section.key`` or ``section.key[i]``) set; validated."""
    return cfg.update({k: float(v) for k, v in values.items()}) if values else cfg


def simulator(cfg: Config, t_end: float | None = None):
    """The fixed-step simulator of cfg's model (cached per geometry, mass, stroke, method);
    strokes are cut at ``t_end`` when it is below stroke.t_max."""
    from ..simulate import Simulator
    if t_end is not None and t_end < cfg.stroke.t_max:
        cfg = cfg.replace(stroke={"t_max": float(t_end)})
    key = (cfg.geometry, cfg.mass, cfg.stroke, cfg.simulate)
    if key not in _SIMS:
        if len(_SIMS) > 32:
            _SIMS.clear()
        _SIMS[key] = Simulator(cfg)
    return _SIMS[key]


def kernel_has_lid_mass(sim) -> bool:
    """True when the kernel takes a per-stroke lid mass (no model per mass needed)."""
    return "lid_mass" in inspect.signature(sim.run_batch).parameters


class _MassFamily:
    """Coefficient tables of one geometry for any lid mass, exact (affine in the mass)."""

    def __init__(self, sim):
        from ..model import LidModel
        self.sim = sim
        m0 = sim.cfg.mass.lid
        m1 = 1.5 * m0
        model1 = LidModel(sim.cfg.replace(mass={"lid": m1}))
        t0 = sim.table
        t1 = copy.copy(t0)
        t1._build(model1, t0.lo, t0.hi, t0.ncell)          # same cells as the base table
        self.m0, self.cc0 = m0, t0.cc
        self.dcc = (t1.cc - t0.cc) / (m1 - m0)

    def simulator(self, m: float):
        tab = copy.copy(self.sim.table)
        tab.cc = np.ascontiguousarray(self.cc0 + (m - self.m0) * self.dcc)
        s = copy.copy(self.sim)
        s.table = tab
        return s


def _run(sim, P: np.ndarray, masses: np.ndarray | None, threads: int | None) -> dict:
    if masses is None:
        return sim.run_batch(P, threads=threads)
    if kernel_has_lid_mass(sim):
        return sim.run_batch(P, lid_mass=masses, threads=threads)
    fam = _MassFamily(sim)
    uniq, inv = np.unique(masses, return_inverse=True)
    order = np.argsort(inv.ravel(), kind="stable")
    bounds = np.searchsorted(inv.ravel()[order], np.arange(len(uniq) + 1))
    groups = [order[bounds[j]:bounds[j + 1]] for j in range(len(uniq))]
    outs: list = [None] * len(uniq)

    def work(js):
        for j in js:
            outs[j] = fam.simulator(float(uniq[j])).run_batch(P[groups[j]], threads=1)

    nthreads = max(1, min(threads or 2, len(uniq)))
    with ThreadPoolExecutor(nthreads) as ex:
        list(ex.map(work, np.array_split(np.arange(len(uniq)), nthreads)))
    res = {k: np.empty(len(P), np.asarray(v).dtype) for k, v in outs[0].items()}
    for rows, o in zip(groups, outs):
        for k, v in o.items():
            res[k][rows] = v
    return res


def evaluate(cfg: Config, keys, X, *, t_end: float | None = None,
             threads: int | None = None) -> dict:
    """Metric columns of the strokes of ``cfg`` with the keys set to the rows of ``X``.

    ``keys`` are numeric config keys, ``X`` (n, len(keys)) their values (absolute).
    ``t_end`` cuts the strokes early (anything slower is infeasible anyway: the
    closing-time window ends before it). Returns a dict of arrays (see ``COLUMNS``).
    """
    keys = list(keys)
    X = np.atleast_2d(np.asarray(X, float)).reshape(-1, len(keys))
    n = len(X)
    P = np.tile(params_of(cfg), (n, 1))
    other = []
    masses = None
    for j, k in enumerate(keys):
        if k in PARAM_COLUMNS:
            P[:, PARAM_COLUMNS[k]] = X[:, j]
        elif k == "mass.lid":
            masses = X[:, j].copy()
        else:
            other.append(j)
    cols = {k: np.full(n, np.nan) for k in METRIC_KEYS + ("theta_dot_max",)}
    cols["closed"] = np.zeros(n, bool)
    cols["status"] = np.full(n, -1, int)
    if other:
        uniq, inv = np.unique(X[:, other], axis=0, return_inverse=True)
        inv = inv.ravel()
    else:
        uniq, inv = np.zeros((1, 0)), np.zeros(n, int)
    for g in range(len(uniq)):
        rows = np.nonzero(inv == g)[0]
        vals = {keys[j]: float(uniq[g, i]) for i, j in enumerate(other)}
        try:
            sim = simulator(with_values(cfg, vals), t_end)
        except SoftcloseError as exc:   # a sampled geometry that cannot close its loop
            raise type(exc)(f"tolerance box: at {', '.join(f'{k} = {v:g}' for k, v in vals.items())}"
                            f" {str(exc).splitlines()[0]}") from None
        out = _run(sim, P[rows], None if masses is None else masses[rows], threads)
        status = np.asarray(out["status"], int)
        ok = (status == 0) | (status == 1)
        for k in METRIC_KEYS[1:] + ("theta_dot_max",):
            v = np.asarray(out[k], float).copy()
            if k != "holding_moment":
                v[~ok] = np.nan
            if k in ("closing_time", "impact_theta_dot", "impact_tip_speed"):
                v[status != 0] = np.nan
            cols[k][rows] = v
        cols["closed"][rows] = status == 0
        cols["status"][rows] = status
    o = cfg.optimise
    cols["objective"] = objective(o, cols["impact_theta_dot"], cols["peak_tip_speed"])
    cols["reason"] = infeasibility(o, cols["closed"], cols["closing_time"],
                                   cols["holding_moment"], cols["theta_dot_max"])
    cols["feasible"] = cols["reason"] == ""
    return cols
