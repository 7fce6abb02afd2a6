"""What a config resolves to: the small immutable objects the model and the simulation take.

A :class:`~softclose.config.Config` is read once, at the top -- by the features, the command
line or the package root, through :func:`softclose.problem.resolve` -- into these; below the
features nothing takes a config:

- :class:`Lid` -- the lid on its mechanism: the ``[geometry]`` and ``[mass]`` values (the
  mechanism's kind, lengths, points; masses, inertias) and the :class:`Mounting` of its
  elements;
- :class:`Mounting` -- the element choices that are not per-stroke values: where the torsion
  spring and the rotary damper sit, the spring's length limits;
- :class:`StrokeEnds` -- the release, closed and open angles of the stroke, its longest time;
- :class:`SolverSettings` -- the fixed-step integrator, its step, the reference's tolerance;
- :class:`Temperatures` -- the operating and reference temperatures and the laws that move
  the parts' values between them;
- :class:`Life` -- what changes by the end of the parts' life, and the state of a stroke;
- :class:`LidCase` -- one config's lid, stroke, design vector p, solver settings,
  temperatures and life together: what a :class:`~softclose.simulation.simulator.Simulator` runs.

Every object is a NamedTuple of values (equal and hashed by value, picklable); the sections
it holds (``geometry``, ``mass``) are the config's immutable section values.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np

from ..coil_spring.materials import DEFAULT_MATERIAL


class Mounting(NamedTuple):
    """Where the elements sit and the limits that are not per-stroke values."""

    #: the pivot of the torsion spring (``design.torsion_pivot``)
    torsion_pivot: str = "O"
    #: where the rotary damper acts (``design.rotary_damper_pivot``)
    rotary_damper_pivot: str = "lid"
    #: the spring's shortest and longest admissible length (m; None: no limit)
    spring_min_length: float | None = None
    spring_max_length: float | None = None


class Lid(NamedTuple):
    """The lid on its mechanism: geometry, masses and the mounting of its elements."""

    #: the ``[geometry]`` values: the mechanism's kind, lengths and points
    geometry: Any
    #: the ``[mass]`` values: masses, inertias, gravity
    mass: Any
    mounting: Mounting = Mounting()
    #: ``mass.inertia_lid`` follows the lid's mass (m1 L²/12: not given in the config)
    inertia_follows_mass: bool = True

    @property
    def mechanism(self) -> str:
        """``four_bar`` or ``hinge``."""
        return self.geometry.mechanism

    def with_lid_mass(self, lid_mass: float) -> "Lid":
        """The same lid at another mass ``mass.lid`` (its inertia m1 L²/12 with it unless the
        config gave the inertia), as a config with that mass would resolve."""
        values = self.mass._asdict()
        values["lid"] = float(lid_mass)
        if self.inertia_follows_mass:
            values["inertia_lid"] = values["lid"] * self.geometry.lid_length ** 2 / 12
        return self._replace(mass=type(self.mass)(**values))


class StrokeEnds(NamedTuple):
    """The stroke's angles (degrees, as the config gives them) and its longest time."""

    theta0_deg: float
    theta_closed_deg: float
    theta_open_deg: float
    t_max: float

    @property
    def theta0(self) -> float:
        """The release angle (rad)."""
        return math.radians(self.theta0_deg)

    @property
    def theta_closed(self) -> float:
        """The closed angle, the rim (rad)."""
        return math.radians(self.theta_closed_deg)


class SolverSettings(NamedTuple):
    """How a stroke is integrated: the fixed-step method and step, the reference's tolerance."""

    integrator: str = "rk4"
    step: float = 0.002
    reference_tol: float = 1e-12


class Temperatures(NamedTuple):
    """The temperature of a stroke and the laws of the parts' values
    (:mod:`softclose.model.temperature`)."""

    temperature_c: float = 23.0
    reference_temperature_c: float = 23.0
    #: beta of every viscous coefficient, c exp(beta (T - T_ref)) (1/K)
    damper_temperature_coeff: float = 0.0
    #: the coil springs' wire (``spring.material``)
    spring_material: str = DEFAULT_MATERIAL


class Life(NamedTuple):
    """What changes by the end of the parts' life and the state of a stroke
    (:mod:`softclose.model.life`); every factor 0: nothing changes."""

    #: a gas strut's force lost (fraction)
    strut_force_loss: float = 0.0
    #: a coil spring's relaxation: the fraction of its shut force lost, at every length
    spring_relaxation: float = 0.0
    #: relative change of every viscous coefficient
    damper_change: float = 0.0
    #: relative change of the friction torque and the strut's friction
    friction_change: float = 0.0
    #: ``new`` or ``end_of_life``: the state of a stroke
    state: str = "new"


class LidCase(NamedTuple):
    """One config, resolved: the lid, its stroke, its design (the parameter vector p, at the
    reference temperature), the solver settings and the temperatures."""

    lid: Lid
    stroke: StrokeEnds
    #: the parameter vector p (:data:`softclose.model.elements.PARAMS`) of the design
    design: tuple[float, ...]
    solver: SolverSettings = SolverSettings()
    temperatures: Temperatures = Temperatures()
    #: what changes by the end of life and the state of the stroke
    life: Life = Life()

    @property
    def p(self) -> np.ndarray:
        """The design's parameter vector as an array."""
        return np.array(self.design, float)


__all__ = ["Lid", "Mounting", "StrokeEnds", "SolverSettings", "Temperatures", "Life", "LidCase"]
