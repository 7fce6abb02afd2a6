"""How the scenario NLP (:mod:`softclose.robust.nlp`) is discretised: its node grid (graded
at the release), its phases (two with an end damper engaging inside the stroke) and the
closing-time limit."""

from __future__ import annotations

import casadi as ca
import numpy as np

from ..config import Config
from ..optimiser.discretise import discretisation, phase_two_substeps
from ..optimiser.interval import end_damper_mode


#: the node grid is graded (:func:`time_grid`) from this many nodes on
GRADED_MIN_NODES = 6


def time_grid(N: int) -> np.ndarray:
    """Fractions of T_s of the N shooting intervals: the first two half as long as the
    others (uniform for N < :data:`GRADED_MIN_NODES`).

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


def t_limit(cfg: Config) -> float:
    """The largest closing time the NLP allows: a stroke must close within stroke.t_max."""
    return min(cfg.optimise.closing_time_max, cfg.stroke.t_max)


def phase_grid(N: int, two_phase: bool) -> np.ndarray:
    """The node grid of a scenario: :func:`time_grid` (fractions of T_s), or with two
    phases phase 1's graded grid (fractions of T1_s) and phase 2's uniform one (fractions
    of T_s - T1_s)."""
    return np.r_[time_grid(N), np.full(N, 1.0 / N)] if two_phase else time_grid(N)


def node_times(N: int, two_phase: bool, T: float, T1: float | None = None) -> np.ndarray:
    """The times (s) of a scenario's nodes on :func:`phase_grid`."""
    g = np.minimum(np.cumsum(time_grid(N)), 1.0)
    if not two_phase:
        return T * g
    return np.r_[T1 * g, T1 + (T - T1) * np.arange(1, N + 1) / N]


def discretise(cfg: Config) -> tuple[int, int, float, list[str]]:
    """(N, M, closing-time limit, notes) of the nominal optimiser's discretisation (with two
    phases, phase 2's sub-steps follow from cfg: :func:`phase_two`)."""
    d = discretisation(cfg)
    return d.nodes, d.substeps, d.t_limit, list(d.notes)


def two_phase(cfg: Config) -> bool:
    """Is cfg's stroke two phases (an end damper engaging inside it)?"""
    return end_damper_mode(cfg) == "two-phase"


def phase_two(cfg: Config, nodes: int, substeps: int) -> int | None:
    """Phase 2's sub-steps (the nominal optimiser's rule), None for one phase."""
    if not two_phase(cfg):
        return None
    return phase_two_substeps(cfg, nodes, substeps)
