"""The sign-off checks of one design: every constraint of the problem, judged by the adaptive
reference, at the nominal lid, at each operating temperature and at the worst corner of the
tolerance box.

A temperature's lid is ``cfg.replace(operating={"temperature_c": T})``: the design stays at
the reference temperature and its parts follow their laws in the stroke. The worst corner of
a constraint is found among the 2^d corners of the ``[tolerance]`` box at every temperature
by the C kernel (one batch of strokes) and then judged by the reference.
"""

from __future__ import annotations

import math

import numpy as np

from ..optimiser.verify import verify
from ..problem import DESIGN_KEYS, design_of, params_of
from ..problem import at_state, condition_parts, condition_text, sign_off_states
from ..problem import at_temperature as _at_temperature, sign_off_temperatures as temperatures
from ..robust.box import box_of
from ..robust.evaluate import evaluate
from ..robust.verify import point_config

#: each constraint in words, its relation to its limit and its unit (the names of
#: :data:`softclose.problem.CONSTRAINTS`)
ROWS = {
    "closed": ("the lid closes", "=", ""),
    "closing_time_max": ("closing time", "≤", "s"),
    "closing_time_min": ("closing time", "≥", "s"),
    "no_rebound": ("largest θ' (no rebound)", "≤", "rad/s"),
    "holding_moment_min": ("holding moment", "≥", "N m"),
    "opening_force_max": ("opening force", "≤", "N"),
    "self_close_min_deg": ("closes by itself up to", "≥", "deg"),
}


def at_temperature(cfg, condition: float):
    """``cfg`` at a sign-off condition: a temperature of the new lid (the new lid when the
    end of life is a sign-off state too), or one at the end of life
    (:func:`softclose.problem.sign_off_conditions`)."""
    if condition_parts(condition)[1] is None and len(sign_off_states(cfg)) > 1:
        cfg = at_state(cfg, "new")
    return _at_temperature(cfg, condition)


def design_values(cfg) -> dict:
    return {k: float(getattr(cfg.design, k)) for k in DESIGN_KEYS}


def constraint_rows(cfg) -> list[str]:
    """The constraints the design must meet, in the order of :data:`ROWS`."""
    o = cfg.optimise
    rows = ["closed", "closing_time_max"]
    if o.closing_time_min > 0:
        rows.append("closing_time_min")
    rows += ["no_rebound", "holding_moment_min"]
    if o.opening_force_max is not None:
        rows.append("opening_force_max")
    if o.self_close_min_deg is not None:
        rows.append("self_close_min_deg")
    return rows


def cell(name: str, c: dict | None, where: str = "") -> dict:
    """One cell of the matrix: value, limit, margin (> 0: met with room), pass."""
    if c is None:
        return {"value": None, "limit": None, "margin": None, "ok": False,
                "where": where or "not computed"}
    v, lim = c.get("value"), c.get("bound")
    margin = None
    if all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in (v, lim)):
        margin = float(lim - v) if ROWS[name][1] == "≤" else float(v - lim)
    out = {"value": v, "limit": lim, "margin": margin, "ok": bool(c.get("ok"))}
    if where:
        out["where"] = where
    if c.get("reason"):
        out["reason"] = c["reason"]
    return out


def check(cfg, *, hand: bool = True):
    """The reference's verification of cfg's design at cfg's temperature (a
    :class:`softclose.optimiser.verify.Verification`)."""
    return verify(cfg, design_values(cfg), hand=hand)


def column(cfg, ver) -> dict:
    """The matrix column of one verification: {constraint: cell}."""
    rows = constraint_rows(cfg)
    if ver.error is not None:
        return {r: {"value": None, "limit": None, "margin": None, "ok": False,
                    "reason": ver.error} for r in rows}
    cons = ver.constraints
    if "valid_range" in cons:          # a spring out of its valid range: every row fails
        why = cons["valid_range"].get("reason", "a spring leaves its valid range")
        return {r: {"value": None, "limit": None, "margin": None, "ok": False,
                    "reason": why} for r in rows}
    closed = ver.stroke is not None and ver.stroke.closed
    return {r: cell(r, cons.get(r)) if r in cons or closed else
            {"value": None, "limit": None, "margin": None, "ok": False,
             "reason": "the lid does not close"} for r in rows}


