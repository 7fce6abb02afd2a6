"""The parts to buy: the spring (a compression spring's EN 13906-1 checks, an extension
spring's EN 13906-2 body checks, a gas strut's datasheet values, an ideal spring's rate) and the
dampers with their coefficients at each operating temperature, c(T) = c exp(β (T − T_ref))."""

from __future__ import annotations

import math

from ..coil_spring import SpringCheck
from ..errors import ConfigError
from ..model import elements
from ..model.elements.springs import strut_stroke
from ..problem import params_of
from ..model.temperature import gas_factor


def _spring(cfg, stroke, temps) -> dict:
    d = cfg.design
    lengths = {"shortest_length": None if stroke is None else stroke.min_spring_length,
               "longest_length": None if stroke is None else stroke.max_spring_length}
    if d.spring_kind == "gas_strut":
        t_ref = cfg.operating.reference_temperature_c
        stroke_s = float(strut_stroke(elements.params(params_of(cfg))))
        return {"kind": "gas_strut", "what": "gas strut (pushes only)",
                "extended_length": d.spring_rest_length, "stroke": stroke_s,
                "force_f1": d.spring_preload, "progression": d.strut_progression,
                "force_f2": d.strut_progression * d.spring_preload,
                "friction": d.strut_friction, "friction_band": 2 * d.strut_friction,
                **lengths,
                "force_f1_at": [{"temperature_c": T, "force_f1": d.spring_preload
                                 * gas_factor(T, t_ref)} for T in temps]}
    if not d.spring_k and not d.spring_preload:
        return {"kind": "none", "what": "no spring"}
    out = {"kind": d.spring_kind, "what": f"{d.spring_kind} spring", "rate": d.spring_k,
           "rest_length": d.spring_rest_length, "preload": d.spring_preload, **lengths}
    if d.spring_kind not in ("compression", "extension"):
        out["note"] = ("the EN 13906-1/-2 checks apply to a compression or extension spring "
                       "made to order; this spring is given by its rate and rest length")
        return out
    from ..optimiser.spring_order import spring_duty, spring_order
    try:
        duty = spring_duty(cfg)
        res = spring_order(cfg, duty)
    except ConfigError as exc:
        out.update(ok=False, message=str(exc).splitlines()[0])
        return out
    payload = res.to_json()
    if isinstance(res, SpringCheck):
        ok, mode = res.ok, "checked"
        msg = ("the spring meets every check" if ok else "the spring fails "
               + ", ".join(c["name"] for c in payload["checks"] if not c["ok"]))
    else:
        ok, mode, msg = res.success, "designed", res.message
    out.update(ok=bool(ok), mode=mode, message=msg, material=cfg.spring.material,
               coil_spring=payload["spring"], checks=payload["checks"])
    return out


def _dampers(cfg, temps) -> list[dict]:
    d = cfg.design
    beta, t_ref = d.damper_temperature_coeff, cfg.operating.reference_temperature_c
    out = []
    for key, what, unit in (("damper_c", "linear dashpot" + (" (one-way)" if d.damper_one_way
                                                              else ""), "N s/m"),
                            ("rotary_damper_c", f"rotary damper at {d.rotary_damper_pivot}",
                             "N m s/rad"),
                            ("end_damper_c", f"end damper below {d.end_damper_angle_deg:g} deg",
                             "N m s/rad")):
        c = getattr(d, key)
        if not c:
            continue
        out.append({"key": f"design.{key}", "what": what, "coefficient": c, "unit": unit,
                    "at": [{"temperature_c": T, "coefficient": c * math.exp(beta * (T - t_ref))}
                           for T in temps]})
    return out


def parts(cfg, stroke, temps) -> dict:
    """The spring and the dampers (see the module docstring); ``failures``: a part that
    cannot be made as required, in words."""
    spring = _spring(cfg, stroke, temps)
    fails = []
    # a spring the config gives ([spring] wire, coil diameter and coils) must pass its
    # checks; one designed here is advice: without one that can be made, the part is bought
    # (a gas strut or a catalog spring of this rate and free length), which is no failure
    if spring.get("ok") is False and spring.get("mode") != "designed":
        fails.append(f"spring: {spring['message']}")
    elif spring.get("ok") is False:
        spring["note"] = ("no coil spring made to order meets every check; buy a gas strut "
                          "or a catalog spring of this rate and free length")
    return {"spring": spring, "dampers": _dampers(cfg, temps),
            "damper_temperature_coeff": cfg.design.damper_temperature_coeff,
            "reference_temperature_c": cfg.operating.reference_temperature_c,
            "failures": fails}


__all__ = ["parts"]
