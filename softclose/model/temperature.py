"""The parts at their operating temperature (SPEC §12): the values of a design are given at
the reference temperature ``operating.reference_temperature_c`` (a datasheet's 23 °C); a
stroke at ``operating.temperature_c`` = T sees them moved by their laws, with
ΔT = T - T_ref:

- every viscous coefficient (the dashpot's c, the rotary damper's c_rot, the end damper's
  c_e): c(T) = c exp(β ΔT), β = ``design.damper_temperature_coeff`` (silicone oil: about
  -0.005 /K);
- a coil spring's rate and preload (the spring of every kind, the torsion spring) follow
  the wire's shear modulus: × (1 - γ_G ΔT), γ_G of ``spring.material``
  (:mod:`softclose.coil_spring.materials`: 2.5e-4 /K for EN 10270-1 steel).

:func:`parameter_factors` gives these factors over the parameter vector p; the simulator
and the reference apply them to every p of a stroke, so a design (and every result that
reports one) stays at the reference temperature. At T = T_ref every factor is exactly 1.
"""

from __future__ import annotations

import math

import numpy as np

from ..coil_spring.materials import material
from . import elements

#: the viscous coefficients, moved by exp(beta dT)
VISCOUS = ("damper_c", "rotary_damper_c", "end_damper_c")
#: the coil springs' rates and preload, moved by the wire's shear modulus
COIL = ("spring_k", "spring_preload", "torsion_k")


def parameter_factors(temperatures) -> np.ndarray | None:
    """The factor of each parameter of p (:data:`softclose.model.elements.PARAMS`) at
    ``temperatures.temperature_c`` (a :class:`softclose.model.resolved.Temperatures`); None
    at the reference temperature (every factor 1), and for None."""
    op = temperatures
    if op is None:
        return None
    dT = op.temperature_c - op.reference_temperature_c
    if dT == 0.0:
        return None
    damping = math.exp(op.damper_temperature_coeff * dT)
    coil = material(op.spring_material).g_factor(op.temperature_c, op.reference_temperature_c)
    names = [q.name for q in elements.PARAMS]
    f = np.ones(len(names))
    for name in VISCOUS:
        f[names.index(name)] = damping
    for name in COIL:
        f[names.index(name)] = coil
    return f


def at_temperature(P: np.ndarray, factors: np.ndarray | None) -> np.ndarray:
    """Parameter vectors (rows) ``P`` at the temperature of ``factors`` (unchanged for
    None)."""
    return P if factors is None else P * factors


__all__ = ["parameter_factors", "at_temperature", "VISCOUS", "COIL"]
