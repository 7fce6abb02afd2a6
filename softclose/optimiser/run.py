"""One Ipopt run of the multiple-shooting NLP (:class:`Run`), and the order of the NLP's
parameters it is read with."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..problem import DESIGN_KEYS, PARAM_KEYS

#: the parameters of p that are not design variables: NLP parameters
FIXED_PARAMS = PARAM_KEYS[len(DESIGN_KEYS):]
#: NLP parameters, in order (then the time grid: the fractions of T of the N intervals)
NLP_PARAMS = ("theta0", "theta_closed", "weight_impact", "weight_peak_tip", "weight_time",
              *FIXED_PARAMS, "J_ref")
J_INDEX = NLP_PARAMS.index("J_ref")


@dataclass(frozen=True, eq=False)
class Run:
    """One Ipopt solve: the primal-dual point, its status and cost, and the problem data
    (parameters ``p`` and ``bounds`` = (lbx, ubx, lbg, ubg)) it was solved with."""

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
    violations: dict = field(default_factory=dict)

    @property
    def J_ref(self) -> float:
        return float(self.p[J_INDEX])


__all__ = ["Run", "NLP_PARAMS", "FIXED_PARAMS", "J_INDEX"]
