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

import sys
from importlib import import_module
from types import ModuleType

#: the package's names and the module of each, imported on first use: the model reads only
#: the materials, and a command that designs or checks no spring loads no standard
_LAZY = {"Check": "design", "CoilSpring": "design", "Duty": "design", "SpringCheck": "design",
         "check": "design", "SpringDesign": "designer", "DEFAULT_MATERIAL": "materials",
         "MATERIALS": "materials", "PREFERRED_WIRE_D": "materials", "Goodman": "materials",
         "Material": "materials", "material": "materials", "Tolerances": "tolerances",
         "spring_tolerances": "tolerances"}

__all__ = ["Check", "CoilSpring", "Duty", "SpringCheck", "SpringDesign", "check", "design",
           "DEFAULT_MATERIAL", "MATERIALS", "PREFERRED_WIRE_D", "Goodman", "Material",
           "material", "Tolerances", "spring_tolerances"]


def __getattr__(name: str):
    if name in _LAZY:
        value = getattr(import_module(f".{_LAZY[name]}", __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_LAZY) | {"design"})


class _Package(ModuleType):
    """This package: ``design`` names the designer (:func:`.designer.design`), never the
    module of the same name (which the import system would set here when it is loaded)."""

    @property
    def design(self):
        return import_module(".designer", __name__).design

    @design.setter
    def design(self, module):
        pass


sys.modules[__name__].__class__ = _Package
