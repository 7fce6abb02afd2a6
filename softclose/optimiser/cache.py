"""Models, NLPs and simulators, built once per geometry and reused.

Building the NLP of a geometry takes ~0.2 s and a model ~0.03 s; a solve takes ~0.1 s. So
everything that only depends on the geometry, mass, stroke and discretisation is cached
here, keyed by those values (Config sections are frozen dataclasses, so they hash), and a
new problem -- other bounds, weights, closing-time limits -- reuses it.
"""

from __future__ import annotations

from ..model import LidModel, model_key
from ..simulate import Simulator
from .interval import free_layout, nlp_elements
from .nlp import ShootingNLP

_MODELS: dict = {}
_NLPS: dict = {}


def get_model(cfg) -> LidModel:
    """The LidModel of cfg's geometry, mass and stroke (cached)."""
    key = model_key(cfg)
    if key not in _MODELS:
        _MODELS[key] = LidModel(cfg)
    return _MODELS[key]


def nlp_key(cfg, nodes: int | None = None, substeps: int | None = None) -> tuple:
    o = cfg.optimise
    return model_key(cfg) + (tuple(e.name for e in nlp_elements(cfg)),
                             o.opening_force_max is not None, free_layout(cfg),
                             nodes or o.nodes, substeps or o.substeps, o.hessian,
                             o.linear_solver, o.max_iter)


def has_nlp(cfg, nodes: int | None = None, substeps: int | None = None) -> bool:
    return nlp_key(cfg, nodes, substeps) in _NLPS


def get_nlp(cfg, nodes: int | None = None, substeps: int | None = None) -> ShootingNLP:
    """The ShootingNLP of cfg's geometry and discretisation (built once, then cached)."""
    o = cfg.optimise
    key = nlp_key(cfg, nodes, substeps)
    if key not in _NLPS:
        nlp = ShootingNLP(get_model(cfg), key[-5], key[-4], o.hessian, o.linear_solver,
                          o.max_iter, els=nlp_elements(cfg),
                          opening=o.opening_force_max is not None,
                          free=free_layout(cfg))
        nlp.key = key
        _NLPS[key] = nlp
    return _NLPS[key]


def stroke_simulator(cfg, t_end: float | None = None) -> Simulator:
    """An RK4 simulator (step <= 1 ms, C kernel) of cfg's model, its strokes cut at
    ``t_end`` when that is shorter than stroke.t_max (a sweep of starts needs no more)."""
    c = cfg
    if t_end is not None and t_end < cfg.stroke.t_max:
        c = cfg.replace(stroke={"t_max": float(t_end)})
    step = min(cfg.simulate.step, 1e-3)
    return Simulator(c, model=get_model(cfg), integrator="rk4", step=step)
