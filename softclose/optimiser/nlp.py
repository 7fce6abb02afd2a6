"""The multiple-shooting NLP of the soft-close problem, and its discretisation.

Decision variables (all of order one): the design scaled by :data:`softclose.problem.SCALES`,
the closing time T (s; time is scaled to [0, 1], so each of the N shooting intervals lasts
T/N and holds M RK4 sub-steps of T/(N·M)), the states (theta, theta') at the nodes 1..N
(node 0 is the release from rest), and an epigraph variable s for the peak tip speed.

    minimise   J(theta'(T), s) / J_ref           (J: :func:`softclose.problem.objective`)
    subject to continuity at every node, theta(T) = theta_closed,
               closing_time_min <= T <= closing_time_max,
               theta' <= 0 and theta >= theta_closed at every sub-step, theta''(release) <= 0,
               s >= |v_T| = tau(theta)·|theta'| at every sub-step, and s >= the maximum of
               the cubic Hermite interpolant of |v_T| inside every sub-step (so the peak
               between sub-steps is caught: error O(h^4), not O(h^2)),
               dV/dtheta(theta_closed) >= holding_moment_min.

s is only an epigraph variable: with ``weight_peak_tip = 0`` nothing pins it, so the
optimiser's own peak tip speed is never read from s but from the sub-step speeds and their
Hermite maxima at the solution (:meth:`ShootingNLP.peak`).

The equation of motion is theta'' = a0(theta) + a1(theta) theta' + a2(theta) theta'^2 with
every element's law affine in its parameters (:mod:`softclose.model.elements.base`):
a0 = sum over the conservative elements of a_e (-q_e'/M) + b_e (-q_e q_e'/M) (T_e = a_e + b_e q),
a1 = sum over the dampers of B_e (-q_e'^2/M), a2 = -M'/(2M). So it depends on theta only
through a few geometric functions (for the seed's elements -dVg/M, -dl/M, -l dl/M, -dd/M,
-1/M, -dM/(2M), and tau = |dT/dtheta|); in the NLP they are Chebyshev series fitted on the
stroke's angles ±3° to machine precision (:class:`ChebyshevFit`). One RK4 sub-step is then ~730 operations instead of ~4200, and the
exact Hessian is cheap. Everything reported is re-checked on the exact equations by the
adaptive reference (:mod:`softclose.optimiser.verify`).

Every number that can change between solves (theta0, theta_closed, weights, the parameters
that are not design variables -- the rotary damper, those of the elements added since --, the
time grid) is an NLP parameter, and closing-time bounds, design bounds and
holding_moment_min are bounds: one NLP per geometry and (N, M) serves multistart, warm
re-solves and Pareto fronts (:func:`softclose.optimiser.cache.get_nlp`).

**Two phases: an end damper that engages near the rim.** An end damper
(:class:`softclose.model.elements.dampers.EndDamper`: a moment -c_e theta' on the lid below its
engagement angle theta_e) switches the equation of motion at theta_e, a discontinuity that
the NLP never smooths: with c_e > 0 (or ``design.end_damper_c`` free) and theta_e inside the
stroke (:func:`softclose.optimiser.interval.end_damper_mode`), the stroke is two phases --
phase 1 from the release to theta_e without the end damper, phase 2 from theta_e to the rim
with it -- of N intervals each (``optimise.nodes``), with their own durations: the variables
are the closing time T and the engagement time T1 (phase 2 lasts T - T1 >=
:data:`PHASE_FLOOR`), and the node between the phases lies on theta_e (the constraint
``engagement``: theta(T1) = theta_e, a parameter, or a design variable when
``design.end_damper_angle_deg`` is free). Phase 1's intervals see the design with c_e = 0,
phase 2's with it; every constraint of the one-phase NLP holds at every sub-step of both
(the tip speed, which typically peaks at the engagement, is a node value of both phases, and
each phase's Hermite maxima use that phase's own equation). Phase 2's sub-steps M_engaged are M
doubled until RK4 is as stable on the end damper as on the dashpot
(:func:`~softclose.optimiser.discretisation.engaged_substeps`).
w = (d, T, T1, X (2N nodes), s).

Attachment points freed in ``optimise.free`` (``geometry.spring_anchor[i]``, ``lid_e[i]``,
``dashpot_anchor[i]``, ``dashpot_lid[i]``) are design variables after the others: the spring
and the dashpot then act through the points (:mod:`softclose.optimiser.free_points`), the
spring kind's validity over the stroke and the keep-out regions are constraints, and the
answer is verified at a config with the points set (:meth:`ShootingNLP.placed_config`).
"""

