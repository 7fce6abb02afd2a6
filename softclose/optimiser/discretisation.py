"""The discretisation of the soft-close NLPs: how many shooting intervals and RK4 sub-steps,
the phases, the closing-time limit and the node grids -- of the nominal NLP
(:mod:`softclose.optimiser.nlp`) and of the scenario NLP (:mod:`softclose.robust.nlp`).

:func:`discretisation` reads ``optimise.nodes`` / ``optimise.substeps`` and raises the
sub-steps until every RK4 step of the NLP keeps the margin :data:`H_MAX` x
:data:`LAMBDA_REF` on the stiffest damper it may meet (the dashpot at its upper bound; in a
two-phase stroke, the engaged phase -- after the end damper engages -- also with the end
damper: :func:`engaged_substeps`); a grid beyond the config's budget (:data:`MAX_STEPS`) is
refused in one line. Both NLPs take the numbers it gives. The nominal NLP's node grid is
uniform (:meth:`~softclose.optimiser.nlp.ShootingNLP.time_grid`); the scenario NLP's is
graded at the release (:func:`graded_grid`, :func:`scenario_grid`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..config import NLP_BUDGET, Config
from ..errors import ConfigError
from .interval import END_C, end_damper_mode, free_of
from ..model.lid import shared_model
from ..model.dynamics import COEFFS
from ..problem import resolve


#: largest RK4 step of the NLP (s) when the sub-steps are chosen automatically: the default
#: discretisation's step (1 s / (10 x 4)); it keeps long strokes accurate and RK4 stable
#: on the damper (h |lambda| <= 0.025 * 70 < 2.79 for damper_c up to 5000 N s/m)
H_MAX = 0.025
#: most RK4 steps (nodes x substeps) of one NLP, the config's budget: ~0.2 ms per step and
#: Ipopt iteration, so one solve at the limit takes ~10 s; larger grids are refused
MAX_STEPS = NLP_BUDGET
#: the damper's rate H_MAX is sized for (1/s): c dd / M of the dashpot at damper_c = 5000
#: N s/m reaches 67 1/s on the default lid; h lambda <= H_MAX * 70 = 1.75 (RK4 is stable to
#: 2.79 on the real axis) is the margin every RK4 step of the NLP keeps
LAMBDA_REF = 70.0


def t_limit(cfg: Config) -> float:
    """The largest closing time the NLP allows: a stroke must close within stroke.t_max."""
    return min(cfg.optimise.closing_time_max, cfg.stroke.t_max)


def two_phase(cfg: Config) -> bool:
    """Is cfg's stroke two phases (an end damper engaging inside it)?"""
    return end_damper_mode(cfg) == "two-phase"


def engaged_rate(cfg) -> float:
    """The largest damping rate of the engaged phase (1/s): max over theta in [theta_closed, the
    highest engagement angle] of (c_max q_d'^2 + c_e,max) / M(theta) -- the dashpot at its
    upper bound and the end damper at its largest coefficient (its upper bound when free)."""
    o, st = cfg.optimise, cfg.stroke
    free = {k: (lo, hi) for k, lo, hi in free_of(cfg)}
    ce = free[END_C][1] if END_C in free else cfg.design.end_damper_c
    a_hi = free.get("design.end_damper_angle_deg", (0, cfg.design.end_damper_angle_deg))[1]
    th = np.radians(np.linspace(st.theta_closed_deg, min(a_hi, st.theta0_deg), 101))
    C = np.asarray(shared_model(resolve(cfg)).coeffs.map(len(th))(th)[0])
    M, dd = C[COEFFS.index("M")], C[COEFFS.index("dd")]
    return float(np.max((o.damper_c[1] * dd + ce) / M))


def engaged_substeps(cfg, nodes: int, substeps: int, t_limit: float | None = None) -> int:
    """The engaged phase's RK4 sub-steps M_e: ``substeps`` doubled until its step at the
    closing-time limit, t_limit / (N M_e), keeps h lambda_e <= H_MAX LAMBDA_REF (the margin
    the one-phase NLP keeps on the dashpot: :data:`H_MAX`) with lambda_e the end damper's
    and the dashpot's largest rate (:func:`engaged_rate`), and h <= H_MAX. The engaged
    phase may last up to the whole limit (T1 is free), so the rule is the one-phase rule
    with the end damper's rate added."""
    if t_limit is None:
        t_limit = min(cfg.optimise.closing_time_max, cfg.stroke.t_max)
    h_max = min(H_MAX, H_MAX * LAMBDA_REF / max(engaged_rate(cfg), 1e-12))
    need = t_limit / (nodes * h_max * (1 + 1e-9))
    M_engaged = int(substeps)
    if M_engaged < need:
        M_engaged *= 2 ** math.ceil(math.log2(need / M_engaged))
    return M_engaged


def phase_substeps(cfg, nodes: int, substeps: int) -> int | None:
    """The engaged phase's sub-steps (:func:`engaged_substeps`), None for one phase."""
    if not two_phase(cfg):
        return None
    return engaged_substeps(cfg, nodes, substeps)


# -- the discretisation ----------------------------------------------------------------------
@dataclass(frozen=True)
class Discretisation:
    """N shooting intervals of M RK4 sub-steps, and the closing-time limit the NLP uses.

    ``t_limit`` is ``min(closing_time_max, stroke.t_max)``: a stroke must close within
    t_max, so a larger limit cannot bind (and must not make the grid huge).
    """

    nodes: int
    substeps: int
    t_limit: float
    notes: tuple[str, ...] = ()
    #: a two-phase stroke (an end damper engaging inside it): the engaged phase's
    #: sub-steps (its nodes are ``nodes`` as the first phase's); None for one phase
    substeps_engaged: int | None = None

    @property
    def steps(self) -> int:
        return self.nodes * (self.substeps + (self.substeps_engaged or 0))


