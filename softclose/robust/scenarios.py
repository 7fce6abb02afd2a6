"""The scenarios of the robust design: points of the tolerance box in unit coordinates (z = ±1
at the faces), how a point maps onto the kernel's parameters and the model's keys
(:func:`maps`), and which of them the scenario NLP starts from (:func:`initial_scenarios`):
the nominal lid and every corner of the box, or, beyond :data:`MAX_CORNERS` corners, the
corners worst for each constraint at a design (every corner simulated in the C kernel) and a
fractional factorial (:func:`fractional_factorial`).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np

from ..config import Config
from ..problem import DESIGN_KEYS, PARAM_COLUMNS, PARAM_KEYS, with_designs
from .box import Box, box_of
from .evaluate import evaluate
from .policy import max_corners, t_end


@dataclass(frozen=True)
class Scenario:
    """One point of the tolerance box, in unit coordinates (z = ±1 at the faces)."""

    z: tuple
    origin: str           # "nominal", "corner", "Monte Carlo, round r"


def maps(box: Box, z) -> tuple[np.ndarray, np.ndarray, dict]:
    """(a, b, model values) of the point z: p = a * p_design + b (the parameter vector,
    PARAM_KEYS), model keys."""
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
    return a, b, values


def scenario_rows(box: Box, designs: np.ndarray, Z: np.ndarray, cfg):
    """Evaluation rows of every design (G, 3) in every scenario (S, d): (keys, X (G S, .))."""
    keys = list(PARAM_COLUMNS) + [k for k in box.keys if k not in PARAM_COLUMNS]
    rows = []
    for q in with_designs(cfg, np.atleast_2d(designs)):
        for z in Z:
            a, b, vals = maps(box, z)
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


def design_dict(problem: "softclose.robust.solve.Problem", d) -> dict:
    """The design vector ``d`` of a solve by name: k, l0, c, then the NLP's free design
    variables (a gas strut's F1, the end damper's), as ``design`` keys."""
    names = DESIGN_KEYS + tuple(k.split(".", 1)[1] for k, _, _ in problem.nlp.free)
    return {n: float(v) for n, v in zip(names, np.asarray(d, float))}


def corner_columns(cfg: Config, scale: float, design):
    """(box at ``design``, its corners Z (2^d, d), cfg with ``design``, the kernel's columns
    of every corner); a box without a dimension has no corners (Z empty, columns None).
    ``design``: (k, l0, c), or a dict of design values by name (with a gas strut's F1)."""
    if not isinstance(design, dict):
        design = dict(zip(DESIGN_KEYS, map(float, design)))
    box_d = box_of(cfg, design, scale=scale)
    c = cfg.with_design(**design)
    if not box_d.dim:
        return box_d, np.zeros((0, 0)), c, None
    Z = box_d.corners()
    return box_d, Z, c, evaluate(c, box_d.keys, box_d.values(Z), t_end=t_end(cfg))


def _worst_corners(cfg: Config, scale: float, design) -> list[tuple[tuple, str]]:
    """The corners of the box worst for each constraint, and for the objective in
    worst-case mode, at ``design``: (z, why) for each distinct one.

    Every corner is simulated in the kernel (2^d strokes: what one NLP scenario costs
    buys thousands of them), so the worst corner is exact at the design, not a first-order
    guess: the slowest (a lid that does not close counts as slowest, the one stopping
    highest first), the fastest (when closing_time_min > 0), the weakest holding moment,
    the one closest to rebounding (only when one rebounds), the largest J.
    """
    _, Z, _, cols = corner_columns(cfg, scale, design)
    out: dict = {}
    for why, v in badness(cfg, cols).items():
        z = tuple(map(float, Z[int(np.argmax(v))]))
        out[z] = f"{out[z]}, {why}" if z in out else why
    return list(out.items())


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
    """The scenarios the NLP starts from: the nominal lid and every corner of the box when
    there are at most :data:`MAX_CORNERS` of them (:func:`~.policy.max_corners` with two
    phases; or no ``cfg`` is given).

    Beyond, the nominal lid and, at each of ``designs``, the corners worst for each
    constraint and for the objective (:func:`_worst_corners`); in mean mode also a
    resolution-III fraction of the corners (:func:`fractional_factorial`, 8 or 16 runs),
    so that the mean objective is not an average over worst cases only.

    Why these: each constraint that binds in a robust design is set by one extreme lid (the
    slowest closes last, the weakest spring holds least, one lid has the worst J), and the
    scenario NLP needs exactly those; the other corners only cost size. Which corner is
    worst can change as the NLP moves the design: the corner check after every solve
    (:func:`softclose.robust.worst_cases.check_corners`) adds any that then violates, so the
    result still holds at every corner. (A fraction or a first-order model would guess the
    worst corners; the kernel simulates them all for less than one NLP scenario costs.)
    """
    out = [Scenario(tuple([0.0] * box.dim), "nominal")]
    if not box.dim:
        return out
    if cfg is None or 2 ** box.dim <= max_corners(cfg):
        return out + [Scenario(tuple(map(float, z)), "corner") for z in box.corners()]
    seen = {out[0].z}
    for design in designs:
        for z, why in _worst_corners(cfg, scale, design):
            if z not in seen:
                seen.add(z)
                out.append(Scenario(z, f"corner ({why})"))
    if cfg.tolerance.robust_objective == "mean":
        for z in fractional_factorial(box.dim):
            z = tuple(map(float, z))
            if z not in seen:
                seen.add(z)
                out.append(Scenario(z, "corner (fractional factorial)"))
    return out
