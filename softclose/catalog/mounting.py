"""Attachment points re-optimised per part (``select --free``): where to mount the part bought.

When ``optimise.free`` names placement keys (``geometry.spring_anchor[i]``, ``lid_e[i]``,
``dashpot_anchor[i]``, ``dashpot_lid[i]``), each of the best pairs gets its own points: the
robust co-design (:func:`softclose.robust.optimise_robust` with the points free) with the
spring and the dashpot's c fixed to the parts' (their tolerances as the box's); the pair is
then screened again at its points in the kernel and keeps them when it ranks better there
than at the config's points. The reference's check of the pair (:mod:`.verify`) is made at
the pair's own points. A pair with a rotary damper keeps the config's points (the robust NLP
fixes only a dashpot's c), and says so.
"""

from __future__ import annotations

from ..config import Config
from ..config.free import PLACEMENT_KEYS
from ..errors import ConfigError, SoftcloseError
from .nlp import spring_config
from ..robust import optimise_robust


#: the design values a pair's parts set: free in a config (an example lid's own problem), they
#: are the parts' in ``select`` (:func:`parts_fix`)
PART_KEYS = ("design.spring_k", "design.spring_rest_length", "design.spring_preload",
             "design.damper_c", "design.rotary_damper_c", "design.strut_stroke",
             "design.strut_progression", "design.strut_friction")


def parts_fix(cfg: Config) -> tuple[Config, list[str]]:
    """``cfg`` without the free design values the parts set (:data:`PART_KEYS`), and a
    warning for each."""
    free = [(k, lo, hi) for k, lo, hi in cfg.optimise.free or ()]
    fixed = [k for k, _, _ in free if k in PART_KEYS]
    if not fixed:
        return cfg, []
    rest = {k: [lo, hi] for k, lo, hi in free if k not in PART_KEYS}
    return cfg.set("optimise.free", rest or None), [
        f"optimise.free: {k} is set by each pair's parts, not chosen" for k in fixed]


def placement_keys(cfg: Config) -> tuple[str, ...]:
    """The placement keys ``optimise.free`` names (refusing the others: the parts fix the
    spring's rate, free length and preload, the damper's c)."""
    keys = [k for k, _, _ in cfg.optimise.free or ()]
    other = [k for k in keys if k not in PLACEMENT_KEYS]
    if other:
        raise ConfigError(f"select --free: {', '.join(other)} cannot be free here (the parts "
                          "fix the spring and the damper); free attachment points only, e.g. "
                          "--free 'geometry.lid_e[1]=0.004:0.024'")
    return tuple(keys)


def place_pair(cfg: Config, spring, damper, samples: int) -> dict:
    """The robust co-design of one pair: {values: {geometry key: value} (None when it found
    none), success, objective (its worst scenario), message}."""
    if damper.kind != "dashpot":
        return {"values": None, "success": False, "objective": None,
                "message": "a rotary damper: the config's points kept (the robust NLP fixes "
                           "only a dashpot's c)"}
    try:
        c = spring_config(cfg, spring, damper).update(
            {"optimise.damper_c": [damper.c, damper.c]})
        r = optimise_robust(c, samples=samples, verify=False, report=False)
    except SoftcloseError as exc:
        return {"values": None, "success": False, "objective": None,
                "message": str(exc).splitlines()[0]}
    d = r.design or {}
    values = {f"geometry.{k}": float(v) for k, v in d.items() if f"geometry.{k}" in
              PLACEMENT_KEYS}
    return {"values": values or None, "success": bool(values), "objective": r.objective,
            "message": (r.message or "").splitlines()[0] if r.message else ""}


__all__ = ["placement_keys", "place_pair", "parts_fix", "PART_KEYS"]
