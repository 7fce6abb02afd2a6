"""Global sensitivity: Sobol indices of closing time and impact speed (SALib).

Inputs are the toleranced keys over the tolerance box of the design: uniform on the box,
or (``distribution = "normal"``) normal with the spread as 3 sigma, truncated at the key's
admissible range like the Monte Carlo samples. Samples come from SALib's Sobol' sequence
with Saltelli's cross-sampling (``SALib.sample.sobol.sample``, N (D + 2) points, first and
total order only), the indices and their 95 % bootstrap confidence intervals from
``SALib.analyze.sobol.analyze`` (Saltelli 2010 / Jansen estimators). Every point is one
stroke in the C kernel.

Strokes that do not close within stroke.t_max have no closing time and no impact. They are
counted (``not_closed``) and enter the indices *censored*: closing time = stroke.t_max (the
stroke ran that long without closing) and impact theta' = 0 (no impact). The indices then
describe the censored outputs; when many samples do not close, read them with that in mind.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from ..config import Config, check_batch
from ..present.display import Display, Displayed, Table, num, with_unit
from ..errors import ConfigError
from ..problem import BARE_LID, design_of, params_of, UNITS
from .box import box_of
from .evaluate import evaluate
from .analysis import nominal_stroke
from ..jsonio import jsonable

#: the outputs analysed
OUTPUTS = ("closing_time", "impact_theta_dot")
CENSORING = ("strokes that do not close count as closing at stroke.t_max (closing_time) "
             "and as an impact at theta' = 0 (impact_theta_dot)")


@dataclass(frozen=True, repr=False)
class SensitivityResult(Displayed):
    """First-order (S1) and total (ST) Sobol indices of each output per toleranced key."""

    success: bool
    message: str
    design: dict
    keys: tuple
    base_samples: int
    evaluations: int
    not_closed: int
    indices: dict          # output -> {"S1": {key: v}, "ST": ..., "S1_conf": ..., "ST_conf": ...}
    distribution: str
    seed: int
    time: float = 0.0
    data: dict = field(default_factory=dict, repr=False, compare=False)
    #: the nominal lid (:func:`softclose.robust.analysis.nominal_stroke`)
    nominal: dict = field(default_factory=dict)
    #: the toleranced keys with no spread at this design (left out of the indices)
    fixed: tuple = ()

    @property
    def warnings(self) -> tuple[str, ...]:
        """The design has no spring and no damper (:data:`softclose.problem.BARE_LID`)."""
        return (BARE_LID,) if self.nominal.get("bare") else ()

    def text(self, source: str = "design") -> str:
        """What ``softclose sensitivity`` prints (``source``: where the design comes from)."""
        from .text import sensitivity_text
        return sensitivity_text(self, source)

    def to_json(self) -> dict:
        out = {"success": self.success, "message": self.message, "design": self.design,
               "nominal": self.nominal, "warnings": list(self.warnings),
               "fixed": list(self.fixed)}
        out.update(self.indices)
        out.update({"not_closed": self.not_closed, "not_closed_treatment": CENSORING,
                    "keys": list(self.keys), "base_samples": self.base_samples,
                    "evaluations": self.evaluations, "distribution": self.distribution,
                    "seed": self.seed, "confidence": 0.95,
                    "method": "SALib: Sobol' sequence with Saltelli sampling; Saltelli 2010 "
                              "(S1) and Jansen (ST) estimators, bootstrap intervals",
                    "time": self.time})
        return jsonable(out)

    def to_frame(self):
        """One row per (output, key): S1, S1_conf, ST, ST_conf."""
        import pandas as pd
        rows = []
        for out, d in self.indices.items():
            for k in self.keys:
                rows.append({"output": out, "key": k, "S1": d["S1"][k],
                             "S1_conf": d["S1_conf"][k], "ST": d["ST"][k],
                             "ST_conf": d["ST_conf"][k]})
        return pd.DataFrame(rows)

    def _display(self) -> Display:
        facts = [(f"{out} driven by", ", ".join(
            f"{k} (ST {d['ST'][k]:.2f})" for k in sorted(self.keys, key=lambda k: -d["ST"][k])[:2]))
            for out, d in self.indices.items()]
        facts += [(k, with_unit(v, UNITS.get(k, ""))) for k, v in self.design.items()]
        facts += [("strokes", f"{num(self.evaluations)} ({num(self.base_samples)} base "
                              f"samples, {self.distribution})"),
                  ("not closed", num(self.not_closed))]
        tables = []
        for out, d in self.indices.items():
            tables.append(Table(f"Sobol indices of {out} (± 95 % bootstrap interval)",
                                ("key", "first order S1", "total ST"),
                                [(k, f"{d['S1'][k]:.3f} ± {d['S1_conf'][k]:.3f}",
                                  f"{d['ST'][k]:.3f} ± {d['ST_conf'][k]:.3f}")
                                 for k in sorted(self.keys, key=lambda k: -d["ST"][k])]))
        return Display("SensitivityResult: Sobol indices over the tolerance box",
                       self.success, self.message, tuple(facts), tuple(tables), short=2)

    def save(self, folder, figure_format: str = "png", figure_style: str | None = None
             ) -> list:
        """The indices (``sobol.csv``) and their bars (``sobol``) in ``folder`` (what
        ``softclose sensitivity --out`` writes); the paths."""
        from ..present.figures import save_with_table
        return save_with_table(folder, "sobol.csv", self.to_frame(), "sobol", self.plot,
                               figure_format, figure_style)

    def plot(self, title: str | None = None):
        """Bars of S1 and ST with their intervals, one panel per output (a Figure)."""
        from ..present.figures.robust import plot_sobol
        return plot_sobol(self, title)


def _sub_box(box, idx):
    """The box restricted to the keys ``idx``."""
    from dataclasses import replace
    return replace(box, keys=tuple(box.keys[j] for j in idx), nominal=box.nominal[idx],
                   half=box.half[idx], z_min=box.z_min[idx],
                   relative=tuple(box.relative[j] for j in idx),
                   spreads=tuple(box.spreads[j] for j in idx))


def sensitivity(cfg: Config, *, samples: int = 1024, seed: int = 0,
                design: dict | None = None) -> SensitivityResult:
    """Sobol indices of closing time and impact theta' over cfg's tolerance box, at cfg's
    design (or ``design``: {name: value} as a result's ``design`` gives it, a co-design's
    attachment points and end damper included).

    ``samples`` is SALib's base sample count N (a power of 2); N (D + 2) strokes are run.
    """
    from SALib.analyze import sobol as sobol_analyze
    from SALib.sample import sobol as sobol_sample
    t0 = time.perf_counter()
    if isinstance(samples, bool) or not isinstance(samples, (int, np.integer)) or samples < 2 \
            or samples & (samples - 1):
        raise ConfigError(f"--samples {samples}: the Sobol base sample count must be a power "
                          "of 2 (e.g. 1024)")
    if design:
        cfg = cfg.with_design(**design)     # (a co-design's points and end damper too)
    full = box_of(cfg)
    # a key varies only if its interval is wider than the value's floating-point resolution
    # (a spread of 1e-98 leaves lo == hi, which SALib rightly refuses)
    live = [j for j in range(full.dim) if full.lo[j] < full.hi[j]]
    if not live:
        raise ConfigError("tolerance: no key has a spread at this design (a relative spread of "
                          "a zero value is zero, and one below the value's floating-point "
                          "resolution is none); give one, e.g. --set tolerance.mass.lid=0.05")
    box = _sub_box(full, live)
    check_batch(cfg, int(samples) * (box.dim + 2), f"--samples {samples}")
    fixed = [k for j, k in enumerate(full.keys) if j not in live]
    keys = list(box.keys)
    if box.distribution == "uniform":
        problem = {"num_vars": box.dim, "names": keys,
                   "bounds": [[float(a), float(b)] for a, b in zip(box.lo, box.hi)]}
    else:   # normal, spread = 3 sigma, truncated at the key's range (as the MC samples)
        lo = box.nominal + box.half * box.z_min
        problem = {"num_vars": box.dim, "names": keys, "dists": ["truncnorm"] * box.dim,
                   "bounds": [[float(a), float(np.inf), float(m), float(h / 3)]
                              for a, m, h in zip(lo, box.nominal, box.half)]}
    X = sobol_sample.sample(problem, int(samples), calc_second_order=False, scramble=True,
                            seed=seed)
    cols = evaluate(cfg, keys, X)
    closed = np.asarray(cols["closed"], bool)
    Y = {"closing_time": np.where(closed, cols["closing_time"], cfg.stroke.t_max),
         "impact_theta_dot": np.where(closed, cols["impact_theta_dot"], 0.0)}
    indices = {}
    for out in OUTPUTS:
        y = np.asarray(Y[out], float)
        if np.ptp(y) == 0:        # a constant output has no variance to apportion
            zero = {k: 0.0 for k in keys}
            indices[out] = {"S1": zero, "ST": zero, "S1_conf": zero, "ST_conf": zero}
            continue
        Si = sobol_analyze.analyze(problem, y, calc_second_order=False, seed=seed)
        indices[out] = {name: {k: float(v) for k, v in zip(keys, Si[name])}
                        for name in ("S1", "ST", "S1_conf", "ST_conf")}
    nc = int((~closed).sum())
    msgs = []
    if fixed:
        msgs.append(f"{', '.join(fixed)}: no spread at this design (a relative spread of a zero "
                    "value, or one below the value's floating-point resolution), left out")
    if nc:
        msgs.append(f"{nc} of {len(X)} strokes did not close; {CENSORING}")
    msg = "; ".join(msgs)
    return SensitivityResult(True, msg, design_of(params_of(cfg)), tuple(keys), int(samples),
                             len(X), nc, indices, box.distribution, seed,
                             time.perf_counter() - t0, {"X": X, "Y": Y, "cols": cols},
                             nominal=nominal_stroke(cfg), fixed=tuple(fixed))
