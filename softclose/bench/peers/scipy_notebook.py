"""The scipy notebook: the default design problem as a student would write it with scipy.

Single shooting. Each evaluation integrates the closing stroke with
``scipy.integrate.solve_ivp`` (DOP853, rtol 1e-10, atol 1e-12) on softclose's reduced
equation of motion (:attr:`softclose.model.lid.LidModel.ode`, the exact equation, called
from Python), stops it at the rim with a terminal event (theta = theta_closed moving down:
the closing time and impact speed to the integrator's accuracy) and reads the peak tip speed
and the largest theta' after the release from the dense output on a 400-point grid, the
peak refined by a bounded scalar search around the grid's maximum. ``scipy.optimize.minimize``
(SLSQP) then minimises J (divided by the start's J: order one) over (k, l0, c) scaled to
order one (by :data:`softclose.problem.SCALES`), in the design box, with the closing-time
bounds, no rebound (max theta' <= 0) and the holding moment as inequality constraints, its
gradients by forward differences (step 1e-6 of the scaled variables: well above the
integrator's noise), from the best feasible design of a 3 x 3 x 3 grid of the box (SLSQP
started where the lid does not close finds no gradient of the closing time and stays
infeasible). One stroke's results are kept per design, so the objective and the constraints
at one point cost one integration. (``method="trust-constr"`` is the other choice a user
has; on this problem it needs more iterations than SLSQP.)

What it does differently from softclose: one start (softclose tries six and keeps the best);
an adaptive integration per evaluation and four per gradient, where softclose's multiple
shooting NLP carries the stroke as variables with exact derivatives (so the closing time's
steep dependence on the design near a lid that nearly stalls is a constraint on states, not
on a shooting function); the stroke's constraints read on a grid of the dense output
(softclose imposes them at every RK4 sub-step and the Hermite maxima between); a linear
spring over the whole box (softclose's default also asks the spring to be one that can be
bought, a compression or an extension spring, one problem each).
"""

from __future__ import annotations

import itertools
import math
import time

import casadi as ca
import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import BFGS, Bounds, NonlinearConstraint, minimize, minimize_scalar

from ... import interrupt
from ...problem import DESIGN_KEYS, SCALES, objective, params_of, resolve
from ...model.lid import LidModel

#: solve_ivp's method and tolerances (tight: the forward differences need a smooth J)
METHOD, RTOL, ATOL = "DOP853", 1e-10, 1e-12
#: the forward-difference step of the scaled design (order one)
FD_STEP = 1e-6
#: points of the dense-output grid the peak tip speed and the largest theta' are read on
GRID = 400
#: the optimiser's iteration limit
MAX_ITER = 200


def stroke_functions(model):
    """(rhs(x, p) -> x', speed(x) -> |v_T|) of softclose's CasADi model, as numpy callables."""
    x, p = ca.SX.sym("x", 2), ca.SX.sym("p", model.ode.size1_in(1))
    rhs = ca.Function("rhs", [x, p], [model.ode(x, p)])
    speed = ca.Function("speed", [x], [ca.norm_2(model.kin(x)[4])])
    return rhs, speed


def start(lo, hi, at, J, o, log):
    """The start: the best feasible design of a 3 x 3 x 3 grid of the (scaled) box's cell
    centres (the box's centre if none is feasible)."""
    levels = [lo + (hi - lo) * f for f in (1 / 6, 1 / 2, 5 / 6)]
    best, best_J = 0.5 * (lo + hi), math.inf
    for z in itertools.product(*zip(*levels)):
        z = np.array(z)
        s = at(z)
        ok = (s["closed"] and o.closing_time_min <= s["T"] <= o.closing_time_max
              and s["thd_max"] <= 0.0 and s["hold"] >= o.holding_moment_min)
        if ok and J(z) < best_J:
            best, best_J = z, J(z)
    log(f"  scipy: start from the grid's best feasible design, J {best_J:.7g}")
    return best


