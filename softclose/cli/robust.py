"""``softclose yield`` and ``softclose sensitivity``; the text of ``optimise --robust``.

``yield``: Monte Carlo yield of the config's design over the ``[tolerance]`` box;
``sensitivity``: Sobol indices of closing time and impact speed per toleranced key. Both
take ``--samples N``, ``--seed S``, ``--out DIR`` (figures and tables) and ``--json``.
:func:`robust_outcome` serves ``softclose optimise --robust``.
"""

from __future__ import annotations

import argparse

from .common import Outcome, add_common, add_out, figures, prepare_out, saved, wrote


YIELD = """\
The share of produced lids that meet every constraint when the config's design is made
with the [tolerance] spreads (springs ±10 %, dampers ±20 %, lid mass ±5 % by default): Monte
Carlo over the tolerance box, a 95 % Wilson interval, why the failing lids fail, percentiles
of closing time, impact and peak tip speed and J, and adaptive-reference checks of the worst
samples. The report states the design it analysed and its nominal lid. The default config's
design has no spring and no damper: to judge the optimum, run `softclose optimise --out D`,
then `softclose yield --config D/design.toml`."""

SENSITIVITY = """\
Variance-based (Sobol) sensitivity of closing time and impact speed to each toleranced key
of the config's design: first-order and total indices with 95 % bootstrap intervals
(SALib). The report states the design it analysed; keys with no spread at that design (a
relative spread of a zero spring) are left out and named. To analyse the optimum: `softclose
optimise --out D`, then `softclose sensitivity --config D/design.toml`."""


def register(sub) -> None:
    p = sub.add_parser("yield", help="Monte Carlo yield of the design under [tolerance]",
                       description=YIELD, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_common(p)
    add_out(p, what="write yield_samples.csv and yield_histograms.png to this folder")
    p.add_argument("--samples", type=int, metavar="N",
                   help="Monte Carlo samples (default: [tolerance] samples)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.set_defaults(run=run_yield)
    p = sub.add_parser("sensitivity",
                       help="Sobol indices of closing time and impact speed per toleranced key",
                       description=SENSITIVITY,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    add_common(p)
    add_out(p, what="write sobol.csv and sobol.png to this folder")
    p.add_argument("--samples", type=int, metavar="N", default=1024,
                   help="Sobol base samples N, a power of 2 (N (D + 2) strokes; default 1024)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.set_defaults(run=run_sensitivity)


def _check_samples(n, what="--samples"):
    from ..errors import ConfigError
    if n is not None and n < 1:
        raise ConfigError(f"{what} {n}: must be at least 1")
    if n is not None and n > 10_000_000:
        raise ConfigError(f"{what} {n}: more than 10^7 samples; use fewer")


def _seed(args):
    from ..errors import ConfigError
    if args.seed < 0:
        raise ConfigError(f"--seed {args.seed}: must be non-negative")
    return args.seed


def _source(args) -> str:
    """Where the analysed design comes from, as the report says it."""
    where = f"from {args.config}" if getattr(args, "config", None) else "the defaults"
    if any(o.split("=", 1)[0].strip().startswith("design.")
           for o in getattr(args, "overrides", ()) or ()):
        where += " with --set"
    return f"design ({where})"


def run_yield(cfg, args) -> Outcome:
    from ..robust import tolerance_analysis
    from ..problem import sign_off_conditions
    _check_samples(args.samples)
    seed = _seed(args)
    out = prepare_out(args.out, ["yield_samples.csv", *figures("yield_histograms")])
    if not cfg.tolerance.spreads:
        from ..errors import ConfigError
        raise ConfigError("tolerance: no key has a spread; give at least one "
                          "(e.g. --set tolerance.design.spring_k=0.1)")
    if len(sign_off_conditions(cfg)) > 1:      # (several temperatures or states)
        return _yield_by_temperature(cfg, args, seed, out)
    r = tolerance_analysis(cfg, samples=args.samples, seed=seed)
    payload = r.to_json()
    files = saved(r, out, payload)
    code = 0 if r.success else 3
    return Outcome(payload, r.text(_source(args)) + wrote(files), code, tuple(files),
                   error=None if r.success else r.message)


def _yield_by_temperature(cfg, args, seed, out) -> Outcome:
    """``softclose yield`` over several sign-off temperatures (operating.temperatures_c):
    each temperature's yield (the same samples) and the joint one."""
    from ..robust import yield_by_temperature
    t = yield_by_temperature(cfg, samples=args.samples, seed=seed)
    payload = t.to_json()
    files = saved(t, out, payload)
    return Outcome(payload, t.text(_source(args)) + wrote(files), 0 if t.meets_required else 3,
                   tuple(files), error=t.message or None)


def run_sensitivity(cfg, args) -> Outcome:
    from ..robust import sensitivity
    _check_samples(args.samples)
    seed = _seed(args)
    out = prepare_out(args.out, ["sobol.csv", *figures("sobol")])
    r = sensitivity(cfg, samples=args.samples, seed=seed)
    payload = r.to_json()
    files = saved(r, out, payload)
    return Outcome(payload, r.text(_source(args)) + wrote(files), 0, tuple(files))


def robust_outcome(cfg, args) -> Outcome:
    """``softclose optimise --robust [--json] [--out DIR]``: 0 verified robust design meeting
    the required yield, 3 otherwise (the reason on stderr)."""
    from ..robust import optimise_robust
    out = prepare_out(getattr(args, "out", None))
    from .common import interactive
    res = optimise_robust(cfg, progress=interactive(args))
    payload = res.to_json()
    files = saved(res, out, payload)
    return Outcome(payload, res.text() + wrote(files), 0 if res.success else 3,
                   tuple(files), error=None if res.success else res.message)
