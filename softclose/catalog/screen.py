"""Screening spring x damper pairs in the C kernel, each over its own tolerance box.

A pair's box has the axes (in unit coordinates z, z = ±1 at the faces): the spring's rate
(``rate (1 + z rate_tolerance)``; a gas strut's force F1 instead, ``F1 (1 + z
force_tolerance)``), its free length (``free_length + z free_length_tolerance``), the
damper's coefficient (``c (1 + z c_tolerance)``), then every other key of ``[tolerance]``
(the config's spreads of ``design.spring_k``, ``spring_rest_length``, ``damper_c`` and
``rotary_damper_c`` are replaced by the parts' own; a spread of the preload, or of a strut's
progression, stroke or friction, is taken around the part's value, and a gas strut's F1
carries its own spread only). Each pair is run at
the 2^d corners, the nominal point and the same Monte Carlo samples (common random numbers:
two pairs see the same relative deviations), all rows of a chunk of pairs in one kernel
batch (:func:`softclose.robust.evaluate.evaluate`).

With several sign-off temperatures (``operating.temperatures_c``, SPEC §12) every corner and
every sample is a row at each temperature (the parts' values given at the reference
temperature, moved by their laws at each): a pair is feasible when every corner meets every
constraint at every temperature, and a sample counts towards the yield when it does at
all of them (the joint yield).

A row meets every constraint of the problem (:func:`softclose.problem.infeasibility`) and
keeps the spring in its valid range: the kind's side of its free length (the kernel's own
range check; a gas strut's stroke from its extended length) and the part's ``min_length`` /
``max_length`` (checked here against the stroke's extremes, as the limits differ per part;
a gas strut's compressed length moves with its extended length, so its ``min_length`` is
its stroke's end, checked by the kernel).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, replace

import numpy as np

from ..simulation import statics
from ..config import Config
from ..config.load import from_dict
from ..model.elements.springs import KINDS
from ..robust.box import Box, box_of
from ..robust.evaluate import evaluate, point_values, simulator, slow_keys
from ..problem import LID_MASS, at_temperature, condition_text, param_rows, resolve
from ..robust.scenarios import temperatures as sign_off
from ..robust.stats import margins
from ..simulation.stroke import NUMERICAL_FAILURES, StrokeStatus

#: the [tolerance] keys a catalog's own tolerances replace
OWNED = ("design.spring_k", "design.spring_rest_length", "design.damper_c",
         "design.rotary_damper_c")
PRELOAD = "design.spring_preload"
#: a gas strut's own values in a row (besides F1 and its extended length)
STRUT_KEYS = ("design.strut_stroke", "design.strut_progression", "design.strut_friction")
#: relative slack of the length limits (the extremes' rounding)
LIMIT_RTOL = 1e-9
#: the reason of a row whose spring leaves its valid range
RANGE = "leaves its valid range"


def without_limits(cfg: Config) -> Config:
    """``cfg`` without spring length limits (each part brings its own)."""
    d = cfg.design
    if d.spring_min_length is None and d.spring_max_length is None:
        return cfg
    raw = {k: dict(v) for k, v in cfg.raw.items()}
    for k in ("spring_min_length", "spring_max_length"):
        raw.get("design", {}).pop(k, None)
    return from_dict(raw)


def limits_view(cfg: Config, lo, hi):
    """What the range check reads of a config, with a part's limits (None: no limit)."""
    return resolve(cfg).lid.mounting._replace(spring_min_length=lo, spring_max_length=hi)


