"""The parts at the end of their life (SPEC §17): the values of a design are the new parts';
``[life]`` says what changes by the end of life, and a stroke in ``life.state =
"end_of_life"`` sees them changed:

- a gas strut's whole force curve × (1 - ℓ), ℓ = ``life.strut_force_loss`` (its F1,
  ``design.spring_preload``; progression and stroke unchanged);
- a coil spring (linear, extension, compression) loses r = ``life.spring_relaxation`` of the
  force it holds while the lid is shut, at every length: ``F_eol(l) = F(l) - r F(l_shut)``,
  l_shut its length at ``stroke.theta_closed_deg``; its rate is unchanged. For an extension or
  a compression spring the loss comes off its preload first (a relaxed spring's free length
  is shorter by the loss over its rate: the preload at its working end drops), and what the
  preload cannot give moves its free length; the seed's linear cartridge moves its free
  length. A torsion spring the same with its moment at the shut angle (its free angle moves);
- every viscous coefficient (dashpot, rotary dampers, end damper) × (1 + δ_c),
  δ_c = ``life.damper_change``;
- ``friction.torque`` and ``design.strut_friction`` × (1 + δ_f), δ_f = ``life.friction_change``.

The changes are applied the way the temperature laws are (:mod:`softclose.model.temperature`):
to the parameter vectors p of the strokes (:func:`at_end_of_life`), before the temperature's
factors -- the two commute: the temperature scales a coil spring's rate and preload alike, and
a relaxed spring's free length does not move with it. Every stroke (the kernel, the adaptive
reference), the statics and the hand force read p after it, so the elements' laws and the
kernel are unchanged. At the defaults (every factor 0) or in ``life.state = "new"`` p is
unchanged.
"""

from __future__ import annotations

import numpy as np

from . import elements
from .elements.springs import GAS
from .keys import Key
from .resolved import Life

#: the states of a lid (``life.state``)
STATES = ("new", "end_of_life")

LIFE_KEYS: tuple[Key, ...] = (
    Key("life", "strut_force_loss", "nonneg", 0.0, "1",
        "fraction of a gas strut's force lost by the end of life: its whole force curve x "
        "(1 - loss) (makers: up to 0.10 over a strut's life)", lo=0.0, hi=0.99),
    Key("life", "spring_relaxation", "nonneg", 0.0, "1",
        "relaxation r of a coil spring (EN 13906-1: force lost at constant length): it loses "
        "r of the force it holds while the lid is shut, at every length, its rate unchanged; a "
        "torsion spring the same with its moment", lo=0.0, hi=0.99),
    Key("life", "damper_change", "real", 0.0, "1",
        "relative change of every viscous coefficient (dashpot, rotary dampers, end damper) "
        "by the end of life: c x (1 + change); negative: fade", lo=-0.99, hi=100.0),
    Key("life", "friction_change", "real", 0.0, "1",
        "relative change of `friction.torque` and `design.strut_friction` by the end of "
        "life: x (1 + change)", lo=-0.99, hi=100.0),
    Key("life", "state", "str:" + ",".join(STATES), "new", "",
        "the state of one stroke (simulate, state, a sweep key): `new` or `end_of_life` (the "
        "parts changed as [life] says)"),
)

#: the strict ends of the factors' ranges (the key records' ends are admissible): key ->
#: (lowest excluded, highest excluded)
STRICT = {"strut_force_loss": (None, 1.0), "spring_relaxation": (None, 1.0),
          "damper_change": (-1.0, None), "friction_change": (-1.0, None)}

_N = elements.PARAM_NAMES
_COL = {name: _N.index(name) for name in
        ("spring_k", "spring_rest_length", "spring_kind", "spring_preload", "torsion_k",
         "torsion_free_angle_deg", "damper_c", "rotary_damper_c", "end_damper_c",
         "friction_torque", "strut_friction")}
#: the viscous coefficients and the friction parameters
VISCOUS = ("damper_c", "rotary_damper_c", "end_damper_c")
FRICTION = ("friction_torque", "strut_friction")


def check_life(values: dict) -> str | None:
    """The one-line message of a ``[life]`` value outside its strict range (the key records'
    ends are included; a loss of 1 or a change of -1 is not a part), else None."""
    for name, (lo, hi) in STRICT.items():
        v = values.get(name)
        if v is None:
            continue
        if hi is not None and not v < hi:
            return f"life.{name}: must be below {hi:g} (a fraction lost), got {v}"
        if lo is not None and not v > lo:
            return f"life.{name}: must be above {lo:g} (a relative change), got {v}"
    return None


def ages(life: Life | None) -> bool:
    """Does ``life`` change any part (a factor non-zero)? Then the end of life is a
    sign-off state beside the new lid."""
    return life is not None and any(
        (life.strut_force_loss, life.spring_relaxation, life.damper_change,
         life.friction_change))


def aged(life: Life | None) -> bool:
    """Is a stroke of ``life`` at the end of life with a part changed?"""
    return life is not None and life.state == "end_of_life" and ages(life)


def factors(life: Life) -> np.ndarray:
    """The multiplicative factors of p at the end of life (1 for a parameter unchanged):
    (2, len(p)), row 0 for a design whose spring is a coil spring, row 1 for one with a gas
    strut (its F1 × (1 - ℓ))."""
    f = np.ones(len(_N))
    for name in VISCOUS:
        f[_COL[name]] = 1.0 + life.damper_change
    for name in FRICTION:
        f[_COL[name]] = 1.0 + life.friction_change
    gas = f.copy()
    gas[_COL["spring_preload"]] = 1.0 - life.strut_force_loss
    return np.vstack([f, gas])


