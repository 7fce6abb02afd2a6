"""The soft-close design problem, stated once: what is designed, what is measured, what is
asked of a design, and how accurately each number must be known.

Every feature reads this module -- the optimiser, sweeps, verification, robust design, the
benchmark -- and none restates it.

- **Design** (:data:`DESIGN_KEYS`): the spring stiffness, its rest length and the damper;
  the stroke kernels take them, with every other element's per-stroke values, as one
  parameter vector ``p = (k, l0, c, c_rot, ...)`` (:data:`PARAM_KEYS`, stated by the element
  registry, :data:`softclose.model.elements.PARAMS`; :func:`params_of`).
- **Metrics** (:data:`METRICS`): the quantities of one closing stroke, with units.
- **Objective**: ``J = weight_impact · impact_theta_dot² + weight_peak_tip · peak_tip_speed²``
  (:func:`objective`).
- **Constraints** (:data:`CONSTRAINTS`): the lid closes, ``closing_time_min <= closing_time
  <= closing_time_max``, no rebound (theta' <= 0 throughout; theta >= theta_closed),
  ``holding_moment >= holding_moment_min``. A design that breaks one is infeasible for the
  first of :data:`REASONS` that applies (:func:`infeasibility`).
- **Accuracy targets** (:data:`TARGETS`): how close to the converged answer a fixed-step
  number must be (absolute, or relative for :data:`RELATIVE`), and how closely the optimiser's
  own numbers must agree with the independent reference (:data:`VERIFY_RTOL`,
  :func:`agreement_tolerance`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .errors import ConfigError
from .config.free import config_value
from .config.load import STEP_BUDGET, TRAJECTORY_BUDGET
from .config.schema import KEYS, RANGES
from .model import elements
from .model.elements import ELEMENTS, PARAM_NAMES, PARAMS
from .model.elements import PARAM_DEFAULTS, as_params  # noqa: F401  (re-exported: their home is the element registry)
from .model.resolved import (Lid, LidCase, Life, Mounting, SolverSettings, StrokeEnds,
                             Temperatures)

#: the design variables the optimiser picks (config section [design], bounds in [optimise])
DESIGN_KEYS = ("spring_k", "spring_rest_length", "damper_c")
#: the stroke kernels' parameter vector p, in order (the element registry's)
PARAM_KEYS = PARAM_NAMES
assert PARAM_KEYS[:len(DESIGN_KEYS)] == DESIGN_KEYS
#: the default closing times of a Pareto front (``softclose pareto``): START:STOP:COUNT[:log],
#: the ends as multiples of optimise.closing_time_max
#: (:func:`softclose.optimiser.pareto.default_closing_times`)
PARETO_DEFAULT = "0.3:3:10:log"

#: config keys of the parameter vector p = (k, l0, c, c_rot), by column
PARAM_COLUMNS = {q.key: i for i, q in enumerate(PARAMS)}
#: the parameters whose config value is a word (a spring's kind, a one-way flag), by config
#: key: p holds each word's number (:attr:`Param.codes`); a sweep takes the words and its
#: tables show them
WORD_PARAMS = {q.key: q for q in PARAMS if q.codes is not None}
#: a word key that is not a parameter of p but a state of the stroke (SPEC §17): a sweep takes
#: its words too, and sets it in the config of each of its values
WORD_PARAMS["life.state"] = elements.Param("state", codes={"new": 0.0, "end_of_life": 1.0},
                                           config_key="life.state")


def word_text(key: str, number: float) -> str:
    """The word a coded parameter's number stands for, as a config file writes it."""
    w = WORD_PARAMS[key].word(float(number))
    return str(w).lower() if isinstance(w, bool) else str(w)


def word_code(key: str, word) -> float:
    """The number p holds for a word (or a TOML boolean) of a coded parameter; ValueError
    naming the words it takes."""
    q = WORD_PARAMS[key]
    for w, c in q.codes.items():
        if word == w or (isinstance(word, str) and word.strip().lower() == str(w).lower()):
            return float(c)
    raise ValueError(f"{key} takes {', '.join(word_text(key, c) for c in q.codes.values())}, "
                     f"got {word!r}")


