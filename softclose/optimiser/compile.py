"""The background compilation of an NLP (``python -m softclose.optimiser.compile LOCK``):
:func:`softclose.buildcache.request_nlp` starts it the second time an NLP is used; it builds
the NLP the lock file names, compiles it into the cache, and hands the lock to the next
compilation that waits (:func:`softclose.buildcache.chain`) or removes it. It lives with
the optimiser, which it builds: the cache below it only stores and finds files."""

from __future__ import annotations

import sys


def build(spec: dict):
    """The optimiser's NLP a background compilation's spec names."""
    from ..config import from_dict
    from .cache import build_nlp
    return build_nlp(from_dict(spec["config"]), spec["nodes"], spec["substeps"],
                     spec.get("substeps2"))


def main(lock: str) -> int:
    """Build the NLP the lock file ``lock`` names, compile it, hand the lock on."""
    from ..buildcache import compile_locked
    return compile_locked(lock, build)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
