"""Models, NLPs and simulators, built once per geometry and reused.

Building the NLP of a geometry takes ~0.2 s and a model ~0.03 s; a solve takes ~0.1 s. So
everything that only depends on the geometry, mass, stroke and discretisation is cached
here, keyed by those values (Config sections are frozen dataclasses, so they hash), and a
new problem -- other bounds, weights, closing-time limits -- reuses it.
"""

from __future__ import annotations

from ..model import model_key, shared_model
from ..simulate import Simulator
from .discretise import phase_two_substeps
from .interval import end_damper_mode, free_layout, nlp_elements
from .nlp import ShootingNLP
from .placement import placement_layout

_NLPS: dict = {}
#: the LidModel of cfg's geometry, mass and stroke, kept for the process
#: (:func:`softclose.model.shared_model`)
get_model = shared_model


def nlp_key(cfg, nodes: int | None = None, substeps: int | None = None,
            substeps2: int | None = None) -> tuple:
    """The NLP's structure: the model, the elements it carries, the free variables, the
    discretisation (with an end damper engaging inside the stroke: two phases, phase 2's
    sub-steps ``substeps2``, by default :func:`.nlp.phase_two_substeps`), the solver."""
    o = cfg.optimise
    N, M = nodes or o.nodes, substeps or o.substeps
    M2 = None
    if end_damper_mode(cfg) == "two-phase":
        M2 = int(substeps2 or phase_two_substeps(cfg, N, M))
    return model_key(cfg) + (tuple(e.name for e in nlp_elements(cfg)),
                             o.opening_force_max is not None, free_layout(cfg),
                             placement_layout(cfg), keep_out_of(cfg), M2,
                             N, M, o.hessian, o.linear_solver, o.max_iter)


def keep_out_of(cfg) -> tuple:
    """optimise.keep_out as a tuple of polygons (tuples of (x, y)); empty without one or
    without free attachment points (fixed points are checked, not optimised)."""
    polys = getattr(cfg.optimise, "keep_out", None)
    if not polys or not placement_layout(cfg):
        return ()
    return tuple(tuple(tuple(float(c) for c in v) for v in poly) for poly in polys)


def _phase2(N, M2):
    """Phase 2's (intervals, sub-steps) of a two-phase NLP: N as phase 1, M2 (None: one
    phase)."""
    return None if M2 is None else (N, M2)


def has_nlp(cfg, nodes: int | None = None, substeps: int | None = None,
            substeps2: int | None = None) -> bool:
    return nlp_key(cfg, nodes, substeps, substeps2) in _NLPS


def build_nlp(cfg, nodes: int, substeps: int, substeps2: int | None = None, library=None,
              meta=None) -> ShootingNLP:
    """The ShootingNLP of cfg's geometry and discretisation, built symbolically (or its
    compiled ``library`` loaded, with its ``meta``)."""
    o = cfg.optimise
    return ShootingNLP(get_model(cfg), nodes, substeps, o.hessian, o.linear_solver,
                       o.max_iter, els=nlp_elements(cfg),
                       opening=o.opening_force_max is not None, free=free_layout(cfg),
                       placement=placement_layout(cfg), keep_out=keep_out_of(cfg),
                       phase2=_phase2(nodes, nlp_key(cfg, nodes, substeps, substeps2)[-6]),
                       library=library, meta=meta)


def describe_nlp(cfg, N: int, M: int, M2: int | None) -> str:
    """The NLP in words, for the line a compilation writes on stderr."""
    kind = cfg.design.spring_kind
    return (f"of the optimiser ({kind} spring, {N} x {M} RK4 steps"
            + (f", phase 2 {N} x {M2}" if M2 else "") + ")")


def get_nlp(cfg, nodes: int | None = None, substeps: int | None = None,
            substeps2: int | None = None) -> ShootingNLP:
    """The ShootingNLP of cfg's geometry and discretisation (built once, then cached).

    Its compiled library, when it is in the cache (:mod:`softclose.buildcache`: compiled by
    ``softclose prepare`` or :func:`prepare`), is loaded instead of building it (the solves
    run ~3x faster, same numbers); else it is built symbolically -- and, inside
    :func:`softclose.buildcache.compiling`, compiled now.
    """
    from .. import buildcache
    key = nlp_key(cfg, nodes, substeps, substeps2)
    if key not in _NLPS:
        N, M, M2 = key[-5], key[-4], key[-6]
        disk = buildcache.key_of("nlp", key)

        def make(library=None, meta=None):
            return build_nlp(cfg, N, M, M2, library=library, meta=meta)
        nlp = buildcache.load_or_build(disk, make, make, describe_nlp(cfg, N, M, M2))
        nlp.key = key
        _NLPS[key] = nlp
    return _NLPS[key]


def prepare(cfg, nodes: int | None = None, substeps: int | None = None):
    """Compile cfg's NLP now, in the foreground (seconds; a line on stderr says what is
    built), unless it is compiled: the path of its library, or None (no cache, no C
    compiler). ``softclose prepare`` compiles every NLP a command would use."""
    from .. import buildcache
    key = nlp_key(cfg, nodes, substeps)
    disk = buildcache.key_of("nlp", key)
    lib = buildcache.compiled_nlp(disk)
    if lib is not None or buildcache.folder() is None:
        return lib
    nlp = build_nlp(cfg, key[-5], key[-4], key[-6])
    buildcache.store("nlpmeta", disk, nlp.meta())
    return buildcache.compile_nlp(nlp.solver, disk,
                                  what=describe_nlp(cfg, key[-5], key[-4], key[-6]))


def stroke_simulator(cfg, t_end: float | None = None) -> Simulator:
    """An RK4 simulator (step <= 1 ms, C kernel) of cfg's model, its strokes cut at
    ``t_end`` when that is shorter than stroke.t_max (a sweep of starts needs no more)."""
    c = cfg
    if t_end is not None and t_end < cfg.stroke.t_max:
        c = cfg.replace(stroke={"t_max": float(t_end)})
    step = min(cfg.simulate.step, 1e-3)
    return Simulator(c, model=get_model(cfg), integrator="rk4", step=step, cached=True)
