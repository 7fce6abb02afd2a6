"""softclose: design soft-closing lids, on a four-bar linkage or a hinge (one pivot).

The public API. Each function takes a :class:`Config` and plain Python values, writes no
file, prints nothing unless ``progress=True``, and returns an immutable result with
``.success``, ``.message``, ``.to_frame()`` (a pandas DataFrame whose columns are the JSON
keys), ``.to_json()`` and ``.plot()`` (a matplotlib Figure):

- :func:`simulate` -- one closing stroke, every metric with its estimated accuracy;
- :func:`optimise` -- the soft-close design (multiple shooting + Ipopt), every reported metric
  verified by an independent adaptive simulation; ``robust=True`` designs for the
  ``[tolerance]`` box;
- :func:`front` -- the verified Pareto front of the objective against ``closing_time_max``;
- :func:`sweep` / :func:`sample` -- metrics over a grid or a quasi-random sample of any
  numeric config keys;
- :func:`tolerance_analysis`, :func:`sensitivity` -- Monte Carlo yield and Sobol indices of a
  design under ``[tolerance]``;
- :func:`select` -- the springs and dampers of catalog files ranked over their own tolerances;
- :func:`fit` -- the model calibrated to measured closing strokes: estimates with 95 %
  intervals, correlations, identifiability, the calibrated config (``softclose.fit``);
- :func:`report` -- the sign-off report of a design: every constraint at the nominal lid, at
  each operating temperature and at the worst tolerance corner, as HTML and PDF
  (``.html()``, ``.save(path)``);
- :func:`load_config`, :func:`default_config`; ``cfg.set("mass.lid", 0.6)`` changes one key.

Lower layers for scripts that need them: :class:`LidModel`, :class:`Simulator`,
:class:`Reference` (each from a config: ``Simulator.from_config(cfg)``; below the features
they take the config resolved once, :func:`resolve`), :mod:`softclose.problem` (design
keys, metrics and units, objective, constraints, accuracy targets). The feature packages
are :mod:`softclose.optimiser`, :mod:`softclose.sweeps`, :mod:`softclose.robust` and
:mod:`softclose.signoff`; they are imported on first use, so ``import softclose`` stays
light.
"""

from importlib import import_module

from .config import Config, default_config, load_config
from .errors import ConfigError, NumericalError, SoftcloseError
from .model.lid import LidModel
from .simulation.reference import Reference
from .problem import resolve
from .simulation.simulator import Simulator
from .simulation.stroke import StrokeResult, StrokeStatus
from .version import __version__  # noqa: F401  (re-exported)

#: public functions and result types of the feature packages, imported on first use
_LAZY = {
    "front": "optimiser", "OptimiseResult": "optimiser",
    "FrontResult": "optimiser",
    "sweep": "sweeps", "sample": "sweeps", "SweepResult": "sweeps",
    "tolerance_analysis": "robust", "sensitivity": "robust", "RobustResult": "robust",
    "YieldResult": "robust", "SensitivityResult": "robust",
    "select": "catalog", "SelectResult": "catalog",
    "fit": "calibration", "FitResult": "calibration",
    "report": "signoff", "ReportResult": "signoff",
}

__all__ = ["simulate", "state", "optimise", "front", "sweep", "sample", "tolerance_analysis",
           "sensitivity", "fit", "FitResult", "load_config", "default_config", "Config", "StrokeResult",
           "StrokeStatus", "OptimiseResult", "FrontResult", "SweepResult", "RobustResult",
           "YieldResult", "SensitivityResult", "select", "SelectResult", "ConfigError",
           "NumericalError", "SoftcloseError", "LidModel", "Reference", "Simulator",
           "report", "ReportResult", "resolve"]


