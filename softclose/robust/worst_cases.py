"""The worst cases the scenario NLP does not hold: after each solve, points of the tolerance
box that break a constraint or exceed the worst scenario's objective at the NLP's design.

- :func:`search` -- a Monte Carlo pass, uniform in the box, in the C kernel; the
  highest-scoring samples, each improved by a local ascent (a compass search), become
  scenarios ("local reduction", Zagorowska et al., arXiv 2204.14145);
- :func:`check_corners` -- every one of the 2^d corners of the box in the kernel; the
  violating ones not yet among the scenarios join them, so that whatever subset the NLP
  started from, every corner holds at the answer.

Both take a solve of the scenario NLP (a :class:`softclose.robust.solve.Run`: its
``design`` and each scenario's objective ``J``) and look at every sign-off temperature
(:func:`softclose.robust.scenarios.temperatures`): a point they return is (z, T).
"""

from __future__ import annotations

import math

import numpy as np

from ..config import Config
from ..problem import at_temperature, condition_parts
from .box import Box, box_of
from .evaluate import evaluate
from .policy import ADD_PER_ROUND, MC_TOL, OBJ_RTOL, t_end
from .scenarios import badness, corner_columns, design_dict, label, temperatures
from .stats import margins


def _scores(cfg: Config, c: Config, box_d: Box, z: np.ndarray, Jmax: float,
            cut: bool = True, cols: dict | None = None):
    """(score, margin) of unit points z at the design of ``c``: the score is the worst
    relative constraint violation (-margin; for a lid that does not close, 10 + the lowest
    angle it reached, so that lids stopping higher score higher) or, in worst-case mode,
    the objective's excess over the worst scenario's, scaled so that an excess of OBJ_RTOL
    scores like a violation of MC_TOL. ``cut``: strokes end shortly after the closing-time
    limit (fast; later closings count as not closed); ``cols``: their kernel columns, if
    already simulated."""
    end = t_end(cfg) if cut else None
    if cols is None:
        cols = evaluate(c, box_d.keys, box_d.values(z), t_end=end)
    m = margins(cols, cfg.optimise)
    th = np.nan_to_num(np.asarray(cols["theta_min"], float), nan=10.0)
    score = np.where(np.isfinite(m), -m, 10.0 + th)
    if cfg.tolerance.robust_objective == "worst":
        J = np.asarray(cols["objective"], float)
        score = np.maximum(score, np.where(np.isfinite(J), (J - Jmax) / Jmax * MC_TOL / OBJ_RTOL,
                                           0.0))
    return score, m


def _climb(cfg, c, box_d, z, f, Jmax, step: float = 0.5, min_step: float = 1e-3):
    """Local ascent of the score from a violating sample (compass search in the box):
    sampling finds the region of a worst case, this finds its point (often a face or
    corner of the box)."""
    d = box_d.dim
    E = np.vstack([np.eye(d), -np.eye(d)])
    f = float(_scores(cfg, c, box_d, z[None, :], Jmax, cut=False)[0][0])  # whole stroke
    while step >= min_step:
        cand = np.clip(z + step * E, -1.0, 1.0)
        fs, _ = _scores(cfg, c, box_d, cand, Jmax, cut=False)
        i = int(np.argmax(fs))
        if fs[i] > f * (1 + 1e-9) + 1e-15:
            z, f = cand[i], float(fs[i])
        else:
            step /= 2
    return z, f


