"""Re-simulation of chosen samples and scenarios by the adaptive reference.

Each point of the tolerance box is a config of its own (lid mass, geometry ...) and a
parameter vector; :func:`reference_check` runs the optimiser's verification
(``verify_design``: CVODES on the exact equation, every constraint of the problem, theta'
on a fine grid for rebounds) on it and compares with the fast kernel's numbers.
"""

from __future__ import annotations

import math

import numpy as np

from ..config import Config
from ..problem import DESIGN_KEYS, METRIC_KEYS, design_of, params_of
from .evaluate import with_values


def _verify_design():
    from ..optimiser.verify import verify_design
    return verify_design


def point_config(cfg: Config, keys, x) -> Config:
    """``cfg`` with the toleranced keys set to the values ``x`` (design keys included)."""
    return with_values(cfg, {k: float(v) for k, v in zip(keys, np.atleast_1d(x))})


def reference_check(cfg: Config, keys, x, label: str = "", kernel: dict | None = None,
                    objective: float | None = None) -> dict:
    """The adaptive reference at one point of the box: its metrics, whether every
    constraint holds, and (with ``kernel``, the fast path's metrics there) the differences."""
    c = point_config(cfg, keys, x)
    design = design_of(params_of(c))
    ver = _verify_design()(c, design, None, objective)
    out = {"label": label, "values": {k: float(v) for k, v in zip(keys, np.atleast_1d(x))}}
    if "error" in ver:
        out.update(ok=False, error=ver["error"])
        return out
    out["reference"] = {k: ver.get(k) for k in METRIC_KEYS}
    out["reference"]["objective"] = ver.get("objective")
    out["constraints"] = ver.get("constraints", {})
    out["ok"] = bool(ver.get("constraints_ok"))
    if objective is not None and ver.get("objective_relative_difference") is not None:
        out["objective_relative_difference"] = ver["objective_relative_difference"]
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


__all__ = ["reference_check", "point_config", "DESIGN_KEYS"]