@dataclass(frozen=True)
class PairBox:
    """The unit points every pair is run at: corners, the nominal point, Monte Carlo samples;
    and the box of the other toleranced keys."""

    other: Box
    Z: np.ndarray          # (n_points, 3 + other.dim)
    corners: int           # the corner rows (2^d at each temperature)
    samples: int           # Monte Carlo samples (at each temperature)
    #: the temperature (°C) of each row, with several sign-off temperatures (corners at each,
    #: the nominal point once, samples at each); None: every row at the config's own
    Ts: np.ndarray | None = None
    #: the config's strut values (stroke, 0 for none; progression; friction): a coil
    #: spring's rows keep them
    strut: tuple = (0.0, 1.3, 0.0)

    @property
    def temperatures(self) -> tuple:
        """The sign-off temperatures of the rows (() when they are the config's own)."""
        return () if self.Ts is None else tuple(dict.fromkeys(map(float, self.Ts)))

    def head(self) -> "PairBox":
        """The corners and the nominal point alone (no samples)."""
        n = self.corners + 1
        return PairBox(self.other, self.Z[:n], self.corners, 0,
                       None if self.Ts is None else self.Ts[:n], self.strut)

    @property
    def outside(self) -> np.ndarray:
        """The sample rows (indices into :attr:`Z`) outside the box (a unit coordinate
        beyond ±1: only with ``distribution = "normal"``, whose spread is 3 sigma), which
        its corners do not bound."""
        first = self.corners + 1
        out = (np.abs(self.Z[first:]) > 1.0 + 1e-12).any(axis=1)
        return first + np.flatnonzero(out)

    def config_at(self, cfg: Config, row: int) -> Config:
        """``cfg`` at the temperature of row ``row``."""
        return cfg if self.Ts is None else at_temperature(cfg, float(self.Ts[row]))

    def row_label(self, row: int, spring, damper) -> str:
        """:meth:`label` of a row, with its temperature when there are several."""
        text = self.label(self.Z[row], spring, damper)
        return text if self.Ts is None else f"{text} at {condition_text(self.Ts[row])}"

    @property
    def points(self) -> int:
        return len(self.Z)

    @property
    def dim(self) -> int:
        return self.Z.shape[1]

    def label(self, z, spring, damper) -> str:
        """``rate +10 %, free length -0.9 mm, c -20 %, mass.lid +5 %`` at unit point z."""
        z = np.asarray(z, float)
        parts = []
        if spring.is_strut:
            if spring.force_tolerance:
                parts.append(f"F1 {100 * z[0] * spring.force_tolerance:+.3g} %")
        elif spring.rate_tolerance:
            parts.append(f"rate {100 * z[0] * spring.rate_tolerance:+.3g} %")
        if spring.free_length_tolerance:
            parts.append(f"free length {1e3 * z[1] * spring.free_length_tolerance:+.3g} mm")
        if damper.c_tolerance:
            parts.append(f"c {100 * z[2] * damper.c_tolerance:+.3g} %")
        rest = self.other.label(z[3:]) if self.other.dim else "nominal"
        if rest != "nominal":
            parts.append(rest)
        return ", ".join(parts) or "nominal"


def pair_box(cfg: Config, samples: int, seed: int = 0) -> PairBox:
    """The unit points of every pair: 2^d corners (d = 3 + the other toleranced keys), the
    nominal point, ``samples`` Monte Carlo points of ``[tolerance] distribution``; with
    several sign-off temperatures (or one other than ``cfg``'s own), the corners at each,
    the nominal point at the one nearest the reference, the same samples at each."""
    tol = cfg.tolerance
    tol = replace(tol, spreads=tuple(s for s in tol.spreads if s.key not in OWNED))
    other = box_of(cfg, tolerance=tol)
    d = 3 + other.dim
    corners = np.array(list(itertools.product((-1.0, 1.0), repeat=d)))
    rng = np.random.default_rng(seed)
    if tol.distribution == "uniform":
        z = rng.uniform(-1.0, 1.0, (samples, d))
    else:
        z = rng.standard_normal((samples, d)) / 3.0
    if other.dim:
        z[:, 3:] = np.maximum(z[:, 3:], other.z_min)
    temps = sign_off(cfg)
    de = cfg.design
    strut = (de.strut_stroke or 0.0, de.strut_progression, de.strut_friction)
    if temps == (cfg.operating.temperature_c,):
        Z = np.vstack([corners, np.zeros((1, d)), z])
        return PairBox(other, Z, len(corners), samples, None, strut)
    nT, ref = len(temps), cfg.operating.reference_temperature_c
    Z = np.vstack([np.tile(corners, (nT, 1)), np.zeros((1, d)), np.tile(z, (nT, 1))])
    Ts = np.r_[np.repeat(temps, len(corners)), min(temps, key=lambda T: abs(T - ref)),
               np.repeat(temps, samples)].astype(float)
    return PairBox(other, Z, nT * len(corners), samples, Ts, strut)


