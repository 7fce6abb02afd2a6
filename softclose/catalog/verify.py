"""The adaptive reference at every corner of a pair's tolerance box.

Each corner is a config of its own (the pair's design values there, the other toleranced
keys' values, a rotary damper's pivot); the reference (CVODES on the exact equation,
:func:`softclose.optimiser.verify.verify`) checks every constraint of the problem there,
and the part's length limits are checked against the reference's own spring-length extremes
(its kind's free length is checked by the reference itself; a gas strut's compressed
length, its extended length less its stroke, too). The models are built without
length limits and kept here per geometry, mass and element choice.
"""

from __future__ import annotations

import math

import numpy as np

from ..problem import DESIGN_KEYS
from .screen import LIMIT_RTOL, PairBox, pair_rows, pivot_config
from ..optimiser.verify import Checker, verify
from ..model.lid import LidModel, model_key
from ..problem import resolve

_CHECKERS: dict = {}


def _checker(cfg):
    key = model_key(resolve(cfg))
    if key not in _CHECKERS:
        if len(_CHECKERS) > 64:
            _CHECKERS.clear()
        _CHECKERS[key] = Checker(LidModel.cached(resolve(cfg)), cfg.simulate.reference_tol)
    return _CHECKERS[key]


def corner_config(cfg, box: PairBox, spring, damper, row: int):
    """The config of one point (row of the box) of a pair: its design values and the other
    toleranced keys set, no spring length limits, at the row's temperature."""
    keys, X = pair_rows(box, spring, damper)
    values = {k: float(v) for k, v in zip(keys, X[row])}
    values["design.spring_kind"] = spring.spring_kind
    if values.get("design.strut_stroke") == 0.0:      # the config's none (0.4 x L_ext)
        del values["design.strut_stroke"]
    return box.config_at(pivot_config(cfg, damper).update(values), row)


def check_point(cfg, box: PairBox, spring, damper, row: int) -> dict:
    """The reference at one point of the pair's box: ``ok`` (every constraint met and the
    spring within its part's limits), ``reason`` when not, the reference's metrics and J."""
    c = corner_config(cfg, box, spring, damper, row)
    v = verify(c, {}, checker=_checker(c), hand=False, opening=False)   # (unless bounded)
    if v.error is not None:
        return {"ok": False, "reason": f"the reference failed: {v.error}", "objective": None}
    s = v.stroke
    why = [k for k, con in v.constraints.items() if not con["ok"]]
    lo, hi = (None if spring.is_strut else spring.min_length), spring.max_length
    if s.min_spring_length is not None and lo is not None \
            and s.min_spring_length < lo * (1 - LIMIT_RTOL):
        why.append(f"shorter than its minimum length {lo * 1e3:.2f} mm")
    if s.max_spring_length is not None and hi is not None \
            and s.max_spring_length > hi * (1 + LIMIT_RTOL):
        why.append(f"longer than its maximum length {hi * 1e3:.2f} mm")
    if s.reason and not s.closed:
        why.insert(0, s.reason)
    J = v.objective
    return {"ok": not why, "reason": "; ".join(why),
            "objective": None if J is None or not math.isfinite(J) else float(J),
            "closing_time": s.closing_time, "time": v.time,
            "design": {k: float(getattr(c.design, k)) for k in DESIGN_KEYS}}


def verify_pair(cfg, box: PairBox, spring, damper, kernel_feasible: np.ndarray,
                kernel_J: np.ndarray) -> dict:
    """The reference at every corner of a pair's box against the kernel's verdicts there:
    {feasible (every corner, by the reference), agree (same verdict at every corner), worst
    reference J over the corners, the corners where the verdicts differ, seconds}."""
    import time
    t0 = time.perf_counter()
    corners = []
    for r in range(box.corners):
        chk = check_point(cfg, box, spring, damper, r)
        chk["label"] = box.row_label(r, spring, damper)
        chk["kernel_feasible"] = bool(kernel_feasible[r])
        kj = kernel_J[r]
        chk["kernel_objective"] = None if not np.isfinite(kj) else float(kj)
        corners.append(chk)
    ok = all(c["ok"] for c in corners)
    J = [c["objective"] for c in corners]
    worst = max(J) if all(j is not None for j in J) else math.inf
    differ = [c["label"] for c in corners if c["ok"] != c["kernel_feasible"]]
    first_bad = next((c for c in corners if not c["ok"]), None)
    return {"feasible": ok, "agree": not differ, "differ": differ,
            "worst_objective": worst,
            "reason": "" if first_bad is None else f"{first_bad['reason']} at the corner "
                                                   f"{first_bad['label']}",
            "corners": corners, "seconds": time.perf_counter() - t0}
