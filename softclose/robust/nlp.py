"""The scenario NLP: one multiple-shooting problem over several scenarios of the lid.

A *scenario* is one point of the tolerance box: a model (geometry and masses: a scenario
with another lid mass has its own model and its own Chebyshev fit of the equation of
motion) and a map from the drawn design to the parameters the lid really has,

    p_s = a_s * p + b_s       (p the parameter vector (k, l0, c, c_rot, ...), elementwise;
                               a_s = 1 + relative deviation, b_s = absolute deviation)

The design d (scaled as in the nominal NLP) is shared; every scenario has its own closing
time T_s, shooting states X_s at the N nodes and peak-speed bound s_s, and its own copy of
every constraint of the problem: continuity, theta(T_s) = theta_closed, the closing-time
window on T_s, theta' <= 0 and theta >= theta_closed at every RK4 sub-step, the peak tip
speed caught by the cubic Hermite bound inside every sub-step, the lid moving down at
release, and the holding moment. The objective is

    worst:  minimise t  subject to  t >= J_s / J_ref  for every scenario (epigraph), or
    mean:   minimise the mean of J_s / J_ref,

with J_s = weight_impact theta'_s(T_s)^2 + weight_peak_tip s_s^2 in the NLP. s_s is only an
epigraph variable: with ``weight_peak_tip = 0`` nothing pins it, and in worst-case mode
nothing pins it in a scenario that is not the worst either. So a scenario's own peak tip
speed is never read from s_s but from its sub-step speeds and their Hermite maxima at the
solution (:meth:`ScenarioNLP.peaks`, as :meth:`ShootingNLP.peak` in the nominal optimiser),
and every J_s reported or compared (:meth:`ScenarioNLP.objectives`) uses that peak. Each
scenario's shooting interval is the nominal optimiser's (``ShootingNLP.interval``: M RK4
sub-steps on the Chebyshev series of its model, with the Hermite peak bound): the robust and
the nominal problem share N and M; only the node grid differs
(:func:`~softclose.optimiser.discretisation.graded_grid`: the first two intervals are half as
long, for the release transient of stiffly damped scenarios). The a_s, b_s are parameters
(:func:`softclose.robust.scenario_cache.get_scenario_nlp` caches the NLP of a scenario list).

With an end damper that engages inside the stroke every scenario is two-phase as in the
nominal NLP (:mod:`softclose.optimiser.nlp`): its own engagement time T1_s, the node
between its phases on its own engagement angle, phase 1 without the end damper (graded
grid), phase 2 with it (uniform grid, sub-steps M_engaged). The end damper's coefficient and
angle may be shared design variables (``optimise.free``; the robust optimiser's first
stage, :mod:`softclose.robust.codesign`), after (k, l0, c) and before the points.
"""

from __future__ import annotations

import dataclasses
import time

import casadi as ca
import numpy as np

from ..config import Config
from ..errors import ConfigError
from ..problem import (DESIGN_KEYS, PARAM_COLUMNS, PARAM_KEYS, held_design, params_of, resolve,
                       SCALES)
from ..optimiser.discretisation import phase_substeps, scenario_grid, t_limit, two_phase
from ..optimiser.free_points import (length_bounds, placed_bounds, placement_layout, slot_values,
                                     spring_moment, strut_law)
from ..model.elements.springs import strut_stroke
from ..optimiser.interval import (ChebyshevFit, combine_function, END_C, free_layout, free_of,
                                  gas_nlp, interval_function, mapped, nlp_elements)
from ..model import elements
from ..optimiser import compiled
from ..optimiser.nlp import check_linear_solver, group_bounds, stroke_bounds
from ..optimiser.base import NLP, Structure
from ..optimiser.ipopt import COLD_OPTIONS, shooting_options
from ..optimiser.run import Run
from ..optimiser.cache import get_model, keep_out_of
from ..config.free import config_value
from ..optimiser.parameters import (holding_moment, LidLayout, opening_angles, opening_bound,
                                    OPENING_INTERVALS, padded_degree, SELF_CLOSE_INTERVALS,
                                    check_self_close, self_close_bound, self_close_function,
                                    SymbolicSeries)
from ..optimiser.keep_out import keep_out_constraints
from ..model.lid import model_key
from .evaluate import with_values

