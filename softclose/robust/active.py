"""What limits the robust design: the bounds and constraints that hold with equality at the
answer of the scenario NLP, each with dJ, the change of the robust objective per unit
relaxation of the limit, read from Ipopt's multipliers as in the nominal optimiser
(:func:`softclose.optimiser.active_set`).

A limit of the problem (closing_time_max, holding_moment_min, ...) is one value shared by
every scenario: relaxing it relaxes the copy of the constraint in each scenario, so its dJ is
the sum of the scenarios' multipliers, and the scenarios where it holds are named. The NLP's
objective is the worst (or mean) scenario objective divided by J_ref, so dJ = J_ref x the
multiplier (divided by the design variable's scale for a design bound).
"""

from __future__ import annotations

import numpy as np

from ..optimiser.result import Active
from ..problem import DESIGN_KEYS, SCALES, UNITS
from .nlp import GROUPS

#: a multiplier (of the scaled NLP) above this marks a limit as active, as in the nominal
#: optimiser (:data:`softclose.optimiser.optimiser.ACTIVE_LAM`)
ACTIVE_LAM = 1e-6


def active_set(run, labels) -> tuple[Active, ...]:
    """The bounds and constraints that limit ``run``'s answer (a
    :class:`softclose.robust.solve.Run`), with dJ per unit relaxation and, for a
    constraint, the scenarios (by ``labels``, one per scenario) where it holds."""
    r = run.r
    if r.lam_x is None or r.lam_g is None:
        return ()
    problem = run.problem
    nlp, cfg = problem.nlp, problem.cfg
    o, st = cfg.optimise, cfg.stroke
    Jr = float(run.J_ref)
    lam_x, lam_g, x = np.asarray(r.lam_x), np.asarray(r.lam_g), np.asarray(r.x)
    lbx, ubx = run.bounds[0], run.bounds[1]
    out: list[Active] = []
    for i, key in enumerate(DESIGN_KEYS):
        lam = float(lam_x[i])
        for side, b, sign in (("upper", ubx[i], 1.0), ("lower", lbx[i], -1.0)):
            at = abs(x[i] - b) <= 1e-7 * max(1.0, abs(b))
            if sign * lam > ACTIVE_LAM or (at and lbx[i] != ubx[i]):
                out.append(Active(key, "bound", side, float(b * SCALES[i]), UNITS[key],
                                  -sign * Jr * lam / SCALES[i]))
                break
    N, S = nlp.N, nlp.S
    per_T = np.array([float(lam_x[nlp.offset(s)]) for s in range(S)])
    groups = _groups(nlp, lam_g)
    thd = [lam_x[nlp.x_offset(s) + 1:nlp.x_offset(s) + 1 + 2 * N:2] for s in range(S)]
    th = [lam_x[nlp.x_offset(s):nlp.x_offset(s) + 2 * (N - 1):2] for s in range(S)]

    def add(name, bound, value, unit, lam_s, sign):
        """One shared limit from the scenarios' multipliers ``lam_s`` (> 0 at an upper,
        < 0 at a lower limit: ``sign``)."""
        lam_s = np.asarray(lam_s, float)
        where = tuple(labels[s] for s in np.nonzero(sign * lam_s > ACTIVE_LAM)[0])
        total = float(np.sum(np.where(sign * lam_s > 0, lam_s, 0.0)))
        if where:
            out.append(Active(name, "constraint", bound, float(value), unit,
                              -sign * Jr * total, where))

    limit = problem.t_hi[0] if problem.t_hi else o.closing_time_max
    name, value = (("closing_time_max", o.closing_time_max)
                   if limit >= o.closing_time_max * (1 - 1e-3) else ("stroke.t_max", st.t_max))
    add(name, "upper", value, "s", per_T, 1.0)
    add("closing_time_min", "lower", o.closing_time_min, "s", per_T, -1.0)
    add("holding_moment_min", "lower", o.holding_moment_min, "N m",
        [g["holding_moment"].sum() for g in groups], -1.0)
    add("no_rebound", "upper", 0.0, "rad/s",
        [np.maximum(g["theta_dot_nonpositive"], 0).sum() + np.maximum(t, 0).sum()
         for g, t in zip(groups, thd)], 1.0)
    add("theta_above_closed", "lower", st.theta_closed, "rad",
        [np.minimum(g["theta_above_closed"], 0).sum() + np.minimum(t, 0).sum()
         for g, t in zip(groups, th)], -1.0)
    add("release_downwards", "upper", 0.0, "rad/s^2",
        [g["release_downwards"].sum() for g in groups], 1.0)
    if o.opening_force_max is not None:
        add("opening_force_max", "upper", o.opening_force_max, "N",
            [np.maximum(g["opening_force"], 0).sum() for g in groups], 1.0)
    if o.self_close_min_deg is not None:
        out += _self_close(problem, x, groups, labels, Jr)
    return tuple(out)


def _self_close(problem, x, groups, labels, Jr) -> list[Active]:
    """optimise.self_close_min_deg when it limits the design: the angle moves every
    scenario's grid, so dJ per degree it is lowered is -J_ref sum_s lam_s . dg_s/dtheta_sc
    (central differences of each scenario's constraint values at its parameters), as in the
    nominal optimiser."""
    nlp, deg, h = problem.nlp, problem.cfg.optimise.self_close_min_deg, 1e-3
    lam = [np.minimum(g["self_close"], 0) for g in groups]
    where = [s for s in range(nlp.S) if -lam[s].sum() > ACTIVE_LAM]
    if not where:
        return []
    design = nlp.unpack(x)[0]
    total = 0.0
    for s in where:
        p = problem.scenario_params(design, s)
        dg = (nlp.self_close_moments(s, p, deg + h) - nlp.self_close_moments(s, p, deg - h)) \
            / (2 * h)
        total += float(lam[s] @ dg)
    return [Active("self_close_min_deg", "constraint", "lower", float(deg), "deg", -Jr * total,
                   tuple(labels[s] for s in where))]


def _groups(nlp, lam_g) -> list[dict]:
    """The constraint multipliers of each scenario, by group (:data:`.nlp.GROUPS`)."""
    out, i = [], 0
    for sizes in nlp.g_sizes:
        row = {}
        for k, n in zip(GROUPS, sizes):
            row[k] = np.asarray(lam_g[i:i + n], float)
            i += n
        out.append(row)
    return out


__all__ = ["active_set", "ACTIVE_LAM"]
