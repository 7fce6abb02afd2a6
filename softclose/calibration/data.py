"""Reading a measured closing stroke and finding the stroke in it.

A file is a CSV (comma, semicolon or tab separated; lines starting with # are comments) with
a header row: a time column
(``time_s``, or a phone sensor app's ``"Time (s)"``) and one measured quantity --
``theta_deg``/``theta_rad`` (a video tracker's angle track) or ``theta_dot_rad_s``/a phone's
``"Gyroscope x (rad/s)"`` (an angular rate; the axis by ``axis``, else the axis that moves
most). Bad files are refused with one line naming the file and the line (:class:`ConfigError`).

:func:`locate` then finds the stroke in the record: the noise level (from the record's
fourth differences, which a smooth stroke leaves alone), the rest before the release, the
first sample surely moving, an estimate of the release time and angle (the onset of a fall
from rest: the drop grows as (t - t_r)^2, the rate as (t - t_r)), a gyroscope's bias and the
sign of its axis, and the closing (the rim reached, or the rate dropping to rest): the
samples after it are left out.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import ConfigError
from ..files import read_text

TIME_COLUMNS = ("time_s", "Time (s)")
ANGLE_COLUMNS = {"theta_deg": math.pi / 180.0, "theta_rad": 1.0}
RATE_COLUMNS = ("theta_dot_rad_s",)
#: fewest samples a stroke must have between release and closing
MIN_SAMPLES = 10
#: samples of the rest before a release that are kept (their mean pins the release angle)
REST_KEEP = 30


@dataclass(frozen=True)
class Record:
    """One file as read: times (s), values (rad or rad/s), what they are."""

    path: str
    kind: str                 # "angle" or "rate"
    column: str
    t: np.ndarray
    y: np.ndarray
    lines: np.ndarray         # the file's line number of every sample


def _sniff(header: str) -> str:
    for d in ("\t", ";", ","):
        if d in header:
            return d
    return ","


def read(path, axis: str | None = None) -> Record:
    """Read one data file (see the module docstring); ``axis`` picks a gyroscope's axis."""
    text = read_text(path, kind="a data file, CSV")
    return parse(text, str(path), axis)


def record_of(data, axis: str | None = None, name: str = "data") -> Record:
    """A :class:`Record` from a path, a table of columns (dict or DataFrame) or a Record."""
    if isinstance(data, Record):
        return data
    if isinstance(data, (str, Path)):
        return read(data, axis)
    if hasattr(data, "to_dict") and hasattr(data, "columns"):     # a pandas DataFrame
        data = {c: data[c].to_numpy() for c in data.columns}
    if isinstance(data, dict):
        names = list(data)
        cols = [np.asarray(data[k], float).ravel() for k in names]
        lines = [",".join(f'"{k}"' for k in names)]
        lines += [",".join(repr(float(v)) for v in row) for row in zip(*cols)]
        return parse("\n".join(lines), name, axis)
    raise ConfigError(f"{name}: expected a CSV path or a table of columns, got "
                      f"{type(data).__name__}")