#: the parameters of p that are not design variables: NLP parameters
FIXED = PARAM_KEYS[len(DESIGN_KEYS):]
NP = len(PARAM_KEYS)

#: NLP parameters before the time grid and the scenario maps
PARAMS = ("theta0", "theta_closed", "weight_impact", "weight_peak_tip", *FIXED, "J_ref")
#: per-scenario constraint groups, in order
GROUPS = ("continuity", "theta_above_closed", "theta_dot_nonpositive", "peak_tip_speed",
          "holding_moment", "release_downwards", "epigraph", "opening_force", "self_close",
          "spring_long", "spring_short", "spring_length", "keep_out", "engagement",
          "phase_two")
#: the warm re-solve's options (the nominal NLP's, :data:`~softclose.optimiser.ipopt.
#: WARM_OPTIONS`, with a larger barrier parameter)
WARM_OPTIONS = {"ipopt.warm_start_init_point": "yes", "ipopt.mu_init": 1e-6,
                "ipopt.warm_start_bound_push": 1e-9, "ipopt.warm_start_mult_bound_push": 1e-9,
                "ipopt.warm_start_slack_bound_push": 1e-9}


def model_config(cfg: Config, values: dict) -> Config:
    """The config of a scenario's model: ``cfg`` with its keys set that are not in the
    parameter vector (those the scenario maps as a q + b)."""
    return with_values(cfg, {k: v for k, v in values.items() if k not in PARAM_COLUMNS})


def _model_key(cfg: Config) -> tuple:
    """A scenario model's key: the model's, and the elements the NLP carries."""
    return model_key(resolve(cfg)) + (tuple(e.name for e in nlp_elements(cfg)), gas_nlp(cfg))


def scenario_fit(cfg_model: Config, placement: bool = False):
    """(model, Chebyshev fit) of a scenario's model: the nominal optimiser's (with
    ``placement`` the closure's series too; the points do not change them)."""
    model = get_model(cfg_model)
    return model, ChebyshevFit(model, els=nlp_elements(cfg_model), pose=placement,
                               gas=gas_nlp(cfg_model))


