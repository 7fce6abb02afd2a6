"""Strokes at sampled config values: toleranced key values per sample -> metric columns.

How each kind of key reaches the C kernel (fastest first):

- design keys (``design.spring_k`` ...) are columns of the kernel's parameter rows
  ``p = (k, l0, c, c_rot)``: one batch call for all samples;
- ``mass.lid`` is the kernel's per-stroke lid-mass column (:mod:`softclose.simulation.kernel.binding`: the
  tabulated coefficients are affine in the lid mass, so one table serves every mass, exactly);
- the attachment points' components (``geometry.spring_anchor[i]``, ``lid_e[i]``,
  ``dashpot_anchor[i]``, ``dashpot_lid[i]``) are the kernel's per-stroke point columns (the
  lengths from the table's pose pieces: one table serves every placement,
  :meth:`softclose.simulation.simulator.Simulator.run_batch`'s ``points``);
- any other key (geometry, crank masses, stroke angles ...) changes the model: samples are
  grouped by their values and each group gets its own model, table and simulator (about
  0.03 s each; correct, slow when every sample has its own value).

Every sample gets the metrics of :data:`softclose.problem.METRIC_KEYS`, ``theta_dot_max``,
``theta_min`` (the lowest angle reached: how far a lid that did not close got),
the kernel status, the objective and the reason it is infeasible ("" if feasible), from
:mod:`softclose.problem`.
"""

from __future__ import annotations

import numpy as np

from ..config import Config
from ..errors import ConfigError, SoftcloseError
from ..config.free import PLACEMENT_KEYS, point_refusals
from ..problem import LID_MASS, METRIC_KEYS, PARAM_COLUMNS, infeasibility, objective, params_of
from ..model import elements
from ..model.lid import model_key
from ..model.life import aged
from ..model.temperature import parameter_factors
from ..simulation.simulator import Simulator
from ..simulation.stroke import StrokeStatus
from ..problem import opening_wanted, resolve

#: the kernel's output columns kept per sample
COLUMNS = METRIC_KEYS + ("theta_dot_max", "theta_min", "status", "objective", "reason", "feasible")
_SIMS: dict = {}
#: the first simulator of each (model key, [simulate] settings): its model and table serve
#: every simulator of that model (:func:`simulator`)
_BASES: dict = {}


def slow_keys(keys) -> list[str]:
    """The keys that need a model per distinct value (neither design, lid mass nor an
    attachment point's component)."""
    return [k for k in keys if k not in PARAM_COLUMNS and k != LID_MASS
            and k not in PLACEMENT_KEYS]


def point_values(keys, X) -> dict | None:
    """The attachment points' components among ``keys`` as ``Simulator.run_batch``'s
    ``points`` ({key: column of X}), or None when there are none."""
    keys = list(keys)
    X = np.asarray(X, float)
    out = {k: X[:, j] for j, k in enumerate(keys) if k in PLACEMENT_KEYS}
    return out or None


def with_values(cfg: Config, values: dict[str, float]) -> Config:
    """``cfg`` with numeric keys (``section.key`` or ``section.key[i]``) set; validated."""
    return cfg.update({k: float(v) for k, v in values.items()}) if values else cfg


def simulator(cfg: Config, t_end: float | None = None):
    """The fixed-step simulator of cfg's model (cached per geometry, mass, stroke, method,
    element choices and spring limits);
    strokes are cut at ``t_end`` when it is below stroke.t_max.

    Simulators of one model (:func:`softclose.model.model_key`) and method share its model
    and coefficient table: another stroke end or other spring length limits (``select``'s
    parts each bring theirs) are read from the simulator's resolved config when it runs, so
    such a simulator is the first one's for its own (``Simulator.for_case``), not a model and
    table built again."""
    if t_end is not None and t_end < cfg.stroke.t_max:
        cfg = cfg.replace(stroke={"t_max": float(t_end)})
    case = resolve(cfg)
    # the element choices (a rotary damper's pivot), the spring's length limits and the
    # parts' factors at the operating temperature are the simulator's too: its table, its
    # range check and its strokes read them
    factors = parameter_factors(case.temperatures)
    key = (cfg.geometry, cfg.mass, cfg.stroke, cfg.simulate,
           elements.structure(case.lid.mounting),
           cfg.design.spring_min_length, cfg.design.spring_max_length,
           None if factors is None else tuple(map(float, factors.ravel())),
           case.life if aged(case.life) else None)         # (the end of life: its changes)
    if key not in _SIMS:
        if len(_SIMS) > 32:
            _SIMS.clear()
        base = (model_key(case), cfg.simulate)
        first = _BASES.get(base)
        if first is None:
            if len(_BASES) > 32:
                _BASES.clear()
            sim = _BASES[base] = Simulator(case)
        else:                   # the same model, table, method and step; cfg's own limits
            sim = first.for_case(case)       # (its own temperature factors too)
        _SIMS[key] = sim
    return _SIMS[key]


