"""The scenario NLPs built in this process: one :class:`~softclose.robust.nlp.ScenarioStructure`
per structure (its scenario count, elements, series, discretisation, free variables, bounds
that are structural -- never a lid's numbers), compiled once by ``softclose prepare --robust``
and loaded from the build cache, or built symbolically; and one
:class:`~softclose.robust.nlp.ScenarioNLP` per set of scenario models bound to it.
"""

from __future__ import annotations

from ..config import Config
from ..optimiser import compiled
from ..optimiser.free_points import placement_layout, slot_values
from ..optimiser.interval import free_layout
from ..optimiser.discretisation import phase_substeps, two_phase
from ..problem import held_design
from .nlp import _STRUCTURES, ScenarioNLP, _model_key  # noqa: F401  (_STRUCTURES: the
#                                                              structures, kept in .nlp)

_NLPS: dict = {}


def forget() -> None:
    """Drop the scenario NLPs and structures this process keeps."""
    _NLPS.clear()
    _STRUCTURES.clear()


def get_scenario_nlp(cfg: Config, model_cfgs: list[Config], nodes: int, substeps: int,
                     robust_objective: str, substeps_engaged: int | None = None
                     ) -> tuple[ScenarioNLP, bool]:
    """The ScenarioNLP of these scenario models (cached); (nlp, was it cached).
    ``substeps_engaged``: the engaged phase's sub-steps of a two-phase stroke (default
    :func:`~softclose.optimiser.discretisation.phase_substeps`)."""
    o = cfg.optimise
    M_engaged = (substeps_engaged or phase_substeps(cfg, nodes, substeps)) \
        if two_phase(cfg) else None
    key = (tuple(_model_key(c)
                 for c in model_cfgs), nodes, substeps, M_engaged, robust_objective, o.hessian,
           o.linear_solver, o.max_iter, o.opening_force_max is not None,
           o.self_close_min_deg,
           placement_layout(cfg), free_layout(cfg), tuple(slot_values(cfg)), held_design(cfg))
    if key in _NLPS:
        return _NLPS[key], True
    if len(_NLPS) > 16:
        _NLPS.clear()
    nlp = ScenarioNLP(cfg, model_cfgs, nodes, substeps, robust_objective,
                      substeps_engaged=M_engaged)
    nlp.key = nlp.structure.disk
    _NLPS[key] = nlp
    return nlp, False


def prepare(cfg: Config, model_cfgs: list[Config], nodes: int, substeps: int,
            robust_objective: str, substeps_engaged: int | None = None):
    """Compile this scenario NLP's structure now, in the foreground (a line on stderr says
    what is built), unless it is compiled: the path of its library, or None (no cache, no C
    compiler). ``softclose prepare --robust`` compiles every one a robust design uses."""
    with compiled.compiling():
        nlp, cached = get_scenario_nlp(cfg, model_cfgs, nodes, substeps, robust_objective,
                                       substeps_engaged)
    if nlp.library is None:      # built in this process before: compile it now
        forget()
        with compiled.compiling():
            nlp, _ = get_scenario_nlp(cfg, model_cfgs, nodes, substeps, robust_objective,
                                      substeps_engaged)
    return nlp.library
