"""The one place softclose calls Ipopt: :func:`ipopt_solver` makes every solver (the nominal, the
scenario and the calibration NLP's, cold and warm), :func:`run` solves once and returns a
:class:`~.run.Run`; the options of a cold solve and of a warm re-solve, and the checks that
an asked-for linear solver can be loaded and that Ipopt took the options."""

from __future__ import annotations

import math
import time

import numpy as np

from ..errors import ConfigError
from ..interrupt import ipopt_options, solving
from .run import Run

#: Ipopt options of the cold solver and of the warm re-solve (same NLP functions)
COLD_OPTIONS = {"ipopt.mu_strategy": "adaptive"}
#: the KKT systems of this small NLP (25 variables, ~160 constraints by default) are well
#: scaled by the NLP's own scaling: no scaling of the linear systems and no residual check of
#: each step (the same iterations and optimum on the default problem, to 1e-12; Ipopt's own
#: work per iteration -16 %)
LINEAR_ALGEBRA = {"ipopt.linear_system_scaling": "none", "ipopt.fast_step_computation": "yes"}
MUMPS_OPTIONS = {"ipopt.mumps_permuting_scaling": 0, "ipopt.mumps_scaling": 0}
WARM_OPTIONS = {"ipopt.warm_start_init_point": "yes", "ipopt.mu_init": 1e-8,
                "ipopt.warm_start_bound_push": 1e-9, "ipopt.warm_start_mult_bound_push": 1e-9,
                "ipopt.warm_start_slack_bound_push": 1e-9}


def shooting_options(tol: float, max_iter: int, hessian: str, linear_solver: str,
                     calc_lam_p: bool = False) -> dict:
    """The nlpsol options of a shooting NLP (the nominal and the scenario NLP): silent, the
    config's tolerance, iterations, Hessian and linear solver, and constraints that hold
    exactly at the answer (no bound relaxation), not to 1e-8."""
    return {"print_time": False, "show_eval_warnings": False, "calc_lam_p": calc_lam_p,
            "ipopt.print_level": 0, "ipopt.sb": "yes", "ipopt.tol": tol,
            "ipopt.max_iter": max_iter, "ipopt.hessian_approximation": hessian,
            "ipopt.linear_solver": linear_solver, "ipopt.bound_relax_factor": 0.0}


#: Ipopt return statuses that count as converged
CONVERGED = ("Solve_Succeeded", "Solved_To_Acceptable_Level")


def ipopt_solver(name: str, problem, options: dict, nx: int, ng: int, np_: int):
    """An Ipopt solver of ``problem``: a dict {x, p, f, g} of CasADi expressions (CasADi's
    virtual machine evaluates it) or the path of its compiled library
    (:mod:`softclose.buildcache`). ``options``: nlpsol's, to which the Ctrl-C iteration
    callback of an NLP of ``nx`` variables, ``ng`` constraints and ``np_`` parameters is
    added (:func:`softclose.interrupt.ipopt_options`)."""
    import casadi as ca
    return ca.nlpsol(name, "ipopt", problem if isinstance(problem, dict) else str(problem),
                     {**options, **ipopt_options(nx, ng, np_)})


def run(solver, x0, p, lbx, ubx, lbg, ubg, lam_x0=None, lam_g0=None, origin: str = "",
        violations=None) -> Run:
    """One Ipopt run of ``solver`` from ``x0`` (and the multipliers ``lam_x0``, ``lam_g0``
    of a warm start); never raises (an evaluation error is a failed status, f NaN, g NaN).
    ``violations(g, lbg, ubg)`` gives the run's :attr:`Run.violations`."""
    args = dict(x0=x0, p=p, lbx=lbx, ubx=ubx, lbg=lbg, ubg=ubg)
    if lam_x0 is not None:
        args.update(lam_x0=lam_x0, lam_g0=lam_g0)
    bounds = (lbx, ubx, lbg, ubg)
    p = np.asarray(p, float)
    t0 = time.perf_counter()
    try:
        with solving():      # Ctrl-C: Ipopt stops, KeyboardInterrupt raised after it
            sol = solver(**args)
        st = solver.stats()
        status, ok, its = st["return_status"], bool(st["success"]), int(st["iter_count"])
    except RuntimeError as exc:  # an evaluation error before Ipopt could report
        g = np.full(np.size(lbg) if np.ndim(lbg) else solver.size1_in(5), np.nan)
        return Run(np.asarray(x0, float), math.nan, g, None, None,
                   f"Error: {str(exc).splitlines()[0]}", False, 0, time.perf_counter() - t0,
                   p, bounds, origin, [] if violations is None else violations(g, lbg, ubg))
    if status.startswith("Invalid") or its < 0:
        its = 0                       # Ipopt stopped before its first iteration
    g = np.asarray(sol["g"]).ravel()
    return Run(np.asarray(sol["x"]).ravel(), float(sol["f"]), g,
               np.asarray(sol["lam_x"]).ravel(), np.asarray(sol["lam_g"]).ravel(),
               status, ok and status in CONVERGED, its, time.perf_counter() - t0, p, bounds,
               origin, [] if violations is None else violations(g, lbg, ubg),
               np.asarray(sol["lam_p"]).ravel())


def warm_solver(name: str, cold, library, options: dict):
    """The solver of warm starts beside the cold solver ``cold`` (the nominal and the
    scenario NLPs build it on first use): loaded from the compiled ``library`` when there is
    one, else on ``cold``'s oracle, sharing its cached derivatives. ``options``: nlpsol's,
    to which the Ctrl-C iteration callback is added."""
    import casadi as ca
    nx, np_, ng = cold.size1_in(0), cold.size1_in(1), cold.size1_in(5)
    if library is not None:
        return ipopt_solver(name, library, options, nx, ng, np_)
    x, p = ca.MX.sym("x", nx), ca.MX.sym("p", np_)
    f, g = cold.oracle()(x, p)
    return ipopt_solver(name, {"x": x, "p": p, "f": f, "g": g}, options, nx, ng, np_)


def check_linear_solver(name: str) -> None:
    """ConfigError unless Ipopt can load the linear solver ``name``.

    MUMPS ships with CasADi's Ipopt. The HSL solvers (ma27, ma57, ma86, ma97) live in a
    separate library (``libhsl``/``libcoinhsl``) that Ipopt loads at run time; asking for one
    that is not installed must be refused here, before Ipopt is called: a failed load of
    ma86/ma97 leaves Ipopt in a state that crashes the process at exit.
    """
    if name == "mumps":
        return
    import ctypes
    import ctypes.util
    for lib in ("hsl", "coinhsl"):
        for candidate in filter(None, (ctypes.util.find_library(lib), f"lib{lib}.so")):
            try:
                ctypes.CDLL(candidate)
                return
            except OSError:
                continue
    raise ConfigError(f"optimise.linear_solver: \"{name}\" needs the HSL library (libhsl or "
                      "libcoinhsl), which is not installed here; use \"mumps\"")


def check_options(run, cfg) -> None:
    """ConfigError when Ipopt refused an option of cfg (e.g. a linear solver that this Ipopt
    build does not have)."""
    if run.status == "Invalid_Option":
        o = cfg.optimise
        raise ConfigError(f"optimise.linear_solver: Ipopt refused its options (status "
                          f"Invalid_Option); \"{o.linear_solver}\" is probably not in this Ipopt "
                          "build: use \"mumps\"")
