"""The Pareto front of the objective against the allowed closing time, by continuation.

:func:`front` solves the first closing_time_max from a few sweep starts and every next one
warm from the previous optimum (its design, T moved to the new bound, the same
normalised-time states); as a guard against following a local branch, the best point of a
coarse sweep of each problem is solved too whenever the warm answer failed or the sweep
already beats it. Every point is polished and verified like :func:`optimise`'s answer.
"""

from __future__ import annotations

import math
import time
from dataclasses import replace

import numpy as np

from ..errors import ConfigError
from ..problem import PARETO_DEFAULT, check_reference_temperature, check_new_parts, describe
from ..present.progress import Progress
from .spring_part import spring_part
from .cache import get_nlp, stroke_simulator
from .discretisation import discretisation
from .kinds import kind_config
from .nlp import J_INDEX
from .optimiser import check_problem, finish, guarded, optimise, start_row
from .polish import nlp_objective
from .result import FrontResult, OptimiseResult
from .starts import initial_guess, sweep_starts, sweep_time

#: most points of one front (each is an optimisation)
MAX_POINTS = 200


@guarded
def front(cfg, closing_times, *, starts: int = 3, progress: bool = False) -> FrontResult:
    """The verified optimum for each closing_time_max in ``closing_times`` (continuation).

    ``starts``: sweep starts of the first point. Returns a :class:`FrontResult` whose
    ``success`` says that every point was found and verified; a point that fails is
    reported in it (and the next point continues from the last good one).
    """
    check_reference_temperature(cfg, "the Pareto front")
    check_new_parts(cfg, "the Pareto front")
    t0 = time.perf_counter()
    try:
        times = [float(t) for t in np.atleast_1d(np.asarray(closing_times, dtype=float))]
    except (TypeError, ValueError):
        raise ConfigError(f"closing_times: expected numbers, got {closing_times!r}") from None
    if not times:
        raise ConfigError("closing_times: expected at least one closing time")
    if len(times) > MAX_POINTS:
        raise ConfigError(f"closing_times: {len(times)} points is more than the limit of "
                          f"{MAX_POINTS}")
    o = cfg.optimise
    for t in times:
        if not (math.isfinite(t) and t > o.closing_time_min):
            raise ConfigError(f"closing_times: {t:g} s is not a finite time above "
                              f"optimise.closing_time_min = {o.closing_time_min:g} s")
    check_problem(cfg, starts)
    points: list[OptimiseResult] = []
    prev = None
    with Progress(len(times), "pareto", enabled=progress, unit="") as bar:
        for i, tm in enumerate(times):
            bar.update(i, f"closing_time_max = {tm:g} s", force=True)
            c = cfg.replace(optimise={"closing_time_max": tm})
            t1 = time.perf_counter()
            r = optimise(c, starts=starts) if prev is None else continue_from(c, prev)
            r = replace(r, total_time=time.perf_counter() - t1)
            points.append(r)
            if r.run is not None and r.design is not None:
                prev = r
            bar.update(i + 1, f"closing_time_max = {tm:g} s: "
                              f"{'verified' if r.success else 'NOT verified'}", force=True)
    return FrontResult(tuple(times), tuple(points), time.perf_counter() - t0)


def continue_from(cfg, prev: OptimiseResult) -> OptimiseResult:
    """The verified optimum of ``cfg`` from ``prev``, the answer of a neighbouring problem
    (same geometry and nodes, and ``prev``'s spring kind): warm from its design and states,
    and from the best point of a coarse sweep when that answer fails or the sweep beats it."""
    if prev.kind is not None:
        c, why = kind_config(cfg, prev.kind)
        if why is None:
            r = _continue(c, prev)
            part = spring_part(c, r.design, r.metrics or r.optimiser) if r.design else None
            return replace(r, kind=prev.kind, part=part,
                           kinds=({"kind": prev.kind, "success": r.success,
                                   "objective": r.objective, "message": r.message},))
    return _continue(cfg, prev)


