"""One Ipopt run of any NLP of softclose (:class:`Run`): what :func:`.ipopt.run` returns and
:meth:`softclose.optimiser.base.NLP.solve` gives back."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True, eq=False)
class Run:
    """One Ipopt solve: the primal-dual point, its status and cost, and the problem data
    (parameters ``p`` and ``bounds`` = (lbx, ubx, lbg, ubg)) it was solved with.

    ``violations``: per block of the NLP's constraints (one block for the nominal and the
    calibration NLP, one per scenario for the scenario NLP), the largest violation of each
    constraint group, {group: value} (0 where it holds; :meth:`.base.NLP.violations`).
    ``lam_p``: the parameters' multipliers (meaningful where the solver computes them)."""

    x: np.ndarray
    f: float
    g: np.ndarray
    lam_x: np.ndarray | None
    lam_g: np.ndarray | None
    status: str
    success: bool
    iterations: int
    time: float
    p: np.ndarray
    bounds: tuple
    origin: str = ""
    violations: list = field(default_factory=list)
    lam_p: np.ndarray | None = None

    @property
    def total_violation(self) -> float:
        """The sum of every block's largest violations."""
        return sum(sum(block.values()) for block in self.violations)


__all__ = ["Run"]