def _badness(name: str, cols: dict) -> np.ndarray | None:
    """How bad each corner stroke is for one constraint (larger is worse); None when the
    kernel's columns do not hold it (judged among the corners checked for the others)."""
    closed = np.asarray(cols["closed"], bool)
    ct = np.asarray(cols["closing_time"], float)
    th = np.nan_to_num(np.asarray(cols["theta_min"], float), nan=10.0)
    if name in ("closed", "closing_time_max"):
        return np.where(closed, ct, 1e3 + th)
    if name == "closing_time_min":
        return np.where(closed, -ct, -np.inf)
    if name == "holding_moment_min":
        return np.nan_to_num(-np.asarray(cols["holding_moment"], float), nan=np.inf)
    if name == "no_rebound":
        return np.nan_to_num(np.asarray(cols["theta_dot_max"], float), nan=-np.inf)
    return None


def worst_corners(cfg, temps) -> tuple[dict, dict]:
    """The worst corner of the tolerance box for each constraint over the temperatures
    ``temps``, judged by the reference: ({constraint: cell with ``where``}, facts: keys,
    corners, strokes in the kernel, corners checked by the reference). Empty without a box."""
    rows = constraint_rows(cfg)
    box0 = box_of(cfg)
    if not box0.dim:
        return {}, {"keys": [], "corners": 0}
    Z = box0.corners()
    boxes = {}
    best: dict = {}
    for T in temps:
        c = at_temperature(cfg, T)
        box = box_of(c)
        boxes[T] = box
        cols = evaluate(c, box.keys, box.values(Z))
        for r in rows:
            b = _badness(r, cols)
            if b is None:
                continue
            i = int(np.argmax(b))
            if r not in best or b[i] > best[r][0]:
                best[r] = (float(b[i]), T, i)
    picks = {(T, i) for _, T, i in best.values()}
    checked = {}
    for T, i in sorted(picks):
        c = at_temperature(cfg, T)
        box = boxes[T]
        pc = point_config(c, box.keys, box.values(Z[i])[0])
        ver = verify(pc, design_of(params_of(pc)), hand=True)
        checked[(T, i)] = (column(cfg, ver), f"{box.label(Z[i])} at {condition_text(T)}")
    out = {}
    for r in rows:
        if r in best:
            _, T, i = best[r]
            col, where = checked[(T, i)]
            out[r] = {**col[r], "where": where}
        else:                            # worst among the corners checked for the others
            worst = None
            for col, where in checked.values():
                x = col[r]
                key = (x["ok"], x["margin"] if x["margin"] is not None else -math.inf)
                if worst is None or key < worst[0]:
                    worst = (key, {**x, "where": where + " (the worst of the corners "
                                                      "checked for the other rows)"})
            out[r] = worst[1]
    facts = {"keys": list(box0.keys), "corners": int(len(Z)),
             "temperatures": list(dict.fromkeys(condition_parts(T)[0] for T in temps)),
             "states": list(dict.fromkeys(condition_parts(T)[1] or "new" for T in temps)),
             "kernel_strokes": int(len(Z) * len(temps)), "reference_checks": len(checked)}
    return out, facts


def relative_margin(cfg, name: str, c: dict) -> float:
    """A cell's margin relative to its limit's scale (to compare rows of other units)."""
    if c["margin"] is None:
        return -math.inf if not c["ok"] else math.inf
    scale = {"closing_time_max": cfg.optimise.closing_time_max,
             "closing_time_min": cfg.optimise.closing_time_max,
             "holding_moment_min": max(abs(cfg.optimise.holding_moment_min), 1e-3),
             "no_rebound": 1.0}.get(name, max(abs(c["limit"] or 0.0), 1e-9))
    return c["margin"] / scale


__all__ = ["ROWS", "temperatures", "at_temperature", "constraint_rows", "check", "column",
           "worst_corners", "relative_margin", "design_values"]
