"""Re-simulation of chosen samples and scenarios by the adaptive reference.

Each point of the tolerance box is a config of its own (lid mass, geometry ...) and a
parameter vector; :func:`reference_check` runs the optimiser's verification
(``verify_design``: CVODES on the exact equation, every constraint of the problem, theta'
on a fine grid for rebounds) on it and compares with the fast kernel's numbers, or with
the numbers a solver claims for that point (the scenario NLP's own closing time, impact
speed, peak tip speed, holding moment and objective), each to
:func:`softclose.problem.agreement_tolerance` (the objective to ``VERIFY_RTOL``);
:func:`scenario_report` does so for every scenario of a robust design.
"""

from __future__ import annotations

import math

import numpy as np

from ..simulation import statics
from ..config import Config
from ..problem import DESIGN_KEYS, ENGAGE_KEYS, METRIC_KEYS, design_of, params_of
from ..problem import PARAM_COLUMNS, at_temperature, condition_parts
from .box import box_of
from .scenarios import design_dict
from .evaluate import with_values
from .scenarios import label, temperatures
from ..optimiser.verify import agree, verify_design


def _verify_design():
    return verify_design


def point_config(cfg: Config, keys, x) -> Config:
    """``cfg`` with the toleranced keys set to the values ``x`` (design keys included)."""
    return with_values(cfg, {k: float(v) for k, v in zip(keys, np.atleast_1d(x))})


#: the metrics a solver's claims are compared on (those the scenario NLP has of its own)
CLAIMED = ("closing_time", "impact_theta_dot", "peak_tip_speed", "holding_moment",
           *ENGAGE_KEYS)


def agreement(claims: dict, reference: dict) -> dict:
    """Each claimed number (:data:`CLAIMED` and ``objective``) against the reference's
    (:func:`softclose.optimiser.verify.agree`, the nominal optimiser's rule):
    {key: {optimiser, reference, difference, tolerance, ok}}."""
    return {k: agree(k, claims[k], reference.get(k)) for k in CLAIMED + ("objective",)
            if claims.get(k) is not None}


def reference_check(cfg: Config, keys, x, label: str = "", kernel: dict | None = None,
                    objective: float | None = None, claims: dict | None = None) -> dict:
    """The adaptive reference at one point of the box: its metrics, whether every
    constraint holds, (with ``kernel``, the fast path's metrics there) the differences, and
    (with ``claims``, a solver's own metrics and objective there) their :func:`agreement`
    with the reference (``agreement``, ``agreement_ok``)."""
    c = point_config(cfg, keys, x)
    design = design_of(params_of(c))
    ver = _verify_design()(c, design, None, objective)
    out = {"label": label, "values": {k: float(v) for k, v in zip(keys, np.atleast_1d(x))}}
    if "error" in ver:
        out.update(ok=False, error=ver["error"])
        return out
    out["reference"] = {k: ver.get(k) for k in METRIC_KEYS + ENGAGE_KEYS
                        if k in METRIC_KEYS or ver.get(k) is not None}
    out["reference"]["objective"] = ver.get("objective")
    out["constraints"] = ver.get("constraints", {})
    out["ok"] = bool(ver.get("constraints_ok"))
    if objective is not None and ver.get("objective_relative_difference") is not None:
        out["objective_relative_difference"] = ver["objective_relative_difference"]
    if claims is not None:
        out["agreement"] = agreement(claims, out["reference"])
        out["agreement_ok"] = all(a["ok"] for a in out["agreement"].values())
    if kernel is not None:
        out["kernel"] = {k: kernel.get(k) for k in METRIC_KEYS + ("objective",)}
        diff = {}
        for k in ("closing_time", "impact_theta_dot", "peak_tip_speed", "holding_moment"):
            a, b = kernel.get(k), out["reference"].get(k)
            if a is not None and b is not None and math.isfinite(a) and math.isfinite(b):
                diff[k] = float(a - b)
        out["differences"] = diff
        out["kernel_feasible"] = bool(kernel.get("feasible"))
        out["verdicts_agree"] = out["kernel_feasible"] == out["ok"]
    return out


def scenario_report(cfg, problem, run, verify: bool) -> tuple[list, bool]:
    """Per scenario: its values, the NLP's metrics and the reference's verdict at the
    scenario's temperature (``temperature_c``, given with several sign-off temperatures or
    one other than the reference) (``problem`` and ``run``: a
    :class:`softclose.robust.solve.Problem` and its solve)."""
    box_d = box_of(cfg, design_dict(problem, run.design), scale=problem.scale)
    temps = temperatures(cfg)
    out, ok_all = [], True
    worst = int(np.argmax(run.J))
    for s, sc in enumerate(problem.scenarios):
        z = np.asarray(sc.z)
        T, X, _ = run.states[s]
        p = problem.scenario_params(run.design, s)
        model = problem.nlp.scenario_models[s]
        metrics = {"closed": True, "closing_time": T, "impact_theta_dot": float(X[1, -1]),
                   "peak_tip_speed": float(run.peaks[s]),
                   "holding_moment": model.holding_moment(p),
                   "opening_force": statics.opening_force_exact(model, p)}
        if run.engage is not None and p[PARAM_COLUMNS["design.end_damper_c"]] != 0:
            # two phases: the node between them, against the reference's engagement
            metrics["engage_time"], metrics["engage_theta_dot"] = run.engage[s]
        T = sc.temperature_c
        entry = {"label": label(box_d, z, T, temps), "origin": sc.origin,
                 "values": {k: float(v) for k, v in zip(box_d.keys, box_d.values(z)[0])},
                 "z": list(map(float, z)), "metrics": metrics, "objective": float(run.J[s]),
                 "worst": s == worst}
        if len(temps) > 1 or (T is not None and T != cfg.operating.reference_temperature_c):
            entry["temperature_c"], state = condition_parts(T)
            if any(condition_parts(c)[1] for c in temps):      # (new and end of life)
                entry["state"] = state or "new"
        if verify:
            # the NLP's own numbers of this scenario against the reference's, the reference
            # at the scenario's temperature (the NLP's parameters moved by its factors)
            c_d = cfg.with_design(**design_dict(problem, run.design))
            if T is not None:
                c_d = at_temperature(c_d, T)
            chk = reference_check(c_d, box_d.keys, box_d.values(z)[0], entry["label"], None,
                                  float(run.J[s]),
                                  claims={**metrics, "objective": entry["objective"]})
            entry["reference"] = chk.get("reference")
            entry["constraints"] = chk.get("constraints")
            entry["agreement"] = chk.get("agreement")
            entry["verified"] = bool(chk.get("ok")) and bool(chk.get("agreement_ok"))
            if "error" in chk:
                entry["error"] = chk["error"]
            ok_all &= entry["verified"]
        out.append(entry)
    return out, ok_all


__all__ = ["reference_check", "agreement", "point_config", "scenario_report", "DESIGN_KEYS"]