def parse(text: str, path: str, axis: str | None = None) -> Record:
    """Parse a data file's text (``path``: how messages name it)."""
    lines_all = text.splitlines()
    # comment lines (starting with #) are skipped; the file's line numbers are kept
    numbered = [(n, ln) for n, ln in enumerate(lines_all, start=1)
                if not ln.lstrip().startswith("#")]
    if not numbered or not any(ln.strip() for _, ln in numbered):
        raise ConfigError(f"{path}: the data file is empty")
    while not numbered[0][1].strip():
        numbered.pop(0)
    head_line = numbered[0][0]
    rows = list(csv.reader([ln for _, ln in numbered], delimiter=_sniff(numbered[0][1])))
    row_lines = [n for n, _ in numbered]
    header = [h.strip() for h in rows[0]]
    tcol = next((c for c in TIME_COLUMNS if c in header), None)
    if tcol is None:
        raise ConfigError(f"{path}:{head_line}: no time column (expected one of "
                          f"{', '.join(repr(c) for c in TIME_COLUMNS)}; found "
                          f"{', '.join(repr(h) for h in header) or 'nothing'})")
    gyro = {h.split()[1].lower(): h for h in header
            if h.startswith("Gyroscope ") and len(h.split()) >= 2}
    scale, kind = 1.0, "angle"
    if axis is not None and axis not in "xyz":
        raise ConfigError(f"--axis {axis}: expected x, y or z")
    if axis is not None:
        if axis not in gyro:
            raise ConfigError(f"{path}:{head_line}: --axis {axis}: no column 'Gyroscope {axis} (rad/s)'")
        ycol, kind = gyro[axis], "rate"
    else:
        ycol = next((c for c in ANGLE_COLUMNS if c in header), None)
        if ycol is not None:
            scale = ANGLE_COLUMNS[ycol]
        else:
            ycol = next((c for c in RATE_COLUMNS if c in header), None)
            kind = "rate"
            if ycol is None and gyro:
                ycol = None      # the axis that moves most, chosen below
            elif ycol is None:
                raise ConfigError(
                    f"{path}:{head_line}: no measured column (expected theta_deg, theta_rad, "
                    f"theta_dot_rad_s or a gyroscope axis 'Gyroscope x (rad/s)'; found "
                    f"{', '.join(repr(h) for h in header)})")
    cols = [tcol] + ([ycol] if ycol else list(gyro.values()))
    idx = [header.index(c) for c in cols]
    data, lines = [], []
    for n, row in zip(row_lines[1:], rows[1:]):
        if not row or all(not c.strip() for c in row):
            continue
        vals = []
        for c, i in zip(cols, idx):
            cell = row[i].strip() if i < len(row) else ""
            try:
                v = float(cell)
            except ValueError:
                v = math.nan
            if not math.isfinite(v):
                raise ConfigError(f"{path}:{n}: column {c!r}: {cell or 'empty'!r} is not a "
                                  "finite number (remove or repair the row)")
            vals.append(v)
        data.append(vals)
        lines.append(n)
    if len(data) < 2:
        raise ConfigError(f"{path}: {len(data)} data rows; a stroke needs at least "
                          f"{MIN_SAMPLES}")
    a = np.array(data)
    t = a[:, 0]
    bad = np.flatnonzero(np.diff(t) <= 0)
    if len(bad):
        i = bad[0] + 1
        raise ConfigError(f"{path}:{lines[i]}: time {t[i]:g} s does not increase (after "
                          f"{t[i - 1]:g} s on line {lines[i - 1]})")
    if ycol is None:       # the gyroscope axis with the largest spread
        j = int(np.argmax(a[:, 1:].std(axis=0))) + 1
        ycol = cols[j]
        y = a[:, j]
    else:
        y = a[:, 1] * scale
    return Record(str(path), kind, ycol, t, y, np.array(lines))


def noise_level(y: np.ndarray) -> float:
    """Standard deviation of white noise on a smooth signal: from the median absolute fourth
    difference (var of a 4th difference of white noise: 70 sigma^2)."""
    if len(y) < 6:
        return 0.0
    d4 = np.diff(y, 4)
    return float(np.median(np.abs(d4 - np.median(d4))) / 0.6745 / math.sqrt(70.0))


@dataclass(frozen=True)
class Stroke:
    """What :func:`locate` found in a record: the samples fitted and the first guesses."""

    record: Record
    sign: float               # +1, or -1 when a gyroscope's axis points the other way
    sigma: float              # noise (rad or rad/s)
    rest: np.ndarray          # indices of rest samples before the release that are fitted
    window: np.ndarray        # indices where the release may lie before (prediction from rest)
    moving: np.ndarray        # indices of the samples surely moving, up to the closing
    t_release: float
    t_release_bounds: tuple
    theta_release: float
    bias: float               # gyroscope bias (rad/s; 0 for angles)
    theta_closed: float       # the rim (rad)
    t_closed: float           # estimated closing time (s)

    @property
    def samples_used(self) -> int:
        return len(self.rest) + len(self.window) + len(self.moving)

    @property
    def y(self) -> np.ndarray:
        """The measured values with a gyroscope's sign turned to theta's."""
        return self.record.y * self.sign


