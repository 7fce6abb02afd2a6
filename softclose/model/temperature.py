"""The parts at their operating temperature (SPEC §12): the values of a design are given at
the reference temperature ``operating.reference_temperature_c`` (a datasheet's 23 °C); a
stroke at ``operating.temperature_c`` = T sees them moved by their laws, with
ΔT = T - T_ref:

- every viscous coefficient (the dashpot's c, the rotary damper's c_rot, the end damper's
  c_e): c(T) = c exp(β ΔT), β = ``design.damper_temperature_coeff`` (silicone oil: about
  -0.005 /K);
- a coil spring's rate and preload (the spring of every coil kind, the torsion spring)
  follow the wire's shear modulus: × (1 - γ_G ΔT), γ_G of ``spring.material``
  (:mod:`softclose.coil_spring.materials`: 2.5e-4 /K for EN 10270-1 steel);
- a gas strut's force (its F1, ``design.spring_preload``) follows its gas at fixed volume:
  × τ = (T + 273.15) / (T_ref + 273.15) (about 0.34 %/K at room temperature).

:func:`parameter_factors` gives these factors over the parameter vector p -- one row for a
design with a coil spring, one for a design with a gas strut --; the simulator and the
reference apply them to every p of a stroke (:func:`at_temperature`, by each row's spring
kind), so a design (and every result that reports one) stays at the reference temperature.
At T = T_ref every factor is exactly 1.
"""

from __future__ import annotations

import math

import numpy as np

from ..coil_spring.materials import material
from . import elements
from .elements.springs import GAS

#: the viscous coefficients, moved by exp(beta dT)
VISCOUS = ("damper_c", "rotary_damper_c", "end_damper_c")
#: the coil springs' rates and preload, moved by the wire's shear modulus
COIL = ("spring_k", "spring_preload", "torsion_k")


def gas_factor(temperature_c: float, reference_c: float) -> float:
    """τ = (T + 273.15) / (T_ref + 273.15): a gas strut's force at T over its force at T_ref
    (an ideal gas at fixed volume)."""
    return (temperature_c + 273.15) / (reference_c + 273.15)


def parameter_factors(temperatures) -> np.ndarray | None:
    """The factor of each parameter of p (:data:`softclose.model.elements.PARAMS`) at
    ``temperatures.temperature_c`` (a :class:`softclose.model.resolved.Temperatures`), (2,
    len(p)): row 0 for a design whose spring is a coil spring, row 1 for one with a gas
    strut; None at the reference temperature (every factor 1), and for None."""
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
    gas = f.copy()
    for name in COIL:
        f[names.index(name)] = coil
    gas[names.index("torsion_k")] = coil
    gas[names.index("spring_preload")] = gas_factor(op.temperature_c,
                                                    op.reference_temperature_c)
    return np.vstack([f, gas])


#: the column of the spring's kind in p
_KIND = elements.PARAM_NAMES.index("spring_kind")


def at_temperature(P: np.ndarray, factors: np.ndarray | None) -> np.ndarray:
    """Parameter vectors (a vector or rows) ``P`` at the temperature of ``factors`` (each row
    by its spring's kind; unchanged for None)."""
    if factors is None:
        return P
    P = np.asarray(P, float)
    return P * factors[(P[..., _KIND] == GAS).astype(int)]


def factors_of(factors: np.ndarray | None, p) -> np.ndarray | None:
    """The factor row of ``factors`` that applies to the design p (its spring's kind)."""
    return None if factors is None else factors[int(np.asarray(p, float)[_KIND] == GAS)]


__all__ = ["parameter_factors", "at_temperature", "factors_of", "gas_factor", "VISCOUS", "COIL"]
