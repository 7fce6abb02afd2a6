"""``softclose prepare``: compile, here and now, the NLPs that ``softclose optimise`` (or,
with ``--select``, ``softclose select``) with the same options would use, so that its runs
load them (the solves ~3x faster).

Nothing of softclose compiles behind the user's back: an NLP is built symbolically (CasADi's
virtual machine) when it is used, and its compiled library loaded when the cache holds one
(:mod:`softclose.buildcache`). This command runs the same optimisation with compiling turned
on, so that exactly the NLPs the command builds -- every spring kind's, a polish's finer one,
the robust co-design's second-stage scenario NLPs -- are compiled, each with a line on stderr
saying what is built and how long it took. The one NLP whose C is slower than the virtual
machine, the robust co-design's first stage (the points free in every scenario), is left to
the virtual machine, and the report says so.

``--select SPRINGS`` runs ``softclose select --springs SPRINGS`` (no damper catalog, the
defaults of ``--samples``, ``--seed`` and ``--verify``): its NLP is the robust scenario NLP
that re-solves the best springs' dashpot c (``--free``: that co-designs their points). That
NLP is keyed by its structure alone -- the scenarios, discretisation and free variables --
and every catalog spring fills the same one with its numbers (its rate and free length as
bounds, its preload, kind and tolerances as parameters), so other springs and other
``select`` options load it too; a spring whose search adds scenarios to its NLP needs a
larger one, built in the virtual machine unless prepared.
"""

from __future__ import annotations

import argparse
import time

from ..errors import ConfigError
from .common import Outcome, add_common

PREPARE = """\
Compile (C, in the foreground: seconds; minutes for --robust) every NLP that `softclose
optimise` with the same --config, --set, --free and --robust would use -- or, with --select
SPRINGS, that `softclose select --springs SPRINGS` would use (the robust NLP re-solving the
best springs' dashpot c; one NLP serves every coil spring, one every gas strut) -- into the cache folder
(SOFTCLOSE_CACHE, default ~/.cache/softclose); later runs of that command load them and solve
~3x faster, with the same numbers. It runs that command once to find them: each NLP built is
compiled, with a line on stderr saying what. NLPs compiled before are loaded, not compiled
again. The robust co-design's first-stage NLP is not compiled: CasADi's virtual machine
evaluates it faster than its C (the report says so)."""


def register(sub) -> None:
    p = sub.add_parser("prepare", help="compile the NLPs of `softclose optimise` (same options) "
                                       "ahead of its runs",
                       description=PREPARE, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_common(p)
    what = p.add_mutually_exclusive_group()
    what.add_argument("--robust", action="store_true",
                      help="the NLPs of `softclose optimise --robust` (the scenario NLPs)")
    what.add_argument("--select", metavar="SPRINGS",
                      help="the NLPs of `softclose select --springs SPRINGS` (no damper "
                           "catalog: the robust NLP that re-solves the best springs' c)")
    p.add_argument("--free", action="append", default=[], metavar="KEY=LO:HI",
                   help="as `softclose optimise --free` (repeatable)")
    p.set_defaults(run=run_prepare)


def run_prepare(cfg, args) -> Outcome:
    import shutil

    from .. import buildcache
    from ..optimiser import compiled
    if buildcache.folder() is None:
        env = buildcache.ENV_FOLDER
        raise ConfigError(f"there is no cache folder to keep compiled NLPs in ({env} is off, "
                          f"or its folder cannot be written): set {env} to a writable folder")
    cc = compiled.compiler()
    if shutil.which(cc) is None:
        raise ConfigError(f"no C compiler '{cc}' found: install one (e.g. gcc) or set CC")
    t0 = time.perf_counter()
    start = {name: len(getattr(compiled, name))
             for name in ("compiled", "loaded", "failed", "interpreted")}
    springs = None
    if args.select:
        from ..catalog import read_springs
        springs = read_springs(args.select)     # (a bad file: exit 2 before anything runs)
    with compiled.compiling():
        if springs is not None:
            from ..catalog import select
            select(cfg, springs)
        elif args.robust:
            from ..robust import optimise_robust
            optimise_robust(cfg)
        else:
            from ..optimiser import optimise
            optimise(cfg)
    done = {name: [str(x) for x in getattr(compiled, name)[start[name]:]]
            for name in start}
    seconds = time.perf_counter() - t0
    what = f"softclose select --springs {args.select}" if args.select else \
        "softclose optimise" + (" --robust" if args.robust else "")
    lines = [f"softclose prepare: {len(done['compiled'])} NLP(s) of `{what}` compiled, "
             f"{len(done['loaded'])} compiled before ({seconds:.1f} s)"]
    lines += [f"  {path}" for path in done["compiled"]]
    lines += [f"  left to CasADi's virtual machine, which evaluates it faster than its C: the "
              f"NLP {name}" for name in done["interpreted"]]
    payload = {"command": what, **done, "seconds": seconds}
    if done["failed"]:
        return Outcome(payload, "\n".join(lines), 3, (),
                       f"could not compile the NLP {done['failed'][0]} (see above)")
    return Outcome(payload, "\n".join(lines))


__all__ = ["register", "run_prepare"]