def locate(rec: Record, theta_closed: float) -> Stroke:
    """Find the stroke in ``rec``; ``theta_closed`` (rad) the rim of the config."""
    t, y = rec.t, rec.y
    n = len(t)
    sigma = noise_level(y)
    if rec.kind == "rate":
        return _locate_rate(rec, sigma, theta_closed)
    first = np.median(y[:5])
    thresh = max(8 * sigma, math.radians(0.3))
    away = np.flatnonzero(np.abs(y - first) > thresh)
    if not len(away):
        raise ConfigError(f"{rec.path}: the lid never moved (the angle stays within "
                          f"{math.degrees(thresh):.2g} deg of {math.degrees(first):.4g} deg)")
    k1 = int(away[0])
    theta_r = float(np.median(y[:k1])) if k1 >= 3 else float(y[0])
    # the closing: the first sample at the rim (the record's end level if it rests there)
    tail = y[-8:]
    rim = float(np.median(tail)) if len(tail) >= 5 and np.ptp(tail) < 10 * sigma + 1e-9 \
        and np.median(tail) < theta_r - thresh else theta_closed
    below = np.flatnonzero(y[k1:] <= rim + 2 * sigma + 1e-12)
    kc = k1 + int(below[0]) if len(below) else n
    # the release: sqrt(drop) grows linearly in t - t_r over the first moving samples
    drop = theta_r - y
    dt = float(np.median(np.diff(t)))
    sel = [k for k in range(k1, min(kc, k1 + 6)) if drop[k] > 0]
    t_r = t[k1] - dt
    if len(sel) >= 2:
        A = np.vstack([t[sel], np.ones(len(sel))]).T
        a, b = np.linalg.lstsq(A, np.sqrt(drop[sel]), rcond=None)[0]
        if a > 0:
            t_r = float(-b / a)
    return _stroke(rec, 1.0, sigma, k1, kc, t_r, theta_r, 0.0, rim)


def _locate_rate(rec: Record, sigma: float, theta_closed: float) -> Stroke:
    t, y = rec.t, rec.y
    n = len(t)
    first = float(np.median(y[:5]))
    thresh = max(8 * sigma, 0.05)
    away = np.flatnonzero(np.abs(y - first) > thresh)
    if not len(away):
        raise ConfigError(f"{rec.path}: the lid never moved (the rate stays within "
                          f"{thresh:.2g} rad/s of {first:.3g} rad/s)")
    k1 = int(away[0])
    bias = float(np.median(y[:k1])) if k1 >= 3 else 0.0
    w = y - bias
    peak = k1 + int(np.argmax(np.abs(w[k1:])))
    sign = -1.0 if w[peak] > 0 else 1.0      # a closing lid turns with theta' < 0
    w = w * sign
    # the closing: the rate back at rest (within 4 sigma) for 3 samples after the peak
    rest = np.abs(w) < max(4 * sigma, 0.02)
    kc = n
    for k in range(peak, n - 2):
        if rest[k] and rest[k + 1] and rest[k + 2]:
            kc = k
            break
    dt = float(np.median(np.diff(t)))
    sel = [k for k in range(k1, min(kc, k1 + 4))]
    t_r = t[k1] - dt
    if len(sel) >= 2:
        a, b = np.polyfit(t[sel], w[sel], 1)
        if a < 0:
            t_r = float(-b / a)
    # the release angle: the rim minus the rate integrated over the stroke (trapezoids; the
    # closing half a sample after the last moving sample)
    k_end = kc - 1
    tt = np.r_[t_r, t[k1:kc]]
    ww = np.r_[0.0, w[k1:kc]]
    travel = float(np.sum(0.5 * (ww[1:] + ww[:-1]) * np.diff(tt))) + w[k_end] * dt / 2
    theta_r = theta_closed - travel
    return _stroke(rec, sign, sigma, k1, kc, t_r, theta_r, bias * sign, theta_closed)


def _stroke(rec, sign, sigma, k1, kc, t_r, theta_r, bias, rim) -> Stroke:
    t = rec.t
    dt = float(np.median(np.diff(t)))
    if kc - k1 < MIN_SAMPLES:
        line = rec.lines[min(kc, len(t) - 1)]
        raise ConfigError(f"{rec.path}:{line}: only {kc - k1} samples between the release "
                          f"and the closing (line {rec.lines[k1]}..{line}); a fit needs at "
                          f"least {MIN_SAMPLES}: record faster or a slower stroke")
    # the release may lie up to 2 frames before the estimate (and never after the first
    # sample surely moving): the samples in between are predicted from the release
    lo = min(t_r, t[k1]) - 2.5 * dt
    j0 = int(np.searchsorted(t, lo, side="right"))
    j0 = max(0, min(j0, k1))
    window = np.arange(j0, k1)
    rest = np.arange(max(0, j0 - REST_KEEP), j0)
    lo_b = t[j0 - 1] if j0 > 0 else t[0] - 3 * dt
    t_r = min(max(t_r, lo_b + 1e-9), t[k1] - 1e-9)
    return Stroke(rec, sign, max(sigma, 1e-12), rest, window, np.arange(k1, kc), float(t_r),
                  (float(lo_b), float(t[k1])), float(theta_r), bias, float(rim),
                  float(t[kc - 1] + dt / 2 if kc <= len(t) else t[-1]))


__all__ = ["Record", "Stroke", "read", "parse", "record_of", "locate", "noise_level", "MIN_SAMPLES"]
