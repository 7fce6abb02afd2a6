"""The result of a fit: estimates with their uncertainty, the verdict on identifiability, the
strokes as fitted, and the hand-over (the calibrated config with a ``[tolerance]`` proposal).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..present.display import Display, Displayed, Table, num, unit_of, with_unit
from ..problem import DESIGN_KEYS

#: variance inflation factor above which keys count as not identifiable (the usual
#: multicollinearity rule; a pair correlated beyond |r| = 0.949; a lid's mass against its
#: damper from one stroke is ~0.98-0.99)
VIF_MAX = 10.0
#: relative standard deviation above which a key counts as not determined by the data
UNDETERMINED = 0.5


@dataclass(frozen=True, repr=False)
class StrokeFit:
    """One record as fitted: every sample (``y`` in the data's unit: deg or rad/s), the
    model at the fitted samples (NaN elsewhere), the release, the residuals."""

    path: str
    kind: str
    column: str
    unit: str
    t: np.ndarray
    y: np.ndarray
    model: np.ndarray
    release_time: float
    release_time_std: float
    release_angle_deg: float
    release_angle_std_deg: float
    bias: float
    axis_sign: float
    t_last: float             # the last sample fitted (the closing lies within the next frame)
    residual_rms: float
    samples_used: int

    @classmethod
    def of(cls, s, t_r, th_r, bias, X, rs, t_std, th_std):
        rec = s.record
        angle = rec.kind == "angle"
        conv = math.degrees(1.0) if angle else 1.0
        y = s.y * conv
        model = np.full(len(y), np.nan)
        used = np.r_[s.rest, s.window, s.moving]
        model[used] = y[used] - rs * conv
        return cls(rec.path, rec.kind, rec.column, "deg" if angle else "rad/s", rec.t, y,
                   model, t_r, t_std, math.degrees(th_r), math.degrees(th_std),
                   bias * s.sign, s.sign, float(rec.t[s.moving[-1]]),
                   float(np.sqrt(np.mean((rs * conv) ** 2))), len(used))

    def to_json(self) -> dict:
        return {"path": self.path, "kind": self.kind, "column": self.column,
                "release_time": self.release_time, "release_time_std": self.release_time_std,
                "release_angle_deg": self.release_angle_deg,
                "release_angle_std_deg": self.release_angle_std_deg,
                "bias": self.bias if self.kind == "rate" else None,
                "axis_sign": self.axis_sign if self.kind == "rate" else None,
                "last_fitted_time": self.t_last,
                "residual_rms": self.residual_rms, "residual_unit": self.unit,
                "samples_used": self.samples_used, "samples": int(len(self.t))}


@dataclass(frozen=True, repr=False)
class FitResult(Displayed):
    """What :func:`softclose.fit` returns: ``values``, ``std``, ``ci95`` by key (the keys'
    own units), ``correlation``, ``identifiable`` (and ``collinear``: the keys the data
    cannot separate), the strokes as fitted, and the calibrated config
    (:meth:`calibrated_config`)."""

    success: bool
    message: str
    keys: tuple
    values: dict
    std: dict
    ci95: dict
    correlation: dict
    identifiable: bool
    collinear: tuple
    strokes: tuple
    status: str
    iterations: int
    dof: int
    variance_factor: float
    initial: dict
    at_bound: tuple
    starts: int
    #: the integration error (Richardson: halving the sub-steps), in units of the noise
    integration_error: float
    substeps: int
    cfg: object = field(compare=False)

    # -- construction --------------------------------------------------------------------
    @classmethod
    def build(cls, cfg, keys, value, std, corr, tq, dof, s2, ok, status, iters, strokes,
              lo, hi, u_init, starts, defect=math.nan, n_move=0):
        nk = len(keys)
        values = {k: float(value[i]) for i, k in enumerate(keys)}
        stds = {k: float(std[i]) for i, k in enumerate(keys)}
        ci = {k: [float(value[i] - tq * std[i]), float(value[i] + tq * std[i])]
              for i, k in enumerate(keys)}
        C = np.where(np.isfinite(corr), corr, 0.0)
        np.fill_diagonal(C, 1.0)
        correlation = {a: {b: float(C[i, j]) for j, b in enumerate(keys)}
                       for i, a in enumerate(keys)}
        at_bound = tuple(k for i, k in enumerate(keys)
                         if np.isfinite(lo[i]) and abs(value[i] - lo[i]) <= 1e-6 * max(
                             1.0, abs(value[i])) or np.isfinite(hi[i])
                         and abs(value[i] - hi[i]) <= 1e-6 * abs(hi[i]))
        collinear, why = (), []
        if ok and nk >= 2 and np.all(np.isfinite(corr)):
            lam, V = np.linalg.eigh(C)
            vif = np.diag(np.linalg.pinv(C))
            if lam[0] <= 0 or np.max(vif) > VIF_MAX:
                v = V[:, 0]
                collinear = tuple(keys[i] for i in np.argsort(-np.abs(v))
                                  if abs(v[i]) >= 0.3 * np.max(np.abs(v)))
                pair = max(((abs(C[i, j]), i, j) for i in range(nk) for j in range(i + 1, nk)))
                why.append(f"not identifiable: the data cannot separate "
                           f"{' and '.join(collinear)} (correlation {C[pair[1], pair[2]]:+.3f} "
                           f"between {keys[pair[1]]} and {keys[pair[2]]}; variance inflation "
                           f"{np.max(vif):.0f} > {VIF_MAX:g}): fix one of them with --set "
                           "(weigh or measure it); their numbers are not to be trusted")
        if not np.all(np.isfinite(std)):
            why.append("the covariance is singular: the data do not determine the keys")
        loose = [k for i, k in enumerate(keys) if k not in collinear and k not in at_bound
                 and np.isfinite(std[i]) and std[i] > UNDETERMINED * abs(value[i])]
        if loose:
            why.append(f"{', '.join(loose)} not determined by the data (standard deviation "
                       f"above {UNDETERMINED:.0%} of the value)")
        identifiable = (not why) if ok else None     # (unknown without a fit)
        msg = []
        if not ok:
            msg.append(f"the fit did not converge (Ipopt: {status}): give better first values "
                       "with --set, or more starts (--starts), and check that the config's "
                       "geometry and stroke are the measured lid's")
        msg += why
        if at_bound:
            msg.append(f"{', '.join(at_bound)} at the bound of its range (its interval is "
                       "one-sided in truth)")
        return cls(bool(ok), "; ".join(msg), tuple(keys), values, stds, ci, correlation,
                   identifiable, collinear, tuple(strokes), status, int(iters), int(dof),
                   float(s2), {k: float(u_init[i]) for i, k in enumerate(keys)}, at_bound,
                   int(starts), float(defect), int(n_move), cfg)

    # -- views ---------------------------------------------------------------------------
    @property
    def residual_rms(self):
        """The rms residual in the data's unit (deg or rad/s); per stroke when several."""
        r = [s.residual_rms for s in self.strokes]
        return r[0] if len(r) == 1 else r

    @property
    def samples_used(self) -> int:
        return sum(s.samples_used for s in self.strokes)

    def text(self) -> str:
        """What ``softclose fit`` prints: the estimates, correlations, identifiability, the
        strokes' releases and residuals."""
        from .text import fit_text
        return fit_text(self)

    def save(self, folder, data=None, figure_format: str = "png",
             figure_style: str | None = None) -> list:
        """The hand-over in ``folder`` (what ``softclose fit --out`` writes): calibrated.toml,
        fit.csv, samples.csv and the figure; the paths."""
        from .folder import save_fit
        return save_fit(self, folder, data, figure_format, figure_style)

    def to_json(self) -> dict:
        one = len(self.strokes) == 1
        rel = [s.release_time for s in self.strokes]
        ang = [s.release_angle_deg for s in self.strokes]
        return {
            "success": self.success,
            "parameters": {k: {"value": self.values[k], "std": self.std[k],
                               "ci95": list(self.ci95[k]), "unit": unit_of(k),
                               "initial": self.initial[k]} for k in self.keys},
            "correlation": self.correlation,
            "identifiable": self.identifiable,
            "collinear": list(self.collinear),
            "release_time": rel[0] if one else rel,
            "release_angle_deg": ang[0] if one else ang,
            "residual_rms": self.residual_rms,
            "residual_unit": self.strokes[0].unit if one else [s.unit for s in self.strokes],
            "samples_used": self.samples_used,
            "message": self.message,
            "status": self.status,
            "iterations": self.iterations,
            "degrees_of_freedom": self.dof,
            "variance_factor": self.variance_factor,
            "at_bound": list(self.at_bound),
            "starts": self.starts,
            "integration_error": self.integration_error,
            "substeps": self.substeps,
            "files": [s.to_json() for s in self.strokes],
        }

    def to_frame(self):
        """One row per fitted key: value, std, the 95 % interval, relative std, unit."""
        import pandas as pd
        return pd.DataFrame([{"key": k, "value": self.values[k], "std": self.std[k],
                              "ci95_lo": self.ci95[k][0], "ci95_hi": self.ci95[k][1],
                              "relative_std": self.std[k] / abs(self.values[k])
                              if self.values[k] else math.nan,
                              "unit": unit_of(k)} for k in self.keys])

    def plot(self):
        """The data against the fit, with the residuals (a Figure)."""
        from ..present.figures.fit import plot_fit
        return plot_fit(self)

    # -- hand-over -----------------------------------------------------------------------
    def tolerance(self) -> dict:
        """The ``[tolerance]`` proposal: for each fitted key of the lid (not a design variable
        the optimiser chooses -- spring_k, spring_rest_length, damper_c, ``optimise.free`` --
        whose spread is that of the parts to buy, not of this prototype), a spread from its
        95 % interval: relative (absolute for a value of 0 or at its bound), in the meaning of
        the configured distribution (uniform: the interval's half width; normal: 3 standard
        deviations), and never below a spread the config already gives the key. Keys the data
        do not determine get none (give them by hand)."""
        skip = {f"design.{k}" for k in DESIGN_KEYS} | {k for k, _, _ in
                                                        (self.cfg.optimise.free or ())}
        given = {sp.key: sp for sp in self.cfg.tolerance.spreads}
        out = {}
        normal = self.cfg.tolerance.distribution == "normal"
        for k in self.keys:
            if k in self.collinear or k in skip:
                continue
            v, s = self.values[k], self.std[k]
            half = 3 * s if normal else 0.5 * (self.ci95[k][1] - self.ci95[k][0])
            if not (np.isfinite(half) and half > 0):
                continue
            old = given.get(k)
            if v != 0 and k not in self.at_bound and half / abs(v) < 0.95:
                rel = half / abs(v)
                if old is not None:
                    rel = max(rel, old.value if old.relative else old.value / abs(v))
                out[k] = float(f"{rel:.3g}")
            elif v == 0 or k in self.at_bound:
                if old is not None and not old.relative:
                    half = max(half, old.value)
                out[k] = {"absolute": float(f"{half:.3g}")}
        return out

    def calibrated_config(self, with_tolerance: bool = True):
        """The config with the fitted keys set (the derived inertias follow the fitted masses
        as in the fit), and the ``[tolerance]`` proposal added."""
        cfg = self.cfg.update({k: self.values[k] for k in self.keys})
        if with_tolerance and self.tolerance():
            cfg = cfg.replace(tolerance=self.tolerance())
        return cfg

    def _display(self) -> Display:
        facts = [(k, f"{with_unit(self.values[k], unit_of(k))} ± {num(self.std[k], 2)}")
                 for k in self.keys]
        facts.append(("identifiable", "yes" if self.identifiable else "—" if
                      self.identifiable is None else
                      "no: " + " / ".join(self.collinear or ("see the message",))))
        facts.append(("residual rms", ", ".join(f"{num(s.residual_rms, 3)} {s.unit}"
                                                for s in self.strokes)))
        facts.append(("samples used", num(self.samples_used)))
        rows = [(k, num(self.values[k]), num(self.std[k], 3),
                 f"{num(self.ci95[k][0])} … {num(self.ci95[k][1])}", unit_of(k))
                for k in self.keys]
        tables = [Table("estimates", ("key", "value", "std", "95 % interval", "unit"), rows)]
        if len(self.keys) > 1:
            tables.append(Table("correlation", ("",) + self.keys,
                                [(a,) + tuple(f"{self.correlation[a][b]:+.3f}"
                                              for b in self.keys) for a in self.keys]))
        tables.append(Table("strokes", ("file", "release (s)", "release angle (deg)",
                                        "rms residual", "samples"),
                            [(s.path, num(s.release_time, 5), num(s.release_angle_deg, 5),
                              f"{num(s.residual_rms, 3)} {s.unit}", s.samples_used)
                             for s in self.strokes]))
        return Display("FitResult", bool(self.success and self.identifiable), self.message,
                       tuple(facts), tuple(tables))


__all__ = ["FitResult", "StrokeFit"]
