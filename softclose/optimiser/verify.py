"""Verification: an answer counts when the independent adaptive reference reproduces it.

:func:`verify` re-simulates a design with CVODES on the exact equation of motion
(:class:`softclose.simulation.reference.Reference`) and checks

- every constraint of the problem on that simulation (closed; closing_time within its
  bounds; holding moment; no rebound: theta' <= 0 on an 800-point CVODES grid over the
  stroke, theta''(release) <= 0, theta >= theta_closed);
- with the optimiser's own numbers (``claims``): each metric against the reference's to
  :func:`softclose.problem.agreement_tolerance`, the objective to
  :data:`softclose.problem.VERIFY_RTOL` (relative). A number that disagrees is a failed
  verification naming it.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from ..errors import ConfigError, NumericalError
from ..interrupt import solving
from ..model.life import aged, shut_coordinates, stroke_params
from ..problem import (CONSTRAINT_TOL, ENGAGE_KEYS, METRIC_KEYS, UNITS, opening_wanted,
                       VERIFY_RTOL, PARAM_KEYS, REFERENCE_TOL, agreement_tolerance, objective,
                       params_of, resolve)
from ..simulation.stroke import StrokeResult, StrokeStatus
from ..simulation.handforce import HandForce, hand_force
from .cache import get_model
from ..jsonio import jsonable
from ..present.display import num
from ..simulation.reference import Reference

#: output grid of the verifying reference simulation (s): events and peaks are located by
#: Newton inside it, to the tolerance; a 2 ms grid changes the metrics by < 1e-9 and takes
#: 3x longer
VERIFY_GRID = 0.01
#: relative slack of the closing-time bounds in verification (the NLP's bound is corrected
#: for its own discretisation error, so the verified closing time meets it to ~1e-10)
CLOSING_RTOL = 1e-6
#: points of the CVODES grid on which theta' <= 0 is checked
REBOUND_GRID = 800


class Checker:
    """Independent checks of one model: the CVODES reference and theta' on a fine grid."""

    def __init__(self, model, reference_tol: float = REFERENCE_TOL):
        """``reference_tol``: the config's ``simulate.reference_tol``."""
        self.model = model
        self.reference = Reference(model, reference_tol, grid_step=VERIFY_GRID)
        x, tau = ca.SX.sym("x", 2), ca.SX.sym("tau")
        p = ca.SX.sym("p", len(PARAM_KEYS))
        tol = min(1e-10, reference_tol * 100)
        grid = list(np.linspace(0.0, 1.0, REBOUND_GRID + 1)[1:])
        dae = {"x": x, "p": ca.vertcat(p, tau), "ode": tau * model.ode(x, p)}
        self._grid_flow = ca.integrator("check_grid", "cvodes", dae, 0.0, grid,
                                        {"abstol": tol, "reltol": tol, "max_num_steps": 200000})
        self._l = model.coordinate_fns["spring"]

    def theta_dot_max(self, p, T) -> float:
        """max theta' over (0, T] of the exact equation (CVODES on a fine grid)."""
        st = self.model.stroke
        with solving():          # Ctrl-C: noted, raised when CVODES returns
            out = self._grid_flow(x0=[st.theta0, 0.0], p=np.r_[p, T])["xf"]
        return float(np.max(np.asarray(out)[1]))

    def spring_extremes(self, a: float, b: float) -> tuple[float, float]:
        """min and max of the spring length over theta in [a, b] (grid + parabola); the
        geometry's alone, so kept per (a, b)."""
        known = self.__dict__.setdefault("_extremes", {})
        if (a, b) not in known:
            known[(a, b)] = self._spring_extremes(a, b)
        return known[(a, b)]

    def _spring_extremes(self, a: float, b: float) -> tuple[float, float]:
        g = np.linspace(a, b, 2001)
        lv = np.asarray(self._l.map(len(g))(g)[0]).ravel()
        out = []
        for sgn in (1, -1):
            i = int(np.argmin(sgn * lv))
            v = lv[i]
            if 0 < i < len(g) - 1:
                y0, y1, y2 = lv[i - 1], lv[i], lv[i + 1]
                den = y0 - 2 * y1 + y2
                if den != 0:
                    v = y1 - (y2 - y0) ** 2 / (8 * den)
            out.append(float(v))
        return out[0], out[1]


