"""Which springs the optimiser may choose: one problem per kind, its free length bounded so
that the spring stays on its side of it over the whole stroke.

A spring of kind ``extension`` only pulls (valid while l >= l0), ``compression`` only pushes
(valid while l <= l0), ``linear`` does both (SPEC §9), a ``gas_strut`` pushes over its stroke
s (valid while l0 - s <= l <= l0, SPEC §12). The optimiser's strokes are monotone
(theta' <= 0 is a constraint), so a stroke visits exactly [theta_closed, theta0], and the
spring's length over it runs over [l_min, l_max] of the geometry alone. Validity is then a
bound on the free length: l0 >= l_max for a compression spring, l0 <= l_min for an extension
spring, l_max <= l0 <= l_min + s for a gas strut (l0 <= l_min / 0.6 when its stroke is the
default 0.4 l0) -- tightened by the free length's own tolerance when the design must hold
over a tolerance box -- plus the length limits (``design.spring_min_length``,
``spring_max_length``), which the geometry either meets or not.

A gas strut's variables are its extended length l0 and its force F1
(``design.spring_preload``; bounded by ``--free design.spring_preload=LO:HI``, or by default
from 0 to :func:`strut_force_bound`); its rate is not used (bounded to 0).
"""

from __future__ import annotations

import math

import numpy as np

from ..config import Config
from ..model.elements.springs import STROKE_FRACTION
from .free_points import placement_layout
from .verify import get_checker


def spring_range(cfg: Config) -> tuple[float, float]:
    """(shortest, longest) spring length over the stroke's angles (the exact model)."""
    st = cfg.stroke
    return get_checker(cfg).spring_extremes(st.theta_closed, st.theta0)


def strut_force_bound(cfg: Config) -> float:
    """A gas strut's largest F1 by default (N): five times the force whose moment along the
    strut's best lever over the stroke equals gravity's largest moment, rounded up to 1, 2 or
    5 times a power of ten -- more than any lid of this geometry can use."""
    from ..model.lid import shared_model
    from ..problem import resolve
    model = shared_model(resolve(cfg))
    st = cfg.stroke
    th = np.linspace(st.theta_closed, st.theta0, 201)
    c = np.asarray(model.coeffs.map(len(th))(th)[0])
    from ..model.dynamics import COEFFS
    dVg = np.abs(c[COEFFS.index("dVg")]).max()
    dl = np.abs(c[COEFFS.index("dl")]).max()
    F = 5 * dVg / max(dl, 1e-9)
    e = 10 ** math.floor(math.log10(F))
    return float(next(m * e for m in (1, 2, 5, 10) if m * e >= F))


def _length_spread(cfg: Config, kind: str, robust: bool):
    """The free length's spread a robust design must stay valid over (None: none)."""
    if kind != "linear" and robust:             # l0 (1 -+ s) or l0 -+ s must stay valid
        return next((x for x in cfg.tolerance.spreads
                     if x.key == "design.spring_rest_length"), None)
    return None


def free_length_bounds(cfg: Config, kind: str, lmin, lmax, robust: bool = False):
    """optimise.spring_rest_length tightened so that a spring of ``kind`` whose length runs
    over [lmin, lmax] stays valid (with ``robust``, over the free length's tolerance too):
    (lo, hi), numbers or arrays like lmin and lmax (lo > hi: none is valid). A gas strut's
    and a linear spring's are the config's."""
    lo, hi = cfg.optimise.spring_rest_length
    s = _length_spread(cfg, kind, robust)
    if kind == "compression":
        need = lmax if s is None else (lmax / (1 - s.value) if s.relative else lmax + s.value)
        lo = np.maximum(lo, need)
    elif kind == "extension":
        need = lmin if s is None else (lmin / (1 + s.value) if s.relative else lmin - s.value)
        hi = np.minimum(hi, need)
    return lo, hi


def kind_config(cfg: Config, kind: str, robust: bool = False) -> tuple[Config, str | None]:
    """``cfg`` for solving with a spring of ``kind``: design.spring_kind set, and the free
    length's bounds tightened so that the spring stays valid over the whole stroke (with
    ``robust``, over the free length's tolerance too). Returns (config, why not) -- the
    reason when no free length within optimise.spring_rest_length keeps it valid."""
    d, o = cfg.design, cfg.optimise
    if placement_layout(cfg):   # the points move: validity is the NLP's constraint
        if kind == "gas_strut":
            return _strut_variables(cfg), None
        return cfg.update({"design.spring_kind": kind}), None
    lmin, lmax = spring_range(cfg)
    lo, hi = o.spring_rest_length
    s = _length_spread(cfg, kind, robust)
    if kind == "gas_strut":
        return _strut_config(cfg, lo, hi, lmin, lmax, s)
    lmin, lmax = _relaxed_range(cfg, kind, lmin, lmax) if robust else (lmin, lmax)
    lo, hi = free_length_bounds(cfg, kind, lmin, lmax, robust)
    if kind == "compression":
        if d.spring_min_length is not None and d.spring_min_length > lmin:
            return cfg, (f"a compression spring would be compressed to {lmin * 1e3:.2f} mm, "
                         f"below its solid length design.spring_min_length = "
                         f"{d.spring_min_length * 1e3:.2f} mm")
    elif kind == "extension":
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