#: the limits the simulation's advice names, from the config's key records: the smallest
#: admissible and the default ``simulate.step`` (s); the work budgets (``STEP_BUDGET``,
#: ``TRAJECTORY_BUDGET``) and the admissible ranges (``RANGES``) are the config's own
MIN_STEP = RANGES["simulate.step"][0]
DEFAULT_STEP = next(k.default for k in KEYS if k.full == "simulate.step")
#: the adaptive reference's default tolerance (``simulate.reference_tol``)
REFERENCE_TOL = next(k.default for k in KEYS if k.full == "simulate.reference_tol")
assert STEP_BUDGET and TRAJECTORY_BUDGET       # (re-exported for the simulation)

#: the config key the kernels also take per stroke, beside p (their lid-mass column: the
#: tabulated coefficients are affine in the lid mass)
LID_MASS = "mass.lid"
#: scale of each design variable in the NLP, so that the scaled values are of order one
SCALES = np.array([1000.0, 0.1, 1000.0])


@dataclass(frozen=True)
class Metric:
    """One quantity of a closing stroke."""

    key: str
    unit: str
    description: str


#: the metrics of one closing stroke, in the order every table and JSON object uses
METRICS = (
    Metric("closed", "", "the lid reached theta_closed moving down within t_max"),
    Metric("closing_time", "s", "time of the closing event"),
    Metric("impact_theta_dot", "rad/s", "theta' at the closing event (negative)"),
    Metric("impact_tip_speed", "m/s", "lid tip speed at the closing event"),
    Metric("peak_tip_speed", "m/s", "largest tip speed over the stroke"),
    Metric("min_spring_length", "m", "shortest spring length over the stroke"),
    Metric("max_spring_length", "m", "longest spring length over the stroke"),
    Metric("holding_moment", "N m", "dV/dtheta at theta_closed (> 0 presses the lid shut)"),
    Metric("opening_force", "N", "largest hand force at the tip, along its path, that lifts "
           "the lid slowly from closed to theta0"),
)
METRIC_KEYS = tuple(m.key for m in METRICS)
#: with an end damper that engages inside the stroke (``design.end_damper_c`` > 0 below
#: ``design.end_damper_angle_deg``): when the lid first reaches its angle and how fast
#: (:class:`softclose.simulation.stroke.StrokeResult`; the two-phase NLP's node between its phases)
ENGAGE_METRICS = (
    Metric("engage_time", "s", "when the lid first reaches the end damper's engagement angle"),
    Metric("engage_theta_dot", "rad/s", "theta' there (negative): the engagement speed"),
)
ENGAGE_KEYS = tuple(m.key for m in ENGAGE_METRICS)
#: the hand force and the zones of a lid (SPEC §13; :mod:`softclose.simulation.handforce`),
#: over [theta_closed, stroke.theta_open_deg], beside the §9 ``opening_force``
HAND_METRICS = (
    Metric("closing_force", "N", "largest force at the tip that pushes the lid down where it "
           "does not close by itself (0 if none)"),
    Metric("self_close_deg", "deg", "highest angle up to which every release closes by itself "
           "(null if none)"),
    Metric("self_rise_deg", "deg", "lowest angle above which the lid rises by itself (null if "
           "none)"),
    Metric("hold_open", "deg", "the [lo, hi] ranges where the lid stays where it is left"),
)

#: units of the metrics, the objective and the design values (by name and by full config key)
UNITS: dict[str, str] = {
    **{m.key: m.unit for m in METRICS + ENGAGE_METRICS + HAND_METRICS},
    "objective": "",
    **{k.name: k.unit for k in KEYS if k.section == "design"},
    **{k.full: k.unit for k in KEYS if k.section == "design"},
}

#: the named constraints of the design problem
CONSTRAINTS = ("closed", "closing_time_max", "closing_time_min", "no_rebound",
               "holding_moment_min", "opening_force_max", "self_close_min_deg")
