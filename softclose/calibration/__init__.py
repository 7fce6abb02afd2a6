"""Calibration: the lid's model fitted to measured closing strokes (``softclose fit``).

:func:`fit` takes a config, one or more records (CSV paths or tables of columns: a video
tracker's angle track or a phone's gyroscope export, :mod:`softclose.calibration.data`) and the keys
to fit, and returns a :class:`FitResult`: estimates with standard deviations and 95 %
intervals, correlations and an identifiability verdict, the calibrated config with a
``[tolerance]`` proposal for robust design. The method: :mod:`softclose.calibration.nlp` (multiple
shooting on the data's grid, Gauss-Newton, Ipopt) and :mod:`softclose.calibration.core` (first
guesses, statistics). Synthetic records of known truth: :mod:`softclose.calibration.synthetic`.
"""

from __future__ import annotations

from .equation import FIT_KEYS
from .result import FitResult, StrokeFit
from ..problem import check_reference_temperature, check_new_parts


def fit(cfg, data, free, *, axis: str | None = None, starts: int = 1,
        seed: int = 0, progress: bool = False) -> FitResult:
    """Fit the keys ``free`` (e.g. ``["design.damper_c", "mass.inertia_lid"]``) of ``cfg``
    to ``data`` (a CSV path, a table of columns, or a list of them: fitted jointly, sharing
    the keys). ``axis``: a gyroscope's axis (x, y, z); ``starts``: how many first guesses
    (the first from the equation error, the others scattered around it). Bad data raise
    :class:`~softclose.errors.ConfigError`; a fit that does not converge returns a result
    with ``success`` False. ``progress``: a progress line over the starts on a terminal."""
    check_reference_temperature(cfg, "the fit")
    check_new_parts(cfg, "the fit")
    from .core import solve
    return solve(cfg, data, free, axis=axis, starts=starts, seed=seed, progress=progress)


__all__ = ["fit", "FitResult", "StrokeFit", "FIT_KEYS"]
