"""The background compilation of a scenario NLP (``python -m softclose.robust.compile LOCK``):
:func:`softclose.buildcache.request_nlp` starts it the second time the robust optimiser
builds the same scenario NLP (:func:`softclose.robust.nlp.get_scenario_nlp`); it builds the
NLP the lock file names, compiles it into the cache (:data:`softclose.buildcache.
SCENARIO_CFLAGS`), and hands the lock to the next compilation that waits
(:func:`softclose.buildcache.chain`) or removes it. The optimiser's own NLPs have
:mod:`softclose.optimiser.compile`."""

from __future__ import annotations

import sys


def main(lock: str) -> int:
    """Build the scenario NLP the lock file ``lock`` names, compile it, hand the lock on."""
    from ..buildcache import SCENARIO_CFLAGS, compile_locked
    from .nlp import build_from_spec
    return compile_locked(lock, build_from_spec, SCENARIO_CFLAGS)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