def _relaxed_range(cfg, kind: str, lmin: float, lmax: float) -> tuple[float, float]:
    """The range a coil spring's new free length must keep valid when it also signs off at
    the end of life relaxed by r (SPEC §17): its relaxed free length (1 - r) l0 + r l_shut
    (without a preload; a preload only helps) stays beyond the stroke's longest length (a
    compression spring) or below its shortest (an extension spring)."""
    from ..model.life import shut_coordinates
    from ..problem import resolve_life, sign_off_states
    r = resolve_life(cfg).spring_relaxation
    if not r or kind not in ("compression", "extension") or len(sign_off_states(cfg)) == 1:
        return lmin, lmax
    from .cache import get_model
    ls = shut_coordinates(get_model(cfg))["spring"]
    moved = lambda length: (length - r * ls) / (1 - r)  # noqa: E731
    return (min(lmin, moved(lmin)), lmax) if kind == "extension" else \
        (lmin, max(lmax, moved(lmax)))


def _strut_config(cfg, lo, hi, lmin, lmax, s) -> tuple[Config, str | None]:
    """:func:`kind_config` of a gas strut: lmax <= l0 (its extended length) and l0 - stroke
    <= lmin; F1 free; the rate 0."""
    d, o = cfg.design, cfg.optimise
    free = dict((k, (a, b)) for k, a, b in o.free or ())
    if "design.strut_stroke" in free:
        return cfg, ("design.strut_stroke cannot be free (the strut's stroke bounds its "
                     "extended length): give it, or leave it at 0.4 x the extended length")
    if d.spring_min_length is not None and d.spring_min_length > lmin:
        return cfg, (f"a gas strut would be pushed in to {lmin * 1e3:.2f} mm, below its "
                     f"compressed length design.spring_min_length = "
                     f"{d.spring_min_length * 1e3:.2f} mm")
    grow = (lambda x: x / (1 - s.value)) if s is not None and s.relative else \
        (lambda x: x + s.value) if s is not None else (lambda x: x)
    shrink = (lambda x: x / (1 + s.value)) if s is not None and s.relative else \
        (lambda x: x - s.value) if s is not None else (lambda x: x)
    lo = max(lo, grow(lmax))
    top = lmin + d.strut_stroke if d.strut_stroke else lmin / (1 - STROKE_FRACTION)
    hi = min(hi, shrink(top))
    if not lo <= hi:
        stroke = (f"its stroke {d.strut_stroke * 1e3:.2f} mm" if d.strut_stroke else
                  f"its stroke {STROKE_FRACTION:g} x its extended length")
        return cfg, (f"a gas strut needs an extended length between {lo * 1e3:.2f} and "
                     f"{hi * 1e3:.2f} mm (its length runs {lmin * 1e3:.2f}..{lmax * 1e3:.2f} "
                     f"mm over the stroke, {stroke}) within optimise.spring_rest_length = "
                     f"[{o.spring_rest_length[0]:g}, {o.spring_rest_length[1]:g}] m: "
                     "none fits; give design.strut_stroke or widen the bounds")
    return _strut_variables(cfg.update(
        {"optimise.spring_rest_length": [float(lo), float(hi)]})), None


def _strut_variables(cfg) -> Config:
    """``cfg`` with a gas strut: its F1 free (by default from 0 to
    :func:`strut_force_bound`), its rate 0."""
    free = {k: (a, b) for k, a, b in cfg.optimise.free or ()}
    if "design.spring_preload" not in free:
        free["design.spring_preload"] = (0.0, strut_force_bound(cfg))
    return cfg.update({"design.spring_kind": "gas_strut", "design.spring_k": 0.0,
                       "optimise.spring_k": [0.0, 0.0],
                       "optimise.free": {k: [float(a), float(b)] for k, (a, b) in free.items()}})


def finite(x) -> bool:
    return x is not None and math.isfinite(x)
