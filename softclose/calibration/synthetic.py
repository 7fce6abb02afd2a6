"""Synthetic measurements: a closing stroke of known parameters, sampled like a camera or a
phone's gyroscope, with noise. The truth comes from the adaptive reference
(:class:`softclose.simulation.reference.Reference`, CVODES on the exact equation of motion), not from the
fixed-step integrator the fit uses, so a fit that recovers it is checked against a second
formulation. Used by the tests, the calibration study and the example data file.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import NumericalError
from ..files import replacing
from ..simulation.reference import Reference
from ..model.lid import LidModel
from ..problem import resolve


def stroke_samples(cfg, rate: float = 120.0, before: float = 0.1, after: float = 0.1,
                   phase: float = 0.37):
    """The exact stroke of ``cfg`` on a camera's time grid: ``(t, theta, theta_dot,
    t_release, t_closed)`` (s, rad, rad/s). The lid rests at ``stroke.theta0_deg`` for
    ``before`` seconds, is released at ``t_release`` (``phase`` of a frame after a frame),
    closes at ``t_closed`` and rests on the rim for ``after`` seconds."""
    case = resolve(cfg)
    model = LidModel.cached(case)
    ref = Reference(model, case.solver.reference_tol)
    p = model.params()
    res = ref.simulate(p, case)
    if not res.closed:
        raise NumericalError("the synthetic stroke does not close: choose other parameters")
    T = float(res.closing_time)
    dt = 1.0 / rate
    t_rel = (math.floor(before * rate) + phase) * dt
    n = int(math.ceil((t_rel + T + after) * rate))
    t = np.arange(n) * dt
    th = np.full(n, cfg.stroke.theta0)
    thd = np.zeros(n)
    x, tx = np.array([cfg.stroke.theta0, 0.0]), t_rel
    ref._moving = -1.0
    for i in np.flatnonzero(t > t_rel):
        if t[i] >= t_rel + T:
            th[i], thd[i] = cfg.stroke.theta_closed, 0.0
            continue
        x = ref.flow(x, p, t[i] - tx)
        tx = t[i]
        th[i], thd[i] = x
    return t, th, thd, t_rel, t_rel + T


def angle_track(cfg, rate: float = 120.0, noise_deg: float = 0.15, seed: int = 0, **kw):
    """A video tracker's angle track of the stroke of ``cfg``: a table (dict of columns)
    ``time_s, theta_deg`` with Gaussian noise of ``noise_deg`` on every sample."""
    t, th, _, _, _ = stroke_samples(cfg, rate, **kw)
    rng = np.random.default_rng(seed)
    return {"time_s": t, "theta_deg": np.degrees(th) + noise_deg * rng.standard_normal(len(t))}


def gyroscope_track(cfg, rate: float = 100.0, noise: float = 0.01, bias: float = 0.02,
                    axis: str = "z", sign: float = 1.0, seed: int = 0, **kw):
    """A phone sensor app's gyroscope export of the stroke of ``cfg`` (the phone lies on the
    lid): columns ``"Time (s)"`` and ``"Gyroscope x/y/z (rad/s)"``, the lid's rate on ``axis``
    times ``sign`` plus a constant ``bias`` and white noise (rad/s), the other axes noise."""
    t, _, thd, _, _ = stroke_samples(cfg, rate, **kw)
    rng = np.random.default_rng(seed)
    out = {"Time (s)": t}
    for a in "xyz":
        w = sign * thd + bias if a == axis else 0.003 * rng.standard_normal(len(t))
        out[f"Gyroscope {a} (rad/s)"] = w + (noise * rng.standard_normal(len(t))
                                             if a == axis else 0.0)
    return out


def write_csv(table: dict, path) -> None:
    """A table of columns as CSV (the header quoted as a phone app writes it)."""
    names = list(table)
    cols = [np.asarray(table[k], float) for k in names]
    with replacing(path) as tmp, open(tmp, "w") as f:
        f.write(",".join(f'"{k}"' if " " in k else k for k in names) + "\n")
        for row in zip(*cols):
            f.write(",".join(f"{v:.9g}" for v in row) + "\n")


__all__ = ["stroke_samples", "angle_track", "gyroscope_track", "write_csv"]
