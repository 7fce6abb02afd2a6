"""The contract every NLP of softclose follows (:class:`NLP`), as scipy's ``OdeSolver`` is
for its integrators: one documented base class, one file per family.

- :class:`softclose.optimiser.nlp.ShootingNLP` -- the nominal multiple-shooting NLP;
- :class:`softclose.robust.nlp.ScenarioNLP` -- the scenario NLP of the robust optimiser;
- :class:`softclose.calibration.nlp.FitNLP` -- the least-squares NLP of a fit.

An NLP is built once per structure and filled by its parameters: the variables ``w`` (``nw``
of them, laid out by the family's ``pack``/``unpack``), the parameters ``p`` (the family's
``params``: every number that may change between solves), the bounds (lbx, ubx, lbg, ubg:
the family's ``bounds``), and the constraints ``g`` in named groups, in blocks
(:meth:`NLP.blocks`: one block, or one per scenario). It is solved by :meth:`NLP.solve`,
which goes through the one Ipopt wrapper (:func:`softclose.optimiser.ipopt.run`) and
returns a :class:`~softclose.optimiser.run.Run` whose ``violations`` are
:meth:`NLP.violations`: per block, {group: largest violation}.

**Adding an NLP.** Subclass :class:`NLP` in the new family's own ``nlp.py``: build the
CasADi problem {x, p, f, g} and its solver with :func:`softclose.optimiser.ipopt.nlpsol`
(never ``casadi.nlpsol`` directly) as :attr:`solver`; give :meth:`blocks`; give
:attr:`warm_solver` (:func:`softclose.optimiser.ipopt.warm_solver`) if it re-solves from a
previous answer's multipliers; set :attr:`library` to a compiled library
(:mod:`softclose.buildcache`, :func:`softclose.optimiser.compiled.load_or_build`) or leave
it None for CasADi's virtual machine; and ``pack``/``unpack``/``params``/``bounds`` in the
terms of its own problem. Everything that differs between two NLPs is then the expression
graph, never the solve.
"""

from __future__ import annotations

import abc

import numpy as np

from . import ipopt
from .run import Run


class NLP(abc.ABC):
    """One NLP of softclose (see the module docstring).

    Attributes a family sets: :attr:`solver` (the cold solver, made by
    :func:`~softclose.optimiser.ipopt.nlpsol`), :attr:`nw` (the number of variables),
    :attr:`library` (its compiled library, or None: CasADi's virtual machine evaluates it);
    :attr:`warm_solver` where warm starts are used. Methods a family gives: :meth:`blocks`,
    and ``pack``, ``unpack``, ``params``, ``bounds`` in its own terms.
    """

    #: the cold solver (Ipopt, :func:`~softclose.optimiser.ipopt.nlpsol`)
    solver = None
    #: the compiled library the solvers are loaded from; None: CasADi's virtual machine
    library = None
    #: is the start clipped into [lbx, ubx] before Ipopt? (a fit re-solves from an answer
    #: Ipopt may leave 1e-8 outside its bounds, and keeps that point as it is)
    clip_start = True

    @property
    def warm_solver(self):
        """The solver of warm starts (the previous answer's multipliers given); a family
        without warm starts has none."""
        raise NotImplementedError(f"{type(self).__name__} has no warm starts")

    @abc.abstractmethod
    def blocks(self) -> list[list[tuple[str, int]]]:
        """The constraint groups of g: per block (one, or one per scenario), the (name,
        size) of each group, in the order of g."""

    def violations(self, g, lbg, ubg) -> list[dict]:
        """Per block, the largest violation of each constraint group at g ({group: value},
        0 where it holds; a NaN counts as an infinite violation)."""
        g = np.asarray(g, float)
        lbg = np.broadcast_to(np.asarray(lbg, float), g.shape)
        ubg = np.broadcast_to(np.asarray(ubg, float), g.shape)
        out, i = [], 0
        for block in self.blocks():
            row = {}
            for name, n in block:
                gi, lo, hi = g[i:i + n], lbg[i:i + n], ubg[i:i + n]
                v = np.maximum(np.maximum(lo - gi, gi - hi), 0.0)
                row[name] = float(np.nan_to_num(v, nan=np.inf).max()) if n else 0.0
                i += n
            out.append(row)
        return out

    def solve(self, x0, p, lbx, ubx, lbg, ubg, lam_x0=None, lam_g0=None, warm: bool = False,
              origin: str = "") -> Run:
        """One Ipopt run from ``x0`` (with ``warm``: by :attr:`warm_solver` from the
        multipliers ``lam_x0``, ``lam_g0``); never raises (an evaluation error is a failed
        status). ``origin`` says where the start came from."""
        solver = self.warm_solver if warm else self.solver
        x0 = np.asarray(x0, float)
        if self.clip_start:
            x0 = np.clip(x0, lbx, ubx)
        return ipopt.run(solver, x0, p, lbx, ubx, lbg, ubg, lam_x0, lam_g0, origin,
                         self.violations)


__all__ = ["NLP"]