#: why a design is infeasible, in the order they are tested (the first that applies is given)
REASONS = ("not closed", "too slow", "too fast", "not held shut", "rebound", "too heavy to open")

#: accuracy targets of the fixed-step metrics against the converged answer
TARGETS = {"closing_time": 1e-7, "impact_theta_dot": 1e-6, "impact_tip_speed": 1e-6,
           "peak_tip_speed": 1e-6}
#: metrics whose target is relative to their magnitude
RELATIVE = ("impact_tip_speed", "peak_tip_speed")
#: the metrics whose fixed-step error is estimated
ERROR_KEYS = tuple(TARGETS)

#: relative agreement of the optimiser's objective with the reference's that counts as verified
VERIFY_RTOL = 1e-3
#: tolerance of the constraint checks in verification (absolute, SI)
CONSTRAINT_TOL = 1e-7


def params_of(cfg, design: dict | None = None) -> np.ndarray:
    """The parameter vector p (:data:`PARAM_KEYS`) of ``cfg``'s design, with ``design`` (a
    dict of some of its keys) taking precedence."""
    d = dict(design or {})
    return np.array([q.number(d[q.name] if q.name in d else config_value(cfg, q.key, number=False))
                     for q in PARAMS])


def resolve_lid(cfg) -> Lid:
    """The lid of ``cfg`` on its mechanism, with its elements' mounting."""
    d = cfg.design
    return Lid(cfg.geometry, cfg.mass,
               Mounting(d.torsion_pivot, d.rotary_damper_pivot, d.spring_min_length,
                        d.spring_max_length),
               cfg.raw.get("mass", {}).get("inertia_lid") is None)


def resolve_stroke(cfg) -> StrokeEnds:
    """The stroke's ends of ``cfg``."""
    st = cfg.stroke
    return StrokeEnds(st.theta0_deg, st.theta_closed_deg, st.theta_open_deg, st.t_max)


def resolve_temperatures(cfg) -> Temperatures:
    """The operating and reference temperatures of ``cfg`` and its parts' laws."""
    op = cfg.operating
    return Temperatures(op.temperature_c, op.reference_temperature_c,
                        cfg.design.damper_temperature_coeff, cfg.spring.material)


def resolve(cfg) -> LidCase:
    """``cfg`` resolved, once, into what the model and the simulation take
    (:mod:`softclose.model.resolved`): the lid on its mechanism, the stroke, the design vector
    p, the solver settings and the temperatures. Below the features nothing takes a config."""
    sim = cfg.simulate
    return LidCase(resolve_lid(cfg), resolve_stroke(cfg),
                   tuple(float(v) for v in params_of(cfg)),
                   SolverSettings(sim.integrator, sim.step, sim.reference_tol),
                   resolve_temperatures(cfg), resolve_life(cfg))


def resolve_life(cfg) -> Life:
    """What changes by the end of life in ``cfg`` and the state of its strokes."""
    lf = cfg.life
    return Life(lf.strut_force_loss, lf.spring_relaxation, lf.damper_change,
                lf.friction_change, lf.state)


def with_designs(cfg, D) -> np.ndarray:
    """Parameter vectors of ``cfg``'s design with the design variables (:data:`DESIGN_KEYS`)
    taken from ``D``: one vector for a design (k, l0, c), rows for an array of them."""
    D = np.asarray(D, float)
    P = np.tile(params_of(cfg), (len(np.atleast_2d(D)), 1))
    P[:, :len(DESIGN_KEYS)] = np.atleast_2d(D)[:, :len(DESIGN_KEYS)]
    return P if D.ndim == 2 else P[0]


def param_rows(cfg, n: int, keys=(), X=None) -> np.ndarray:
    """n rows of the parameter vector of ``cfg``'s design, with the columns of the config
    keys ``keys`` that are parameters (:data:`PARAM_COLUMNS`) set from the columns of X."""
    P = np.tile(params_of(cfg), (n, 1))
    for j, k in enumerate(keys):
        if k in PARAM_COLUMNS:
            P[:, PARAM_COLUMNS[k]] = X[:, j]
    return P


