"""The equation of motion with the fitted keys as symbols.

A fit may free any numeric parameter of the lid's dynamics: the masses, inertias and gravity
of ``[mass]`` (they enter the generalised mass M(theta) and gravity's potential), and the
elements' parameters of the stroke's parameter vector p (``[design]``, ``friction.torque``).
The equation is the model's own (:func:`softclose.model.dynamics.coefficients`,
:func:`softclose.model.dynamics.theta_ddot`) with those values replaced by CasADi symbols; the
geometry stays the config's. The stroke closes monotonically (theta' <= 0), so dry friction
acts as the constant moment against a closing lid (``moving = -1``), as in the NLP of the
optimiser and the reference's closing phase.

Keys that are not free keep the config's values, except derived keys the config does not
give: with ``mass.lid`` free and ``mass.inertia_lid`` not given, the inertia follows the mass
as the config derives it (m L^2/12), as it does in the calibrated config written from the fit
(:func:`derived_followers` names them).
"""

from __future__ import annotations


import casadi as ca
import numpy as np

from ..model import elements
from ..config.schema import BY_NAME, KEYS, RANGES
from ..model.dynamics import coefficients, theta_ddot
from ..errors import ConfigError
from ..problem import PARAM_COLUMNS

#: the [mass] keys a fit may free
MASS_KEYS = tuple(f"mass.{k}" for k in ("lid", "crank_oa", "crank_bc", "inertia_lid",
                                        "inertia_oa", "inertia_bc", "gravity"))
#: the parameter-vector keys a fit may free (numeric ones: not a spring's kind or a flag)
PARAM_FIT_KEYS = tuple(q.key for q in elements.PARAMS if q.codes is None)
#: every key a fit may free, in the order results list them
FIT_KEYS = MASS_KEYS + PARAM_FIT_KEYS


def why_not_fit(key: str) -> str | None:
    """Why ``key`` cannot be fitted (None: it can)."""
    if key in FIT_KEYS:
        return None
    base = key.split("[")[0]
    if base in BY_NAME:
        return (f"--free {key}: only the lid's dynamic parameters can be fitted (the geometry "
                f"and the settings stay as configured): {', '.join(FIT_KEYS)}")
    return f"--free {key}: unknown key (keys that can be fitted: {', '.join(FIT_KEYS)})"


def check_keys(keys) -> tuple[str, ...]:
    """The free keys, checked (one line naming a bad or repeated key)."""
    keys = tuple(keys)
    if not keys:
        raise ConfigError("--free: name at least one key to fit, e.g. --free design.damper_c")
    for k in keys:
        why = why_not_fit(k)
        if why:
            raise ConfigError(why)
    dup = [k for k in set(keys) if keys.count(k) > 1]
    if dup:
        raise ConfigError(f"--free {dup[0]}: named twice")
    return keys


def value_of(cfg, key: str) -> float:
    section, name = key.split(".")
    return float(getattr(getattr(cfg, section), name))


def bounds_of(key: str) -> tuple[float, float]:
    """Admissible values of a fitted key (its kind's sign and the config's range)."""
    k = BY_NAME[key]
    lo, hi = (RANGES[key][0], RANGES[key][1]) if key in RANGES else (-np.inf, np.inf)
    if k.kind == "pos":
        lo = max(lo, 0.0)
    elif k.kind == "nonneg":
        lo = max(lo, 0.0)
    return lo, hi


def derived_followers(cfg, keys) -> tuple[str, ...]:
    """The [mass] keys the config derives (not given, not fitted): they follow the fitted
    masses (the inertias m l^2/12)."""
    given = cfg.raw.get("mass", {})
    return tuple(k.full for k in KEYS if k.section == "mass" and k.derive is not None
                 and k.name not in given and k.full not in keys)


def fit_ode(model, cfg, keys) -> ca.Function:
    """``ode(x, u) -> x'`` of ``model``'s lid (that of ``cfg``) with the values ``u`` of
    ``keys`` (in the keys' own units) as inputs; the closing direction's dry friction
    (theta' <= 0)."""
    u = ca.SX.sym("u", len(keys))
    mass = cfg.mass._asdict()
    for i, k in enumerate(keys):
        if k in MASS_KEYS:
            mass[k.split(".")[1]] = u[i]
    if any(k in MASS_KEYS for k in keys):
        values = {"geometry": cfg.geometry._asdict(), "mass": mass}
        for full in derived_followers(cfg, keys):
            mass[full.split(".")[1]] = BY_NAME[full].derive(values)
    lid = model.lid._replace(mass=type(cfg.mass)(**mass))
    th, thd = ca.SX.sym("theta"), ca.SX.sym("theta_dot")
    p = ca.SX(model.params())
    for i, k in enumerate(keys):
        if k in PARAM_COLUMNS:
            p[PARAM_COLUMNS[k]] = u[i]
    cf = coefficients(th, lid, model.sigma)
    tdd = theta_ddot(cf, thd, p, -1.0)
    x = ca.vertcat(th, thd)
    return ca.Function("fit_ode", [x, u], [ca.cse(ca.vertcat(thd, tdd))], ["x", "u"], ["xdot"])


__all__ = ["MASS_KEYS", "PARAM_FIT_KEYS", "FIT_KEYS", "why_not_fit", "check_keys",
           "value_of", "bounds_of", "derived_followers", "fit_ode"]