def solve(cfg, log=None, method: str = "SLSQP") -> dict:
    """The notebook's optimum of ``cfg``'s design problem: {design, objective (its own J),
    iterations (SLSQP's), evaluations (strokes integrated), time (s), status, message}."""
    log = log or (lambda *a: None)
    t0 = time.perf_counter()
    case = resolve(cfg)
    model = LidModel(case)
    st, o = model.stroke, cfg.optimise
    rhs, speed = stroke_functions(model)
    p_base = params_of(cfg)
    lo, hi = np.array([getattr(o, k) for k in DESIGN_KEYS], float).T   # the design box
    evaluations = [0]

    def params(z):
        p = p_base.copy()
        p[:3] = z * SCALES
        return p

    def stroke(z):
        interrupt.check()
        evaluations[0] += 1
        p = params(z)

        def f(t, y):
            return np.asarray(rhs(y, p)).ravel()

        def closed(t, y):
            return y[0] - st.theta_closed
        closed.terminal, closed.direction = True, -1
        sol = solve_ivp(f, (0.0, st.t_max), [st.theta0, 0.0], method=METHOD, rtol=RTOL,
                        atol=ATOL, events=closed, dense_output=True)
        if sol.t_events[0].size:
            T, impact = float(sol.t_events[0][0]), float(sol.y_events[0][0][1])
        else:
            T, impact = float(sol.t[-1]), float(sol.y[1, -1])
        tt = np.linspace(0.0, T, GRID + 1)[1:]    # (at the release theta' = 0)
        Y = sol.sol(tt)
        v = np.asarray(speed.map(GRID)(Y)).ravel()
        i = int(np.argmax(v))
        peak = float(v[i])
        if 0 < i < GRID - 1:        # refine the peak between the grid's neighbours
            r = minimize_scalar(lambda t: -float(speed(sol.sol(t))),
                                bounds=(tt[i - 1], tt[i + 1]), method="bounded",
                                options={"xatol": 1e-12})
            peak = max(peak, -float(r.fun))
        return {"closed": bool(sol.t_events[0].size), "T": T, "impact": impact, "peak": peak,
                "thd_max": float(Y[1].max()), "hold": float(model.dV(st.theta_closed, p))}

    cache: dict = {}       # one stroke per design: J and the constraints read it

    def at(z):
        key = tuple(np.round(z, 15))
        if key not in cache:
            cache[key] = stroke(np.asarray(z, float))
        return cache[key]

    def J(z):
        s = at(z)
        return objective(o, s["impact"], s["peak"])

    def g(z):             # the constraints, each >= 0
        s = at(z)
        return np.array([o.closing_time_max - s["T"], s["T"] - o.closing_time_min,
                         -s["thd_max"], s["hold"] - o.holding_moment_min])

    z0 = start(lo / SCALES, hi / SCALES, at, J, o, log)
    J0 = J(z0)            # J scaled by the start's: order one (BFGS starts from the identity)
    iterations = [0]

    def callback(z, *_):
        iterations[0] += 1
        log(f"  scipy {method} iteration {iterations[0]}: J {J(z):.7g}")

    box = list(zip(lo / SCALES, hi / SCALES))
    if method == "SLSQP":
        r = minimize(lambda z: J(z) / J0, z0, method="SLSQP", bounds=box,
                     constraints=[{"type": "ineq", "fun": g}], callback=callback,
                     options={"ftol": 1e-10, "eps": FD_STEP, "maxiter": MAX_ITER})
    else:
        con = NonlinearConstraint(g, 0.0, np.inf, jac="2-point", hess=BFGS(),
                                  finite_diff_rel_step=FD_STEP)
        r = minimize(lambda z: J(z) / J0, z0, method="trust-constr", jac="2-point",
                     hess=BFGS(), bounds=Bounds(*zip(*box)), constraints=[con],
                     callback=callback,
                     options={"xtol": 1e-10, "gtol": 1e-8, "maxiter": MAX_ITER,
                              "finite_diff_rel_step": FD_STEP})
    design = dict(zip(DESIGN_KEYS, (float(v) for v in r.x * SCALES)))
    return {"design": design, "objective": float(J(r.x)), "iterations": int(r.nit),
            "evaluations": evaluations[0], "time": time.perf_counter() - t0,
            "status": "converged" if r.success else "not converged", "message": str(r.message)}


__all__ = ["solve", "stroke_functions", "METHOD", "RTOL", "ATOL", "FD_STEP", "GRID"]
