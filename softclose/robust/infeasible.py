"""No robust design: which constraint fails, in which scenario, by how much, and what spreads
would do (:func:`diagnose`).

The spreads' scale is bisected (each trial solved as the robust optimiser solves the full
box: start sweep, scenario NLP, every corner in the kernel when the NLP had a subset), and the
worst violation at the full spreads of the best design found is reported.

A trial counts as feasible only with a design that solves it, so the scale reported is one
at which a robust design was found. Ipopt proves a trial infeasible slowly (150-330
iterations at the default problem with a closing-time window of 0.7-0.9 s, against ~20 for a
trial it solves), so a trial's solve stops at TRIAL_MAX_ITER iterations and counts as not
shown feasible: the scale reported can only come out lower, never wrong (there the diagnosis
took 53 s and now 27 s, interpreted; the same scale, x0.39).
"""

from __future__ import annotations

import numpy as np

from ..config import Config
from ..errors import NumericalError
from ..problem import at_temperature
from .box import box_of
from .evaluate import evaluate
from .policy import MC_TOL
from .scenarios import all_corners, corner_columns, design_dict, initial_scenarios, temperatures
from .scenarios import label as scenario_label
from .solve import Problem, Run, start_design
from .stats import margins

#: Ipopt iterations of one bisection trial (a trial it solves takes ~20)
TRIAL_MAX_ITER = 80


def _violation(cols: dict, i: int, o) -> tuple[str, str]:
    """(constraint, 'by how much') of sample i."""
    reason = cols["reason"][i]
    ct, hm = cols["closing_time"][i], cols["holding_moment"][i]
    if reason == "too slow":
        return "closing_time_max", (f"closes in {ct:.4g} s > closing_time_max = "
                                    f"{o.closing_time_max:g} s "
                                    f"(by {ct - o.closing_time_max:.3g} s)")
    if reason == "too fast":
        return "closing_time_min", (f"closes in {ct:.4g} s < closing_time_min = "
                                    f"{o.closing_time_min:g} s "
                                    f"(by {o.closing_time_min - ct:.3g} s)")
    if reason == "not held shut":
        return "holding_moment_min", (f"holding moment {hm:.4g} N m < holding_moment_min = "
                                      f"{o.holding_moment_min:g} N m (by "
                                      f"{o.holding_moment_min - hm:.3g} N m)")
    if reason == "rebound":
        return "no_rebound", f"rebounds (theta' reaches {cols['theta_dot_max'][i]:.3g} rad/s)"
    return "closed", "does not close within stroke.t_max"


def diagnose(cfg: Config, run: Run, problem: Problem, N: int, M: int, seed: int):
    """Why the scenario NLP has no solution: bisection on the spreads' scale, then the worst
    violation at the full spreads of the best design found."""
    o = cfg.optimise
    trial_cfg = cfg.set("optimise.max_iter", min(o.max_iter, TRIAL_MAX_ITER))
    lo, hi, best, capped = 0.0, 1.0, None, 0
    subset = not all_corners(cfg, problem.box)

    def holds(a, design) -> bool:
        """With a subset of the corners as scenarios, a design counts only if every corner
        holds in the kernel."""
        if not subset:
            return True
        _, _, _, _, cols = corner_columns(cfg, a, design)
        return bool(np.all(margins(cols, o) >= -MC_TOL))

    for _ in range(6):
        a = 0.5 * (lo + hi)
        box_a = box_of(cfg, scale=a)
        try:
            scen = initial_scenarios(box_a, cfg, [run.design], a)
            start, info_a = start_design(cfg, box_a, scen)
        except NumericalError:
            hi = a
            continue
        if info_a["robust_feasible"] and holds(a, start):   # a sweep design meets everything
            lo, best = a, start
            continue
        try:
            pa = Problem(trial_cfg, a, scen, N, M)
            x0, J_ref = pa.initial(start)
            ra = pa.solve(x0, J_ref)
        except NumericalError:
            ra = None
        if ra is not None and ra.success and holds(a, ra.design):
            lo, best = a, ra.design
        else:
            hi = a
            capped += ra is not None and ra.r.status == "Maximum_Iterations_Exceeded"
    design = best if best is not None else run.design
    named = design_dict(run.problem, design)       # (with its free values: a strut's F1)
    box1 = box_of(cfg, named)
    corners = box1.corners()
    c = cfg.with_design(**named)
    temps = temperatures(cfg)
    parts = [evaluate(at_temperature(c, T), box1.keys, box1.values(corners)) for T in temps]
    cols = {k: np.concatenate([np.asarray(q[k]) for q in parts]) for k in parts[0]}
    Z = np.tile(corners, (len(temps), 1))
    Ts = np.repeat(np.asarray(temps, float), len(corners))
    m = margins(cols, o)
    i = int(np.argmin(m))
    info = {"feasible_scale": lo if best is not None else 0.0,
            "design_tried": named}
    parts = []
    if m[i] < 0:
        constraint, amount = _violation(cols, i, o)
        label = scenario_label(box1, Z[i], Ts[i], temps)
        info.update(constraint=constraint, scenario=label, detail=amount)
        ds = ", ".join(f"{k} = {v:.5g}" for k, v in info["design_tried"].items())
        parts.append(f"at the best design found ({ds}) the scenario {label} {amount}")
    else:
        if run.violations:
            info["nlp_violations"] = max(run.violations,
                                         key=lambda v: max(v.values(), default=0.0))
        parts.append(f"Ipopt stopped with {run.r.status}")
    if best is not None:
        spreads = ", ".join(f"{s.key} ±{s.value * lo * (100 if s.relative else 1):.3g}"
                            f"{' %' if s.relative else ''}" for s in cfg.tolerance.spreads)
        info["feasible_spreads"] = {s.key: s.value * lo for s in cfg.tolerance.spreads}
        parts.append(f"a robust design exists for spreads up to x{lo:.2f} of the configured "
                     f"ones ({spreads})")
    else:
        cap = (f" (trials stop at {TRIAL_MAX_ITER} Ipopt iterations; {capped} of them "
               "did)") if capped else ""
        parts.append("no robust design was found even for spreads of x0.02 of the configured "
                     f"ones{cap}: check that the nominal problem has a solution (softclose "
                     "optimise)")
    return "no design meets every constraint over the tolerance box: " + "; ".join(parts), info
