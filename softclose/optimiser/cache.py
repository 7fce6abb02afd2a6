"""Models, NLPs and simulators, built once and reused.

An NLP is built once per structure (:func:`nlp_key`: its elements, free variables,
discretisation -- never the lid's numbers) and bound to a lid by its numbers
(:class:`softclose.optimiser.nlp.ShootingNLP`); models and their Chebyshev fits are kept per
geometry, mass and stroke. A new problem -- other bounds, weights, closing-time limits,
another lid of the same structure -- builds nothing.
"""

from __future__ import annotations

from ..model import elements
from ..model.lid import model_key, shared_model
from ..simulation.simulator import Simulator
from .discretisation import engaged_substeps
from .interval import (ChebyshevFit, end_damper_mode, free_layout, gas_nlp, map_threads,
                       nlp_elements)
from .parameters import padded_degree
from .nlp import ShootingNLP, ShootingStructure
from .free_points import placement_layout, slot_values
from . import compiled
from ..problem import resolve

_NLPS: dict = {}
#: the NLP structures built in this process, by :func:`nlp_key`
_STRUCTURES: dict = {}
#: the lids' Chebyshev fits, by model and elements (at most FITS_KEPT: a sweep over lids
#: would otherwise keep one per point)
_FITS: dict = {}
FITS_KEPT = 32


def get_model(cfg):
    """The LidModel of cfg's geometry, mass and stroke, kept for the process
    (:func:`softclose.model.lid.shared_model` of the config resolved)."""
    return shared_model(resolve(cfg))


def lid_fit(cfg) -> ChebyshevFit:
    """The Chebyshev fit of cfg's model for its NLP (the elements it carries, the closure's
    series with free attachment points), kept for the process."""
    els = nlp_elements(cfg)
    pose, gas = bool(placement_layout(cfg)), gas_nlp(cfg)
    key = model_key(resolve(cfg)) + (tuple(e.name for e in els), pose, gas)
    if key not in _FITS:
        if len(_FITS) >= FITS_KEPT:
            _FITS.pop(next(iter(_FITS)))          # the oldest
        _FITS[key] = kept_fit(get_model(cfg), els, pose, gas)
    return _FITS[key]


def kept_fit(model, els, pose: bool, gas: bool) -> ChebyshevFit:
    """``ChebyshevFit(model, ...)``, its numbers kept in the disk cache beside the model's
    (:mod:`softclose.buildcache`; keyed by the model's key and the series, as the model is:
    the geometry's, never a design's) and read back from there: fitting costs ~30 ms of a
    command's start, reading its numbers well under one."""
    from .. import buildcache
    key = getattr(model, "cache_key", None)          # (a model loaded or stored: cached)
    if key is None:
        return ChebyshevFit(model, els=els, pose=pose, gas=gas)
    disk = buildcache.key_of("fit", key, tuple(e.name for e in els), pose, gas)
    entry = buildcache.load("fit", disk)
    if entry is not None:
        try:
            return ChebyshevFit.restore(entry, els)
        except (KeyError, TypeError, ValueError):      # a foreign or damaged entry
            pass
    fit = ChebyshevFit(model, els=els, pose=pose, gas=gas)
    buildcache.store("fit", disk, fit.state())
    return fit


def nlp_key(cfg, nodes: int | None = None, substeps: int | None = None,
            substeps_engaged: int | None = None) -> tuple:
    """The NLP's structure, and nothing of the lid's numbers: the elements it carries and
    the series' padded degree, the free variables and points (which), the opening bound,
    the self-close constraint (whether; its angle is a parameter), the keep-out regions, the
    discretisation (with an end damper engaging inside the stroke: two phases, the engaged
    phase's sub-steps ``substeps_engaged``, by default
    :func:`~softclose.optimiser.discretisation.engaged_substeps`), the solver."""
    o = cfg.optimise
    N, M = nodes or o.nodes, substeps or o.substeps
    M_engaged = None
    if end_damper_mode(cfg) == "two-phase":
        M_engaged = int(substeps_engaged or engaged_substeps(cfg, N, M))
    fit = lid_fit(cfg)
    return (tuple(e.name for e in fit.elements), fit.names, padded_degree(fit.degree),
            o.opening_force_max is not None, o.self_close_min_deg is not None, coil_nlp(cfg),
            tuple((k, col) for k, col, _ in free_layout(cfg)),
            tuple((k, slot) for k, slot, _ in placement_layout(cfg)), keep_out_of(cfg), M_engaged,
            N, M, o.hessian, o.linear_solver, o.max_iter)


def coil_nlp(cfg) -> bool:
    """Does cfg's NLP carry its compression spring made to order (``spring.material`` given,
    the geometry not; the kind a compression spring; its points fixed)? Its wire, coil
    diameter and coils are then variables of the NLP (:mod:`.coil_nlp`)."""
    from .coil_nlp import made_to_order
    return (made_to_order(cfg) and cfg.design.spring_kind == "compression"
            and not placement_layout(cfg))


def keep_out_of(cfg) -> tuple:
    """optimise.keep_out as a tuple of polygons (tuples of (x, y)); empty without one or
    without free attachment points (fixed points are checked, not optimised)."""
    polys = getattr(cfg.optimise, "keep_out", None)
    if not polys or not placement_layout(cfg):
        return ()
    return tuple(tuple(tuple(float(c) for c in v) for v in poly) for poly in polys)


