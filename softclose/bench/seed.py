"""The seed notebook's computation: its gravity-only drop (Euler-Cromer at 1 kHz, the impact
read off the sample grid) against the adaptive reference and the configured default
(:func:`seed_reproduction`).
"""

from __future__ import annotations

import math

import numpy as np

from ..simulation.kernel import binding
from ..config import Config
from ..numerics.integrators import SEED
from ..simulation.reference import Reference
from ..simulation.simulator import Simulator
from ..problem import resolve

#: the seed notebook's step (1000 samples per second)
SEED_STEP = SEED[1]
#: the metrics the seed reads off its drop
SEED_KEYS = ("closing_time", "impact_theta_dot", "impact_tip_speed")


def seed_reading(sim: Simulator) -> dict:
    """The seed's numbers: ``sim`` (Euler-Cromer at 1 ms) with the impact read at the first
    sample at or below theta_closed, as the seed notebook does, instead of located in the
    step. Also returns the same stroke with the event located (``located_event``) and the
    trajectory."""
    res = sim.run(trajectory=True, estimate_error=False)
    tr = res.trajectory
    # the kernel stops at the located event; the sample the seed reads is one full step on
    # from the last node before it
    t, th, thd = tr["t"][-2], tr["theta"][-2], tr["theta_dot"][-2]
    x1 = binding.kernel_step(sim.table, sim.method, sim.model.params(), sim.step,
                            np.array([th, thd]))
    v_T = np.asarray(sim.model.kin(np.array([x1[0], x1[1]]))[4]).ravel()
    return {"closing_time": t + sim.step, "impact_theta_dot": float(x1[1]),
            "impact_tip_speed": float(np.hypot(v_T[0], v_T[1])),
            "theta_at_sample_deg": math.degrees(x1[0]), "located_event": res.metrics(),
            "trajectory": tr}


def _slope(hs, errs, above: float = 1e-8):
    """Slope of log error against log step over the errors above ``above`` (NaN if < 2)."""
    e, h = np.asarray(errs, float), np.asarray(hs, float)
    ok = e > above
    if ok.sum() < 2:
        return math.nan
    return float(np.polyfit(np.log(h[ok]), np.log(e[ok]), 1)[0])


def seed_reproduction(cfg: Config, fast: bool = False) -> dict:
    """The seed notebook's gravity-only drop (Euler-Cromer at 1 kHz, impact read off the
    sample grid) against the adaptive reference (tolerance ``simulate.reference_tol``) and
    the configured default (``simulate.integrator`` at ``simulate.step``, event located).

    Returns the metrics and errors of each, the errors of Euler-Cromer and rk4 against the
    step (``convergence``), their observed orders, and the trajectories of the seed's drop
    and of the default (``trajectories``, for the figure).
    """
    case = resolve(cfg)
    ec = Simulator(case, integrator=SEED[0], step=SEED_STEP)
    seed = seed_reading(ec)
    default = Simulator(case, model=ec.model).run(trajectory=True)
    ref = Reference(ec.model, case.solver.reference_tol).simulate(None, case)
    steps = SEED_STEP * 2.0 ** -np.arange(0, 4 if fast else 8)
    steps = np.r_[SEED_STEP * np.array([8, 4, 2]), steps]
    conv = {"step": steps.tolist()}
    for name in ("euler_cromer", "rk4"):
        for k in SEED_KEYS[:2]:
            conv[f"{name}_{k}_error"] = []
        for h in steps:
            r = Simulator(resolve(cfg), model=ec.model, integrator=name, step=float(h)).run(
                estimate_error=False)
            for k in SEED_KEYS[:2]:
                conv[f"{name}_{k}_error"].append(abs(getattr(r, k) - getattr(ref, k)))
    order = {n: _slope(steps, conv[f"{n}_impact_theta_dot_error"])
             for n in ("euler_cromer", "rk4")}
    refv = {k: getattr(ref, k) for k in SEED_KEYS}
    loc = seed["located_event"]
    return {
        "reference": refv, "reference_tol": ref.tolerance,
        "seed_grid_reading": {k: seed[k] for k in SEED_KEYS},
        "seed_theta_at_sample_deg": seed["theta_at_sample_deg"],
        "seed_errors": {k: seed[k] - refv[k] for k in SEED_KEYS},
        "euler_cromer_located_event": {k: loc[k] for k in SEED_KEYS},
        "euler_cromer_located_errors": {k: loc[k] - refv[k] for k in SEED_KEYS},
        "default": {"method": default.method, "step": default.step,
                    **{k: getattr(default, k) for k in SEED_KEYS}},
        "default_errors": {k: getattr(default, k) - refv[k] for k in SEED_KEYS},
        "default_accuracy": {k: (default.accuracy or {}).get(k) for k in SEED_KEYS},
        "observed_order": order, "convergence": conv,
        "trajectories": {"seed": seed["trajectory"], "default": default.trajectory},
    }