def _continue(cfg, prev: OptimiseResult) -> OptimiseResult:
    o = cfg.optimise
    disc = discretisation(cfg, prev.nodes)
    nlp = get_nlp(cfg, disc.nodes, disc.substeps)
    bounds = nlp.bounds(cfg)
    lbx, ubx = bounds[0], bounds[1]
    p = nlp.params(cfg, J_ref=max(prev.objective or 1.0, 1e-8))
    # the previous optimum, its states moved to the new grid (same normalised time)
    st = cfg.stroke
    d_old, T_old, X_old, s_old = nlp.unpack(prev.run.x)      # same N: the same layout
    T_new = float(np.clip(T_old, lbx[nlp.iT], ubx[nlp.iT]))
    if nlp.two_phase:   # each phase's states at the same fractions of its duration
        Xn, T1 = X_old.copy(), nlp.engagement(prev.run.x)[0] * T_new / T_old
    else:
        tau_old = np.r_[0.0, np.cumsum(nlp.grid_of(prev.run.p))]      # same N
        tau_new = np.cumsum(nlp.grid_of(p))
        Xo = np.column_stack([[st.theta0, 0.0], X_old])
        Xn = np.vstack([np.interp(tau_new, tau_old, Xo[0]),
                        np.interp(tau_new, tau_old, Xo[1])])
        T1 = None
    Xn[0, -1] = st.theta_closed
    x0 = nlp.pack(d_old, T_new, Xn, s_old, T1)
    runs = [nlp.solve(x0, p, *bounds, origin="previous optimum")]
    starts = [d_old]
    J0s = [None]
    # guard against following a local branch: the best point of a coarse sweep of this
    # problem is solved too when the warm answer failed or the sweep already beats it
    sim = stroke_simulator(cfg, sweep_time(cfg, disc.t_limit))
    designs, info = sweep_starts(cfg, 1, disc.t_limit, sim, shape=(6, 5, 6))
    J_warm = nlp_objective(nlp, cfg, runs[0]) if runs[0].success else math.inf
    J_sweep = info["best_feasible_objective"]
    if not runs[0].success or (J_sweep is not None and J_sweep < J_warm * (1 - 1e-3)):
        p2 = nlp.params(cfg)
        w0, J0 = initial_guess(nlp, cfg, designs[0], sim, p2, disc.t_limit)
        p2[J_INDEX] = max(J0, 1e-8)
        runs.append(nlp.solve(w0, p2, *bounds, origin="best sweep point"))
        starts.append(designs[0])
        J0s.append(J0)
    rows = tuple(start_row(nlp, cfg, s, r, J0) for s, r, J0 in zip(starts, runs, J0s))
    ok = [i for i, r in enumerate(runs) if r.success]
    notes = list(disc.notes)
    base = dict(starts=rows, sweep=info, iterations=sum(r.iterations for r in runs),
                solve_time=sum(r.time for r in runs))
    if not ok:
        return OptimiseResult(False, f"Ipopt did not converge ({runs[0].status}) from the "
                              "previous optimum or the best sweep point; solve this point "
                              "alone with optimise()", runs[0].status, None, None,
                              nodes=nlp.nodes, substeps=nlp.M, substeps_engaged=nlp.M_engaged,
                              hessian=o.hessian,
                              problem=describe(cfg), config=cfg, notes=tuple(notes), **base)
    best = runs[min(ok, key=lambda i: rows[i]["objective"])]
    return finish(cfg, nlp, best, disc, verify=True, polish=True, notes=notes, **base)

def parse_closing_times(text: str) -> np.ndarray:
    """``START:STOP:COUNT`` (linear) or ``START:STOP:COUNT:log`` -> array of closing times."""
    parts = str(text).split(":")
    bad = f"--closing-times {text}: "
    if len(parts) not in (3, 4) or (len(parts) == 4 and parts[3] != "log"):
        raise ConfigError(bad + "expected START:STOP:COUNT or START:STOP:COUNT:log")
    try:
        a, b = float(parts[0]), float(parts[1])
        n = int(parts[2])
    except ValueError:
        raise ConfigError(bad + "START and STOP must be numbers (s), COUNT a whole number") \
            from None
    if not (math.isfinite(a) and math.isfinite(b) and 0 < a <= b):
        raise ConfigError(bad + "expected 0 < START <= STOP (finite, in s)")
    if not 1 <= n <= MAX_POINTS:
        raise ConfigError(bad + f"COUNT must lie in 1..{MAX_POINTS}, got {n}")
    if a == b and n > 1:
        raise ConfigError(bad + "START equals STOP: use COUNT 1")
    return np.geomspace(a, b, n) if len(parts) == 4 else np.linspace(a, b, n)


def default_closing_times(cfg) -> str:
    """:data:`PARETO_DEFAULT` scaled to the config's closing-time window: its ends times
    optimise.closing_time_max (in s), the first above 1.05 x closing_time_min (the
    default config's: unchanged)."""
    a, b, n, kind = PARETO_DEFAULT.split(":")
    o = cfg.optimise
    lo = max(float(a) * o.closing_time_max, 1.05 * o.closing_time_min)
    hi = max(float(b) * o.closing_time_max, lo)
    return f"{lo:.6g}:{hi:.6g}:{n if hi > lo else 1}:{kind}"


def closing_times(cfg, text: str | None = None) -> np.ndarray:
    """The closing_time_max values of a front: ``text`` (``START:STOP:COUNT[:log]``, s) or,
    without it, :data:`PARETO_DEFAULT` scaled to ``cfg``'s closing-time window."""
    return parse_closing_times(text or default_closing_times(cfg))
