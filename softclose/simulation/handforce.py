"""The hand force and the zones of a lid (SPEC §13), quasi-static, from the exact model.

Over theta from ``stroke.theta_closed_deg`` to ``stroke.theta_open_deg`` (fully open), with V
the potential (gravity and every spring), T_fr the friction moment on the lid's rotation
(``friction.torque``, 0 without friction) and tau = |dr_T/dtheta| the tip's lever:

- ``F_open = (dV/dtheta + T_fr) / tau`` (the force at the tip, normal to the lid, that lifts
  it slowly), ``F_close = (dV/dtheta - T_fr) / tau`` (< 0: it must be pushed down);
- zones: self-close where dV/dtheta > T_fr, self-rise where dV/dtheta < -T_fr, hold-open
  where |dV/dtheta| <= T_fr; their edges are roots of dV/dtheta -+ T_fr, located by the
  bracketed root finder (:func:`softclose.numerics.roots.illinois`), not to the grid.

The opening force is :func:`softclose.simulation.statics.opening_force_exact` (§9) when the
lid opens to the release angle (the default), else the same search over the wider range.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import ConfigError
from ..model.life import aged, at_end_of_life, shut_coordinates
from ..model.temperature import at_temperature, parameter_factors
from ..numerics.roots import illinois
from .statics import _parabola_max, opening_force_exact

#: angles of the hand-force grid (sign changes on it are then refined to the root)
HAND_GRID = 2001


@dataclass(frozen=True)
class HandForce:
    """The hand force over the opening angle and the lid's zones (SPEC §13); immutable.

    ``theta_deg``, ``f_open``, ``f_close`` (N), ``slope`` (dV/dtheta, N m), ``friction``
    (T_fr, N m), ``lever`` (|dr_T/dtheta|, m) on the grid; ``zones``: ((name, lo_deg,
    hi_deg), ...) covering [theta_closed, theta_open] in order; the metrics."""
    theta_deg: tuple
    f_open: tuple
    f_close: tuple
    slope: tuple
    friction: tuple
    lever: tuple
    zones: tuple
    opening_force: float
    closing_force: float
    self_close_deg: float | None
    self_rise_deg: float | None
    hold_open: tuple

    def metrics(self) -> dict:
        """The SPEC JSON keys of §13."""
        return {"opening_force": self.opening_force, "closing_force": self.closing_force,
                "self_close_deg": self.self_close_deg, "self_rise_deg": self.self_rise_deg,
                "hold_open": [list(r) for r in self.hold_open]}

    def describe(self) -> str:
        """One line: where the lid closes, stays and rises by itself, and the closing force."""
        f = lambda v: f"{v:.4g}"                      # noqa: E731
        parts = [f"closes by itself up to {f(self.self_close_deg)} deg"
                 if self.self_close_deg is not None else "never closes by itself from rest"]
        if self.hold_open:
            parts.append("stays open over " + ", ".join(f"{f(a)}–{f(b)} deg"
                                                        for a, b in self.hold_open))
        if self.self_rise_deg is not None:
            parts.append(f"rises by itself above {f(self.self_rise_deg)} deg")
        return "; ".join(parts) + f"; closing force {f(self.closing_force)} N"

    def to_json(self) -> dict:
        """The metrics, the zones and the curves (strict JSON: plain floats and lists)."""
        out = self.metrics()
        out["zones"] = [{"zone": z, "lo_deg": lo, "hi_deg": hi} for z, lo, hi in self.zones]
        out["curve"] = {"theta_deg": list(self.theta_deg), "f_open": list(self.f_open),
                        "f_close": list(self.f_close)}
        return out

    def to_frame(self):
        """The curves as a table: one row per angle."""
        import pandas as pd
        return pd.DataFrame({"theta_deg": self.theta_deg, "f_open": self.f_open,
                             "f_close": self.f_close, "dV_dtheta": self.slope,
                             "friction_torque": self.friction, "lever": self.lever})


def _parts(model, p, th):
    """(dV/dtheta, T_fr, tau) at the angles th (rad) from the exact model."""
    return _hand_parts(model, p, th)[:3]


def _hand_parts(model, p, th):
    """(dV/dtheta, T_fr, tau, F_open, dF_open/dtheta) at the angles th (rad): the model's
    ``hand`` function (one function of what the grid needs)."""
    th = np.atleast_1d(np.asarray(th, float))
    n = len(th)
    P = np.repeat(np.asarray(p, float)[:, None], n, 1)
    maps = model.__dict__.setdefault("_hand_maps", {})  # (mapping builds a Function: once)
    if n not in maps:
        maps[n] = model.hand if n == 1 else model.hand.map(n)
    dV, F, dF, tau = (np.asarray(v).ravel() for v in maps[n](th, P))
    fr = F * tau - dV                             # (the model's friction moment)
    fr = np.where(np.abs(fr) < 1e-12 * np.maximum(1.0, np.abs(dV)), 0.0, fr)
    return dV, fr, np.abs(tau), F, dF


def _roots(g, th, gv):
    """The roots of g between the sign changes of its grid values gv on th (rad)."""
    out = []
    for i in np.flatnonzero(np.sign(gv[:-1]) * np.sign(gv[1:]) < 0):
        out.append(illinois(g, th[i], th[i + 1], gv[i], gv[i + 1],
                            lambda a, b, x, r: r == 0 or b - a < 1e-14, 100))
    for i in np.flatnonzero(gv[1:-1] == 0.0):
        out.append(th[i + 1])
    return out


def hand_force(model, p=None, case=None, grid: int = HAND_GRID) -> HandForce:
    """The hand force and the zones of the lid ``model`` with parameters ``p`` (default: the
    design of ``case``, a resolved config (:class:`softclose.model.resolved.LidCase`; a
    shared model's own design may be another's of the same structure), default the model's;
    a design at the reference temperature, its parts moved to the case's operating
    temperature) over [stroke.theta_closed_deg, stroke.theta_open_deg] of the case's stroke
    (default the model's)."""
    if p is None:
        p = model.params() if case is None else case.p
    p = np.asarray(p, float)
    if case is not None:                 # the parts at the end of life, at the temperature
        if aged(case.life):
            p = at_end_of_life(p, case.life, shut_coordinates(model))
        p = at_temperature(p, parameter_factors(case.temperatures))
    st = model.stroke if case is None else case.stroke
    lo, hi = st.theta_closed, math.radians(st.theta_open_deg)
    th = np.linspace(lo, hi, grid)
    dV, fr, tau, F, dF = _hand_parts(model, p, th)
    bad = ~(np.isfinite(dV) & np.isfinite(fr) & (tau > 0))
    if bad.any():
        raise ConfigError(f"stroke.theta_open_deg: the linkage does not assemble (or stands "
                          f"in a toggle) at {np.degrees(th[bad][0]):.4g} deg, below the open "
                          f"angle {st.theta_open_deg:g} deg")

    def g(sign):
        def f(x):
            d, t, _ = _parts(model, p, x)
            return float(d[0] - sign * t[0])
        return f
    g_close, g_rise = g(+1), g(-1)          # dV - T_fr, dV + T_fr
    edges = sorted(set(_roots(g_close, th, dV - fr) + _roots(g_rise, th, dV + fr)))
    cuts = [lo] + [e for e in edges if lo < e < hi] + [hi]
    zones = []
    for a, b in zip(cuts[:-1], cuts[1:]):
        if b - a <= 0:
            continue
        m = 0.5 * (a + b)
        d, f, _ = (v[0] for v in _parts(model, p, m))
        z = "self_close" if d > f else "self_rise" if d < -f else "hold_open"
        if zones and zones[-1][0] == z:
            zones[-1][2] = b
        else:
            zones.append([z, a, b])
    deg = lambda x: st.theta_closed_deg if x == lo else st.theta_open_deg if x == hi \
        else math.degrees(x)                          # noqa: E731  (the ends exactly)
    zones = tuple((z, deg(a), deg(b)) for z, a, b in zones)
    f_open, f_close = (dV + fr) / tau, (dV - fr) / tau
    if st.theta_open_deg == st.theta0_deg and model.stroke.theta0_deg == st.theta0_deg:
        opening = float(opening_force_exact(model, p, grid=(th, F, dF)))
    else:
        opening = float(_parabola_max(f_open[None, :], th)[0])
    closing = float(max(0.0, _parabola_max(-f_close[None, :], th)[0]))
    self_close = zones[0][2] if zones[0][0] == "self_close" else None
    self_rise = zones[-1][1] if zones[-1][0] == "self_rise" else None
    hold = tuple((a, b) for z, a, b in zones if z == "hold_open")
    tl = lambda v: tuple(np.asarray(v, float).tolist())   # noqa: E731  (plain floats)
    return HandForce(tl(np.degrees(th)), tl(f_open), tl(f_close), tl(dV), tl(fr), tl(tau),
                     zones, opening, closing, self_close, self_rise, hold)


__all__ = ["HandForce", "hand_force", "HAND_GRID"]
