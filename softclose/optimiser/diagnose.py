"""Why a problem has no solution: the constraint that cannot be met, with its numbers.

When no start converges, :func:`diagnose` checks in order: Ipopt stopped at its iteration
limit; the largest holding moment within the design bounds (linear in k for fixed l0, so a
box corner) is below holding_moment_min; the fastest (and, with a lower bound, the slowest)
stroke that meets every other constraint misses the closing-time window (the same NLP with
objective ±T and the closing-time bounds relaxed to [0, t_max]); a self-close angle
(optimise.self_close_min_deg) out of reach when its constraint is the most violated; otherwise
Ipopt's verdict and the largest violated constraint group.
"""

from __future__ import annotations

import math

import numpy as np

from ..problem import DESIGN_KEYS, with_designs
from .cache import stroke_simulator
from .nlp import T_FLOOR, Run, ShootingNLP
from .starts import initial_guess
from .polish import _sim

#: Ipopt statuses that suggest that the constraints cannot be met
INFEASIBLE = ("Infeasible_Problem_Detected", "Restoration_Failed",
              "Search_Direction_Becomes_Too_Small", "Not_Enough_Degrees_Of_Freedom")


def extreme_sweep_designs(cfg, count: int, sense: float, sim) -> np.ndarray:
    """Sweep designs that close (and hold) the fastest (sense 1) or the slowest (sense -1)."""
    o = cfg.optimise
    axes = [np.linspace(*getattr(o, k), n) for k, n in zip(DESIGN_KEYS, (6, 5, 5))]
    G = np.array(np.meshgrid(*axes, indexing="ij")).reshape(3, -1).T
    r = sim.run_batch(with_designs(cfg, G))
    T = np.where(r["closed"] & (r["holding_moment"] >= o.holding_moment_min),
                 sense * r["closing_time"], np.inf)
    return G[np.argsort(T)[:count]]


def diagnose(cfg, nlp: ShootingNLP, runs: list[Run]) -> tuple[str, dict]:
    """Which constraint cannot be met: (a one-line message, the numbers behind it)."""
    o, st = cfg.optimise, cfg.stroke
    info: dict = {"statuses": sorted({r.status for r in runs})}
    if not any(r.status in INFEASIBLE for r in runs):
        if all(r.status == "Maximum_Iterations_Exceeded" for r in runs):
            return (f"Ipopt stopped at optimise.max_iter = {o.max_iter} iterations from every "
                    "start (status Maximum_Iterations_Exceeded); raise optimise.max_iter", info)
        return (f"Ipopt did not converge from any start (statuses: "
                f"{', '.join(info['statuses'])}); try more starts (optimise.starts), more "
                "iterations (optimise.max_iter) or hessian = \"limited-memory\"", info)
    # 1. the holding moment is linear in k for fixed l0: its maximum over the box is at a corner
    model = nlp.model
    corners = [(k, l0) for k in o.spring_k for l0 in o.spring_rest_length]
    hm = [(model.holding_moment(with_designs(cfg, [k, l0, 0.0])), k, l0) for k, l0 in corners]
    hmax, kb, lb = max(hm)
    info["largest_holding_moment"] = {"value": hmax, "spring_k": kb, "spring_rest_length": lb}
    if hmax < o.holding_moment_min:
        return (f"holding_moment_min = {o.holding_moment_min:g} N m cannot be met: the largest "
                f"holding moment within the design bounds is {hmax:.4g} N m (spring_k = {kb:g}, "
                f"spring_rest_length = {lb:g}); lower holding_moment_min or widen the spring "
                "bounds", info)
    # 2. the fastest and (with a lower bound) the slowest stroke that meets everything else
    relaxed = cfg.replace(optimise={"closing_time_min": 0.0, "closing_time_max": st.t_max})
    sim = stroke_simulator(cfg)
    lbx, ubx, lbg, ubg = nlp.bounds(relaxed, t_max=st.t_max, t_min=T_FLOOR)
    for sense, name in ((1.0, "fastest"), (-1.0, "slowest")):
        if sense < 0 and o.closing_time_min <= 0:
            continue
        best = None
        for d0 in extreme_sweep_designs(relaxed, 2, sense, sim):
            pp = nlp.params(cfg, 1.0, weight_time=sense, weights=(0.0, 0.0))
            w0, _ = initial_guess(nlp, relaxed, d0, sim, pp, t_max=st.t_max)
            r = nlp.solve(w0, pp, lbx, ubx, lbg, ubg)
            if r.success and (best is None or sense * r.x[nlp.iT] < sense * best.x[nlp.iT]):
                best = r
        if best is None:
            continue
        d, T, _, _ = nlp.unpack(best.x)
        rs = _sim(cfg, nlp, d, sim).run(nlp.param_vector(cfg, d), estimate_error=False)
        T_sim = rs.closing_time if rs.closed else T
        dd = nlp.design_dict(cfg, d)
        info[f"{name}_stroke"] = {"closing_time": T_sim, "design": dd}
        ds = ", ".join(f"{k} = {v:.4g}" for k, v in dd.items())
        if sense > 0 and T_sim > o.closing_time_max * (1 + 1e-6):
            return (f"closing_time_max = {o.closing_time_max:g} s cannot be met: the fastest "
                    f"stroke that any design within the bounds can make (holding moment >= "
                    f"{o.holding_moment_min:g} N m, no rebound) closes in {T_sim:.4g} s ({ds}); "
                    f"raise closing_time_max to at least {T_sim:.4g} s or widen the spring bounds",
                    info)
        if sense < 0 and T_sim < o.closing_time_min * (1 - 1e-6):
            return (f"closing_time_min = {o.closing_time_min:g} s cannot be met: the slowest "
                    f"stroke within the bounds closes in {T_sim:.4g} s ({ds}); lower "
                    "closing_time_min or widen the damper bounds", info)
    # 3. nothing obvious: Ipopt's verdict and the worst violated constraint group
    r = min(runs, key=lambda r: r.total_violation or math.inf)
    viol = r.violations[0] if r.violations else {}     # the nominal NLP: one block
    worst = max(viol, key=viol.get) if viol else None
    info["violations"] = viol
    if worst == "self_close" and viol[worst] > 0:
        return (f"optimise.self_close_min_deg = {o.self_close_min_deg:g} deg cannot be met: "
                f"at best (Ipopt: {r.status}) the self-closing moment dV/dtheta - T_fr falls "
                f"{viol[worst]:.3g} N m short somewhere below it; lower self_close_min_deg or "
                "widen the spring bounds", info)
    hint = (f"the largest violation is in {worst} ({viol[worst]:.3g})" if worst and viol[worst] > 0
            else "no constraint group is clearly violated")
    return (f"Ipopt did not converge from any start (best status {r.status}); {hint}; "
            "try more starts (optimise.starts), more iterations (optimise.max_iter) or "
            "hessian = \"limited-memory\"", info)