from __future__ import annotations

import time

import casadi as ca
import numpy as np

from ..errors import ConfigError
from ..problem import DESIGN_KEYS, PARAM_COLUMNS, PARAM_KEYS, SCALES, params_of
from ..model import elements
from .interval import (END_C, ChebyshevFit, bound_interval, combine_function, free_of,
                       interval_function, mapped)
from .parameters import (FIXED_PARAMS, J_INDEX, NLP_PARAMS,  # noqa: F401  (re-exported)
                         OPENING_INTERVALS, SELF_CLOSE_INTERVALS, SELF_CLOSE_MARGIN, LidLayout,
                         SymbolicSeries, check_self_close, holding_moment, opening_angles,
                         opening_bound, self_close_bound, self_close_function)
from .keep_out import keep_out_constraints
from .coil_nlp import COIL_PARAMS, GROUPS as COIL_GROUPS, coil_params, spring_of, z_bounds, \
    z_start
from .coil_nlp import nlp_terms as coil_terms
from .free_points import placed_bounds, placed_config, placed_constraints, slot_values
from .base import NLP, Structure
from .run import Run  # noqa: F401  (re-exported)
from .ipopt import (COLD_OPTIONS, LINEAR_ALGEBRA, MUMPS_OPTIONS, WARM_OPTIONS,
                    check_linear_solver, shooting_options)
#: smallest closing time the NLP may take (s): T = 0 would make every step vanish
T_FLOOR = 1e-3
#: shortest phase of a two-phase stroke (s): the engagement time T1 and T - T1 (a phase of
#: no duration would be a node on both sides of the switch)
PHASE_FLOOR = 1e-4


def stroke_bounds(lbx, ubx, stroke, iT: int, iT1: int | None, iX: int, N: int,
                  t_lo: float, t_hi: float) -> None:
    """Set in (lbx, ubx) the bounds of one stroke's variables in a shooting NLP: its closing
    time T (at ``iT``) in [max(t_lo, T_FLOOR), t_hi], its engagement time T1 (at ``iT1``;
    None: one phase), its N nodes' states (from ``iX``: theta in [theta_closed, theta0],
    theta' <= 0, the last node on the rim) and its peak-speed bound s >= 0 (after them)."""
    st = stroke
    lbx[iT], ubx[iT] = max(t_lo, T_FLOOR), t_hi
    if iT1 is not None:
        lbx[iT1], ubx[iT1] = PHASE_FLOOR, ubx[iT]
    j = iX
    lbx[j:j + 2 * N:2], ubx[j:j + 2 * N:2] = st.theta_closed, st.theta0
    ubx[j + 1:j + 1 + 2 * N:2] = 0.0
    lbx[j + 2 * (N - 1)] = ubx[j + 2 * (N - 1)] = st.theta_closed
    lbx[j + 2 * N] = 0.0


def group_bounds(o) -> tuple[dict, dict]:
    """(lower, upper) bound of each constraint group the shooting NLPs (the nominal and the
    scenario NLP) share, by group name, of the config's [optimise] ``o``. (The group
    ``phase_two``: the engaged phase's duration T - T1.)"""
    lo = {"continuity": 0.0, "theta_above_closed": 0.0, "theta_dot_nonpositive": -np.inf,
          "peak_tip_speed": 0.0, "holding_moment": o.holding_moment_min,
          "release_downwards": -np.inf, "opening_force": -np.inf,
          "self_close": SELF_CLOSE_MARGIN, "engagement": 0.0,
          "phase_two": PHASE_FLOOR}
    hi = {"continuity": 0.0, "theta_above_closed": np.inf, "theta_dot_nonpositive": 0.0,
          "peak_tip_speed": np.inf, "holding_moment": np.inf, "release_downwards": 0.0,
          "opening_force": np.inf if o.opening_force_max is None else o.opening_force_max,
          "self_close": np.inf, "engagement": 0.0, "phase_two": np.inf}
    return lo, hi