def _rates(element) -> tuple[str, ...]:
    """The parameters whose non-zero value makes a spring or damper exert a force (its rate
    or coefficient; a spring's rest length alone exerts none)."""
    if element.acting_params is not None:
        return tuple(element.acting_params)
    rate = getattr(element, "rate", "")
    return (rate,) if rate else tuple(q.name for q in element.params)


#: the spring rates and damper coefficients of [design], from the element registry
RATE_KEYS = tuple(name for e in ELEMENTS if e.name != "gravity"
                  and (e in elements.SPRINGS or e in elements.DAMPERS) for name in _rates(e))


def bare_lid(cfg, design: dict | None = None) -> bool:
    """True when ``cfg``'s design (``design`` taking precedence) has no spring and no
    damper: every rate and coefficient of :data:`RATE_KEYS` is zero, so the lid falls under
    gravity alone (the default config's design)."""
    d = dict(design or {})
    return all(float(d.get(k, getattr(cfg.design, k))) == 0.0 for k in RATE_KEYS)


#: what a report says about a design without spring or damper
BARE_LID = ("this design has no spring and no damper (design.spring_k, torsion_k, damper_c and "
            "rotary_damper_c are all 0: the default config's design): the lid falls freely "
            "and slams shut, and relative spreads of the spring and the damper are spreads of "
            "zero")


def design_of(p) -> dict:
    """The design dict ``{spring_k, spring_rest_length, damper_c}`` of a parameter vector."""
    return {k: float(v) for k, v in zip(DESIGN_KEYS, np.asarray(p, float)[:3])}


def objective(opt, impact_theta_dot, peak_tip_speed):
    """``J = weight_impact · impact_theta_dot² + weight_peak_tip · peak_tip_speed²``.

    ``opt`` is the [optimise] section (``cfg.optimise``). Scalars give a float (None when
    either metric is None: a stroke that did not close has no objective); arrays give an
    array (NaN where a metric is NaN).
    """
    if impact_theta_dot is None or peak_tip_speed is None:
        return None
    J = opt.weight_impact * np.square(impact_theta_dot) \
        + opt.weight_peak_tip * np.square(peak_tip_speed)
    return float(J) if np.ndim(J) == 0 else J


def infeasibility(opt, closed, closing_time, holding_moment, theta_dot_max,
                  opening_force=None) -> np.ndarray:
    """Why each design is infeasible: the first of :data:`REASONS` that applies, "" if none.

    Vectorised over designs; ``theta_dot_max`` is the largest theta' of the stroke (> 0 is
    a rebound). NaN closing times (not closed) never count as too slow or too fast. The
    opening force counts only when ``optimise.opening_force_max`` is set and it is given.
    """
    closed = np.atleast_1d(np.asarray(closed, bool))
    ct = np.atleast_1d(np.asarray(closing_time, float))
    hm = np.broadcast_to(np.asarray(holding_moment, float), closed.shape)
    tdm = np.broadcast_to(np.asarray(theta_dot_max, float), closed.shape)
    reason = np.full(closed.shape, "", dtype=object)
    with np.errstate(invalid="ignore"):
        # assigned in reverse order of REASONS so that the first applicable one is kept
        if opt.opening_force_max is not None and opening_force is not None:
            of = np.broadcast_to(np.asarray(opening_force, float), closed.shape)
            reason[of > opt.opening_force_max] = "too heavy to open"
        reason[closed & (tdm > 0)] = "rebound"
        reason[hm < opt.holding_moment_min] = "not held shut"
        reason[closed & (ct < opt.closing_time_min)] = "too fast"
        reason[closed & (ct > opt.closing_time_max)] = "too slow"
    reason[~closed] = "not closed"
    return reason


def feasible(opt, closed, closing_time, holding_moment, theta_dot_max,
             opening_force=None) -> np.ndarray:
    """True where a design meets every constraint (see :func:`infeasibility`)."""
    return infeasibility(opt, closed, closing_time, holding_moment, theta_dot_max,
                         opening_force) == ""


