"""The coil spring made to order (SPEC §14): EN 13906-1 design and checks of cylindrical
helical compression springs, EN 13906-2's checks of an extension spring's body, EN 10270
spring wire, EN 15800 tolerances.

Pure calculations in SI units (no CasADi, nothing else of softclose but its errors):

- :mod:`~softclose.coil_spring.materials`: the wires (E, G, rho, R_m(d), Goodman data,
  gamma_G) and the preferred wire diameters;
- :mod:`~softclose.coil_spring.standard`: EN 13906-1's formulas;
  :mod:`~softclose.coil_spring.extension`: EN 13906-2's (the body; hooks not covered);
- :mod:`~softclose.coil_spring.tolerances`: EN 15800's tolerances;
- :mod:`~softclose.coil_spring.design`: :func:`check` a spring against a :class:`Duty`;
  :mod:`~softclose.coil_spring.designer`: :func:`design` one.

Example::

    from softclose.coil_spring import CoilSpring, Duty, check, design
    duty = Duty(rate=4682.0, free_length=0.060, longest_length=0.055,
                shortest_length=0.040, cycles=1e5)
    check(CoilSpring(0.002, 0.016, 8.5), duty).ok
    design(duty, max_outer_d=0.020).best
    # an extension spring: free length 40 mm, initial tension 4 N, pulled to 50..60 mm
    check(CoilSpring(0.001, 0.008, 20), Duty(rate=994.87, free_length=0.040,
          longest_length=0.060, shortest_length=0.050, kind="extension",
          initial_tension=4.0)).ok
"""

from .design import Check, CoilSpring, Duty, SpringCheck, check
from .designer import SpringDesign, design
from .materials import (DEFAULT_MATERIAL, MATERIALS, PREFERRED_WIRE_D, Goodman, Material,
                        material)
from .tolerances import Tolerances, spring_tolerances

__all__ = ["Check", "CoilSpring", "Duty", "SpringCheck", "SpringDesign", "check", "design",
           "DEFAULT_MATERIAL", "MATERIALS", "PREFERRED_WIRE_D", "Goodman", "Material",
           "material", "Tolerances", "spring_tolerances"]
