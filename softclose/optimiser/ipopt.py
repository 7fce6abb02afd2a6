"""How the optimisers call Ipopt: the options of a cold solve and of a warm re-solve, and the
checks that an asked-for linear solver can be loaded and that Ipopt took the options."""

from __future__ import annotations

from ..errors import ConfigError
from ..interrupt import ipopt_options

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


def warm_solver(name: str, cold, library, options: dict):
    """The solver of warm starts beside the cold solver ``cold`` (the nominal and the
    scenario NLPs build it on first use): loaded from the compiled ``library`` when there is
    one, else on ``cold``'s oracle, sharing its cached derivatives. ``options``: nlpsol's,
    to which the Ctrl-C iteration callback is added."""
    import casadi as ca
    nx, np_, ng = cold.size1_in(0), cold.size1_in(1), cold.size1_in(5)
    opts = {**options, **ipopt_options(nx, ng, np_)}
    if library is not None:
        return ca.nlpsol(name, "ipopt", str(library), opts)
    x, p = ca.MX.sym("x", nx), ca.MX.sym("p", np_)
    f, g = cold.oracle()(x, p)
    return ca.nlpsol(name, "ipopt", {"x": x, "p": p, "f": f, "g": g}, opts)


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
