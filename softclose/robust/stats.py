"""Small statistics of Monte Carlo samples: the yield's confidence interval, percentiles,
and how far each sample is from breaking a constraint."""

from __future__ import annotations

import math

import numpy as np

#: confidence level of every interval reported
CONFIDENCE = 0.95
#: how the yield's interval is computed (said in every report)
CI_METHOD = "Wilson score interval, 95 %"
#: the percentiles reported (of closing time and impact speeds)
PERCENTILES = (1, 50, 99)


def _z(conf: float) -> float:
    """Two-sided standard-normal quantile (1.959964 for 95 %), by bisection on erf."""
    target = conf
    lo, hi = 0.0, 10.0
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if math.erf(mid / math.sqrt(2)) < target else (lo, mid)
    return 0.5 * (lo + hi)


def wilson(k: int, n: int, conf: float = CONFIDENCE) -> tuple[float, float]:
    """Wilson score interval of a binomial proportion k/n.

    Chosen over the normal-approximation (Wald) interval because yields sit near 1, where
    Wald collapses to zero width at k = n; Wilson stays inside [0, 1] and keeps close to its
    nominal coverage there (Brown, Cai & DasGupta, Statist. Sci. 16, 2001).
    """
    if n <= 0:
        return (0.0, 1.0)
    z = _z(conf)
    p = k / n
    den = 1 + z * z / n
    centre = (p + z * z / (2 * n)) / den
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / den
    return (max(0.0, centre - half), min(1.0, centre + half))


def percentiles(values, qs=PERCENTILES) -> dict[str, float | None]:
    """Sample percentiles without interpolation (each is a sample value; +inf stays +inf,
    e.g. the closing time of a lid that did not close). Empty input gives None."""
    v = np.asarray(values, float)
    v = v[~np.isnan(v)]
    if not len(v):
        return {f"p{q}": None for q in qs}
    out = np.percentile(v, qs, method="inverted_cdf")
    return {f"p{q}": float(x) for q, x in zip(qs, out)}


def margins(cols: dict, opt) -> np.ndarray:
    """Each sample's smallest relative slack over the constraints (< 0: infeasible).

    closing time against its window (relative to closing_time_max), holding moment against
    holding_moment_min (relative to max(|holding_moment_min|, 1e-3 N m)), a rebound
    (theta'_max > 0) has -theta'_max (rad/s); a lid that did not close has -inf.
    """
    ct = np.asarray(cols["closing_time"], float)
    m = (opt.closing_time_max - ct) / opt.closing_time_max
    if opt.closing_time_min > 0:
        m = np.minimum(m, (ct - opt.closing_time_min) / opt.closing_time_max)
    hm = np.asarray(cols["holding_moment"], float)
    m = np.minimum(m, (hm - opt.holding_moment_min) / max(abs(opt.holding_moment_min), 1e-3))
    tdm = np.asarray(cols["theta_dot_max"], float)
    m = np.where(tdm > 0, np.minimum(m, -tdm), m)
    m = np.where(np.asarray(cols["closed"], bool) & np.isfinite(m), m, -np.inf)
    return m