def opening_wanted(opt, asked: bool) -> bool:
    """Is the opening effort computed? When ``asked``, and always where
    ``optimise.opening_force_max`` (``opt``) makes it a constraint: the one rule of
    :func:`softclose.robust.evaluate.evaluate` and :func:`softclose.optimiser.verify.verify`
    (its statics over 241 angles are a fifth of a stroke's time)."""
    return asked or opt.opening_force_max is not None


def held_design(cfg) -> tuple:
    """Which of the design variables (k, l0, c) ``cfg`` holds at one value (its bounds
    ``optimise.spring_k`` ... with lo = hi, as ``softclose select`` holds a catalog spring's
    rate and free length): the robust scenario NLP takes them as parameters."""
    o = cfg.optimise
    return tuple(bool(getattr(o, k)[0] == getattr(o, k)[1]) for k in DESIGN_KEYS)


def target(key: str, value: float) -> float:
    """The accuracy target of one metric value (absolute units of the metric)."""
    return TARGETS[key] * (abs(value) if key in RELATIVE else 1.0)


def agreement_tolerance(key: str, value: float, accuracy: float | None = None) -> float:
    """How far the optimiser's own value of a metric may lie from the reference's.

    The optimiser's numbers come from its own discretisation (N intervals of RK4 sub-steps);
    they count as confirmed when they agree with the adaptive reference to
    :data:`VERIFY_RTOL` relative (the objective's criterion) or to the stated ``accuracy``,
    whichever is larger, with an absolute floor of the metric's fixed-step target.
    """
    tol = VERIFY_RTOL * abs(value)
    if accuracy is not None:
        tol = max(tol, accuracy)
    if key in TARGETS:
        tol = max(tol, TARGETS[key])
    return tol


def describe(cfg) -> dict[str, Any]:
    """The problem of ``cfg`` as plain values (for reports and JSON)."""
    o = cfg.optimise
    return {"closing_time_min": o.closing_time_min, "closing_time_max": o.closing_time_max,
            "holding_moment_min": o.holding_moment_min,
            "opening_force_max": o.opening_force_max,
            "self_close_min_deg": o.self_close_min_deg, "weight_impact": o.weight_impact,
            "weight_peak_tip": o.weight_peak_tip, "t_max": cfg.stroke.t_max,
            "bounds": {k: list(getattr(o, k)) for k in DESIGN_KEYS}}


#: categories of an infeasible design: the problem's reasons, then invalid config values,
#: then strokes the method could not integrate
CATEGORIES = REASONS + ("invalid", "not integrated")


def categorise(status: np.ndarray, reason: np.ndarray) -> np.ndarray:
    """Category code per row: -1 feasible, else an index into :data:`CATEGORIES`."""
    reason = np.asarray(reason, dtype=object)
    out = np.full(len(reason), CATEGORIES.index("not integrated"), np.int64)
    invalid = np.asarray(status, dtype=object) == "invalid"
    valid = np.flatnonzero(~invalid)     # (an invalid row's reason, often its own, is not read)
    why = reason[valid]
    known = np.zeros(len(valid), bool)
    for code, r in ((-1, ""),) + tuple(enumerate(REASONS)):   # the common cases, vectorised
        m = why == r
        out[valid[m]] = code
        known |= m
    rest = np.flatnonzero(~known)
    if rest.size:   # e.g. "not closed (held open at ...)", a stroke's diagnosis
        closed_not = {r: str(r).startswith("not closed") for r in set(why[rest].tolist())}
        nc = np.array([closed_not[r] for r in why[rest].tolist()], bool)
        out[valid[rest[nc]]] = REASONS.index("not closed")
    out[invalid] = CATEGORIES.index("invalid")
    return out


def check_reference_temperature(cfg, what: str) -> None:
    """ConfigError (one line, naming ``operating.temperature_c``) unless ``cfg``'s strokes run
    at the reference temperature: ``what`` (the optimiser, the Pareto front, the fit)
    designs at the temperature the parts' values are given at; strokes, sweeps and yields
    run at any other (:mod:`softclose.model.temperature`), and the robust optimiser and the
    catalog selection meet every constraint at each sign-off temperature
    (:func:`sign_off_temperatures`)."""
    op = cfg.operating
    if op.temperature_c != op.reference_temperature_c:
        raise ConfigError(
            f"operating.temperature_c: {what} works at the reference temperature "
            f"(operating.reference_temperature_c = {op.reference_temperature_c:g} °C), not at "
            f"{op.temperature_c:g} °C; simulate, sweep and yield run strokes at other "
            "temperatures, optimise --robust and select sign off at them")