def pair_rows(box: PairBox, spring, damper) -> tuple[list[str], np.ndarray]:
    """The keys and their values at every unit point of one pair's box (a gas strut: its
    rate 0, its F1 spread by ``force_tolerance`` on the first axis)."""
    Z = box.Z
    n = len(Z)
    strut = spring.is_strut
    if strut:
        k = np.zeros(n)
        F0 = np.maximum(spring.preload * (1 + Z[:, 0] * spring.force_tolerance), 0.0)
        own = dict(zip(STRUT_KEYS, (spring.stroke, spring.progression, spring.friction)))
    else:
        k = np.maximum(spring.rate * (1 + Z[:, 0] * spring.rate_tolerance), 0.0)
        F0 = np.full(n, spring.preload)
        own = dict(zip(STRUT_KEYS, box.strut))
    l0 = np.maximum(spring.free_length + Z[:, 1] * spring.free_length_tolerance, 1e-4)
    c = np.maximum(damper.c * (1 + Z[:, 2] * damper.c_tolerance), 0.0)
    dash = damper.kind == "dashpot"
    cols = {"design.spring_k": k, "design.spring_rest_length": l0,
            "design.spring_kind": np.full(n, KINDS[spring.spring_kind]),
            "design.spring_preload": F0,
            "design.damper_c": c if dash else np.zeros(n),
            "design.rotary_damper_c": np.zeros(n) if dash else c,
            **{key: np.full(n, float(v)) for key, v in own.items()}}
    around = {PRELOAD: spring.preload, **(own if strut else {})}
    if box.other.dim:
        V = box.other.values(Z[:, 3:])
        for j, key in enumerate(box.other.keys):
            if key == PRELOAD and strut:      # its own spread (force_tolerance) stands
                continue
            if key in around:           # a spread around this part's value
                x = around[key]
                h = box.other.half[j] / box.other.nominal[j] * x \
                    if box.other.relative[j] and box.other.nominal[j] else box.other.half[j]
                cols[key] = np.maximum(x + Z[:, 3 + j] * h, 0.0)
            else:
                cols[key] = V[:, j]
    return list(cols), np.column_stack(list(cols.values()))


def pivot_config(cfg: Config, damper) -> Config:
    """The config a damper is run in: its pivot for a rotary damper (on a hinge lid, whatever
    the catalog's pivot, the hinge H: the lid's only pivot), its temperature coefficient when
    the catalog gives one, no spring limits."""
    cfg = without_limits(cfg)
    pivot = "H" if cfg.geometry.mechanism == "hinge" else damper.pivot
    if damper.kind == "rotary" and cfg.design.rotary_damper_pivot != pivot:
        cfg = cfg.replace(design={"rotary_damper_pivot": pivot})
    beta = getattr(damper, "temperature_coeff", None)
    if beta is not None and cfg.design.damper_temperature_coeff != beta:
        cfg = cfg.replace(design={"damper_temperature_coeff": beta})
    return cfg


def damper_group(damper) -> tuple:
    """What of a damper makes its own config (:func:`pivot_config`): a rotary damper's pivot,
    its temperature coefficient."""
    return (damper.pivot if damper.kind == "rotary" else None,
            getattr(damper, "temperature_coeff", None))


def run_pairs(cfg: Config, box: PairBox, pairs: list, rows: list | None = None) -> dict:
    """Every row of every pair ``(spring, damper)``: the metric columns of
    :func:`softclose.robust.evaluate.evaluate`, ``reason`` and ``feasible`` with the parts'
    length limits checked, and the row's lower and upper length limit; rows pair-major.
    ``rows``: per pair, the rows of the box it is run at (indices into ``box.Z``; None:
    every row); the opening effort is computed at its nominal row when it is among them."""
    n = box.points
    every = np.arange(n)
    rows = [every] * len(pairs) if rows is None else [np.asarray(r, int) for r in rows]
    starts = np.r_[0, np.cumsum([len(r) for r in rows])]
    total = int(starts[-1])
    groups: dict = {}
    for i, (s, d) in enumerate(pairs):
        if len(rows[i]):
            groups.setdefault(damper_group(d), []).append(i)
    out = None
    for _, idx in groups.items():
        c = pivot_config(cfg, pairs[idx[0]][1])
        keys, X = None, []
        for i in idx:
            keys, x = pair_rows(box, *pairs[i])
            X.append(x if len(rows[i]) == n else x[rows[i]])
        mine = np.concatenate([rows[i] for i in idx])
        cols = _evaluate(c, box, keys, np.vstack(X), mine)
        if out is None:
            out = {k: np.empty((total,) + np.shape(v)[1:], np.asarray(v).dtype)
                   for k, v in cols.items()}
            out["reason"] = np.empty(total, dtype=object)
        at = np.concatenate([np.arange(starts[i], starts[i + 1]) for i in idx])
        for k, v in cols.items():
            out[k][at] = v
    if out is None:
        return _no_rows()
    counts = np.diff(starts)
    lo = np.repeat([np.nan if s.min_length is None or s.is_strut else s.min_length
                    for s, _ in pairs], counts)
    hi = np.repeat([np.nan if s.max_length is None else s.max_length for s, _ in pairs],
                   counts)
    with np.errstate(invalid="ignore"):
        bad = (out["min_spring_length"] < lo * (1 - LIMIT_RTOL)) \
            | (out["max_spring_length"] > hi * (1 + LIMIT_RTOL)) | (out["status"] == StrokeStatus.OUT_OF_RANGE)
    numerical = np.isin(out["status"], NUMERICAL_FAILURES)
    out["reason"] = np.asarray(out["reason"], dtype=object)
    out["reason"][bad] = RANGE
    out["reason"][numerical] = "not integrated"
    out["feasible"] = out["reason"] == ""
    out["lo"], out["hi"] = lo, hi
    return out