def has_nlp(cfg, nodes: int | None = None, substeps: int | None = None,
            substeps_engaged: int | None = None) -> bool:
    return nlp_key(cfg, nodes, substeps, substeps_engaged) in _STRUCTURES


def build_structure(key: tuple, library=None, meta=None, threads: int = 1
                    ) -> ShootingStructure:
    """The ShootingStructure of a :func:`nlp_key`, built symbolically (or its compiled
    ``library`` loaded, with its ``meta``); ``threads``: those of its interval maps."""
    els, names, degree, opening, self_close, coil, free, place, keep_out, M_engaged, N, M, hess, \
        lin, it = key
    return ShootingStructure(tuple(elements.BY_NAME[e] for e in els), names, degree, N, M,
                             None if M_engaged is None else (N, M_engaged), free, place, opening,
                             keep_out, hess, lin, it, library=library, meta=meta,
                             self_close=self_close, coil=coil, threads=threads)


def get_structure(key: tuple, what: str = "") -> ShootingStructure:
    """The ShootingStructure of ``key`` (built once, then kept): its compiled library when
    one is in the cache (:mod:`softclose.buildcache`, compiled by ``softclose prepare``),
    else built symbolically for CasADi's virtual machine -- and, inside
    :func:`softclose.optimiser.compiled.compiling`, compiled now (``what`` names it)."""
    def load(library, meta):
        return build_structure(key, library=library, meta=meta)

    def build():    # threads for the virtual machine; C maps serially (interval.mapped)
        return build_structure(key, threads=1 if compiled.will_compile() else map_threads())
    return compiled.kept_structure(_STRUCTURES, key, "nlp", load, build, what)


def build_nlp(cfg, nodes: int, substeps: int, substeps_engaged: int | None = None) -> ShootingNLP:
    """The ShootingNLP of cfg's lid and discretisation, its structure built symbolically
    now (not the shared one)."""
    key = nlp_key(cfg, nodes, substeps, substeps_engaged)
    return _bind(cfg, build_structure(key))


def _bind(cfg, structure) -> ShootingNLP:
    nlp = ShootingNLP(get_model(cfg), structure, lid_fit(cfg), free=free_layout(cfg),
                      placement=placement_layout(cfg))
    if structure.coil:
        nlp.coil_params(cfg)
    return nlp


def describe_nlp(cfg, N: int, M: int, M_engaged: int | None) -> str:
    """The NLP's structure in words, for the line a compilation writes on stderr (one
    structure serves every lid and spring kind)."""
    free = [k for k, _, _ in free_layout(cfg) + placement_layout(cfg)]
    return (f"of the optimiser ({', '.join(e.name for e in nlp_elements(cfg))}"
            + ("; the spring's wire, coil diameter and coils" if coil_nlp(cfg) else "") + "; "
            f"{N} x {M} RK4 steps" + (f", phase 2 {N} x {M_engaged}" if M_engaged else "")
            + (f"; free {', '.join(free)}" if free else "") + ")")


def get_nlp(cfg, nodes: int | None = None, substeps: int | None = None,
            substeps_engaged: int | None = None) -> ShootingNLP:
    """The ShootingNLP of cfg's lid and discretisation: the structure's NLP (built once per
    structure, :func:`get_structure`) bound to the lid's numbers (kept per lid)."""
    key = nlp_key(cfg, nodes, substeps, substeps_engaged)
    lid = (key, model_key(resolve(cfg)), free_layout(cfg), placement_layout(cfg),
           tuple(slot_values(cfg)))
    if lid not in _NLPS:
        nlp = _bind(cfg, get_structure(key, describe_nlp(cfg, key[-5], key[-4], key[-6])))
        nlp.key = lid
        _NLPS[lid] = nlp
    return _NLPS[lid]


def prepare(cfg, nodes: int | None = None, substeps: int | None = None):
    """Compile cfg's NLP structure now, in the foreground (seconds; a line on stderr says
    what is built), unless it is compiled: the path of its library, or None (no cache, no C
    compiler). ``softclose prepare`` compiles every NLP a command would use."""
    from .. import buildcache
    key = nlp_key(cfg, nodes, substeps)
    disk = buildcache.key_of("nlp", key)
    lib = compiled.compiled_nlp(disk)
    if lib is not None or buildcache.folder() is None:
        return lib
    st = build_structure(key)
    buildcache.store("nlpmeta", disk, st.meta())
    return compiled.compile_nlp(st.solver, disk,
                                  what=describe_nlp(cfg, key[-5], key[-4], key[-6]))


def stroke_simulator(cfg, t_end: float | None = None) -> Simulator:
    """An RK4 simulator (step <= 1 ms, C kernel) of cfg's model, its strokes cut at
    ``t_end`` when that is shorter than stroke.t_max (a sweep of starts needs no more)."""
    c = cfg
    if t_end is not None and t_end < cfg.stroke.t_max:
        c = cfg.replace(stroke={"t_max": float(t_end)})
    step = min(cfg.simulate.step, 1e-3)
    return Simulator(resolve(c), model=get_model(cfg), integrator="rk4", step=step, cached=True)


def forget() -> None:
    """Drop the NLPs, structures and fits this process keeps (tests; a long session)."""
    _NLPS.clear()
    _STRUCTURES.clear()
    _FITS.clear()