_CHECKERS: dict = {}


def get_checker(cfg) -> Checker:
    """The Checker of cfg's model (cached with the model)."""
    model = get_model(cfg)
    if id(model) not in _CHECKERS:
        _CHECKERS[id(model)] = Checker(model, cfg.simulate.reference_tol)
    return _CHECKERS[id(model)]


@dataclass(frozen=True)
class Verification:
    """What the adaptive reference says about one design.

    ``stroke``: the reference's stroke (its metrics are the verified ones); ``objective``:
    J of those metrics; ``constraints``: name -> {value, bound, unit, ok} (names of
    :data:`softclose.problem.CONSTRAINTS`); ``agreement``: for each number the optimiser
    claimed, {optimiser, reference, difference, tolerance, ok}; ``error``: why the
    reference could not simulate the design (then nothing else is known).
    """

    stroke: StrokeResult | None
    objective: float | None
    constraints: dict = field(default_factory=dict)
    agreement: dict = field(default_factory=dict)
    method: str = ""
    time: float = 0.0
    error: str | None = None
    hand: HandForce | None = None        # the hand force and the zones (SPEC §13)

    @property
    def constraints_ok(self) -> bool:
        return self.error is None and all(c["ok"] for c in self.constraints.values())

    @property
    def agreement_ok(self) -> bool:
        return all(a["ok"] for a in self.agreement.values())

    @property
    def ok(self) -> bool:
        """The reference simulated the design, every constraint holds and every claimed
        number agrees within its tolerance."""
        return self.error is None and self.constraints_ok and self.agreement_ok

    @property
    def metrics(self) -> dict | None:
        """The verified §4 metrics (the reference's), with the end damper's engagement time
        and speed when it engages (:data:`softclose.problem.ENGAGE_KEYS`)."""
        if self.stroke is None:
            return None
        out = self.stroke.metrics()
        out.update({k: getattr(self.stroke, k) for k in ENGAGE_KEYS
                    if getattr(self.stroke, k) is not None})
        return out

    @property
    def failures(self) -> tuple[str, ...]:
        """One phrase per failed check, naming it with its numbers."""
        if self.error is not None:
            return (f"the adaptive reference could not simulate the design ({self.error})",)
        out = []
        for k, c in self.constraints.items():
            if not c["ok"] and c.get("reason"):
                out.append(f"{k} is violated in the reference simulation: {c['reason']}")
            elif not c["ok"] and isinstance(c["value"], bool):
                out.append(f"{k} is violated in the reference simulation "
                           f"({c['value']} against the bound {c['bound']})")
            elif not c["ok"]:
                u = f" {c['unit']}" if c.get("unit") else ""
                out.append(f"{k} is violated in the reference simulation "
                           f"({num(c['value'], spec='.9g')}{u} against the bound "
                           f"{num(c['bound'], spec='.9g')}{u})")
        for k, a in self.agreement.items():
            if not a["ok"]:
                u = f" {UNITS.get(k, '')}" if UNITS.get(k) else ""
                if a["difference"] is None:
                    out.append(f"{k}: the optimiser has {a['optimiser']}, the reference "
                               f"{a['reference']}")
                else:
                    out.append(f"{k}: the optimiser's {num(a['optimiser'], spec='.9g')}{u} "
                               f"differs from the reference's "
                               f"{num(a['reference'], spec='.9g')}{u} by "
                               f"{abs(a['difference']):.2e} (allowed {a['tolerance']:.1e})")
        return tuple(out)

    @property
    def message(self) -> str:
        """'' when verified, else why not and what to change."""
        if self.ok:
            return ""
        msg = "not confirmed by the adaptive reference: " + "; ".join(self.failures)
        if any(not a["ok"] for a in self.agreement.values()):
            msg += "; raise optimise.nodes or optimise.substeps"
        return msg

    def to_json(self) -> dict:
        """Plain values: ok, the reference's metrics (top level) and objective, the
        differences from the optimiser's numbers with their tolerances, the constraints."""
        if self.error is not None:
            return {"ok": False, "error": self.error, "method": self.method,
                    "failures": list(self.failures)}
        out = {"ok": self.ok, **self.metrics, "objective": self.objective}
        diffs = {k: a["difference"] for k, a in self.agreement.items()
                 if k not in ("closed", "objective") and a["difference"] is not None}
        if self.agreement:
            out["differences"] = diffs
            out["tolerances"] = {k: a["tolerance"] for k, a in self.agreement.items()
                                 if k not in ("closed", "objective")}
        obj = self.agreement.get("objective")
        if obj is not None and obj["difference"] is not None:
            out["objective_difference"] = obj["difference"]
            out["objective_relative_difference"] = (obj["difference"] / abs(self.objective)
                                                    if self.objective else math.inf)
            out["objective_ok"] = obj["ok"]
        out["agreement_ok"] = self.agreement_ok
        out["constraints"] = self.constraints
        out["constraints_ok"] = self.constraints_ok
        out["failures"] = list(self.failures)
        out["method"] = self.method
        out["time"] = self.time
        return jsonable(out)