class ScenarioStructure(Structure):
    """The symbolic scenario NLP of one structure: S scenarios of a model with the elements
    ``els`` (series ``names`` at the padded ``degree``), the free variables and points
    (which), the discretisation, the objective, the opening bound, the self-close constraint
    (every scenario closes by itself up to optimise.self_close_min_deg) and keep-out regions.
    No number of a lid or a scenario is in it: the scenario maps (a_s, b_s), the free
    variables' scales, the attachment points and every scenario's lid vector
    (:mod:`softclose.optimiser.parameters`, with the self-close angle) are parameters
    (:meth:`ScenarioNLP.params`)."""

    name = "softclose_robust"
    kept = {"peak": "peak_fn", "J": "J_fn"}

    def __init__(self, S: int, els, names, degree: int, nodes: int, substeps: int,
                 M_engaged: int | None, free: tuple, place: tuple, robust_objective: str,
                 opening: bool, keep_out: tuple, hessian: str, linear_solver: str,
                 max_iter: int, tol: float = 1e-10, library=None, meta=None,
                 self_close: bool = False, held: tuple = (False, False, False)):
        t0 = time.perf_counter()
        self.S, self.nodes, self.M, self.M_engaged = S, nodes, substeps, M_engaged
        self.two_phase = M_engaged is not None
        self.N = N = 2 * nodes if self.two_phase else nodes
        self.free, self.place = tuple(free), tuple(place)
        self.placed = bool(self.place)
        self.robust_objective = robust_objective
        self.nd = 3 + len(self.free) + len(self.place)
        #: which of (k, l0, c) are held at a value (their bounds lo = hi): parameters, the
        #: last three of P; their variables stay in w (bounded to the value) but nothing
        #: depends on them, so the Hessian and the Jacobian need fewer directions
        self.held = tuple(bool(h) for h in held)
        #: does ``softclose prepare`` compile it? Not with free points (a co-design's first
        #: stage): its C is slower than the VM (docs/bench_structures.json)
        self.prepared = not self.place
        self.series = SymbolicSeries(names, els, degree)
        self.spring = "gas" if "spring:l" in self.series.names else "coil"
        if self.placed and self_close:
            raise ConfigError("optimise.self_close_min_deg cannot yet be combined with free "
                              "attachment points (optimise.free geometry.*): fix the points "
                              "or drop the constraint")
        self.lid = LidLayout(self.series, 0, False, OPENING_INTERVALS + 1 if opening else 0,
                             SELF_CLOSE_INTERVALS + 1 if self_close else 0)
        n_sc = len(self.free) + len(self.place)
        self.n_params = len(PARAMS) + N + 2 * NP * S + n_sc + (8 if self.placed else 0) + \
            S * self.lid.size + (3 if any(self.held) else 0)
        check_linear_solver(linear_solver)
        self.options = shooting_options(tol, max_iter, hessian, linear_solver,
                                        calc_lam_p=any(self.held))
        self.cold_options = {**self.options, **COLD_OPTIONS}
        self.warm_options = {**self.options, **WARM_OPTIONS}
        if library is not None:
            self.load(library, meta)
            self.build_time = time.perf_counter() - t0
            return
        n1, M = nodes, substeps
        f, ode = interval_function(self.series, M, with_ode=True, placement=self.placed)
        f2 = None if M_engaged is None else f if M_engaged == M else interval_function(
            self.series, M_engaged, placement=self.placed)
        combine = combine_function(self.series, self.placed)
        npar = len(PARAMS)
        P = ca.MX.sym("P", self.n_params)
        theta0, thc, wi, wp = (P[i] for i in range(4))
        fixed, Jref = P[4:4 + len(FIXED)], P[npar - 1]
        grid = P[npar:npar + N]
        i0 = npar + N
        A = ca.reshape(P[i0:i0 + NP * S], NP, S)
        B = ca.reshape(P[i0 + NP * S:i0 + 2 * NP * S], NP, S)
        i0 += 2 * NP * S
        scales = P[i0:i0 + n_sc]
        i0 += n_sc
        if self.placed:
            points = P[i0:i0 + 8]
            i0 += 8
        lids = [self.lid.split(P[i0 + s * self.lid.size:i0 + (s + 1) * self.lid.size])
                for s in range(S)]
        d, t = ca.MX.sym("d", self.nd), ca.MX.sym("t")
        T = [ca.MX.sym(f"T{s}") for s in range(S)]
        T1 = [ca.MX.sym(f"T1_{s}") for s in range(S)] if self.two_phase else []
        X = [ca.MX.sym(f"X{s}", 2, N) for s in range(S)]
        pk = [ca.MX.sym(f"s{s}") for s in range(S)]
        values = P[self.n_params - 3:] if any(self.held) else None
        entries = [values[i] if self.held[i] else d[i] * SCALES[i] for i in range(3)] + \
            [fixed[i] for i in range(len(FIXED))]
        for j, (_, col) in enumerate(self.free):
            entries[col] = d[3 + j] * scales[j]
        q = ca.vertcat(*entries)
        gin = []
        if self.placed:
            gl = [points[i] for i in range(8)]
            for j, (_, slot) in enumerate(self.place):
                gl[slot] = d[3 + len(self.free) + j] * scales[len(self.free) + j]
            gvec = ca.vertcat(*gl)
            gin = [gvec]
        ps = [A[:, s] * q + B[:, s] for s in range(S)]
        cs = [combine(ps[s], *gin, lids[s]["series"]) for s in range(S)]
        if self.two_phase:      # phase 1 without the end damper
            off = np.ones(NP)
            off[PARAM_COLUMNS[END_C]] = 0.0
            cs1 = [combine(ps[s] * ca.DM(off), *gin, lids[s]["series"]) for s in range(S)]
        # the shooting intervals of every scenario: one map (per phase)
        X0 = [ca.horzcat(ca.vertcat(theta0, 0), X[s][:, :N - 1]) for s in range(S)]
        outs: list = [None] * S
        if not self.two_phase:
            C = ca.horzcat(*[ca.repmat(cs[s], 1, N) for s in range(S)])
            H = ca.horzcat(*[T[s] * grid.T / M for s in range(S)])
            res = mapped(f, N * S)(ca.horzcat(*X0), C, H)
            for s in range(S):
                cols = slice(s * N, (s + 1) * N)
                outs[s] = tuple(r[:, cols] for r in res)
        else:
            C1 = ca.horzcat(*[ca.repmat(cs1[s], 1, n1) for s in range(S)])
            H1 = ca.horzcat(*[T1[s] * grid[:n1].T / M for s in range(S)])
            r1 = mapped(f, n1 * S)(ca.horzcat(*[x[:, :n1] for x in X0]), C1, H1)
            C2 = ca.horzcat(*[ca.repmat(cs[s], 1, n1) for s in range(S)])
            H2 = ca.horzcat(*[(T[s] - T1[s]) * grid[n1:].T / M_engaged for s in range(S)])
            r2 = mapped(f2, n1 * S)(ca.horzcat(*[x[:, n1:] for x in X0]), C2, H2)
            for s in range(S):
                cols = slice(s * n1, (s + 1) * n1)
                outs[s] = (ca.horzcat(r1[0][:, cols], r2[0][:, cols]),
                           *(ca.vertcat(ca.vec(r1[k][:, cols]), ca.vec(r2[k][:, cols]))
                             for k in (1, 2, 3)))
        g, self.g_sizes, J, peaks = [], [], [], []
        none = ca.MX(0, 1)
        for s in range(S):
            xe, a, b, sp = outs[s]
            Ls = lids[s]["series"]
            Js = wi * X[s][1, N - 1] ** 2 + wp * pk[s] ** 2
            J.append(Js)
            peaks.append(ca.mmax(sp))     # the scenario's own peak: sub-steps, Hermite maxima
            release = ode(ca.vertcat(theta0, 0), cs[s])[1]
            if self.placed:     # the spring at the shared points g (optimiser.placement)
                mask = np.ones(NP)
                mask[[PARAM_COLUMNS["design.spring_k"], PARAM_COLUMNS["design.spring_preload"]]] = 0
                sa, sb = elements.BY_NAME["spring"].affine(elements.params(ps[s]))
                gas = strut_law(self, ps[s])
                hold = holding_moment(lids[s]["closed"], elements.params(ps[s] * ca.DM(mask),
                                                                          self.spring)) \
                    + spring_moment(self.series, thc, gvec, sa, sb, Ls, gas)
                Ln, Lmax, Lmin = length_bounds(self.series, theta0, thc, gvec, Ls)
                l0 = ps[s][PARAM_COLUMNS["design.spring_rest_length"]]
                short = l0 if gas is None else \
                    l0 - strut_stroke(elements.params(ps[s], "gas"))     # its compressed end
                lengths = [l0 - ca.vertcat(ca.vec(Ln), ca.vec(Lmax)),
                           ca.vertcat(ca.vec(Ln), ca.vec(Lmin)) - short,
                           ca.vertcat(ca.vec(Ln), ca.vec(Lmax), ca.vec(Lmin))]
            else:
                hold = holding_moment(lids[s]["closed"], elements.params(ps[s], self.spring))
                lengths = [none, none, none]
            if self.two_phase:  # the node between the phases on the scenario's theta_e
                phases = [X[s][0, n1 - 1] - elements.params(ps[s])["end_damper_angle_deg"],
                          T[s] - T1[s]]
            else:
                phases = [none, none]
            if opening and not self.placed:
                op = opening_bound(self.lid, lids[s]["opening"], theta0, thc, ps[s],
                                   self.spring)
            else:
                op = none
            sc = self_close_bound(self.lid, lids[s]["self_close"], thc, ps[s], self.spring) \
                if self_close else none
            ko = none
            if self.placed and s == 0 and keep_out:
                ko = keep_out_constraints(self.series, theta0, thc, gvec, keep_out,
                                          self.place, Ls)
            blocks = [ca.vec(xe - X[s]), ca.vec(a) - thc, ca.vec(b), pk[s] - ca.vec(sp),
                      hold, release, t - Js / Jref, op, sc] + lengths + [ko] + phases
            g += blocks
            self.g_sizes.append([int(v.numel()) for v in blocks])
        self.block = sum(self.g_sizes[0])
        if robust_objective == "worst":
            f_obj = t
        else:
            f_obj = sum(J) / (S * Jref)
        w = ca.vertcat(d, t, *[ca.vertcat(T[s], *(T1[s:s + 1]), ca.vec(X[s]), pk[s])
                               for s in range(S)])
        self.nw = int(w.numel())
        # each scenario's own peak tip speed (not s_s) and its objective with that peak
        pv = ca.vertcat(*peaks)
        thd = ca.vertcat(*[X[s][1, N - 1] for s in range(S)])
        self.peak_fn = ca.Function("peaks", [w, P], [pv])
        self.J_fn = ca.Function("J", [w, P], [wi * thd ** 2 + wp * pv ** 2])
        self.make_solver({"x": w, "f": f_obj, "g": ca.vertcat(*g), "p": P})
        self.build_time = time.perf_counter() - t0

    def load(self, library, meta: dict) -> None:
        """The solvers from a compiled library (:mod:`softclose.buildcache`) and the numbers
        :meth:`meta` kept: nothing symbolic is built."""
        super().load(library, meta)
        if len(self.g_sizes) != self.S:
            raise ValueError("the compiled scenario NLP has other dimensions")
        self.block = sum(self.g_sizes[0])