def evaluate(cfg: Config, keys, X, *, t_end: float | None = None,
             threads: int | None = None, explain: bool = True, opening: bool = True) -> dict:
    """Metric columns of the strokes of ``cfg`` with the keys set to the rows of ``X``.

    ``keys`` are numeric config keys, ``X`` (n, len(keys)) their values (absolute).
    ``t_end`` cuts the strokes early (anything slower is infeasible anyway: the
    closing-time window ends before it); ``explain=False`` skips locating where a spring
    leaves its valid range (:meth:`softclose.simulation.simulator.Simulator.run_batch`);
    ``opening=False`` skips the opening effort (its column NaN) unless
    ``optimise.opening_force_max`` makes it a constraint (:func:`softclose.problem.opening_wanted`).
    Returns a dict of arrays (see ``COLUMNS``).
    """
    opening = opening_wanted(cfg.optimise, opening)
    keys = list(keys)
    X = np.atleast_2d(np.asarray(X, float)).reshape(-1, len(keys))
    n = len(X)
    P = np.tile(params_of(cfg), (n, 1))
    other = []
    masses = None
    for j, k in enumerate(keys):
        if k in PARAM_COLUMNS:
            P[:, PARAM_COLUMNS[k]] = X[:, j]
        elif k == LID_MASS:
            masses = X[:, j].copy()
        elif k not in PLACEMENT_KEYS:
            other.append(j)
    pts = point_values(keys, X)
    if pts is not None:
        why = point_refusals(cfg, pts, n)
        if (why != "").any():
            raise ConfigError(f"tolerance box: {why[why != ''][0]}")
    cols = {k: np.full(n, np.nan) for k in METRIC_KEYS + ("theta_dot_max", "theta_min")}
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
            where = ", ".join(f"{k} = {v:g}" for k, v in vals.items())
            raise type(exc)(f"tolerance box: at {where} {str(exc).splitlines()[0]}") from None
        prow = None if pts is None else {k: v[rows] for k, v in pts.items()}
        out = sim.run_batch(P[rows], threads=threads,
                            lid_mass=None if masses is None else masses[rows],
                            explain=explain, points=prow, opening=opening)
        status = np.asarray(out["status"], int)
        ok = (status == StrokeStatus.CLOSED) | (status == StrokeStatus.NOT_CLOSED)
        for k in METRIC_KEYS[1:] + ("theta_dot_max", "theta_min"):
            if k not in out:        # (the opening effort, not asked for: NaN)
                continue
            v = np.asarray(out[k], float).copy()
            if k not in ("holding_moment", "opening_force"):
                v[~ok] = np.nan
            if k in ("closing_time", "impact_theta_dot", "impact_tip_speed"):
                v[status != StrokeStatus.CLOSED] = np.nan
            cols[k][rows] = v
        cols["closed"][rows] = status == StrokeStatus.CLOSED
        cols["status"][rows] = status
    o = cfg.optimise
    cols["objective"] = objective(o, cols["impact_theta_dot"], cols["peak_tip_speed"])
    cols["reason"] = infeasibility(o, cols["closed"], cols["closing_time"],
                                   cols["holding_moment"], cols["theta_dot_max"],
                                   cols["opening_force"])
    cols["feasible"] = cols["reason"] == ""
    return cols
