"""The scenarios of the robust design: points of the tolerance box in unit coordinates (z = ±1
at the faces), how a point maps onto the kernel's parameters and the model's keys
(:func:`maps`), and which of them the scenario NLP starts from (:func:`initial_scenarios`):
the nominal lid and every corner of the box, or, beyond :data:`MAX_CORNERS` corners, the
corners worst for each constraint at a design (every corner simulated in the C kernel) and a
fractional factorial (:func:`fractional_factorial`).

Temperature is a scenario dimension (SPEC §12): a scenario is a point z of the box at one
sign-off temperature T (:func:`temperatures`). The design's values are given at the reference
temperature; at T every parameter p_i moves by its factor f_i
(:func:`softclose.model.temperature.parameter_factors`), so a scenario at T maps
``p_T = f (a p + b)``: (a f, b f), more scenarios of the same NLP. The robust procedure runs on
:func:`at_reference` of the config (its strokes at the reference temperature, the sign-off
temperatures in ``operating.temperatures_c``) and moves each scenario to its own T.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np

from ..config import Config
from ..model.temperature import factors_of, parameter_factors
from ..model.life import aged, life_map, shut_coordinates
from ..optimiser.cache import get_model
from ..problem import (DESIGN_KEYS, PARAM_COLUMNS, PARAM_KEYS, at_temperature, condition_text,
                       params_of, resolve_life, resolve_temperatures, sign_off_conditions,
                       sign_off_temperatures, with_designs)
from .box import Box, box_of
from .evaluate import evaluate
from .policy import max_corners, t_end


@dataclass(frozen=True)
class Scenario:
    """One point of the tolerance box, in unit coordinates (z = ±1 at the faces)."""

    z: tuple
    origin: str           # "nominal", "corner", "Monte Carlo, round r"
    #: the sign-off temperature (°C) of the stroke; None: the reference temperature
    temperature_c: float | None = None


def at_reference(cfg: Config) -> Config:
    """``cfg`` as the robust procedure runs on it: its strokes at the reference temperature
    (the design's values are given there) and its sign-off temperatures
    (:func:`softclose.problem.sign_off_temperatures`: ``operating.temperatures_c``, or
    ``[operating.temperature_c]`` alone) listed in ``operating.temperatures_c``. The same
    config back when it is so already (the default)."""
    op = cfg.operating
    temps = sign_off_temperatures(cfg)
    if cfg.life.state != "new":          # (the new lid; the end of life is a condition)
        cfg = cfg.replace(life={"state": "new"})
    if op.temperature_c == op.reference_temperature_c and tuple(op.temperatures_c) in (
            (), temps) and temps == (op.reference_temperature_c,):
        return cfg
    return cfg.replace(operating={"temperature_c": float(op.reference_temperature_c),
                                  "temperatures_c": [float(t) for t in temps]})


def temperatures(cfg: Config) -> tuple[float, ...]:
    """The sign-off conditions every scenario point is checked at: the sign-off temperatures
    (°C) of the new lid and, when ``[life]`` changes a part, each at the end of life
    (:func:`softclose.problem.sign_off_conditions`)."""
    return sign_off_conditions(cfg)


def factors(cfg: Config, temperature_c: float | None) -> np.ndarray | None:
    """The parameter factors of a stroke of ``cfg``'s design at ``temperature_c``: the row of
    its spring's kind (a coil spring's or a gas strut's; every scenario of a robust design
    has the design's kind). None at the reference temperature, and for None."""
    if temperature_c is None:
        return None
    c = at_temperature(cfg, temperature_c)
    f = factors_of(parameter_factors(resolve_temperatures(c)), params_of(cfg))
    life = resolve_life(c)
    if not aged(life):
        return f
    return life_map(params_of(cfg), life, shut_coordinates(get_model(cfg)), f)


def label(box: Box, z, temperature_c: float | None, temps=()) -> str:
    """A scenario's name: the box's label of z, and `` at T °C`` with several sign-off
    temperatures."""
    text = box.label(z)
    return text if temperature_c is None or len(temps) <= 1 else \
        f"{text} at {condition_text(temperature_c)}"


def maps(box: Box, z, factors: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, dict]:
    """(a, b, model values) of the point z: p = a * p_design + b (the parameter vector,
    PARAM_KEYS), model keys. With the ``factors`` of a temperature (:func:`factors`) the
    stroke's p is f (a p_design + b): (a f, b f)."""
    a, b, values = np.ones(len(PARAM_KEYS)), np.zeros(len(PARAM_KEYS)), {}
    for j, key in enumerate(box.keys):
        if key in PARAM_COLUMNS:
            col = PARAM_COLUMNS[key]
            zj = max(z[j], box.z_min[j])
            if box.relative[j]:
                a[col] = 1.0 + box.spreads[j] * zj
            else:
                b[col] = box.spreads[j] * zj
        else:
            values[key] = float(box.nominal[j] + box.half[j] * max(z[j], box.z_min[j]))
    if factors is not None:            # (at the end of life: rows f and an added term)
        f, add = (factors, 0.0) if np.ndim(factors) == 1 else factors
        a, b = a * f, b * f + add
    return a, b, values


def scenario_rows(box: Box, designs: np.ndarray, scenarios, cfg):
    """Evaluation rows of every design (G, 3) in every scenario (a list of
    :class:`Scenario`, or unit points (S, d) at the reference temperature): (keys, X (G S,
    .)), to evaluate at ``cfg``'s reference temperature (a scenario's temperature is in its
    parameter columns)."""
    keys = list(PARAM_COLUMNS) + [k for k in box.keys if k not in PARAM_COLUMNS]
    scen = [s if isinstance(s, Scenario) else Scenario(tuple(s), "") for s in scenarios]
    m = [maps(box, s.z, factors(cfg, s.temperature_c)) for s in scen]
    rows = []
    for q in with_designs(cfg, np.atleast_2d(designs)):
        for a, b, vals in m:
            rows.append(np.r_[a * q + b, [vals[k] for k in keys[len(PARAM_KEYS):]]])
    return keys, np.array(rows)


def fractional_factorial(d: int) -> np.ndarray:
    """A regular two-level fractional factorial of resolution >= III in d factors: (n, d)
    of ±1 with n = 2^m the smallest power of two above d.

    Columns are the m base factors of the full 2^m factorial, then their products, highest
    order first (4 factors: A, B, C, ABC, resolution IV). Distinct products are never equal
    or opposite, so no main effect is aliased with another: every key is at each level in
    half the runs and every pair of keys in all four combinations (X^T X = n I), and the
    mean over the runs of any function additive in the keys is the full factorial's.
    """
    if d <= 0:
        return np.zeros((1, 0))
    m = max(1, math.ceil(math.log2(d + 1)))
    base = np.array(list(itertools.product((-1.0, 1.0), repeat=m)))
    ones = [1 << i for i in range(m)]
    rest = sorted((u for u in range(1, 1 << m) if u not in ones),
                  key=lambda u: (-bin(u).count("1"), u))
    cols = [np.prod(base[:, [i for i in range(m) if u >> i & 1]], axis=1)
            for u in (ones + rest)[:d]]
    return np.column_stack(cols)


def design_dict(problem, d) -> dict:
    """The design vector ``d`` of a solve by name: k, l0, c, then the NLP's free design
    variables (a gas strut's F1, the end damper's), as ``design`` keys."""
    names = DESIGN_KEYS + tuple(k.split(".", 1)[1] for k, _, _ in problem.nlp.free)
    return {n: float(v) for n, v in zip(names, np.asarray(d, float))}


def corner_columns(cfg: Config, scale: float, design):
    """(box at ``design``, its corners Z, their temperatures Ts, cfg with ``design``, the
    kernel's columns of every corner): every corner at every sign-off temperature
    (:func:`temperatures`), temperature by temperature (Z (n T 2^d, d), Ts (n T 2^d,)); a
    box without a dimension has no corners (Z empty, columns None). ``design``: (k, l0, c),
    or a dict of design values by name (with a gas strut's F1)."""
    if not isinstance(design, dict):
        design = dict(zip(DESIGN_KEYS, map(float, design)))
    box_d = box_of(cfg, design, scale=scale)
    c = cfg.with_design(**design)
    if not box_d.dim:
        return box_d, np.zeros((0, 0)), np.zeros(0), c, None
    corners = box_d.corners()
    temps = temperatures(cfg)
    parts = [evaluate(at_temperature(c, T), box_d.keys, box_d.values(corners),
                      t_end=t_end(cfg)) for T in temps]
    cols = parts[0] if len(parts) == 1 else \
        {k: np.concatenate([np.asarray(q[k]) for q in parts]) for k in parts[0]}
    Z = np.tile(corners, (len(temps), 1))
    Ts = np.repeat(np.asarray(temps, float), len(corners))
    return box_d, Z, Ts, c, cols


def corner_count(cfg: Config, box: Box) -> int:
    """The corner scenarios of the box: its 2^d corners at every sign-off temperature."""
    return (2 ** box.dim if box.dim else 0) * len(temperatures(cfg))


def all_corners(cfg: Config, box: Box) -> bool:
    """True when every corner at every sign-off temperature enters the scenario NLP
    together (at most :func:`~.policy.max_corners`)."""
    return corner_count(cfg, box) <= max_corners(cfg)


def _worst_corners(cfg: Config, scale: float, design) -> list[tuple[tuple, float, str]]:
    """The corners of the box worst for each constraint, and for the objective in
    worst-case mode, at ``design``, over every sign-off temperature: (z, T, why) for each
    distinct one.

    Every corner is simulated in the kernel (2^d strokes at each temperature: what one NLP
    scenario costs buys thousands of them), so the worst corner is exact at the design, not
    a first-order guess: the slowest (a lid that does not close counts as slowest, the one
    stopping highest first), the fastest (when closing_time_min > 0), the weakest holding
    moment, the one closest to rebounding (only when one rebounds), the largest J.
    """
    _, Z, Ts, _, cols = corner_columns(cfg, scale, design)
    out: dict = {}
    for why, v in badness(cfg, cols).items():
        i = int(np.argmax(v))
        key = (tuple(map(float, Z[i])), float(Ts[i]))
        out[key] = f"{out[key]}, {why}" if key in out else why
    return [(z, T, why) for (z, T), why in out.items()]


def badness(cfg: Config, cols: dict) -> dict:
    """How bad each stroke of ``cols`` is for each constraint (and the objective in
    worst-case mode): larger is worse (see :func:`_worst_corners`)."""
    o = cfg.optimise
    closed = np.asarray(cols["closed"], bool)
    ct = np.asarray(cols["closing_time"], float)
    th = np.nan_to_num(np.asarray(cols["theta_min"], float), nan=10.0)
    worst = {"slowest": np.where(closed, ct, 1e3 + th),
             "weakest holding moment": np.nan_to_num(-np.asarray(cols["holding_moment"], float),
                                                     nan=-np.inf)}
    if o.closing_time_min > 0:
        worst["fastest"] = np.where(closed, -ct, -np.inf)
    tdm = np.nan_to_num(np.asarray(cols["theta_dot_max"], float), nan=-np.inf)
    if np.any(tdm > 0):
        worst["rebound"] = tdm
    if cfg.tolerance.robust_objective == "worst":
        J = np.asarray(cols["objective"], float)
        if np.any(np.isfinite(J)):
            worst["largest J"] = np.where(np.isfinite(J), J, -np.inf)
    return worst


def initial_scenarios(box: Box, cfg: Config | None = None, designs=(),
                      scale: float = 1.0) -> list[Scenario]:
    """The scenarios the NLP starts from: the nominal lid and every corner of the box, each
    at every sign-off temperature (:func:`temperatures`; the nominal lid nearest the
    reference temperature first), when there are at most :data:`MAX_CORNERS` corner
    scenarios (:func:`~.policy.max_corners` with two phases; or no ``cfg`` is given: the
    reference temperature alone).

    Beyond, the nominal lid at every temperature and, at each of ``designs``, the corners
    worst for each constraint and for the objective over every temperature
    (:func:`_worst_corners`); in mean mode also a resolution-III fraction of the corners
    (:func:`fractional_factorial`, 8 or 16 runs) at every temperature, so that the mean
    objective is not an average over worst cases only.

    Why these: each constraint that binds in a robust design is set by one extreme lid (the
    slowest closes last -- often the coldest, its damper the thickest --, the weakest spring
    holds least, one lid has the worst J), and the scenario NLP needs exactly those; the
    other corners only cost size. Which corner is worst can change as the NLP moves the
    design: the corner check after every solve
    (:func:`softclose.robust.worst_cases.check_corners`) adds any that then violates, so the
    result still holds at every corner at every temperature. (A fraction or a first-order
    model would guess the worst corners; the kernel simulates them all for less than one NLP
    scenario costs.)
    """
    if cfg is None:
        temps, ref = (None,), None
    else:
        ref = cfg.operating.reference_temperature_c
        temps = sorted(temperatures(cfg), key=lambda T: abs(T - ref))
    zero = tuple([0.0] * box.dim)
    out = [Scenario(zero, "nominal", T) for T in temps]
    if not box.dim:
        return out
    if cfg is None or all_corners(cfg, box):
        return out + [Scenario(tuple(map(float, z)), "corner", T)
                      for T in (temps if cfg is None else temperatures(cfg))
                      for z in box.corners()]
    seen = {(s.z, s.temperature_c) for s in out}
    for design in designs:
        for z, T, why in _worst_corners(cfg, scale, design):
            if (z, T) not in seen:
                seen.add((z, T))
                out.append(Scenario(z, f"corner ({why})", T))
    if cfg.tolerance.robust_objective == "mean":
        for T in temperatures(cfg):
            for z in fractional_factorial(box.dim):
                z = tuple(map(float, z))
                if (z, T) not in seen:
                    seen.add((z, T))
                    out.append(Scenario(z, "corner (fractional factorial)", T))
    return out
