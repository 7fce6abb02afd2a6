"""Fitting the lid's model to measured strokes: the problem, the first guesses, the solve and
the statistics of the estimates.

:func:`fit` reads the records, finds each stroke (:func:`softclose.calibration.data.locate`), guesses
the fitted keys by the equation error (the measured theta'' against the model's at the
smoothed measured states: a few Gauss-Newton steps, exact in one step for keys the equation
is affine in -- masses, inertias, dampers, friction, a spring's rate and preload), solves the
multiple-shooting least squares (:mod:`softclose.calibration.nlp`) from the data's states, and
derives the statistics:

- covariance of the estimates: s^2 times the parameter block of the inverse of the KKT matrix
  [[J^T J, G^T], [G, 0]] (J the Jacobian of the weighted residuals, G of the continuity
  constraints; casiopeia's estimate), s^2 = r^T r / (m - n) with m residuals and n the
  unknowns the constraints leave free (keys, release angles and times, biases);
- 95 % intervals: value +- t(0.975, m - n) std;
- correlations, and the identifiability verdict: a variance inflation factor (the diagonal
  of the inverse correlation matrix, i.e. of the Fisher information normalised by the
  variances) above :data:`VIF_MAX` means a combination of keys the data cannot separate --
  for a pair, a correlation beyond 0.95 --; the eigenvector of the correlation matrix's
  smallest eigenvalue names the keys. Such estimates may look precise under the model's
  own noise, but any error of the fixed keys (a spring rate off by 1 %) moves them by the
  inflation factor: they are reported, not trusted.
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np

from ..errors import ConfigError
from ..model.lid import LidModel
from .data import locate, record_of
from .equation import bounds_of, check_keys, fit_ode, value_of
from .nlp import DEFECT_MAX, get_nlp, substeps
from ..optimiser.ipopt import CONVERGED
from .result import UNDETERMINED, VIF_MAX  # noqa: F401  (the verdict's thresholds)
from ..present.progress import Progress
from ..interrupt import check
from .result import FitResult, StrokeFit
from ..problem import resolve



def t_quantile(nu: float, z: float = 1.959963984540054) -> float:
    """Student's t quantile (0.975 by default) by the Cornish-Fisher expansion (to 1e-4
    from 5 degrees of freedom on)."""
    if not nu > 0:
        return math.inf
    return z + (z ** 3 + z) / (4 * nu) + (5 * z ** 5 + 16 * z ** 3 + 3 * z) / (96 * nu ** 2) \
        + (3 * z ** 7 + 19 * z ** 5 + 17 * z ** 3 - 15 * z) / (384 * nu ** 3)


def _smooth(t, y, idx, half: int = 10, deg: int = 3):
    """Local polynomial fits at the samples ``idx`` (their neighbours within the same set):
    (value, first and second derivative)."""
    v, d1, d2 = [], [], []
    lo, hi = idx[0], idx[-1]
    for k in idx:
        a, b = max(lo, k - half), min(hi, k + half)
        if b - a < deg + 1:
            a, b = max(lo, b - deg - 2), min(hi, a + deg + 2)
        tt = t[a:b + 1] - t[k]
        c = np.polyfit(tt, y[a:b + 1], min(deg, len(tt) - 1))[::-1]
        c = np.r_[c, 0.0, 0.0]
        v.append(c[0])
        d1.append(c[1])
        d2.append(2 * c[2])
    return np.array(v), np.array(d1), np.array(d2)


def measured_states(stroke):
    """The states (theta, theta') and theta'' at the moving samples, smoothed from the data."""
    t, y, mv = stroke.record.t, stroke.y, stroke.moving
    if stroke.record.kind == "angle":
        return _smooth(t, y, mv)
    w = y - stroke.bias
    wv, wd, _ = _smooth(t, w, mv, deg=1)
    tt = np.r_[stroke.t_release, t[mv]]
    ww = np.r_[0.0, w[mv]]
    th = stroke.theta_release + np.r_[0.0, np.cumsum(0.5 * (ww[1:] + ww[:-1]) * np.diff(tt))]
    return th[1:], w[mv], wd


def equation_error_guess(model, cfg, keys, strokes, u0, lo, hi, iterations: int = 8):
    """First guesses of the keys: Gauss-Newton on theta''(measured) - theta''(model) at the
    smoothed measured states (relative steps limited to x3 per iteration)."""
    f = fit_ode(model, cfg, keys)
    xs, a = [], []
    for s in strokes:
        th, thd, thdd = measured_states(s)
        xs.append(np.vstack([th, thd]))
        a.append(thdd)
    X, A = np.hstack(xs), np.concatenate(a)
    u = ca.SX.sym("u", len(keys))
    e = A - f.map(X.shape[1])(X, ca.repmat(u, 1, X.shape[1]))[1, :].T
    F = ca.Function("ee", [u], [e, ca.jacobian(e, u)])
    x = np.array(u0, float)
    ref = np.where(np.abs(x) > 0, np.abs(x), 1.0)
    for _ in range(iterations):
        r, Jm = (np.asarray(v) for v in F(x))
        r = r.ravel()
        if not np.all(np.isfinite(r)) or not np.all(np.isfinite(Jm)):
            break
        Js = Jm * ref
        step = -np.linalg.lstsq(Js, r, rcond=1e-10)[0] * ref
        big = np.max(np.abs(step) / np.maximum(np.abs(x), ref))
        if big > 2.0:
            step *= 2.0 / big
        x = np.clip(x + step, lo, hi)
    return x


#: most samples a fit takes (all records): the NLP has two states a sample
MAX_SAMPLES = 20000
#: largest KKT matrix (rows) whose pseudo-inverse is tried when the sparse solve fails
DENSE_MAX = 3000


def kkt_columns(J, G, want):
    """Columns ``want`` of the inverse of the KKT matrix [[J'J, G'], [G, 0]] at those rows
    (scipy sparse J, G): the parameter block of the estimates' covariance (times s^2).
    Sparse LU; a singular matrix (keys the data cannot tell apart at all) gives the
    pseudo-inverse's when small, else NaN."""
    import warnings

    import scipy.sparse as sp
    import scipy.sparse.linalg as spla
    nw, ng = J.shape[1], G.shape[0]
    K = sp.bmat([[J.T @ J, G.T], [G, None]], format="csc")
    E = np.zeros((nw + ng, len(want)))
    E[want, range(len(want))] = 1.0
    Z = np.full(E.shape, np.nan)
    if not np.all(np.isfinite(K.data)):
        return Z[want, :]
    try:
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("error", spla.MatrixRankWarning)
            Z = np.asarray(spla.spsolve(K, E)).reshape(E.shape)
        if not np.all(np.isfinite(Z)):
            raise np.linalg.LinAlgError
    except (np.linalg.LinAlgError, RuntimeError, spla.MatrixRankWarning):
        Z = np.full(E.shape, np.nan)
        if K.shape[0] <= DENSE_MAX:
            try:
                Z = np.linalg.pinv(K.toarray()) @ E
            except np.linalg.LinAlgError:
                pass
    return Z[want, :]


def _bounds(keys):
    lo, hi = zip(*(bounds_of(k) for k in keys))
    return np.array(lo, float), np.array(hi, float)


def prepare(cfg, data, free, axis=None):
    """(model, keys, strokes) of a fit, checked."""
    keys = check_keys(free)
    if isinstance(data, (str, bytes)) or hasattr(data, "__fspath__") or isinstance(data, dict) \
            or hasattr(data, "columns"):
        data = [data]
    data = list(data)
    if not data:
        raise ConfigError("fit: no data file given")
    records = [record_of(d, axis, f"data[{i}]") for i, d in enumerate(data)]
    model = LidModel.cached(resolve(cfg))
    strokes = [locate(r, cfg.stroke.theta_closed) for r in records]
    used = sum(st.samples_used for st in strokes)
    if used > MAX_SAMPLES:
        raise ConfigError(f"fit: {used} samples in the strokes, above the budget of "
                          f"{MAX_SAMPLES}; keep every n-th sample (a 120 Hz video of a 1 s "
                          "stroke has 120)")
    return model, keys, strokes


def _parameters(stroke, scale):
    t, y = stroke.record.t, stroke.y
    mv = stroke.moving
    pars = [np.array([stroke.sigma]), y[stroke.rest], y[stroke.window], t[stroke.window],
            y[mv], np.diff(t[mv]), np.array([t[mv[0]]])]
    if stroke.record.kind == "rate":
        dt = float(np.median(np.diff(t)))
        sc = max(abs(y[mv[-1]] - stroke.bias) * dt, 4 * stroke.sigma * dt, 1e-6)
        pars.append(np.array([sc]))
    return np.concatenate(pars)


def solve(cfg, data, free, *, axis=None, starts: int = 1, seed: int = 0, prepared=None,
          progress: bool = False):
    """The fit of the keys ``free`` to ``data``: a :class:`softclose.calibration.FitResult`."""
    model, keys, strokes = prepared or prepare(cfg, data, free, axis)
    nk = len(keys)
    lo, hi = _bounds(keys)
    u_cfg = np.array([value_of(cfg, k) for k in keys])
    u_init = equation_error_guess(model, cfg, keys, strokes, u_cfg, lo, hi)
    # the equation error differentiates noise twice: a guess more than a decade from the
    # config's value (when it has one) is not trusted
    with np.errstate(all="ignore"):
        far = (u_cfg != 0) & ~((np.abs(u_init / u_cfg) > 0.1) & (np.abs(u_init / u_cfg) < 10))
    bad = ~np.isfinite(u_init) | far
    u_init[bad] = u_cfg[bad]
    scale = np.where(np.abs(u_cfg) > 0, np.abs(u_cfg),
                     np.where(np.abs(u_init) > 0, np.abs(u_init), 1.0))
    h_move = max(float(np.max(np.diff(s.record.t[s.moving]))) for s in strokes)
    h_rel = max(s.record.t[s.moving[0]] - s.t_release_bounds[0] for s in strokes)
    shapes = tuple((s.record.kind, len(s.rest), len(s.window), len(s.moving)) for s in strokes)
    P = np.concatenate([scale] + [_parameters(s, scale) for s in strokes])
    w0, lbw, ubw = [np.zeros(nk)], [lo / scale], [hi / scale]
    for s in strokes:
        th, thd, _ = measured_states(s)
        v0 = [s.theta_release, s.t_release] + ([s.bias] if s.record.kind == "rate" else [])
        vlo = [-np.inf, s.t_release_bounds[0]] + ([-np.inf] if len(v0) == 3 else [])
        vhi = [np.inf, s.t_release_bounds[1]] + ([np.inf] if len(v0) == 3 else [])
        w0 += [np.array(v0), np.vstack([th, thd]).T.ravel()]
        lbw += [np.array(vlo), np.full(2 * len(th), -np.inf)]
        ubw += [np.array(vhi), np.full(2 * len(th), np.inf)]
    w0, lbw, ubw = np.concatenate(w0), np.concatenate(lbw), np.concatenate(ubw)
    rng = np.random.default_rng(seed)
    n_move, n_rel = substeps(h_move), substeps(h_rel)
    best = None
    bar = Progress(int(starts), "fit", enabled=progress and starts > 1, unit="")
    for i in range(max(1, int(starts))):
        check()                       # Ctrl-C between starts (Ipopt may swallow it)
        bar.update(i, f"best 1/2 r'r = {best[1]:.6g}" if best else "")
        factor = np.ones(nk) if i == 0 else np.exp(0.7 * rng.standard_normal(nk))
        w = w0.copy()
        w[:nk] = np.clip(u_init * factor / scale, lbw[:nk], ubw[:nk])
        nlp = get_nlp(model, cfg, keys, shapes, n_move, n_rel)
        run = nlp.fit(w, P, lbw, ubw)
        ws, f, status, it = run.x, run.f, run.status, run.iterations
        ok = status in CONVERGED and np.isfinite(f)
        if best is None or (ok, -f) > (best[3], -best[1]):
            best = (ws, f, status, ok, it)
    bar.close()
    ws, f, status, ok, iters = best
    # the integration error: sub-steps doubled until halving them changes no sample by more
    # than DEFECT_MAX of the noise (the solution re-solved from the last one)
    defect = float(nlp.defect(ws, P))
    while ok and defect > DEFECT_MAX and n_move < 256:
        n_move, n_rel = 2 * n_move, 2 * n_rel
        nlp = get_nlp(model, cfg, keys, shapes, n_move, n_rel)
        run = nlp.fit(ws, P, lbw, ubw)
        ws2, f2, status2, it2 = run.x, run.f, run.status, run.iterations
        ok = status2 in CONVERGED and np.isfinite(f2)
        ws, f, status, iters = ws2, f2, status2, iters + it2
        defect = float(nlp.defect(ws, P))
    r, J, G = nlp.jac(ws, P)
    r = np.asarray(r).ravel()
    m, nfree = len(r), nlp.nw - nlp.ng
    dof = m - nfree
    s2 = float(r @ r) / dof if dof > 0 else math.nan
    want = list(range(nk))
    for ix in nlp.index:
        want += list(range(ix["v"].start, ix["v"].stop))
    Z = kkt_columns(J.sparse(), G.sparse(), want)
    C = s2 * Z
    C = 0.5 * (C + C.T)
    value = ws[:nk] * scale
    cov = C[:nk, :nk] * np.outer(scale, scale)
    with np.errstate(all="ignore"):
        std = np.sqrt(np.clip(np.diag(cov), 0, None))
        corr = cov / np.outer(std, std)
    tq = t_quantile(dof)
    # per stroke: the release, the residuals in the data's unit, the model at the samples
    per, pos = [], 0
    for s, ix in zip(strokes, nlp.index):
        nres = len(s.rest) + len(s.window) + len(s.moving)
        rs = r[pos:pos + nres] * s.sigma
        pos += nres + (1 if s.record.kind == "rate" else 0)
        v = ws[ix["v"]]
        X = ws[ix["X"]].reshape(-1, 2).T
        vi = [want.index(q) for q in range(ix["v"].start, ix["v"].stop)]
        with np.errstate(all="ignore"):
            vstd = np.sqrt(np.clip(np.diag(C)[vi], 0, None))
        per.append(StrokeFit.of(s, float(v[1]), float(v[0]), float(v[2]) if len(v) > 2 else 0.0,
                                X, rs, float(vstd[1]), float(vstd[0])))
    return FitResult.build(cfg, keys, value, std, corr, tq, dof, s2, ok, status, iters,
                           per, lo, hi, u_init, int(starts), defect, n_move)


__all__ = ["solve", "prepare", "equation_error_guess", "measured_states", "t_quantile",
           "VIF_MAX", "UNDETERMINED"]
