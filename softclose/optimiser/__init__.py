"""The soft-close design problem (:mod:`softclose.problem`) by direct multiple shooting and
Ipopt, every answer verified by the independent adaptive reference.

- :func:`optimise` -- multistart, polish, verification, active limits -> :class:`OptimiseResult`;
- :func:`front` -- the verified optima over a series of closing_time_max -> :class:`FrontResult`;
- :func:`solve` -- one Ipopt solve, cold or warm (benchmarks, continuation).

Modules: :mod:`.interval` (the equation of motion as the NLP sees it: Chebyshev series of
the geometry, one shooting interval, the Hermite peak bound, the elements and free design
variables the NLP carries), :mod:`.nlp` (the NLP and its discretisation), :mod:`.kinds` (the
spring kinds), :mod:`.cache` (models and NLPs built once), :mod:`.starts` (starts from a
coarse sweep, initial guesses), :mod:`.polish` (sub-step refinement, closing-time
correction), :mod:`.verify` (the adaptive reference's verdict), :mod:`.diagnose` (why a
problem is infeasible), :mod:`.result` (result types), :mod:`.optimiser`, :mod:`.pareto`,
:mod:`.placement` (attachment points as design variables: the lengths as expressions of the
points on the fitted closure, the spring kind's validity over the stroke) and
:mod:`.keep_out` (regions the spring and dashpot lines must not cross).
See docs/optimise.md.
"""

from ..problem import DESIGN_KEYS, METRIC_KEYS, SCALES
from .cache import get_model, get_nlp
from .discretisation import H_MAX, MAX_STEPS, Discretisation, discretisation
from .interval import ChebyshevFit, hermite_max, interval_function
from .ipopt import CONVERGED
from .nlp import Run, ShootingNLP
from .optimiser import active_set, claims, optimise, solve
from .pareto import continue_from, front
from .result import Active, FrontResult, OptimiseResult
from .starts import initial_guess, sweep_starts
from .verify import Verification, verify, verify_design

__all__ = ["optimise", "front", "solve", "OptimiseResult", "FrontResult", "Active",
           "Verification", "verify", "verify_design", "get_nlp", "get_model", "ShootingNLP",
           "ChebyshevFit", "Discretisation", "discretisation", "Run", "hermite_max",
           "interval_function", "continue_from",
           "sweep_starts", "initial_guess", "claims", "active_set", "DESIGN_KEYS",
           "METRIC_KEYS", "SCALES", "CONVERGED", "H_MAX", "MAX_STEPS"]