def check_new_parts(cfg, what: str) -> None:
    """Refuse (ConfigError, one line) a config whose strokes are at the end of life for
    ``what``, which designs with the new parts (SPEC §17: a design's values are the new
    parts'; ``optimise --robust``, yield, select and report sign off at the end of life)."""
    from .model.life import aged
    if aged(resolve_life(cfg)):
        raise ConfigError(
            f'life.state: {what} designs with the new parts, not at "end_of_life"; simulate, '
            "state and sweep run strokes at the end of life, optimise --robust, yield, select "
            "and report sign off at it")


def sign_off_states(cfg) -> tuple[str, ...]:
    """The states a design must meet its constraints in (SPEC §17): the new lid, and the end
    of life when ``[life]`` changes a part."""
    from .model.life import ages
    return ("new", "end_of_life") if ages(resolve_life(cfg)) else ("new",)


def at_state(cfg, state: str):
    """``cfg`` with its strokes in ``state`` (``life.state``: new or end_of_life)."""
    if cfg.life.state == state:
        return cfg
    return cfg.replace(life={"state": state})


def sign_off_temperatures(cfg) -> tuple[float, ...]:
    """The temperatures a design must meet its constraints at (SPEC §12):
    ``operating.temperatures_c``, or ``[operating.temperature_c]`` when it is empty; each
    once, in order."""
    temps = cfg.operating.temperatures_c or (cfg.operating.temperature_c,)
    return tuple(dict.fromkeys(float(t) for t in temps))


#: a sign-off condition at the end of life is its temperature (°C) + this: one number, above
#: every admissible temperature (the config's end at 150 °C), so that the robust design's
#: arrays of scenario temperatures carry the state too (:func:`sign_off_conditions`)
END_OF_LIFE = 1000.0


def sign_off_conditions(cfg) -> tuple[float, ...]:
    """The conditions a design must meet its constraints in (SPEC §12, §17): each sign-off
    temperature of the new lid, then, when ``[life]`` changes a part, each at the end of life
    (its temperature + :data:`END_OF_LIFE`; :func:`condition_parts`)."""
    temps = sign_off_temperatures(cfg)
    if len(sign_off_states(cfg)) == 1:
        return temps
    return temps + tuple(T + END_OF_LIFE for T in temps)


def condition_parts(condition: float) -> tuple[float, str | None]:
    """(temperature °C, state) of a sign-off condition (:func:`sign_off_conditions`): the
    state None for a plain temperature (the config's own state)."""
    c = float(condition)
    return (c - END_OF_LIFE, "end_of_life") if c >= END_OF_LIFE / 2 else (c, None)


def condition_text(condition: float) -> str:
    """A condition in words: ``-10 °C``, ``-10 °C at the end of life``."""
    T, state = condition_parts(condition)
    return f"{T:g} °C" + (" at the end of life" if state == "end_of_life" else "")


def condition_tag(condition: float) -> str:
    """A condition in a file name: ``-10C``, ``-10C_end_of_life``."""
    T, state = condition_parts(condition)
    return f"{T:g}C" + (f"_{state}" if state else "")


def at_temperature(cfg, temperature_c: float):
    """``cfg`` with its strokes at ``temperature_c`` (the design's values stay those given at
    the reference temperature); a sign-off condition at the end of life
    (:func:`sign_off_conditions`) sets ``life.state`` too."""
    T, state = condition_parts(temperature_c)
    if state is not None and cfg.life.state != state:
        cfg = at_state(cfg, state)
    if cfg.operating.temperature_c == T:
        return cfg
    return cfg.replace(operating={"temperature_c": float(T)})