def simulate(cfg: Config, trajectory: bool = False, hand_force: bool = False) -> StrokeResult:
    """One closing stroke of ``cfg``'s design with ``cfg``'s integrator and step.

    Returns a :class:`~softclose.simulation.stroke.StrokeResult`: the metrics, each fixed-step
    one with its estimated distance from the converged answer (``accuracy``), and with
    ``trajectory=True`` the time histories (``.plot()``, ``.trajectory_frame()``; ``.save()``
    writes them and the figures). With ``hand_force=True`` also what ``softclose simulate``
    reports beside them: the hand force and the lid's zones (``.hand_force``), at each
    sign-off temperature of ``operating.temperatures_c`` when it lists several
    (``.hand_forces``), and what the end damper did when it does not engage on the way down
    (``.end_damper``). A stroke the method cannot integrate is reported (``ok`` False,
    ``message`` says what to change), never raised.
    """
    from dataclasses import replace
    sim = Simulator(resolve(cfg), cached=True)
    res = sim.run(trajectory=trajectory)
    if trajectory:
        res = replace(res, model=sim.model)
    if not (hand_force and res.ok):
        return res

    from .problem import at_temperature, sign_off_temperatures
    from .simulation.handforce import hand_force as hand_force_of
    from .simulation.stroke import end_damper_note
    temps = sign_off_temperatures(cfg)
    by_temperature = tuple((T, hand_force_of(sim.model, case=resolve(at_temperature(cfg, T))))
                           for T in temps) if len(temps) > 1 else ()
    d, st = cfg.design, cfg.stroke
    res = replace(res, hand_force=hand_force_of(sim.model, case=sim.case),
                  hand_forces=by_temperature,
                  end_damper=end_damper_note(res, d.end_damper_c, d.end_damper_angle_deg,
                                             st.theta0_deg, st.theta_closed_deg))
    from .problem import at_state, sign_off_states
    if len(sign_off_states(cfg)) == 1:
        return res
    states = []        # the stroke in each state, beside this one (SPEC §17)
    for state in sign_off_states(cfg):
        if state == cfg.life.state:
            states.append((state, res))
            continue
        case = resolve(at_state(cfg, state))
        other = sim.for_case(case).run()
        states.append((state, replace(other, hand_force=hand_force_of(sim.model, case=case))
                       if other.ok else other))
    return replace(res, states=tuple(states))


def state(cfg: Config, theta_deg: float, theta_dot: float = 0.0):
    """The linkage of ``cfg`` at the lid angle ``theta_deg`` (degrees) and rate ``theta_dot``
    (rad/s), on the branch followed from the release: the crank angles and rates (none for a
    hinge lid), theta'' from the equation of motion, the tip velocity and the pin reactions
    (Newton-Euler; a hinge lid's one reaction is the hinge's, ``H``). Returns a
    :class:`~softclose.simulation.state.LinkageState` (``.to_json()``, ``.text()``)."""
    import math

    from .model.life import aged, at_end_of_life, shut_coordinates
    from .simulation.state import linkage_state
    case = resolve(cfg)
    model = LidModel(case)
    p = at_end_of_life(case.p, case.life, shut_coordinates(model)) if aged(case.life) else None
    return linkage_state(model, cfg.stroke.theta0, math.radians(theta_deg), theta_dot, p)


def _model_from_config(cls, cfg: Config, cached: bool = False) -> LidModel:
    """The lid model of ``cfg`` (``cached``: from the disk cache when built before):
    ``LidModel(resolve(cfg))``."""
    return cls.cached(resolve(cfg)) if cached else cls(resolve(cfg))


def _simulator_from_config(cls, cfg: Config, model: LidModel | None = None,
                           integrator: str | None = None, step: float | None = None,
                           cached: bool = False) -> Simulator:
    """The simulator of ``cfg``: ``Simulator(resolve(cfg), ...)``."""
    return cls(resolve(cfg), model, integrator, step, cached)


def _reference_from_config(cls, cfg: Config, model: LidModel | None = None,
                           grid_step: float = 2e-3) -> Reference:
    """The adaptive reference of ``cfg`` (its ``simulate.reference_tol``; its strokes judged
    by its spring limits, at its temperature), of ``model`` or ``cfg``'s own."""
    case = resolve(cfg)
    return cls(model or LidModel(case), case.solver.reference_tol, grid_step, case)


# the public classes' constructors from a config, defined here, where the config is read
# (below the features nothing takes a config)
LidModel.from_config = classmethod(_model_from_config)
Simulator.from_config = classmethod(_simulator_from_config)
Reference.from_config = classmethod(_reference_from_config)


def optimise(cfg: Config, *, robust: bool = False, progress: bool = False, **options):
    """The soft-close design of ``cfg``, verified: :func:`softclose.optimiser.optimise`
    (``options``: ``starts``, ``verify``, ``nodes``, ``substeps``), or with ``robust=True``
    the design for the ``[tolerance]`` box, :func:`softclose.robust.optimise_robust`."""
    if robust:
        if options:
            raise TypeError(f"optimise(robust=True): no option {', '.join(sorted(options))} "
                            "(the robust design takes its settings from [tolerance])")
        from .robust import optimise_robust
        return optimise_robust(cfg, progress=progress)
    from .optimiser import optimise as nominal
    return nominal(cfg, progress=progress, **options)


def __getattr__(name: str):
    if name in _LAZY:
        value = getattr(import_module(f".{_LAZY[name]}", __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'softclose' has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_LAZY))
