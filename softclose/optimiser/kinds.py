"""Which springs the optimiser may choose: one problem per kind, its free length bounded so
that the spring stays on its side of it over the whole stroke.

A spring of kind ``extension`` only pulls (valid while l >= l0), ``compression`` only pushes
(valid while l <= l0), ``linear`` does both (SPEC §9). The optimiser's strokes are monotone
(theta' <= 0 is a constraint), so a stroke visits exactly [theta_closed, theta0], and the
spring's length over it runs over [l_min, l_max] of the geometry alone. Validity is then a
bound on the free length: l0 >= l_max for a compression spring, l0 <= l_min for an extension
spring -- tightened by the free length's own tolerance when the design must hold over a
tolerance box -- plus the length limits (``design.spring_min_length``,
``spring_max_length``), which the geometry either meets or not.
"""

from __future__ import annotations

import math

from ..config import Config
from .free_points import placement_layout
from .verify import get_checker


def spring_range(cfg: Config) -> tuple[float, float]:
    """(shortest, longest) spring length over the stroke's angles (the exact model)."""
    st = cfg.stroke
    return get_checker(cfg).spring_extremes(st.theta_closed, st.theta0)


def free_length_spread(cfg: Config, l0: float) -> float:
    """The half-width of the free length's tolerance at ``l0`` (m; 0 without one)."""
    for s in cfg.tolerance.spreads:
        if s.key == "design.spring_rest_length":
            return s.half_width(l0)
    return 0.0


def kind_config(cfg: Config, kind: str, robust: bool = False) -> tuple[Config, str | None]:
    """``cfg`` for solving with a spring of ``kind``: design.spring_kind set, and the free
    length's bounds tightened so that the spring stays valid over the whole stroke (with
    ``robust``, over the free length's tolerance too). Returns (config, why not) -- the
    reason when no free length within optimise.spring_rest_length keeps it valid."""
    d, o = cfg.design, cfg.optimise
    if placement_layout(cfg):   # the points move: validity is the NLP's constraint
        return cfg.update({"design.spring_kind": kind}), None
    lmin, lmax = spring_range(cfg)
    lo, hi = o.spring_rest_length
    if kind != "linear" and robust:             # l0 (1 -+ s) or l0 -+ s must stay valid
        s = next((x for x in cfg.tolerance.spreads if x.key == "design.spring_rest_length"),
                 None)
    else:
        s = None
    if kind == "compression":
        need = lmax if s is None else (lmax / (1 - s.value) if s.relative else lmax + s.value)
        lo = max(lo, need)
        if d.spring_min_length is not None and d.spring_min_length > lmin:
            return cfg, (f"a compression spring would be compressed to {lmin * 1e3:.2f} mm, "
                         f"below its solid length design.spring_min_length = "
                         f"{d.spring_min_length * 1e3:.2f} mm")
    elif kind == "extension":
        need = lmin if s is None else (lmin / (1 + s.value) if s.relative else lmin - s.value)
        hi = min(hi, need)
        if d.spring_max_length is not None and d.spring_max_length < lmax:
            return cfg, (f"an extension spring would be stretched to {lmax * 1e3:.2f} mm, "
                         f"beyond its maximum length design.spring_max_length = "
                         f"{d.spring_max_length * 1e3:.2f} mm")
    else:
        for limit, length, word in ((d.spring_min_length, lmin, "shorter"),
                                    (d.spring_max_length, lmax, "longer")):
            if limit is not None and ((word == "shorter" and length < limit)
                                      or (word == "longer" and length > limit)):
                return cfg, (f"the spring would be {word} than its limit {limit * 1e3:.2f} mm "
                             f"({length * 1e3:.2f} mm over the stroke)")
    if not lo <= hi:
        side = ("at least" if kind == "compression" else "at most")
        return cfg, (f"a {kind} spring needs a free length {side} "
                     f"{(lo if kind == 'compression' else hi) * 1e3:.2f} mm (its length runs "
                     f"{lmin * 1e3:.2f}..{lmax * 1e3:.2f} mm over the stroke), outside "
                     f"optimise.spring_rest_length = [{o.spring_rest_length[0]:g}, "
                     f"{o.spring_rest_length[1]:g}] m")
    out = cfg.update({"design.spring_kind": kind,
                      "optimise.spring_rest_length": [float(lo), float(hi)]})
    return out, None


def describe_range(cfg: Config) -> str:
    """One line: the spring's length over the stroke and what each kind needs."""
    lmin, lmax = spring_range(cfg)
    return (f"the spring's length runs {lmin * 1e3:.2f}..{lmax * 1e3:.2f} mm over the stroke: "
            f"a compression spring needs a free length >= {lmax * 1e3:.2f} mm, an extension "
            f"spring <= {lmin * 1e3:.2f} mm")


def finite(x) -> bool:
    return x is not None and math.isfinite(x)
