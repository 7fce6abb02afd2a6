"""The machine elements: one home per element (the registry).

Every force on the linkage is one :class:`~softclose.model.elements.base.Element` of
:data:`ELEMENTS` (the contract is :mod:`softclose.model.elements.base`; where each acts,
:mod:`softclose.model.elements.coordinates`). The reduced equation, Newton-Euler with pin
reactions, the statics (holding moment, release check, equilibria), the CasADi model, the
coefficient table and the kernel's parameter rows, the adaptive reference and the
optimisers' dynamics all sum over this list; the config keys of each element come from it
too. The kernel states the same laws once, in the element section of ``_kernel.c``; its
design-row columns come from this registry (the generated header ``_layout.h``), and the
kernel's library is checked at load time against the same layout.

To add an element: write its unit (a subclass with its keys, parameters, coordinate and law),
add it to :data:`ELEMENTS`, regenerate the kernel's layout header (``python -m
softclose.simulation.kernel --write``), add its law to ``_kernel.c``'s element section, and
test it.
"""

from __future__ import annotations

import numpy as np

from ..keys import Key
from .base import Element, Param, Params
from .dampers import Dashpot, EndDamper, RotaryDamper
from .friction import Friction, StrutFriction
from .gravity import Gravity
from .springs import Spring, TorsionSpring

#: every element, in the order their contributions are summed (gravity first, then the
#: springs, then the dampers: the order of the seed's equation, so its sums are unchanged);
#: the end damper and the strut's friction, added last, put their parameters after every
#: earlier one in p
ELEMENTS: tuple[Element, ...] = (Gravity(), Spring(), TorsionSpring(), Dashpot(),
                                 RotaryDamper(), Friction(), EndDamper(), StrutFriction())
BY_NAME = {e.name: e for e in ELEMENTS}
#: the seed's parameters, which come first in p: (k, l0, c, c_rot)
SEED = ("spring_k", "spring_rest_length", "damper_c", "rotary_damper_c")
#: the per-stroke parameters: the columns of the parameter vector p. The seed's four come
#: first, then the others, in the order of :data:`ELEMENTS`.
PARAMS: tuple[Param, ...] = tuple(q for name in SEED for e in ELEMENTS for q in e.params
                                  if q.name == name) + tuple(
    q for e in ELEMENTS for q in e.params if q.name not in SEED)
#: their names (``design`` keys without the section)
PARAM_NAMES: tuple[str, ...] = tuple(q.name for q in PARAMS)
#: the config keys every element owns
KEYS: tuple[Key, ...] = tuple(k for e in ELEMENTS for k in e.keys)
#: the elements whose force is conservative (a law T(q)) and those that are viscous (B)
SPRINGS = tuple(e for e in ELEMENTS if e.affine.__func__ is not Element.affine)
DAMPERS = tuple(e for e in ELEMENTS if e.viscous.__func__ is not Element.viscous)
FRICTIONS = tuple(e for e in ELEMENTS if e.coulomb.__func__ is not Element.coulomb)
#: the elements that act only below an engagement angle (:attr:`Element.engagement`)
ENGAGING = tuple(e for e in ELEMENTS if e.engagement is not None)


def params(p, spring: str | None = None) -> Params:
    """The parameter vector (or rows) p as named SI values: ``params(p)["spring_k"]``;
    ``spring`` = "coil" or "gas": the spring law symbolic expressions serve (default: the
    kind in p decides; :class:`Params`)."""
    return Params(p, PARAMS, spring)


#: the parameters' defaults (their keys' defaults: the elements added since the seed absent)
PARAM_DEFAULTS = np.array([q.number(next(k.default for k in KEYS if k.full == q.key))
                           for q in PARAMS])


def as_params(p) -> np.ndarray:
    """A parameter vector (or rows of them) as a float array of every parameter: a shorter
    vector -- the seed's four (k, l0, c, c_rot), say -- gets the others from their defaults,
    which leave the elements added since absent."""
    p = np.asarray(p, float)
    n = p.shape[-1] if p.ndim else 0
    if n == len(PARAMS):
        return p
    if not 0 < n < len(PARAMS):
        raise ValueError(f"a parameter vector has {len(PARAMS)} values "
                         f"({', '.join(PARAM_NAMES)}), got {n}")
    rest = np.broadcast_to(PARAM_DEFAULTS[n:], p.shape[:-1] + (len(PARAMS) - n,))
    return np.concatenate([p, rest], axis=-1)


def structure(mounting) -> tuple:
    """The element choices of ``mounting`` (:class:`softclose.model.resolved.Mounting`) that
    change the model itself (not a per-stroke value): part of every cache key of a model, its
    table or an NLP."""
    return tuple(x for e in ELEMENTS for x in e.structure(mounting))


#: the elements whose coordinate the kernel reads from the coordinate table (tabulated when a
#: stroke needs it)
TABULATED = tuple(e for e in ELEMENTS if e.table == "coordinates")


def acting(p, extra_values: dict | None = None) -> tuple[Element, ...]:
    """The elements that exert a force with the design's parameter vector ``p`` (and
    ``extra_values``, a dict of design values that vary, e.g. swept or freed: their largest
    magnitude)."""
    values = {q.name: float(v) for q, v in zip(PARAMS, p)}
    values.update(extra_values or {})
    return tuple(e for e in ELEMENTS if bool(e.acts(values)))


def needs_coordinates(P, mounting) -> bool:
    """Does any row of P (parameter vectors) have an element acting that reads the table of
    element columns with ``mounting`` (a torsion spring, a rotary damper at a pivot)?"""
    import numpy as np
    P = np.atleast_2d(np.asarray(P, float))
    values = {q.name: P[:, i] for i, q in enumerate(PARAMS)}
    return any(bool(np.any(e.acts(values))) for e in TABULATED if e.in_coordinate_table(mounting))


#: the flags of a table the kernel reads (after ncell, lo, h, m0): its structural element
#: choices -- the rotary damper at a pivot rather than the lid
KERNEL_META = ("rotary_at_pivot",)


def kernel_meta(mounting) -> tuple[float, ...]:
    """The values of :data:`KERNEL_META` with ``mounting``."""
    return (float(BY_NAME["rotary"].in_coordinate_table(mounting)),)


def one_way(P, theta_d):
    """The dampers' factor with ``design.damper_one_way``: 0 while the lid opens (theta' > 0),
    else 1 (numbers, arrays or CasADi expressions alike)."""
    ow = P["damper_one_way"]
    if hasattr(theta_d, "is_symbolic") or hasattr(ow, "is_symbolic"):
        import casadi as ca
        return 1 - ow * ca.if_else(theta_d > 0, 1, 0)
    import numpy as np
    return 1 - ow * (np.asarray(theta_d) > 0)


__all__ = ["ELEMENTS", "BY_NAME", "ENGAGING", "FRICTIONS", "TABULATED", "needs_coordinates", "one_way", "PARAMS", "PARAM_NAMES", "KEYS", "SPRINGS", "DAMPERS",
           "Element", "Param", "Params", "params", "structure", "acting"]