def _no_rows() -> dict:
    """:func:`run_pairs`'s columns of no row."""
    return {"feasible": np.zeros(0, bool), "reason": np.zeros(0, object),
            "lo": np.zeros(0), "hi": np.zeros(0)}


def _evaluate(c: Config, box: PairBox, keys, X: np.ndarray, rows: np.ndarray) -> dict:
    """:func:`softclose.robust.evaluate.evaluate` of the rows X (rows ``rows`` of the box,
    of one pair after another), each row at its temperature. The opening effort (statics
    over 241 angles a row, a fifth of the screen's time) is computed at every row only
    where it is a constraint (``optimise.opening_force_max``: ``evaluate`` computes it
    then); else at each pair's nominal row, which reports it."""
    Trow = None if box.Ts is None else box.Ts[rows]
    cols = _at_temperatures(c, box, keys, X, Trow, False)
    nominal = np.flatnonzero(rows == box.corners) if box.corners else np.zeros(0, int)
    if c.optimise.opening_force_max is not None or not len(nominal):
        return cols
    part = _at_temperatures(c, box, keys, X[nominal], None if Trow is None else Trow[nominal],
                            True)
    cols["opening_force"][nominal] = part["opening_force"]
    return cols


def _at_temperatures(c: Config, box: PairBox, keys, X: np.ndarray, Trow, opening: bool
                     ) -> dict:
    """:func:`softclose.robust.evaluate.evaluate` of the rows X, row i at the temperature
    Trow[i] (None: the config's)."""
    if Trow is None:
        return evaluate(c, keys, X, explain=False, opening=opening)
    cols: dict = {}
    for T in box.temperatures:
        m = Trow == T
        if not m.any():
            continue
        part = evaluate(at_temperature(c, T), keys, X[m], explain=False, opening=opening)
        for k, v in part.items():
            v = np.asarray(v)
            if k not in cols:
                cols[k] = np.empty((len(X),) + v.shape[1:], v.dtype)
            cols[k][m] = v
    return cols


def limiting_temperature(box: PairBox, cols: dict, opt, p: int, fail_row: int) -> float:
    """The temperature that limits pair ``p``: the one of the corner it fails at
    (``fail_row``), else of its corner with the smallest constraint margin
    (:func:`softclose.robust.stats.margins`)."""
    if 0 <= fail_row < box.corners:
        return float(box.Ts[fail_row])
    rows = slice(p * box.points, p * box.points + box.corners)
    m = margins({k: cols[k][rows] for k in ("closing_time", "holding_moment",
                                            "theta_dot_max", "closed")}, opt)
    return float(box.Ts[int(np.argmin(m))])