def search(cfg: Config, scale: float, run, seed: int, n: int) -> tuple[list, dict]:
    """Points inside the box that break a constraint or exceed the worst objective: the
    highest-scoring of ``n`` uniform samples at each sign-off temperature (the same samples
    at each: :func:`_scores`), each improved by a local ascent at its temperature
    (:func:`_climb`); those scoring above MC_TOL become scenarios, as (z, T)."""
    design = design_dict(run.problem, run.design)
    box_d = box_of(cfg, design, scale=scale)
    z = box_d.draw(n, seed, "uniform")
    c = cfg.with_design(**design)
    Jmax = float(np.max(run.J))
    temps = temperatures(cfg)
    parts = [_scores(cfg, at_temperature(c, T), box_d, z, Jmax) for T in temps]
    score = np.concatenate([q[0] for q in parts])
    m = np.concatenate([q[1] for q in parts])
    bad = score > MC_TOL
    picks = []
    for i in np.argsort(-score)[:ADD_PER_ROUND]:
        if not bad[i]:
            break
        T = temps[i // n]
        zi, fi = _climb(cfg, at_temperature(c, T), box_d, z[i % n], float(score[i]), Jmax)
        if all(T != Tj or np.max(np.abs(zi - zj)) > 1e-6 for zj, Tj, _ in picks):
            picks.append((zi, T, fi))
    info = {"samples": int(n * len(temps)), "violating": int(bad.sum()),
            "worst_margin": float(np.min(m)) if len(m) else None,
            "added": [label(box_d, zi, T, temps) for zi, T, _ in picks],
            "added_scores": [fi for _, _, fi in picks]}
    return [(tuple(map(float, zi)), T) for zi, T, _ in picks], info


def check_corners(cfg: Config, scale: float, run, have=()) -> tuple[list, dict]:
    """Every corner of the box at every sign-off temperature at the design of ``run``, in
    the kernel. A corner violates when it breaks a constraint by more than MC_TOL or, in
    worst-case mode, its J exceeds the worst scenario's by more than OBJ_RTOL (as in
    :func:`_scores`). Returns the violating corners to add, as (z, T) -- among those not in
    ``have`` ((z, T) of the scenarios), the most violating one and the worst for each
    constraint and the objective (:func:`softclose.robust.scenarios.badness`): at most six
    a round, so that a poor design (say the nominal optimum, where most corners fail) does
    not bring all 2^d corners into the NLP at once -- and a summary (``breaking``: every
    corner outside ``have`` that breaks a constraint; ``temperatures``: the smallest margin
    over the corners at each temperature; ``limiting_temperature_c``: the temperature of the
    corner with the smallest margin of all, the one closest to breaking a constraint or
    breaking one the most)."""
    box_d, Z, Ts, c, cols = corner_columns(cfg, scale, design_dict(run.problem, run.design))
    if not len(Z):
        return [], {"corners": 0, "violating": 0, "breaking": [], "added": []}
    temps = temperatures(cfg)
    score, m = _scores(cfg, c, box_d, Z, float(np.max(run.J)), cols=cols)
    ref = cfg.operating.reference_temperature_c        # (a scenario without one: there)
    have = [(np.asarray(h, float), ref if T is None else T) for h, T in have
            if len(h) == box_d.dim]
    outside = np.array([all(T != Th or np.max(np.abs(h - z)) > 1e-6 for h, Th in have)
                        for z, T in zip(Z, Ts)])
    bad = (score > MC_TOL) & outside
    picks = []
    if bad.any():
        crit = {"most violating": score, **badness(cfg, cols)}
        for v in crit.values():
            i = int(np.argmax(np.where(bad, v, -np.inf)))
            if bad[i] and i not in picks:
                picks.append(i)
    breaking = [label(box_d, Z[i], Ts[i], temps)
                for i in np.nonzero(outside & (m < -MC_TOL))[0]]
    by_T = [float(np.min(m[Ts == T])) for T in temps]
    return [(tuple(map(float, Z[i])), float(Ts[i])) for i in picks], {
        "corners": int(len(Z)), "violating": int(np.sum(score > MC_TOL)),
        "worst_margin": float(np.min(m)) if np.all(np.isfinite(m)) else -math.inf,
        "breaking": breaking, "added": [label(box_d, Z[i], Ts[i], temps) for i in picks],
        "temperatures": [{"temperature_c": condition_parts(T)[0],
                          "state": condition_parts(T)[1] or "new", "worst_margin": w}
                         for T, w in zip(temps, by_T)],
        "limiting_temperature_c": float(Ts[int(np.argmin(m))])}
