"""``softclose fit DATA [DATA ...] --free KEY ... [--out DIR]``: the model calibrated to
measured closing strokes."""

from __future__ import annotations


import argparse

from ..errors import ConfigError
from .common import (Outcome, add_common, add_out, figures, interactive, prepare_out, saved,
                     wrote)

DESCRIPTION = """\
Fit config keys of the lid's dynamics (masses, inertias, the dampers, friction, a spring's
rate or preload) to measured closing strokes: a video tracker's angle track (CSV columns
time_s and theta_deg or theta_rad) or a phone's gyroscope export ("Time (s)", "Gyroscope x
(rad/s)"; --axis, its bias is estimated), or theta_dot_rad_s. The record may start before the
release and run past the closing: the release time and angle are estimated, the samples after
the closing left out. Several files are fitted jointly, sharing the keys. Multiple shooting on
the data's own time grid with the config's integrator, Gauss-Newton, Ipopt.

Each estimate comes with its standard deviation and 95 % interval (from the residuals and the
Jacobian), the correlations and a verdict: keys the data cannot separate (a variance
inflation above 10, e.g. the lid's mass against the damper from one stroke) are named, and
their numbers are not to be trusted. Give the keys you know (the lid weighed) with --set.
With --out: calibrated.toml (the config with the fitted keys and a [tolerance] proposal from
the 95 % intervals of the lid's keys -- masses, inertias, friction; the design variables keep
the spreads of the parts to buy --: `softclose optimise --robust --config DIR/calibrated.toml`),
fit.csv (the estimates), samples.csv (every sample: measured, model, residual, in deg or
rad/s, a gyroscope's turned to theta' with its bias) and the figure fit.png."""


def register(sub) -> None:
    p = sub.add_parser("fit", help="calibrate the model to measured closing strokes",
                       description=DESCRIPTION,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("data", nargs="+", metavar="DATA",
                   help="CSV file(s) of a measured stroke (fitted jointly)")
    p.add_argument("--free", dest="fit_free", action="append", default=[], metavar="KEY",
                   help="a config key to fit, e.g. design.damper_c or mass.inertia_lid "
                        "(repeatable; its configured value is the first guess)")
    p.add_argument("--axis", choices=("x", "y", "z"), default=None,
                   help="the gyroscope axis of a phone's export (default: the axis that "
                        "moves most)")
    p.add_argument("--starts", default="1", metavar="N",
                   help="first guesses to start from (1..50; the best fit is kept)")
    add_common(p)
    add_out(p, what="also write the calibrated config, the tables and the figure here")
    p.set_defaults(run=run)


def _starts(text: str) -> int:
    try:
        n = int(text)
    except ValueError:
        raise ConfigError(f"--starts {text}: expected a whole number 1..50") from None
    if not 1 <= n <= 50:
        raise ConfigError(f"--starts {text}: outside 1..50")
    return n


def run(cfg, args) -> Outcome:
    from ..calibration import fit
    from ..calibration.equation import check_keys
    keys = check_keys(args.fit_free)
    starts = _starts(args.starts)
    out = prepare_out(args.out, ["calibrated.toml", "fit.csv", "samples.csv", *figures("fit")])
    res = fit(cfg, args.data, keys, axis=args.axis, starts=starts, progress=interactive(args))
    payload = res.to_json()
    files = saved(res, out if res.success else None, payload, args.data)
    text = res.text() + wrote(files)
    if not res.success:
        return Outcome(payload, text, 3, tuple(files), error=res.message)
    return Outcome(payload, text, 0, tuple(files))