class ShootingStructure(Structure):
    """The multiple-shooting NLP of one structure: the elements it carries, the series'
    names and padded degree, the free variables and points (which, not their values), the
    discretisation, the opening bound, the self-close constraint and the keep-out regions. It
    holds no number of a lid (nor the self-close angle):
    those are the lid vector L at the end of the NLP's parameters
    (:mod:`softclose.optimiser.parameters`), so one structure serves every lid
    (:class:`ShootingNLP` binds one).

    Built symbolically (CasADi's virtual machine evaluates it), or -- ``library`` a compiled
    library of this structure (:mod:`softclose.buildcache`) and ``meta`` what :meth:`meta`
    stored -- loaded: nothing symbolic is built, the solves call the compiled functions.
    ``threads``: the threads its interval maps run in (:func:`~.interval.mapped`; more than
    one only for the virtual machine).
    """

    #: ``softclose prepare`` compiles every nominal structure (-O1 solves ~2x faster than
    #: the virtual machine: ``softclose bench --structures``)
    prepared = True
    name = "softclose_ms"
    kept = {"peak": "_peak"}

    def __init__(self, els, names: tuple, degree: int, nodes: int, substeps: int,
                 engaged: tuple | None = None, free: tuple = (), place: tuple = (),
                 opening: bool = False, keep_out: tuple = (), hessian: str = "exact",
                 linear_solver: str = "mumps", max_iter: int = 500, tol: float = 1e-10,
                 library=None, meta: dict | None = None, self_close: bool = False,
                 coil: bool = False, threads: int = 1):
        t0 = time.perf_counter()
        check_linear_solver(linear_solver)
        self.els = tuple(els)
        self.two_phase = engaged is not None
        self.nodes, self.M = nodes, substeps
        self.N_engaged, self.M_engaged = (int(engaged[0]), int(engaged[1])) if self.two_phase \
            else (0, None)
        self.N = N = nodes + self.N_engaged
        M, substeps_engaged = substeps, self.M_engaged
        # free: (key, column of p) of the free design variables; place: (key, slot in g)
        self.free, self.place = tuple(free), tuple(place)
        self.placed = bool(self.place)
        self.nd = len(DESIGN_KEYS) + len(self.free) + len(self.place)
        self.iT = self.nd
        self.iT1 = self.nd + 1 if self.two_phase else None
        self.iX = self.nd + (2 if self.two_phase else 1)
        #: the compression spring made to order: z = (d, D, n) after s (:mod:`.coil_nlp`)
        self.coil = bool(coil)
        self.iS = self.iX + 2 * N
        self.series = SymbolicSeries(names, self.els, degree)
        #: the spring law of the structure: a gas strut's NLP carries its length's series
        self.spring = "gas" if "spring:l" in self.series.names else "coil"
        self.lid = LidLayout(self.series, len(self.free) + len(self.place), self.placed,
                             OPENING_INTERVALS + 1 if opening else 0,
                             SELF_CLOSE_INTERVALS + 1 if self_close else 0)
        self.n_params = len(NLP_PARAMS) + N + self.lid.size
        self.i_coil = self.n_params                 # the spring's block, after the lid's
        if self.coil:
            self.n_params += len(COIL_PARAMS)
        self.ipopt_options = {**shooting_options(tol, max_iter, hessian, linear_solver),
                              **LINEAR_ALGEBRA}
        if linear_solver == "mumps":
            self.ipopt_options.update(MUMPS_OPTIONS)
        self.cold_options = {**self.ipopt_options, **COLD_OPTIONS}
        self.warm_options = {**self.ipopt_options, **WARM_OPTIONS}
        if library is not None:
            self.load(library, meta)
            self.build_time = time.perf_counter() - t0
            return
        if self.placed and opening:
            raise ConfigError("optimise.opening_force_max cannot yet be combined with free "
                              "attachment points (optimise.free geometry.*): fix the points "
                              "or drop the bound")
        if self.placed and self_close:
            raise ConfigError("optimise.self_close_min_deg cannot yet be combined with free "
                              "attachment points (optimise.free geometry.*): fix the points "
                              "or drop the constraint")
        self.interval, self.f = interval_function(self.series, substeps, with_ode=True,
                                                  placement=self.placed)
        if self.two_phase:
            self.interval_engaged = self.interval if substeps_engaged == substeps else \
                interval_function(self.series, substeps_engaged, placement=self.placed)
        # the NLP: MX graph over the SX interval, mapped over the N intervals
        d, T = ca.MX.sym("d", self.nd), ca.MX.sym("T")
        T1 = ca.MX.sym("T1") if self.two_phase else None
        X, s = ca.MX.sym("X", 2, N), ca.MX.sym("s")
        npar = len(NLP_PARAMS)
        P = ca.MX.sym("P", self.n_params)
        theta0, thc, wi, wp, wt = (P[i] for i in range(5))
        fixed, Jref = P[5:5 + len(FIXED_PARAMS)], P[J_INDEX]
        grid = P[npar:npar + N]
        lid = self.lid.split(P[npar + N:])
        L, scales = lid["series"], lid["scales"]
        entries = [d[i] * SCALES[i] for i in range(len(DESIGN_KEYS))] + \
            [fixed[i] for i in range(len(FIXED_PARAMS))]
        for j, (_, col) in enumerate(self.free):
            entries[col] = d[len(DESIGN_KEYS) + j] * scales[j]
        design = ca.vertcat(*entries)
        Xs = ca.horzcat(ca.vertcat(theta0, 0), X[:, :N - 1])
        gin = []
        if self.placed:     # the points g: the lid's, the free components variables
            points = lid["points"]
            gl = [points[i] for i in range(8)]
            for j, (_, slot) in enumerate(self.place):
                gl[slot] = d[len(DESIGN_KEYS) + len(self.free) + j] * scales[len(self.free) + j]
            gvec = ca.vertcat(*gl)
            gin = [gvec]
        self.combine = combine_function(self.series, self.placed)
        c = self.combine(design, *gin, L)
        if not self.two_phase:
            xe, a, b, sp = mapped(self.interval, N, threads)(Xs, ca.repmat(c, 1, N),
                                                             T * grid.T / M)
        else:   # phase 1 without the end damper (c_e = 0), phase 2 with it
            n1, n2 = nodes, self.N_engaged
            off = list(entries)
            off[PARAM_COLUMNS[END_C]] = ca.MX(0.0)
            c1 = self.combine(ca.vertcat(*off), *gin, L)
            o1 = mapped(self.interval, n1, threads)(Xs[:, :n1], ca.repmat(c1, 1, n1),
                                       T1 * grid[:n1].T / M)
            o2 = mapped(self.interval_engaged, n2, threads)(Xs[:, n1:], ca.repmat(c, 1, n2),
                                        (T - T1) * grid[n1:].T / substeps_engaged)
            xe = ca.horzcat(o1[0], o2[0])
            a, b, sp = (ca.vertcat(ca.vec(o1[k]), ca.vec(o2[k])) for k in (1, 2, 3))
            theta_e = elements.params(design)["end_damper_angle_deg"]
        if self.placed:     # the holding moment: the spring's part at the points g
            g_all = placed_constraints(self, design, gvec, theta0, thc, lid["closed"], L, c)
            if keep_out:    # the lines with a free point clear the regions
                g_all["keep_out"] = keep_out_constraints(self.series, theta0, thc, gvec,
                                                         keep_out, self.place, L)
        else:
            g_all = {"holding_moment": holding_moment(lid["closed"],
                                                      elements.params(design, self.spring)),
                     "release_downwards": self.f(ca.vertcat(theta0, 0), c)[1]}
        g_all = {"continuity": ca.vec(xe - X),                  # = 0
                 "theta_above_closed": ca.vec(a) - thc,          # >= 0
                 "theta_dot_nonpositive": ca.vec(b),             # <= 0
                 "peak_tip_speed": s - ca.vec(sp),               # >= 0
                 **g_all}      # holding moment >= holding_moment_min, release <= 0, ...
        if opening:        # the opening effort (optimise.opening_force_max): <= the bound
            g_all["opening_force"] = opening_bound(self.lid, lid["opening"], theta0, thc,
                                                   design, self.spring)
        if self_close:     # closes by itself up to optimise.self_close_min_deg: >= margin
            g_all["self_close"] = self_close_bound(self.lid, lid["self_close"], thc, design,
                                                   self.spring)
        if self.two_phase:  # the node between the phases on theta_e; phase 2 lasts
            g_all["engagement"] = X[0, nodes - 1] - theta_e           # = 0
            g_all["phase_two"] = T - T1                               # >= PHASE_FLOOR
        z, mass_term = [], 0.0
        if self.coil:      # the spring's wire, coil diameter and coils, and its checks
            zs = ca.MX.sym("z", 3)
            checks, mass_term = coil_terms(zs, design, P[self.i_coil:])
            g_all.update(checks)
            z = [zs]
        self.g_names = list(g_all)
        self.g_sizes = [int(v.numel()) for v in g_all.values()]
        # softclose.problem.objective with the weights as NLP parameters (+ a time term that
        # only the infeasibility diagnosis uses: fastest / slowest stroke)
        J = wi * X[1, N - 1] ** 2 + wp * s ** 2 + wt * T
        w = ca.vertcat(d, T, *([T1] if self.two_phase else []), ca.vec(X), s, *z)
        self.nw = int(w.numel())
        # the largest sub-step speed or Hermite maximum: the NLP's own peak tip speed
        self._peak = ca.Function("peak", [w, P], [ca.mmax(sp)])
        f = J / Jref + mass_term if self.coil else J / Jref
        self.make_solver({"x": w, "f": f, "g": ca.vertcat(*g_all.values()), "p": P})
        self.build_time = time.perf_counter() - t0

    def load(self, library, meta: dict) -> None:
        """The solvers from a compiled library and the numbers :meth:`meta` kept (the
        constraint groups' names too)."""
        self.g_names = [str(n) for n in meta["g_names"]]
        super().load(library, meta)

    def meta(self) -> dict:
        """What a compiled library of this structure needs beside it
        (:mod:`softclose.buildcache`): the constraint groups, the size of w, the peak
        function."""
        return {"g_names": np.array(self.g_names), **super().meta()}

    def __getattr__(self, name):
        """``interval``, ``f`` and ``interval_engaged`` of a structure loaded from its compiled
        library: built on first use (tests and reports ask for them; the solves do not)."""
        if name in ("interval", "f", "interval_engaged") and \
                self.__dict__.get("library") is not None:
            self.interval, self.f = interval_function(self.series, self.M, with_ode=True,
                                                      placement=self.placed)
            if self.two_phase:
                self.interval_engaged = interval_function(self.series, self.M_engaged,
                                                   placement=self.placed)
            return getattr(self, name)
        raise AttributeError(name)


