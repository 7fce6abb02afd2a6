"""The words and numbers the optimise and robust reports share: a design with its units, the
objective with its weights, the closing-time window as solved."""

from __future__ import annotations

import math


def design_text(d: dict) -> str:
    """A design as the reports quote it, every variable with its unit: 7 significant digits
    (enough to reproduce the default optimum within its active limits; the design file has
    every digit)."""
    from ..problem import UNITS
    unit = {k: UNITS.get(k) or ("m" if "[" in k else "") for k in d}   # (a point: m)
    return ", ".join(f"{k} = {v:.7g}" + (f" {unit[k]}" if unit[k] else "")
                     for k, v in d.items())


def objective_text(pr: dict) -> str:
    """J with its weights and their units: J is dimensionless (the weights are the inverse
    squares of a reference rate and a reference speed)."""
    wi, wp = pr["weight_impact"], pr["weight_peak_tip"]
    return (f"J = {wi:g} s²·impact_theta_dot² + {wp:g} s²/m²·peak_tip_speed² "
            "(dimensionless)")


def hand_limits_text(pr: dict) -> str:
    """The hand-force limits of the problem when set (", opening effort <= F N, closes by
    itself up to A deg"), else ""."""
    parts = []
    if pr.get("opening_force_max") is not None:
        parts.append(f"opening effort <= {pr['opening_force_max']:g} N")
    if pr.get("self_close_min_deg") is not None:
        parts.append(f"closes by itself up to {pr['self_close_min_deg']:g} deg")
    return "".join(", " + t for t in parts)


def closing_time_text(pr: dict) -> str:
    """The closing-time window of the problem, and the window the NLP solved when that
    differs (closing_time_min raised to the NLP's floor, a limit corrected for the NLP's own
    discretisation error or clamped to stroke.t_max)."""
    lo, hi = pr["closing_time_min"], pr["closing_time_max"]
    text = f"{lo:g} s <= closing_time <= {hi:g} s"
    solved = pr.get("closing_time_solved")
    if not solved or (solved[0] == lo and solved[1] == hi):
        return text
    from ..optimiser.nlp import T_FLOOR
    why = []
    if solved[0] != lo:
        why.append("closing_time_min raised to the NLP's floor of "
                   f"{T_FLOOR * 1e3:g} ms" if solved[0] == max(lo, T_FLOOR) else
                   "closing_time_min corrected for the NLP's discretisation error")
    if solved[1] != hi:
        why.append("closing_time_max corrected for the NLP's discretisation error (note)"
                   if solved[1] < hi and pr.get("t_max", math.inf) >= hi else
                   "closing_time_max clamped to stroke.t_max")
    return text + f" (solved as [{solved[0]:.9g}, {solved[1]:.9g}] s: {'; '.join(why)})"


__all__ = ["design_text", "objective_text", "closing_time_text"]
