"""The discretisation of the soft-close NLP: how many shooting intervals and RK4 sub-steps.

:func:`discretisation` reads ``optimise.nodes`` / ``optimise.substeps`` and raises the
sub-steps until every RK4 step of the NLP keeps the margin :data:`H_MAX` x
:data:`LAMBDA_REF` on the stiffest damper it may meet (the dashpot at its upper bound; in a
two-phase stroke, phase 2 also with the end damper: :func:`phase_two_substeps`); a grid
beyond the config's budget (:data:`MAX_STEPS`) is refused in one line. The NLP itself
(:mod:`softclose.optimiser.nlp`) takes the numbers it gives.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..config import NLP_BUDGET
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


def phase_two_rate(cfg) -> float:
    """The largest damping rate of phase 2 (1/s): max over theta in [theta_closed, the
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


def phase_two_substeps(cfg, nodes: int, substeps: int, t_limit: float | None = None) -> int:
    """Phase 2's RK4 sub-steps: ``substeps`` doubled until its step at the closing-time
    limit, t_limit / (N M2), keeps h lambda_2 <= H_MAX LAMBDA_REF (the margin the
    one-phase NLP keeps on the dashpot: :data:`H_MAX`) with lambda_2 the end damper's and
    the dashpot's largest rate (:func:`phase_two_rate`), and h <= H_MAX. Phase 2 may last up
    to the whole limit (T1 is free), so the rule is the one-phase rule with the end
    damper's rate added."""
    if t_limit is None:
        t_limit = min(cfg.optimise.closing_time_max, cfg.stroke.t_max)
    h_max = min(H_MAX, H_MAX * LAMBDA_REF / max(phase_two_rate(cfg), 1e-12))
    need = t_limit / (nodes * h_max * (1 + 1e-9))
    M2 = int(substeps)
    if M2 < need:
        M2 *= 2 ** math.ceil(math.log2(need / M2))
    return M2


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
    #: a two-phase stroke (an end damper engaging inside it): phase 2's sub-steps (its
    #: nodes are ``nodes`` as phase 1's); None for one phase
    substeps2: int | None = None

    @property
    def steps(self) -> int:
        return self.nodes * (self.substeps + (self.substeps2 or 0))


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
    M2 = None
    if end_damper_mode(cfg) == "two-phase":
        M2 = phase_two_substeps(cfg, N, M, t_limit)
        notes.append(f"two phases (the end damper engages inside the stroke): {N} intervals "
                     f"of {M} RK4 sub-steps each before the engagement, {N} of {M2} after it"
                     + (" (raised so that RK4 is as stable on the end damper as on the "
                        "dashpot)" if M2 > M else ""))
    steps = N * (M + (M2 or 0))
    if steps > MAX_STEPS:
        if M2 is None and (substeps or M == o.substeps):
            raise ConfigError(
                f"optimise.nodes x optimise.substeps = {N} x {M} = {N * M} RK4 steps exceeds "
                f"the limit of {MAX_STEPS}; lower optimise.nodes or optimise.substeps")
        if M2 is not None:
            raise ConfigError(
                f"the two phases of the end damper's stroke need {N} x {M} + {N} x {M2} = "
                f"{steps} RK4 steps, more than the limit of {MAX_STEPS}; lower "
                "optimise.nodes, optimise.substeps, optimise.closing_time_max or the end "
                "damper's upper bound (design.end_damper_c)")
        raise ConfigError(
            f"optimise.closing_time_max: closing times up to {t_limit:g} s need "
            f"{N} x {M} = {N * M} RK4 steps of at most {H_MAX:g} s, more than the limit of "
            f"{MAX_STEPS}; lower optimise.closing_time_max (or stroke.t_max) or "
            "optimise.nodes")
    return Discretisation(N, M, t_limit, tuple(notes), M2)