class ShootingNLP(NLP):
    """The multiple-shooting NLP of one lid: a :class:`ShootingStructure` and the lid's
    numbers that fill it (its model, its Chebyshev fit, the scales of its free variables,
    its attachment points: the lid vector of :meth:`params`).

    :func:`softclose.optimiser.cache.get_nlp` builds the structure once and binds it per
    lid; :meth:`solve` takes the bounds and parameters of one problem, so changing
    closing_time_max, weights, design bounds or holding_moment_min -- or the lid -- never
    rebuilds anything.
    """

    def __init__(self, model, structure: ShootingStructure, fit: ChebyshevFit,
                 free: tuple = (), placement: tuple = ()):
        self.model, self.structure, self.fit = model, structure, fit
        for k in ("two_phase", "nodes", "M", "N_engaged", "M_engaged", "N", "nd", "iT", "iT1",
                  "iX", "iS",
                  "coil",
                  "placed", "g_names", "g_sizes", "nw", "solver", "_peak",
                  "ipopt_options", "library", "build_time"):
            setattr(self, k, getattr(structure, k))
        # the design variables: k, l0, c, then the free ones (optimise.free: free_layout),
        # then the free attachment points (placement_layout): (key, column/slot, scale)
        self.free, self.place = tuple(free), tuple(placement)
        self.g0 = slot_values(model.lid)
        self.scales = np.r_[SCALES, [sc for _, _, sc in self.free],
                            [sc for _, _, sc in self.place]]
        lay = structure.lid
        self.lid_vector = lay.values(
            model, fit, self.scales[len(DESIGN_KEYS):], self.g0,
            opening_angles(model, OPENING_INTERVALS) if lay.opening_angles else None)
        self._self_close = {}       # the lid vector's self-close part, per angle
        self.key = None
        self._coil_key, self._coil, self._zcfg = None, None, None   # the spring made to order

    def self_close_part(self, self_close_deg: float | None) -> np.ndarray:
        """The lid vector's self-close part at ``self_close_deg`` (the structure's
        constraint; empty without one): the angle is a parameter of the problem, like
        holding_moment_min, so one bound NLP serves every angle."""
        lay = self.structure.lid
        if not lay.self_close_angles:
            return np.zeros(0)
        if self_close_deg is None:
            raise ValueError("this NLP constrains the self-close angle: give one")
        deg = float(self_close_deg)
        if deg not in self._self_close:
            self._self_close[deg] = lay.self_close_values(self.model, deg)
        return self._self_close[deg]

    def self_close_moments(self, p, self_close_deg: float) -> np.ndarray:
        """The NLP's self-close constraint values (N m: the moment at the grid's nodes, then
        the Hermite minima between them) of the parameter vector ``p`` at the angle
        ``self_close_deg``: the same expressions as the NLP's, evaluated apart (the active
        set's price per degree differentiates them in the angle)."""
        fn = self_close_function(self.structure.lid, self.structure.spring)
        return np.asarray(fn(self.self_close_part(self_close_deg), np.asarray(p, float),
                             self.model.stroke.theta_closed)).ravel()

    def __getattr__(self, name):
        """``interval``, ``f``, ``interval_engaged``: the structure's with this lid's series bound
        (built on first use)."""
        if name in ("interval", "f", "interval_engaged"):
            fns = bound_interval(self.fit, self.M, with_ode=True, placement=self.placed,
                                 degree=self.structure.series.degree)
            self.interval, self.f = fns
            if self.two_phase:
                self.interval_engaged = bound_interval(self.fit, self.M_engaged,
                                                       placement=self.placed,
                                                degree=self.structure.series.degree)
            return getattr(self, name)
        raise AttributeError(name)

    # -- packing -------------------------------------------------------------------------
    def pack(self, design, T, X, s, T1: float | None = None) -> np.ndarray:
        """The point w of ``design`` (the design variables, or a whole parameter vector),
        T, X (2, N) and s; ``T1`` the engagement time of a two-phase stroke."""
        d = np.asarray(design, float)
        if len(d) == len(PARAM_KEYS):
            d = np.r_[d[:len(DESIGN_KEYS)], [d[col] for _, col, _ in self.free],
                      [self.g0[slot] for _, slot, _ in self.place]]
        t1 = [] if not self.two_phase else [0.5 * T if T1 is None else T1]
        z = [] if not self.coil else (z_start(self._zcfg, d[0]) if self._zcfg is not None
                                      else np.ones(3))
        return np.r_[d[:self.nd] / self.scales, T, t1, np.asarray(X, float).T.ravel(), s, z]

    def unpack(self, w):
        """(design (k, l0, c, then the free variables), T, X (2, N), s) of a point ``w``."""
        w = np.asarray(w, float).ravel()
        N, i, j = self.N, self.iT, self.iX
        X = w[j:j + 2 * N].reshape(N, 2).T
        return w[:i] * self.scales, float(w[i]), X, float(w[self.iS])

    def spring_of(self, w) -> dict | None:
        """{wire_d, coil_d, active_coils} (SI) of the NLP's spring at ``w`` (None: none)."""
        return spring_of(np.asarray(w, float)[self.iS + 1:]) if self.coil else None

    def engagement(self, w) -> tuple[float, float] | None:
        """(time, theta') of the node between the phases at ``w``: the NLP's own engagement
        time and speed (None for one phase)."""
        if not self.two_phase:
            return None
        w = np.asarray(w, float).ravel()
        return float(w[self.iT1]), float(w[self.iX + 2 * (self.nodes - 1) + 1])

    def node_times(self, p, T: float, T1: float | None = None) -> np.ndarray:
        """The times (s) of the nodes 1..N on the time grid of ``p`` for closing time T (and
        engagement time T1: phase 1's grid is a fraction of T1, phase 2's of T - T1)."""
        g = self.grid_of(p)
        if not self.two_phase:
            return T * np.minimum(np.cumsum(g), 1.0)
        n = self.nodes
        return np.r_[T1 * np.minimum(np.cumsum(g[:n]), 1.0),
                     T1 + (T - T1) * np.minimum(np.cumsum(g[n:]), 1.0)]

    def full_design(self, cfg, design) -> np.ndarray:
        """The design variables of ``design``: as given when it has them all; (k, l0, c)
        alone gets the free ones from ``cfg``'s values, clipped into their bounds."""
        d = np.asarray(design, float)
        if len(d) >= self.nd:
            return d[:self.nd]
        P = params_of(cfg)
        bounds = {k: (lo, hi) for k, lo, hi in free_of(cfg)}
        g = slot_values(cfg)
        return np.r_[d[:len(DESIGN_KEYS)],
                     [float(np.clip(P[col], *bounds.get(k, (-np.inf, np.inf))))
                      for k, col, _ in self.free],
                     [float(np.clip(g[slot], *bounds.get(k, (-np.inf, np.inf))))
                      for k, slot, _ in self.place]]

    def param_vector(self, cfg, design) -> np.ndarray:
        """The parameter vector p of ``cfg`` with ``design``'s variables."""
        d = self.full_design(cfg, design)
        p = params_of(cfg)
        p[:len(DESIGN_KEYS)] = d[:len(DESIGN_KEYS)]
        for j, (_, col, _) in enumerate(self.free):
            p[col] = d[len(DESIGN_KEYS) + j]
        return p

    def design_dict(self, cfg, design) -> dict:
        """{name: value} of the design variables (k, l0, c, the free ones by their names)."""
        d = self.full_design(cfg, design)
        names = DESIGN_KEYS + tuple(k.split(".", 1)[1] for k, _, _ in self.free + self.place)
        return {n: float(v) for n, v in zip(names, d)}

    def points(self, design) -> dict:
        """{key: value} of the free attachment points in ``design`` (the design variables)."""
        d = np.asarray(design, float)
        n0 = len(DESIGN_KEYS) + len(self.free)
        return {k: float(d[n0 + j]) for j, (k, _, _) in enumerate(self.place)}

    def placed_config(self, cfg, design):
        """``cfg`` with the attachment points of ``design`` (itself without free points)."""
        return placed_config(cfg, self.points(design)) if self.placed else cfg

    def peak(self, run: Run) -> float:
        """The NLP's own peak tip speed at ``run``'s point: the largest sub-step speed or
        Hermite maximum (not the epigraph variable s, which is free when weight_peak_tip
        is zero)."""
        return float(self._peak(run.x, run.p))

    def bounds(self, cfg, t_max: float | None = None, t_min: float | None = None):
        """(lbx, ubx, lbg, ubg) of ``cfg``'s problem; the closing-time bounds default to
        [closing_time_min, min(closing_time_max, stroke.t_max)]."""
        o, st = cfg.optimise, cfg.stroke
        N = self.N
        lbx, ubx = np.full(self.nw, -np.inf), np.full(self.nw, np.inf)
        for i, (lo, hi) in enumerate(self.design_bounds(cfg)):
            lbx[i], ubx[i] = lo / self.scales[i], hi / self.scales[i]
        stroke_bounds(lbx, ubx, st, self.iT, self.iT1, self.iX, N,
                      o.closing_time_min if t_min is None else t_min,
                      min(o.closing_time_max, st.t_max) if t_max is None else t_max)
        if self.coil:
            lbx[self.iS + 1:], ubx[self.iS + 1:] = z_bounds(cfg)
        lo, hi = group_bounds(o)
        if self.placed:
            placed_bounds(cfg, lo, hi)
        for k, (a, b) in COIL_GROUPS.items():
            lo[k], hi[k] = a, b
        lbg = np.concatenate([np.full(n, lo[k]) for k, n in zip(self.g_names, self.g_sizes)])
        ubg = np.concatenate([np.full(n, hi[k]) for k, n in zip(self.g_names, self.g_sizes)])
        return lbx, ubx, lbg, ubg

    def design_bounds(self, cfg) -> list[tuple[float, float]]:
        """(lo, hi) of each design variable (k, l0, c from [optimise], then the free ones)."""
        o = cfg.optimise
        free = {k: (lo, hi) for k, lo, hi in free_of(cfg)}
        missing = [k for k, _, _ in self.free + self.place if k not in free]
        if missing:
            raise ConfigError(f"optimise.free: this NLP chooses {', '.join(missing)}, which "
                              "the config does not bound")
        return [tuple(getattr(o, k)) for k in DESIGN_KEYS] + [free[k] for k, _, _ in
                                                              self.free + self.place]

    def params(self, cfg, J_ref: float = 1.0, weight_time: float = 0.0,
               weights: tuple | None = None) -> np.ndarray:
        """NLP parameters of ``cfg``'s problem (``weights`` overrides the objective's)."""
        o, st = cfg.optimise, cfg.stroke
        wi, wp = (o.weight_impact, o.weight_peak_tip) if weights is None else weights
        fixed = params_of(cfg)[len(DESIGN_KEYS):]
        if self.structure.lid.self_close_angles:
            check_self_close(cfg)
        coil = [] if not self.coil else self.coil_params(cfg)
        return np.r_[st.theta0, st.theta_closed, wi, wp, weight_time, fixed, J_ref,
                     self.time_grid(), self.lid_vector,
                     self.self_close_part(o.self_close_min_deg), coil]

    def coil_params(self, cfg) -> np.ndarray:
        """The spring block of ``cfg`` (kept per config); z's start follows its material."""
        key = (cfg.spring, cfg.operating, cfg.stroke, self.model.lid)
        if self._coil_key != key:
            self._coil_key, self._coil = key, coil_params(cfg)
        self._zcfg = cfg
        return self._coil

    def time_grid(self) -> np.ndarray:
        """Fractions of T of the N intervals: uniform (two phases: each phase's N intervals
        fractions of its own duration, uniform).

        The grid is an NLP parameter, so graded grids need no rebuild; but a graded grid
        does not pay here: the tip speed peaks early (~0.1 s) while the creep to the rim is
        limited by RK4's stability on the damper (h |lambda| < 2.79, lambda = c dd / M up
        to ~70 1/s), so long strokes need more steps anyway (see :func:`discretisation`).
        """
        if not self.two_phase:
            return np.full(self.N, 1.0 / self.N)
        return np.r_[np.full(self.nodes, 1.0 / self.nodes),
                     np.full(self.N_engaged, 1.0 / self.N_engaged)]

    def grid_of(self, p) -> np.ndarray:
        """The time grid in the parameters ``p`` of this NLP."""
        return np.asarray(p, float)[len(NLP_PARAMS):len(NLP_PARAMS) + self.N]

    def blocks(self) -> list[list[tuple[str, int]]]:
        """One block: the constraint groups of g (:meth:`groups`)."""
        return [list(zip(self.g_names, self.g_sizes))]

    def groups(self):
        """(name, slice of g) of each constraint group."""
        i = 0
        for name, n in zip(self.g_names, self.g_sizes):
            yield name, slice(i, i + n)
            i += n
