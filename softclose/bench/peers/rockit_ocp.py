"""The rockit peer: the default design problem as a user of rockit (``rockit-meco``, CasADi's
optimal-control toolkit) would state it, on softclose's own CasADi model of the lid.

An :class:`rockit.Ocp` with a free end time (the closing time), the states theta and theta',
the design (k, l0, c) and the square of the peak tip speed as static variables (the design
scaled by :data:`softclose.problem.SCALES`), the exact equation of motion
(:attr:`softclose.model.lid.LidModel.ode`), the release from rest, theta = theta_closed at
the end, the closing-time bounds, theta''(release) <= 0, theta' <= 0, theta >= theta_closed
and |v_T|^2 <= peak^2 on the integrator grid, the holding moment at the rim, and J as the
objective. Transcribed by ``MultipleShooting(N, M, intg="rk", expand=True)`` -- the same
grid and integrator as softclose's NLP (``optimise.nodes`` x ``optimise.substeps`` RK4
steps) -- and solved by Ipopt with softclose's options (exact Hessian, MUMPS, tolerance
1e-10, adaptive barrier, no bound relaxation), from the centre of the design box and the
straight line from the release to the rim.

What it does differently from softclose: the tip speed is sampled only at the ends of the
RK4 sub-steps (softclose also bounds the cubic Hermite maximum inside each sub-step, so its
peak is O(h^4)-accurate and its closing-time bound is corrected for the discretisation
error); the equation is the exact closure-based one, expanded to SX in every sub-step
(softclose's NLP evaluates Chebyshev series of the geometry fitted to machine precision, a
quarter of the operations); the NLP is built and differentiated symbolically at each run
and evaluated in CasADi's virtual machine (softclose loads it compiled, built once per
structure); one start (softclose tries six); and a linear spring over the whole box.
"""

from __future__ import annotations

import time

import casadi as ca
import numpy as np

from ... import interrupt
from ...model.lid import LidModel
from ...problem import DESIGN_KEYS, SCALES, params_of, resolve

#: the closing time's floor (s): a free end time needs one above zero
T_FLOOR = 1e-3


def available() -> bool:
    """Is rockit installed (the ``peers`` extra)?"""
    import importlib.util
    return importlib.util.find_spec("rockit") is not None


def solve(cfg, log=None) -> dict:
    """rockit's optimum of ``cfg``'s design problem: {design, objective (its own J),
    iterations (Ipopt's), time (s), status, message}."""
    from rockit import FreeTime, MultipleShooting, Ocp
    log = log or (lambda *a: None)
    t0 = time.perf_counter()
    model = LidModel(resolve(cfg))
    st, o = model.stroke, cfg.optimise
    p_base = params_of(cfg)
    lo, hi = np.array([getattr(o, k) for k in DESIGN_KEYS], float).T   # the design box

    ocp = Ocp(t0=0.0, T=FreeTime(0.5))
    theta, theta_dot = ocp.state(), ocp.state()
    z = ocp.variable(3)                      # the design, scaled
    peak2 = ocp.variable()                   # the peak tip speed, squared (epigraph)
    p = ca.vertcat(z * SCALES, ca.DM(p_base[3:]))
    x = ca.vertcat(theta, theta_dot)
    xdot = model.ode(x, p)
    ocp.set_der(theta, xdot[0])
    ocp.set_der(theta_dot, xdot[1])
    ocp.subject_to(ocp.at_t0(theta) == st.theta0)
    ocp.subject_to(ocp.at_t0(theta_dot) == 0.0)
    ocp.subject_to(ocp.at_tf(theta) == st.theta_closed)
    ocp.subject_to(max(o.closing_time_min, T_FLOOR) <= (ocp.T <= o.closing_time_max))
    ocp.subject_to(lo / SCALES <= (z <= hi / SCALES))
    ocp.subject_to(model.ode(ca.vertcat(st.theta0, 0.0), p)[1] <= 0.0)   # released: down
    ocp.subject_to(model.dV(st.theta_closed, p) >= o.holding_moment_min)
    ocp.subject_to(theta_dot <= 0.0, grid="integrator")
    ocp.subject_to(theta >= st.theta_closed, grid="integrator")
    ocp.subject_to(ca.sumsqr(model.kin(x)[4]) <= peak2, grid="integrator")
    ocp.add_objective(o.weight_impact * ocp.at_tf(theta_dot) ** 2 + o.weight_peak_tip * peak2)
    ocp.set_initial(z, 0.5 * (lo + hi) / SCALES)
    ocp.set_initial(theta, st.theta0 + (st.theta_closed - st.theta0) * ocp.t / 0.5)
    ocp.set_initial(theta_dot, (st.theta_closed - st.theta0) / 0.5)
    ocp.set_initial(peak2, 1.0)
    ocp.method(MultipleShooting(N=o.nodes, M=o.substeps, intg="rk", expand=True))
    iterations = [0]

    def callback(i, _solution):
        iterations[0] = i
        interrupt.check()                   # Ctrl-C noted: Ipopt stops at this iteration

    ocp.callback(callback)
    ocp.solver("ipopt", {"expand": True, "print_time": False,
                         "ipopt.print_level": 0, "ipopt.sb": "yes", "ipopt.tol": 1e-10,
                         "ipopt.max_iter": o.max_iter, "ipopt.hessian_approximation": "exact",
                         "ipopt.linear_solver": "mumps", "ipopt.mu_strategy": "adaptive",
                         "ipopt.bound_relax_factor": 0.0})
    log("  rockit: transcribing and solving ...")
    try:
        # Ctrl-C: raised at once in rockit's Python code, and inside Ipopt in the
        # iteration callback, which ends the solve (CasADi's own building, in C++, ends first)
        sol = ocp.solve()
        status = "converged"
    except RuntimeError as exc:              # Ipopt did not converge: its last iterate
        if interrupt.interrupted():
            raise KeyboardInterrupt from exc
        sol, status = ocp.non_converged_solution, "not converged"
    stats = sol.stats
    zs = np.asarray(sol.value(z), float).ravel() * SCALES
    J = float(sol.value(o.weight_impact * ocp.at_tf(theta_dot) ** 2 + o.weight_peak_tip * peak2))
    return {"design": dict(zip(DESIGN_KEYS, (float(v) for v in zs))), "objective": J,
            "iterations": int(stats.get("iter_count", iterations[0])),
            "time": time.perf_counter() - t0, "status": status,
            "message": str(stats.get("return_status", ""))}


__all__ = ["solve", "available", "T_FLOOR"]