def summarise(box: PairBox, cols: dict, npairs: int) -> dict:
    """Per pair: feasible at every corner, yield over the samples, worst J (over corners,
    nominal and samples; inf when a row did not close), the nominal metrics, why it fails
    (the most frequent reason over corners, else samples) and at which row."""
    n, nc = box.points, box.corners
    F = cols["feasible"].reshape(npairs, n)
    J = cols["objective"].reshape(npairs, n)
    R = cols["reason"].reshape(npairs, n)
    corners_ok = F[:, :nc].all(axis=1)
    corner_count = F[:, :nc].sum(axis=1)
    nT = max(len(box.temperatures), 1)        # (a sample counts when it holds at every T)
    yld = F[:, nc + 1:].reshape(npairs, nT, -1).all(axis=1).mean(axis=1) if box.samples \
        else corners_ok.astype(float)
    with np.errstate(invalid="ignore"):
        worst = np.where(np.isnan(J).any(axis=1), np.inf, np.nanmax(np.where(
            np.isnan(J), -np.inf, J), axis=1))
    why, at = [], []
    for p in range(npairs):
        fail = np.flatnonzero(~F[p])
        if not len(fail):
            why.append("")
            at.append(-1)
            continue
        deciding = fail[fail < nc] if (fail < nc).any() else fail   # corners, else samples
        reasons, counts = np.unique(R[p, deciding].astype(str), return_counts=True)
        r = reasons[np.argmax(counts)]
        why.append(str(r))
        at.append(int(deciding[R[p, deciding] == r][0]))
    nominal = {k: cols[k].reshape(npairs, n)[:, nc] for k in
               ("closing_time", "impact_tip_speed", "peak_tip_speed", "holding_moment",
                "opening_force", "min_spring_length", "max_spring_length", "objective")}
    return {"corners_ok": corners_ok, "corner_count": corner_count, "yield": yld,
            "worst_objective": worst, "reason": why, "fail_row": at,
            "nominal": nominal}


def reason_text(box: PairBox, cols: dict, p: int, row: int, reason: str, spring, damper,
                range_text: str = "") -> str:
    """One line: why pair ``p`` fails at its row ``row`` (a point of its box);
    ``range_text``: where the spring leaves its valid range there (:func:`range_texts`)."""
    r = p * box.points + row
    if row == box.corners:
        what = "at the nominal point"
    else:
        what = ("at the corner " if row < box.corners else "at the sample ") \
            + box.row_label(row, spring, damper)
    if reason in ("too slow", "too fast"):
        return f"{reason}: closes in {cols['closing_time'][r]:.4g} s {what}"
    if reason == "not held shut":
        return f"not held shut: holding moment {cols['holding_moment'][r]:.4g} N m {what}"
    if reason == "not closed" and np.isfinite(cols["theta_min"][r]):
        return (f"not closed: the lid stops at theta = {np.degrees(cols['theta_min'][r]):.3g} "
                f"deg {what}")
    if reason == "too heavy to open":
        return f"too heavy to open: {cols['opening_force'][r]:.4g} N {what}"
    if reason == RANGE:
        return f"{range_text or RANGE} ({what})"
    return f"{reason} {what}"


def range_texts(cfg, box: PairBox, items: list) -> list[str]:
    """Where the spring leaves its valid range, for each ``(spring, damper, row)`` of
    ``items`` (the kernel's stroke at that point of the pair's box,
    :func:`softclose.simulation.statics.out_of_range`, which names the angle); one batch per pivot and
    part limits."""
    out = [RANGE] * len(items)
    groups: dict = {}
    for n, (s, d, row) in enumerate(items):
        key = (damper_group(d), None if s.is_strut else s.min_length, s.max_length,
               None if box.Ts is None else float(box.Ts[row]))
        groups.setdefault(key, []).append(n)
    for (_, lo, hi, _), idx in groups.items():
        c0 = box.config_at(pivot_config(cfg, items[idx[0]][1]), items[idx[0]][2])
        rows, keys = [], None
        for n in idx:
            s, d, row = items[n]
            keys, X = pair_rows(box, s, d)
            rows.append(X[row])
        X = np.array(rows)
        slow = slow_keys(keys)
        batches = [(c0, np.arange(len(idx)))] if not slow else [
            (c0.update({k: float(X[j, keys.index(k)]) for k in slow}), np.array([j]))
            for j in range(len(idx))]
        for c, js in batches:
            P = param_rows(c, len(js), keys, X[js])
            m = X[js, keys.index(LID_MASS)] if LID_MASS in keys else None
            sim = simulator(c)
            res = sim.run_batch(P, lid_mass=m, points=point_values(keys, X[js]))
            _, why = statics.out_of_range(statics.table_coordinate(sim.table,
                                                                   res.get("points")),
                                          limits_view(c, lo, hi), P, res)
            for j, w in zip(js, why):
                if w:
                    out[idx[j]] = str(w)
    return out