def agree(key: str, claimed, reference) -> dict:
    """One number a solver claims against the adaptive reference's (the nominal and the
    robust optimiser's one rule): {optimiser, reference, difference, tolerance, ok}.
    ``closed`` agrees when both say the same; a number only one side has, or a non-finite
    one, disagrees (no difference); the objective agrees within VERIFY_RTOL (relative), a
    metric within :func:`softclose.problem.agreement_tolerance`."""
    a, b = claimed, reference
    if key == "closed":
        return {"optimiser": a, "reference": b, "difference": None, "tolerance": None,
                "ok": bool(a) == bool(b)}
    if a is None or b is None or not math.isfinite(a) or not math.isfinite(b):
        return {"optimiser": a, "reference": b, "difference": None, "tolerance": None,
                "ok": a is None and b is None}
    tol = VERIFY_RTOL * abs(b) if key == "objective" else agreement_tolerance(key, b)
    return {"optimiser": float(a), "reference": float(b), "difference": float(a - b),
            "tolerance": float(tol), "ok": bool(abs(a - b) <= tol)}


def verify(cfg, design: dict, claims: dict | None = None,
           claimed_objective: float | None = None, checker: Checker | None = None,
           hand: bool = True, opening: bool = True) -> Verification:
    """Re-simulate ``design`` with the adaptive reference and check it (module docstring).

    ``claims``: the optimiser's own §4 metrics; ``claimed_objective``: its J; ``checker``:
    the :class:`Checker` of cfg's model (default: the cached one of its geometry). Never
    raises for a design the reference cannot simulate: ``error`` says why. ``hand=False``:
    no hand force and zones (``hand`` None) unless ``optimise.self_close_min_deg`` needs them;
    ``opening=False``: no opening effort (None) unless ``optimise.opening_force_max`` bounds it.
    """
    o, st = cfg.optimise, cfg.stroke
    chk = checker or get_checker(cfg)
    model = chk.model
    p = params_of(cfg, design)
    method = (f"CVODES (adaptive BDF) on the exact equation, tolerance "
              f"{chk.reference.tol:g}")
    t0 = time.perf_counter()
    try:
        ref = chk.reference.simulate(p, resolve(cfg),   # cfg's limits, not the cached model's
                                     opening_wanted(o, opening))
    except NumericalError as exc:
        return Verification(None, None, method=method, time=time.perf_counter() - t0,
                            error=str(exc))
    J = objective(o, ref.impact_theta_dot, ref.peak_tip_speed)
    T = ref.closing_time
    cons = {"closed": {"value": bool(ref.closed), "bound": True, "unit": "",
                       "ok": bool(ref.closed)}}
    if ref.status == StrokeStatus.OUT_OF_RANGE:   # a spring out of its valid range: why
        cons = {"valid_range": {"value": False, "bound": True, "unit": "", "ok": False,
                                "reason": ref.reason}}
    if T is not None:
        cons["closing_time_max"] = {"value": T, "bound": o.closing_time_max, "unit": "s",
                                    "ok": T <= o.closing_time_max * (1 + CLOSING_RTOL)}
        cons["closing_time_min"] = {"value": T, "bound": o.closing_time_min, "unit": "s",
                                    "ok": T >= o.closing_time_min * (1 - CLOSING_RTOL)}
    # no rebound: theta' <= 0 throughout (from the release: theta''(0) <= 0), and the lid
    # never passes the rim
    case = resolve(cfg)
    q = p if not aged(case.life) else stroke_params(      # (the parts at the end of life)
        p, case, lambda: shut_coordinates(model))
    release = float(model.ode(ca.vertcat(st.theta0, 0.0), q)[1])
    try:                            # (a lid friction holds where it is released: at rest)
        held = not ref.closed and float(ref.theta_min) >= st.theta0 - 1e-12
        thd_max = 0.0 if held else chk.theta_dot_max(q, T if T is not None else st.t_max)
    except RuntimeError as exc:     # CVODES on the equation without its stick (a lid that
        if ref.closed:              # friction holds where it is released chatters there)
            return Verification(None, None, method=method, time=time.perf_counter() - t0,
                                error=f"theta' on the fine grid: {str(exc).splitlines()[-1]}")
        thd_max = None              # (it did not close: that fails it already)
    th_min = float(ref.theta_min)
    if thd_max is not None:
        cons["no_rebound"] = {"value": max(thd_max, min(release, 0.0)), "bound": 0.0,
                              "unit": "rad/s", "theta_ddot_release": release,
                              "theta_min": th_min,
                              "ok": thd_max <= CONSTRAINT_TOL and release <= 0.0
                              and th_min >= st.theta_closed - 1e-12}
    hm = ref.holding_moment
    cons["holding_moment_min"] = {"value": hm, "bound": o.holding_moment_min, "unit": "N m",
                                  "ok": hm >= o.holding_moment_min - CONSTRAINT_TOL}
    if o.opening_force_max is not None:
        of = ref.opening_force
        cons["opening_force_max"] = {"value": of, "bound": o.opening_force_max, "unit": "N",
                                     "ok": of <= o.opening_force_max + CONSTRAINT_TOL}
    hand_zones = None
    if hand or o.self_close_min_deg is not None:
        try:                                # the hand force and the zones (SPEC §13)
            hand_zones = hand_force(model, p, resolve(cfg))
        except ConfigError:                 # (the linkage does not reach theta_open)
            pass
    if o.self_close_min_deg is not None:    # closes by itself from every angle up to it
        sc = None if hand_zones is None else hand_zones.self_close_deg
        cons["self_close_min_deg"] = {"value": sc, "bound": o.self_close_min_deg,
                                      "unit": "deg",
                                      "ok": sc is not None and sc >= o.self_close_min_deg
                                      - 1e-9}
    agreement = {}
    if claims is not None:
        # the engagement (two phases): its time and speed as the NLP's node between the
        # phases has them, against the reference's located event
        for k in METRIC_KEYS + tuple(k for k in ENGAGE_KEYS if k in claims):
            agreement[k] = agree(k, claims.get(k), getattr(ref, k))
    if claimed_objective is not None:
        agreement["objective"] = agree("objective", claimed_objective, J)
    return Verification(ref, J, cons, agreement, method, time.perf_counter() - t0,
                        hand=hand_zones)


def verify_design(cfg, design: dict, metrics: dict | None = None,
                  objective: float | None = None) -> dict:
    """:func:`verify` as plain JSON values (``Verification.to_json()``, which holds no hand
    force: it is computed only where ``optimise.self_close_min_deg`` needs it)."""
    return verify(cfg, design, metrics, objective, hand=False).to_json()
