"""The contract of a machine element: a coordinate, a law on it, the keys it owns.

Every force on the linkage comes from one element (:mod:`softclose.model.elements` lists them).
An element states, once:

- its **coordinate** q(theta) (:mod:`softclose.model.elements.coordinates`): a length between a
  lid point and a ground point, the relative rotation at a pivot (O: phi, B: gamma,
  A: theta - phi, C: theta - gamma, the lid: theta), or -- for gravity -- the weights'
  potential itself. The equation of motion needs q and its theta-derivative q' = dq/dtheta;
  the speed along the coordinate is q' theta';
- its **law** on that coordinate: the potential ``V(q)`` and the conservative force along q,
  ``T(q) = dV/dq`` (a spring's tension: it resists an increase of q), and a viscous
  coefficient ``B`` (a damper's force along q is ``-B q-dot``). The reduced equation is

      M theta'' + 1/2 M' theta'^2 = -sum T_e(q_e) q_e'  -  (sum B_e q_e'^2) theta',

  the energy ``1/2 M theta'^2 + sum V_e`` falls by the dampers' power
  ``-(sum B_e q_e'^2) theta'^2``, and the holding moment is ``sum T_e q_e'`` at the rim;
- ``affine(P) = (a, b)`` with ``T = a + b q`` on its valid range: the NLP's fast form of the
  equation (every conservative law here is affine in q where it is valid);
- its **valid range** of q (``valid``; a stroke that leaves it is an invalid design) -- the
  whole line for the elements of the seed;
- its **parameters**: the per-stroke values (columns of the parameter vector p, in the
  order of :data:`softclose.model.elements.PARAMS`), with the factor that turns each into SI;
- the **kernel columns** it needs (``columns``: its q, q' or q'^2 tabulated over theta) and
  the name of its law in ``_kernel.c``'s element section, which also states what the law
  contributes to the early exit's energy bound;
- its **config keys** (:class:`softclose.model.keys.Key`: kind, default, range, unit, spread, doc).

A law is arithmetic on its arguments only, so one definition serves CasADi expressions (the
model, the NLP), numpy arrays (statics over the coefficient table) and floats alike.

What comes next fits the same contract: a spring that only pulls or only pushes is an
affine law with a valid range (the kink at the free length is where the range ends, and a
stroke that reaches it is reported, never integrated through); a preload is the constant a
of its affine law; friction is an element whose force along q is set-valued at zero speed
(``stick``: the largest force it can hold), which the stroke loop treats as a stick/slip
state.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ..keys import Key


class Param(NamedTuple):
    """A per-stroke parameter of an element: its ``design`` key and the factor to SI, or --
    for a key whose value is a word (a spring's kind) -- the number each word stands for in p."""

    name: str
    si: float = 1.0
    codes: dict | None = None
    config_key: str | None = None        # when not ``design.<name>``
    none: float | None = None            # the number p holds for a key left at none

    @property
    def key(self) -> str:
        return self.config_key or f"design.{self.name}"

    def number(self, value) -> float:
        """The config value as the number p holds (a word by its code; none by :attr:`none`)."""
        if value is None and self.none is not None:
            return self.none
        return float(self.codes[value] if self.codes is not None else value)

    def word(self, number: float) -> str:
        """The word of a coded parameter's number."""
        return next(w for w, c in self.codes.items() if c == number)


class Params:
    """The parameter vector p as named SI values: ``P["spring_k"]``.

    ``p`` is a vector (CasADi or numpy, one design) or an array of rows (numpy, one design a
    row); a parameter with an SI factor other than 1 (an angle in degrees) is scaled, the
    others are passed through untouched. ``spring``: the spring law the expressions serve
    (:attr:`spring`).
    """

    def __init__(self, p, order: tuple[Param, ...], spring: str | None = None):
        self._p = p
        #: the spring law an expression serves: "coil", "gas" (a gas strut), or None -- any,
        #: by the kind in p (a CasADi expression of a symbolic kind then holds both laws,
        #: selected by the kind; an NLP, whose spring kind is part of its structure, names one)
        self.spring = spring
        self._index = {q.name: (i, q.si) for i, q in enumerate(order)}
        self._rows = getattr(p, "ndim", 1) == 2

    def __getitem__(self, name: str):
        i, si = self._index[name]
        v = self._p[:, i] if self._rows else self._p[i]
        return v if si == 1.0 else v * si


class Element:
    """One machine element (see the module docstring). Subclasses set the class attributes
    and override the laws they have; the defaults are "no force of that kind"."""

    #: short name (the element's entry in reports and in ``_kernel.c``)
    name: str = ""
    #: one line: what it is
    doc: str = ""
    #: the config keys it owns
    keys: tuple[Key, ...] = ()
    #: its per-stroke parameters, in the order they take in p
    params: tuple[Param, ...] = ()
    #: the kernel's tabulated functions of theta it reads: names of its q ("q"), q' ("dq")
    #: or q'^2 ("dq2"), as (column name, what)
    columns: tuple[tuple[str, str], ...] = ()
    #: "base": in the kernel's fixed table (always tabulated); "coordinates": in the
    #: coordinate table of element columns, tabulated when a stroke needs it; another
    #: element's name: it reads that element's columns (the same coordinate), tabulated for it
    table: str = "base"
    #: one of the seed's elements (gravity, the spring, the dashpot, the rotary damper)
    seed: bool = False
    #: for an element with a valid range: the stroke metrics that hold its coordinate's
    #: extremes over the stroke (checked against :meth:`valid`)
    extremes: tuple[str, str] | None = None

    # -- the coordinate ---------------------------------------------------------------------
    def coordinate(self, lid):
        """The element's coordinate on ``lid`` (a :class:`softclose.model.resolved.Lid`:
        its geometry and mounting; :mod:`.coordinates`)."""
        raise NotImplementedError

    # -- the law ----------------------------------------------------------------------------
    def potential(self, q, P):
        """V(q) (J)."""
        return 0.0

    def tension(self, q, P):
        """T(q) = dV/dq: the conservative force along q (N, or N m on an angle)."""
        return 0.0

    def affine(self, P):
        """(a, b) with T = a + b q on the valid range (None: no conservative force)."""
        return None

    def viscous(self, P):
        """B: the force along q is -B q-dot (None: not a damper)."""
        return None

    def coulomb(self, P):
        """C: a dry-friction force along q, -C sign(q-dot) while sliding; at rest it holds
        any driving force up to C (stick). None: no friction."""
        return None

    def valid(self, P, mounting=None):
        """The valid range (lo, hi) of q (per design for rows of P; ``mounting``, a
        :class:`softclose.model.resolved.Mounting`, gives the limits that are not per-stroke
        values): a stroke that leaves it is an invalid design."""
        return (-math.inf, math.inf)

    def range_message(self, P, mounting, i: int, short: bool, where: tuple,
                      excess: float) -> str:
        """One line: design i takes the element out of its valid range (``short``: below its
        lower end), from the angle ``where[0]``, furthest at ``where[1]`` (rad), by
        ``excess``."""
        side = "below" if short else "above"
        edge = ("over the whole stroke" if where[0] is None else
                f"from theta = {math.degrees(where[0]):.1f} deg")
        return (f"the {self.name} leaves its valid range ({side} it {edge}, by up to "
                f"{excess:.3g} at theta = {math.degrees(where[1]):.1f} deg)")

    def range_messages(self, P, mounting, rows, short, edge, worst, excess) -> list[str]:
        """:meth:`range_message` of the designs ``rows`` (arrays: ``edge`` NaN for "over the
        whole stroke"); an element may state them at once, faster for many rows."""
        return [self.range_message(P, mounting, int(i), bool(sh),
                                   (None if np.isnan(e) else float(e), float(w)), float(x))
                for i, sh, e, w, x in zip(rows, short, edge, worst, excess)]

    def unit_rate(self, mounting) -> bool:
        """True when the element's coordinate is the lid's own angle with ``mounting`` (q' =
        1: no column is read for it)."""
        return False

    def in_coordinate_table(self, mounting) -> bool:
        """Does the element read the table of element columns with ``mounting``?"""
        return self.table == "coordinates" and not self.unit_rate(mounting)

    # -- what it changes in the model ---------------------------------------------------------
    def structure(self, mounting) -> tuple:
        """The element's choices that change the model itself rather than a per-stroke value
        (where it is mounted, say): part of every model's cache key."""
        return ()

    # -- when it acts -----------------------------------------------------------------------
    #: the parameters whose non-zero value makes the element act (None: any of them)
    acting_params: tuple[str, ...] | None = None
    #: an element that acts only while the lid is below an angle (an end damper that the lid
    #: meets near the rim): the name of that parameter in P (rad); None: it acts everywhere.
    #: The switch is a discontinuity in theta that every integrator locates as an event and
    #: the NLP makes a phase boundary (:meth:`engaged`)
    engagement: str | None = None

    def engaged(self, theta, P):
        """1 where the element acts at angle ``theta``, else 0 (numbers, arrays or CasADi
        expressions); always 1 for an element without :attr:`engagement`."""
        if self.engagement is None:
            return 1.0
        if hasattr(theta, "is_symbolic") or hasattr(P[self.engagement], "is_symbolic"):
            import casadi as ca
            return ca.if_else(theta < P[self.engagement], 1, 0)
        return (np.asarray(theta) < P[self.engagement]) * 1.0

    def acts(self, values: dict):
        """Whether the element exerts any force with these parameter values (a dict of
        ``design`` values, numbers or arrays of rows: then elementwise)."""
        names = self.acting_params if self.acting_params is not None else \
            tuple(q.name for q in self.params)
        out = False
        for name in names:
            out = np.logical_or(out, np.asarray(values.get(name, 0.0)) != 0.0)
        return out