def discretisation(cfg, nodes: int | None = None, substeps: int | None = None) -> Discretisation:
    """optimise.nodes, and optimise.substeps doubled if needed so that the RK4 step
    t_limit/(N M) stays <= :data:`H_MAX`; explicit arguments are kept as given.

    Raises ConfigError when the grid would exceed :data:`MAX_STEPS` RK4 steps.
    """
    o, st = cfg.optimise, cfg.stroke
    N = int(nodes or o.nodes)
    notes = []
    t_limit = o.closing_time_max
    if o.closing_time_max > st.t_max:     # (closing_time_min < t_max: checked by the config)
        t_limit = st.t_max
        notes.append(f"closing_time_max = {o.closing_time_max:g} s lies beyond stroke.t_max = "
                     f"{st.t_max:g} s (a stroke must close within t_max): the NLP uses "
                     f"closing_time <= {st.t_max:g} s")
    if substeps:
        M = int(substeps)
    else:
        M = o.substeps
        need = t_limit / (N * H_MAX * (1 + 1e-9))
        if M < need:   # doublings: few distinct NLPs to build (refinement doubles too)
            M *= 2 ** math.ceil(math.log2(need / M))
            if N * M <= MAX_STEPS:
                notes.append(f"substeps raised from {o.substeps} to {M} so that the RK4 step "
                             f"stays <= {H_MAX:g} s for closing times up to {t_limit:g} s")
    Me = None
    if end_damper_mode(cfg) == "two-phase":
        Me = engaged_substeps(cfg, N, M, t_limit)
        notes.append(f"two phases (the end damper engages inside the stroke): {N} intervals "
                     f"of {M} RK4 sub-steps each before the engagement, {N} of {Me} after it"
                     + (" (raised so that RK4 is as stable on the end damper as on the "
                        "dashpot)" if Me > M else ""))
    steps = N * (M + (Me or 0))
    if steps > MAX_STEPS:
        if Me is None and (substeps or M == o.substeps):
            raise ConfigError(
                f"optimise.nodes x optimise.substeps = {N} x {M} = {N * M} RK4 steps exceeds "
                f"the limit of {MAX_STEPS}; lower optimise.nodes or optimise.substeps")
        if Me is not None:
            raise ConfigError(
                f"the two phases of the end damper's stroke need {N} x {M} + {N} x {Me} = "
                f"{steps} RK4 steps, more than the limit of {MAX_STEPS}; lower "
                "optimise.nodes, optimise.substeps, optimise.closing_time_max or the end "
                "damper's upper bound (design.end_damper_c)")
        raise ConfigError(
            f"optimise.closing_time_max: closing times up to {t_limit:g} s need "
            f"{N} x {M} = {N * M} RK4 steps of at most {H_MAX:g} s, more than the limit of "
            f"{MAX_STEPS}; lower optimise.closing_time_max (or stroke.t_max) or "
            "optimise.nodes")
    return Discretisation(N, M, t_limit, tuple(notes), Me)


# -- the scenario NLP's node grid --------------------------------------------------------------
#: the scenario NLP's node grid is graded (:func:`graded_grid`) from this many nodes on
GRADED_MIN_NODES = 6


def graded_grid(N: int) -> np.ndarray:
    """Fractions of T_s of the scenario NLP's N shooting intervals: the first two half as
    long as the others (uniform for N < :data:`GRADED_MIN_NODES`).

    Why: robust designs sit at stiff springs and strong dampers, and the scenarios add
    +20 % to them. The lid then accelerates from rest with a time constant of ~20 ms and
    reaches its peak tip speed at ~0.07 s, inside the first interval, while a uniform
    sub-step is T/(N M) = 25 ms at T = 1 s (h |lambda| ~ 1.5). RK4's error on that
    transient decays by the rim (closing time 4e-5 relative) but not at the peak: the
    scenario's own peak tip speed was 2.9e-3 below the adaptive reference's, beyond
    VERIFY_RTOL. Halving the first two intervals (the first 10 % of the stroke at N = 10)
    cuts that to 1.2e-4 at no cost; the other intervals grow by (N-1)/(N-2) (12.5 % at
    N = 10), which moved no metric of the default problem by more than 1.2e-4 (the
    accuracy loop of :mod:`softclose.robust.design` refines M if a scenario still
    disagrees). Doubling M instead costs ~3 s more per robust optimisation.
    """
    if N < GRADED_MIN_NODES:
        return np.full(N, 1.0 / N)
    rest = (1.0 - 1.0 / N) / (N - 2)
    return np.r_[0.5 / N, 0.5 / N, np.full(N - 2, rest)]


def scenario_grid(N: int, two_phase: bool) -> np.ndarray:
    """The node grid of a scenario: :func:`graded_grid` (fractions of T_s), or with two
    phases the first phase's graded grid (fractions of T1_s) and the engaged phase's
    uniform one (fractions of T_s - T1_s)."""
    return np.r_[graded_grid(N), np.full(N, 1.0 / N)] if two_phase else graded_grid(N)


def scenario_node_times(N: int, two_phase: bool, T: float,
                        T1: float | None = None) -> np.ndarray:
    """The times (s) of a scenario's nodes on :func:`scenario_grid`."""
    g = np.minimum(np.cumsum(graded_grid(N)), 1.0)
    if not two_phase:
        return T * g
    return np.r_[T1 * g, T1 + (T - T1) * np.arange(1, N + 1) / N]
