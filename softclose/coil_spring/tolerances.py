"""EN 15800: tolerances of cylindrical helical compression springs.

With d, D in mm, forces in N and the rate R in N/mm (SI at the interface: the formulas
are unit-consistent once alpha_F is in N, so ``A_L0 = alpha_F k_F Q / R`` comes out in
metres for R in N/m)::

    alpha_F = 65.92 d^3.3 / D^1.6 * (-0.84 (w/10)^3 + 3.781 (w/10)^2 - 4.244 (w/10) + 2.274)   [N]
    k_F     = 1/(3 n^2) + 8/(5 n) + 0.803
    A_F     = +-(alpha_F k_F + 1.5 F / 100) Q          force F at a given length      [N]
    A_L0    = +-alpha_F k_F Q / R                      free length                    [mm]

with the grade's factor Q = 0.63, 1.0, 1.6 for grades 1, 2, 3 (grade 2 the default).
"""

from __future__ import annotations

from dataclasses import dataclass

from ..errors import ConfigError

#: EN 15800's factor Q of each grade
QUALITY = {1: 0.63, 2: 1.0, 3: 1.6}
#: the default of ``spring.grade``
DEFAULT_GRADE = 2


def quality_factor(grade) -> float:
    """Q of an EN 15800 grade (1, 2 or 3); anything else is refused naming ``spring.grade``."""
    if isinstance(grade, bool) or grade not in QUALITY:
        raise ConfigError(f"spring.grade: EN 15800 grade must be 1, 2 or 3, got {grade!r}")
    return QUALITY[int(grade)]


def alpha_f(d: float, D: float) -> float:
    """alpha_F (N) of wire diameter ``d`` and mean coil diameter ``D`` (m; the formula
    takes mm): ``65.92 d^3.3 / D^1.6 (-0.84 (w/10)^3 + 3.781 (w/10)^2 - 4.244 (w/10) + 2.274)``."""
    d_mm, D_mm = d * 1e3, D * 1e3
    x = (D / d) / 10.0
    return 65.92 * d_mm ** 3.3 / D_mm ** 1.6 * (-0.84 * x ** 3 + 3.781 * x ** 2
                                                  - 4.244 * x + 2.274)


def k_f(n: float) -> float:
    """k_F = 1/(3 n^2) + 8/(5 n) + 0.803 of ``n`` active coils."""
    return 1.0 / (3.0 * n ** 2) + 8.0 / (5.0 * n) + 0.803


def force_tolerance(d: float, D: float, n: float, F: float, grade: int = DEFAULT_GRADE) -> float:
    """A_F = (alpha_F k_F + 1.5 F / 100) Q (N): the +- tolerance on a force ``F`` (N) at a
    given length."""
    return (alpha_f(d, D) * k_f(n) + 1.5 * F / 100.0) * quality_factor(grade)


def free_length_tolerance(d: float, D: float, n: float, R: float,
                          grade: int = DEFAULT_GRADE) -> float:
    """A_L0 = alpha_F k_F Q / R (m, for R in N/m): the +- tolerance on the free length."""
    return alpha_f(d, D) * k_f(n) * quality_factor(grade) / R


@dataclass(frozen=True)
class Tolerances:
    """A spring's EN 15800 tolerances (each a +- half-width).

    Attributes
    ----------
    grade : int
        1, 2 or 3.
    alpha_f, k_f : float
        The standard's alpha_F (N) and k_F.
    force : dict
        ``{"F1": A_F1, "F2": A_F2}`` (N): at the longest and shortest working length.
    free_length : float
        A_L0 (m).
    """

    grade: int
    alpha_f: float
    k_f: float
    force: dict
    free_length: float

    def to_json(self) -> dict:
        return {"grade": self.grade, "force": dict(self.force),
                "free_length": self.free_length, "alpha_F": self.alpha_f, "k_F": self.k_f}


def spring_tolerances(d: float, D: float, n: float, R: float, F1: float, F2: float,
               grade: int = DEFAULT_GRADE) -> Tolerances:
    """The EN 15800 tolerances of a spring (d, D in m, R in N/m) whose working forces are
    ``F1``, ``F2`` (N)."""
    q = quality_factor(grade)
    a, kf = alpha_f(d, D), k_f(n)
    return Tolerances(grade=int(grade), alpha_f=a, k_f=kf,
                      force={"F1": (a * kf + 1.5 * F1 / 100.0) * q,
                             "F2": (a * kf + 1.5 * F2 / 100.0) * q},
                      free_length=a * kf * q / R)