def shut_coordinates(model) -> dict:
    """The coordinates of the springs at the shut angle ``stroke.theta_closed_deg`` of the lid
    ``model`` (a :class:`softclose.model.lid.LidModel`): {"spring": l_shut (m), "torsion":
    psi_shut (rad)}, exact (the model's own coordinate functions)."""
    th = model.stroke.theta_closed
    return {name: float(model.coordinate_fns[name](th)[0]) for name in ("spring", "torsion")}


def at_end_of_life(P, life: Life | None, shut: dict | None) -> np.ndarray:
    """Parameter vectors (a vector or rows) ``P`` of new parts at the end of ``life``: the
    same P when no stroke of ``life`` is aged (:func:`aged`). ``shut``: the springs'
    coordinates at the shut angle (:func:`shut_coordinates`; a value or one per row)."""
    if not aged(life):
        return P
    P = np.array(P, float)
    one = P.ndim == 1
    P = np.atleast_2d(P)
    kind = P[:, _COL["spring_kind"]]
    gas = kind == GAS
    P = P * factors(life)[gas.astype(int)]
    r = life.spring_relaxation
    if r:
        k, l0 = P[:, _COL["spring_k"]], P[:, _COL["spring_rest_length"]]
        F0 = P[:, _COL["spring_preload"]]
        coil = ~gas
        s = np.where(coil, kind, 0.0)
        l_shut = np.broadcast_to(np.asarray(shut["spring"], float), k.shape)
        # the tension it holds shut, T = s F0 + k (l - l0), and its loss r T: off the preload
        # first (extension, compression), the rest moves its free length
        loss = r * (s * F0 + k * (l_shut - l0)) * coil
        held = s * loss                       # the loss in the preload's own sense
        from_preload = np.where(s != 0, np.clip(held, 0.0, F0), 0.0)
        P[:, _COL["spring_preload"]] = F0 - from_preload
        rest = loss - s * from_preload
        stiff = coil & (k > 0)           # (without a rate the loss is the preload's alone)
        P[:, _COL["spring_rest_length"]] = np.where(stiff, l0 + rest / np.where(stiff, k, 1.0),
                                                    l0)
        kt = P[:, _COL["torsion_k"]]
        q0 = P[:, _COL["torsion_free_angle_deg"]]
        # (p holds the free angle in degrees)
        q_shut = np.broadcast_to(np.degrees(np.asarray(shut["torsion"], float)), kt.shape)
        P[:, _COL["torsion_free_angle_deg"]] = np.where(kt > 0, q0 + r * (q_shut - q0), q0)
    return P[0] if one else P


def life_map(p, life: Life, shut: dict, temperature=None) -> np.ndarray:
    """The end of ``life`` as an affine map of a stroke's parameters, for the scenario NLP
    (whose scenarios map the design's p as ``a p + b``): (2, len(p)), rows f and g with
    ``p_eol = f p + g``, then the ``temperature``'s factor row (None: 1) on both. The factors
    of the strut, the dampers and the friction are exact; a relaxed coil spring without a
    preload moves its free length to (1 - r) l0 + r l_shut (exact, affine), a torsion
    spring's free angle the same; with a preload its loss is taken at the design ``p`` (exact
    there; the verification judges the design with :func:`at_end_of_life`)."""
    p = np.asarray(p, float)
    gas = p[_COL["spring_kind"]] == GAS
    f = factors(life)[int(gas)].copy()
    g = np.zeros(len(p))
    r = life.spring_relaxation
    if r and not gas:
        i, j = _COL["spring_rest_length"], _COL["spring_preload"]
        f[i], g[i] = 1.0 - r, r * float(np.mean(shut["spring"]))
        if p[j] > 0 and p[_COL["spring_k"]] > 0:     # (the preload's part: at the design)
            old = at_end_of_life(p, life, shut)
            g[i] = old[i] - (1.0 - r) * p[i]
            f[j] = old[j] / p[j]
        if p[_COL["torsion_k"]] > 0:
            i = _COL["torsion_free_angle_deg"]
            f[i], g[i] = 1.0 - r, r * float(np.degrees(shut["torsion"]))
    if temperature is not None:
        f, g = f * temperature, g * temperature
    return np.vstack([f, g])


def stroke_params(P, case, shut_of=None) -> np.ndarray:
    """Parameter vectors ``P`` (new parts at the reference temperature) as a stroke of the
    resolved ``case`` (:class:`softclose.model.resolved.LidCase`) sees them: at the end of its
    life when ``life.state`` says so (``shut_of()`` gives the springs' shut coordinates,
    called only then), then at its operating temperature."""
    from .temperature import at_temperature, parameter_factors
    if case is None:
        return P
    life = getattr(case, "life", None)
    if aged(life):
        P = at_end_of_life(P, life, shut_of())
    return at_temperature(P, parameter_factors(case.temperatures))


__all__ = ["LIFE_KEYS", "STATES", "Life", "ages", "aged", "factors", "shut_coordinates",
           "at_end_of_life", "life_map", "stroke_params", "check_life"]