class ScenarioNLP(NLP):
    """The multiple-shooting NLP of S scenarios (see the module docstring): a
    :class:`ScenarioStructure` bound to the scenarios' models (their lid vectors).

    ``model_cfgs`` lists the scenarios' model configs (equal configs share a model and its
    fit). Variables: w = (d, t, then per scenario T_s, [T1_s], X_s (2N_all), s_s); d = (k,
    l0, c, the free end damper's c_e and angle, the free points), scaled. ``nodes``:
    intervals (per phase); ``substeps_engaged``: phase 2's sub-steps (two phases: by default
    :func:`~softclose.optimiser.discretisation.phase_substeps` of ``cfg``).
    """

    def __init__(self, cfg: Config, model_cfgs: list[Config], nodes: int, substeps: int,
                 robust_objective: str = "worst", tol: float = 1e-10,
                 substeps_engaged: int | None = None, structure: ScenarioStructure | None = None):
        t0 = time.perf_counter()
        o = cfg.optimise
        self.two_phase = two_phase(cfg)
        self.M_engaged = (substeps_engaged or phase_substeps(cfg, nodes, substeps)) \
            if self.two_phase else None
        self.nodes, self.M, self.S = nodes, substeps, len(model_cfgs)
        self.N = 2 * nodes if self.two_phase else nodes
        self.robust_objective = robust_objective
        # the free end damper (optimise.free) and attachment points, shared by every scenario
        # (a gas strut's force F1 too: its design variable beside l0 and c)
        self.free = free_layout(cfg)
        self.place = placement_layout(cfg)
        self.placed = bool(self.place)
        self.g0 = slot_values(cfg)
        self.nd = 3 + len(self.free) + len(self.place)
        bounds = {k: (lo, hi) for k, lo, hi in free_of(cfg)}
        #: the free variables' values when a design gives only (k, l0, c): cfg's, clipped
        self.free_values = np.r_[[float(np.clip(config_value(cfg, k), *bounds[k]))
                                  for k, _, _ in self.free],
                                 [self.g0[slot] for _, slot, _ in self.place]]
        self.scales = np.r_[SCALES, [sc for _, _, sc in self.free],
                            [sc for _, _, sc in self.place]]
        # one model and fit per distinct model config
        keys, self.model_index, self.models, fits = [], [], [], []
        for c in model_cfgs:
            key = _model_key(c)
            if key not in keys:
                keys.append(key)
                model, fit = scenario_fit(c, self.placed)
                self.models.append(model)
                fits.append(fit)
            self.model_index.append(keys.index(key))
        self.scenario_models = [self.models[i] for i in self.model_index]
        self.fits = fits
        degree = padded_degree(max(f.degree for f in fits))
        self.held = held_design(cfg)
        self.structure_key = (self.S, tuple(e.name for e in fits[0].elements), fits[0].names,
                              degree, nodes, substeps, self.M_engaged,
                              tuple((k, col) for k, col, _ in self.free),
                              tuple((k, slot) for k, slot, _ in self.place),
                              robust_objective, o.opening_force_max is not None,
                              keep_out_of(cfg), o.hessian, o.linear_solver, o.max_iter, tol,
                              o.self_close_min_deg is not None, self.held)
        st = structure or get_scenario_structure(self.structure_key)
        self.structure = st
        for k in ("g_sizes", "block", "nw", "peak_fn", "J_fn", "solver", "library",
                  "options"):
            setattr(self, k, getattr(st, k))
        lay = st.lid
        if lay.self_close_angles:
            check_self_close(cfg)
        per_model = [lay.values(m, f, (), None, opening_angles(m, OPENING_INTERVALS)
                                if lay.opening_angles else None,
                                o.self_close_min_deg if lay.self_close_angles else None)
                     for m, f in zip(self.models, fits)]
        self.lid_vector = np.r_[self.scales[3:], self.g0 if self.placed else [],
                                np.concatenate([per_model[i] for i in self.model_index])]
        self.build_time = time.perf_counter() - t0

    def self_close_moments(self, s: int, p, self_close_deg: float) -> np.ndarray:
        """Scenario s's self-close constraint values (N m) at its parameter vector ``p`` and
        the angle ``self_close_deg`` (as the nominal NLP's ``self_close_moments``): the
        active set's price per degree differentiates them in the angle."""
        lay, model = self.structure.lid, self.scenario_models[s]
        fn = self_close_function(lay, self.structure.spring)
        return np.asarray(fn(lay.self_close_values(model, self_close_deg), np.asarray(p, float),
                             model.stroke.theta_closed)).ravel()

    # -- layout ------------------------------------------------------------------------
    @property
    def per(self) -> int:
        """Variables per scenario: T, [T1], X (2N), s."""
        return 2 * self.N + 2 + int(self.two_phase)

    def offset(self, s: int) -> int:
        """Where scenario s's variables start (its T)."""
        return self.nd + 1 + s * self.per

    def x_offset(self, s: int) -> int:
        """Where scenario s's states X start."""
        return self.offset(s) + 1 + int(self.two_phase)

    def pack(self, design, t, states, T1s=None) -> np.ndarray:
        """w from the design (SI; k, l0, c alone: the free variables from the config), t,
        and per scenario (T, X (2, N), s) (and its engagement time, ``T1s``, with two
        phases)."""
        d = np.asarray(design, float)
        if len(d) < self.nd:
            d = np.r_[d[:3], self.free_values[:self.nd - 3]]
        parts = [d[:self.nd] / self.scales, [t]]
        for s, (T, X, pk) in enumerate(states):
            t1 = [] if not self.two_phase else [0.5 * T if T1s is None else T1s[s]]
            parts += [[T], t1, np.asarray(X, float).T.ravel(), [pk]]
        return np.concatenate([np.atleast_1d(np.asarray(p, float)) for p in parts])

    def unpack(self, w):
        """(design (SI), t, [(T, X (2, N), s) per scenario])."""
        w = np.asarray(w, float).ravel()
        N = self.N
        states = []
        for s in range(self.S):
            i, j = self.offset(s), self.x_offset(s)
            states.append((float(w[i]), w[j:j + 2 * N].reshape(N, 2).T, float(w[j + 2 * N])))
        return w[:self.nd] * self.scales, float(w[self.nd]), states

    def engagements(self, w) -> list | None:
        """Per scenario (T1_s, theta' at the node between the phases): each scenario's own
        engagement time and speed (None for one phase)."""
        if not self.two_phase:
            return None
        w = np.asarray(w, float).ravel()
        return [(float(w[self.offset(s) + 1]),
                 float(w[self.x_offset(s) + 2 * (self.nodes - 1) + 1])) for s in range(self.S)]

    def params(self, cfg: Config, maps: list[tuple[np.ndarray, np.ndarray]],
               J_ref: float = 1.0) -> np.ndarray:
        o, st = cfg.optimise, cfg.stroke
        A = np.concatenate([np.asarray(a, float) for a, _ in maps])
        B = np.concatenate([np.asarray(b, float) for _, b in maps])
        held = [getattr(o, k)[0] for k in DESIGN_KEYS] if any(self.held) else []
        return np.r_[st.theta0, st.theta_closed, o.weight_impact, o.weight_peak_tip,
                     params_of(cfg)[len(DESIGN_KEYS):], J_ref,
                     scenario_grid(self.nodes, self.two_phase), A, B, self.lid_vector, held]

    def bounds(self, cfg: Config, t_hi: list[float] | None = None,
               t_lo: list[float] | None = None, design_lb=None):
        """(lbx, ubx, lbg, ubg); ``t_hi``/``t_lo`` give per-scenario closing-time bounds
        (corrected for the discretisation error), ``design_lb`` raised lower design bounds."""
        o, st = cfg.optimise, cfg.stroke
        N = self.N
        lbx, ubx = np.full(self.nw, -np.inf), np.full(self.nw, np.inf)
        for i, key in enumerate(("spring_k", "spring_rest_length", "damper_c")):
            lo, hi = getattr(o, key)
            if design_lb is not None:
                lo = max(lo, design_lb[i])
            lbx[i], ubx[i] = lo / SCALES[i], hi / SCALES[i]
        free = {k: (lo, hi) for k, lo, hi in free_of(cfg)}
        for j, (k, _, sc) in enumerate(self.free + self.place):
            lbx[3 + j], ubx[3 + j] = free[k][0] / sc, free[k][1] / sc
        if self.robust_objective != "worst":
            lbx[self.nd] = ubx[self.nd] = 0.0
        for s in range(self.S):
            i = self.offset(s)
            stroke_bounds(lbx, ubx, st, i, i + 1 if self.two_phase else None,
                          self.x_offset(s), N,
                          o.closing_time_min if t_lo is None else t_lo[s],
                          t_limit(cfg) if t_hi is None else t_hi[s])
        lo, hi = group_bounds(o)
        lo["epigraph"] = 0.0 if self.robust_objective == "worst" else -np.inf
        hi["epigraph"] = np.inf
        placed_bounds(cfg, lo, hi)
        lbg = np.concatenate([np.full(n, lo[k]) for sizes in self.g_sizes
                              for k, n in zip(GROUPS, sizes)])
        ubg = np.concatenate([np.full(n, hi[k]) for sizes in self.g_sizes
                              for k, n in zip(GROUPS, sizes)])
        return lbx, ubx, lbg, ubg

    def blocks(self) -> list[list[tuple[str, int]]]:
        """Per scenario, its constraint groups (:data:`GROUPS`) and their sizes."""
        return [list(zip(GROUPS, sizes)) for sizes in self.g_sizes]

    def peaks(self, w, p) -> np.ndarray:
        """Each scenario's own peak tip speed at w: its largest sub-step speed or Hermite
        maximum (not the epigraph variable s_s, which nothing pins when weight_peak_tip is
        zero or the scenario is not the worst)."""
        return np.asarray(self.peak_fn(w, p)).ravel() * 1.0

    def objectives(self, w, p) -> np.ndarray:
        """J_s of every scenario at w (unscaled), with its own peak (:meth:`peaks`)."""
        return np.asarray(self.J_fn(w, p)).ravel() * 1.0

    def solve(self, x0, p, lbx, ubx, lbg, ubg, lam_x0=None, lam_g0=None, warm: bool = False,
              origin: str = "") -> Run:
        """One Ipopt run (:meth:`~softclose.optimiser.base.NLP.solve`); a held design
        value's multiplier is its parameter's, in the place of its variable's."""
        run = super().solve(x0, p, lbx, ubx, lbg, ubg, lam_x0, lam_g0, warm, origin)
        if run.lam_x is None or not any(self.held):
            return run
        lam_x = run.lam_x.copy()
        for i in np.flatnonzero(self.held):
            lam_x[i] = float(run.lam_p[len(p) - 3 + i]) * SCALES[i]
        return dataclasses.replace(run, lam_x=lam_x)


#: the structures built in this process, by :attr:`ScenarioNLP.structure_key`
_STRUCTURES: dict = {}


def get_scenario_structure(key: tuple) -> ScenarioStructure:
    """The ScenarioStructure of ``key`` (:attr:`ScenarioNLP.structure_key`), built once:
    its compiled library when ``softclose prepare`` built one, else symbolically."""
    (S, els, names, degree, nodes, substeps, M_engaged, free, place, objective, opening,
     keep_out, hessian, linear_solver, max_iter, tol, self_close, held) = key

    def make(library=None, meta=None):
        return ScenarioStructure(S, tuple(elements.BY_NAME[e] for e in els), names, degree,
                                 nodes, substeps, M_engaged, free, place, objective, opening,
                                 keep_out, hessian, linear_solver, max_iter, tol,
                                 library=library, meta=meta, self_close=self_close, held=held)
    what = (f"of the robust optimiser ({S} scenarios, {nodes} x {substeps} RK4 steps, "
            f"{objective} case{', the points free' if place else ''})")
    # (the points free: never compiled, ScenarioStructure.prepared)
    return compiled.kept_structure(_STRUCTURES, key, "scenario-nlp", make, make, what,
                                   compiled.SCENARIO_CFLAGS, compile_it=not place)
