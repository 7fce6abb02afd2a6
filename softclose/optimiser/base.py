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

What is built once per structure -- the cold and the warm Ipopt solver, and what a compiled
library keeps beside it -- is a :class:`Structure`: the nominal and the scenario NLP bind one
(:attr:`NLP.structure`) to a lid's numbers; the calibration NLP is its own.

**Adding an NLP.** Subclass :class:`NLP` in the new family's own ``nlp.py`` and, for what
is built once, :class:`Structure` (one class may be both, as :class:`FitNLP
<softclose.calibration.nlp.FitNLP>`): set :attr:`Structure.name`,
:attr:`Structure.cold_options` (and :attr:`Structure.warm_options` if it re-solves from a
previous answer's multipliers), build the CasADi problem {x, p, f, g} and call
:meth:`Structure.make_solver` with it (never ``casadi.nlpsol``); give :meth:`NLP.blocks`;
to be compiled (:func:`softclose.optimiser.compiled.load_or_build`), name in
:attr:`Structure.kept` the functions its solves need beside the solver, and
:meth:`Structure.load` restores them with the solver from the library; and
``pack``/``unpack``/``params``/``bounds`` in the terms of its own problem. Everything that
differs between two NLPs is then the expression graph, never the solve.
"""

from __future__ import annotations

import abc
import functools

import numpy as np

from . import ipopt
from .run import Run


class Structure:
    """What an NLP builds once: its cold Ipopt solver (:meth:`make_solver`, from the CasADi
    problem or a compiled library), its warm solver (:attr:`warm_solver`, on first use) and
    what a compiled library keeps beside it (:meth:`meta`, :meth:`load`).

    A structure sets :attr:`name`, :attr:`cold_options` (nlpsol's), :attr:`warm_options`
    where it re-solves warm, and before :meth:`make_solver`: :attr:`nw`, :attr:`g_sizes`
    (the sizes of its constraint groups: a list, or one list per block) and
    :attr:`n_params`."""

    #: the solvers' name (the warm one's: with ``_warm``)
    name = "nlp"
    #: the compiled library the solvers are loaded from; None: CasADi's virtual machine
    library = None
    #: nlpsol's options of the cold solve, and of the warm re-solve (None: no warm starts)
    cold_options: dict = {}
    warm_options: dict | None = None
    #: the CasADi functions a compiled structure keeps beside its solver: {meta key:
    #: attribute}
    kept: dict = {}

    @property
    def ng(self) -> int:
        """The number of constraints (every group of every block)."""
        sizes = np.asarray(self.g_sizes, int)
        return int(sizes.sum())

    def make_solver(self, problem) -> None:
        """:attr:`solver`: the cold Ipopt solver of ``problem`` -- a dict {x, p, f, g} of
        CasADi expressions, or the path of the structure's compiled library (then its
        dimensions must be the structure's: ValueError)."""
        self.solver = ipopt.ipopt_solver(self.name, problem, self.cold_options, self.nw,
                                         self.ng, self.n_params)
        if not isinstance(problem, dict) and (self.solver.size1_in(0), self.solver.size1_in(1),
                                              self.solver.size1_in(5)) != \
                (self.nw, self.n_params, self.ng):
            raise ValueError(f"the compiled NLP {self.name} has other dimensions")

    @functools.cached_property
    def warm_solver(self):
        """The solver of warm starts (the previous answer's multipliers given), built on
        first use beside the cold one (:func:`~softclose.optimiser.ipopt.warm_solver`)."""
        if self.warm_options is None:
            raise NotImplementedError(f"{type(self).__name__} has no warm starts")
        return ipopt.warm_solver(f"{self.name}_warm", self.solver, self.library,
                                 self.warm_options)

    def meta(self) -> dict:
        """What a compiled library of this structure needs beside it
        (:mod:`softclose.buildcache`): the constraint groups' sizes, the size of w, the
        functions of :attr:`kept`."""
        return {"g_sizes": np.array(self.g_sizes), "nw": np.array([self.nw]),
                **{k: getattr(self, a).serialize().encode() for k, a in self.kept.items()}}

    def load(self, library, meta: dict) -> None:
        """The solver from the compiled ``library`` and the numbers and functions
        :meth:`meta` kept: nothing symbolic is built."""
        import casadi as ca
        from ..buildcache import text
        self.library = library
        self.g_sizes = np.asarray(meta["g_sizes"]).astype(int).tolist()
        self.nw = int(meta["nw"][0])
        for k, a in self.kept.items():
            setattr(self, a, ca.Function.deserialize(text(meta[k])))
        self.make_solver(library)


class NLP(abc.ABC):
    """One NLP of softclose (see the module docstring).

    Attributes a family sets: :attr:`structure` (its :class:`Structure`, which made
    :attr:`solver`, the cold solver), :attr:`nw` (the number of variables), :attr:`library`
    (its compiled library, or None: CasADi's virtual machine evaluates it). Methods a family
    gives: :meth:`blocks`, and ``pack``, ``unpack``, ``params``, ``bounds`` in its own terms.
    """

    #: the cold solver (Ipopt, :meth:`Structure.make_solver`)
    solver = None
    #: the compiled library the solvers are loaded from; None: CasADi's virtual machine
    library = None
    #: what was built once (the solvers); an NLP that is its own structure needs none
    structure: Structure | None = None
    #: is the start clipped into [lbx, ubx] before Ipopt? (a fit re-solves from an answer
    #: Ipopt may leave 1e-8 outside its bounds, and keeps that point as it is)
    clip_start = True

    @property
    def warm_solver(self):
        """The solver of warm starts (the previous answer's multipliers given): its
        structure's (:attr:`Structure.warm_solver`)."""
        if self.structure is None:
            raise NotImplementedError(f"{type(self).__name__} has no warm starts")
        return self.structure.warm_solver

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


__all__ = ["NLP", "Structure"]
