"""Closed-form four-bar position analysis and Archimedes' linearised transfer ratio (seed 003).

Seed geometry: input crank A0A = 60 about A0 = (0, 0), output crank B0B = 40 about B0, coupler
AB = 59.91.  Angles are measured from the downward vertical, counter-clockwise, as in the seed:
a crank of length r at angle t points along (sin t, -cos t).  In the reference position both
cranks stand at 80 deg (parallel) and the coupler is vertical, which fixes
B0 = ((A0A - B0B) sin 80 deg, AB - (A0A - B0B) cos 80 deg) = (19.696..., 56.437...).

Closed form: with u = (sin tB, -cos tB) and d = B0 - A, |d + r_B u|^2 = AB^2 gives
    P sin tB + Q cos tB = R,  P = 2 r_B d_x,  Q = -2 r_B d_y,  R = AB^2 - |d|^2 - r_B^2,
and with the half-angle tangent tau = tan(tB/2),
    (R + Q) tau^2 - 2 P tau + (R - Q) = 0  ->  tB = 2 atan2(P +- sqrt(P^2 + Q^2 - R^2), R + Q).
Linearisation: in the reference position the cranks are parallel, the coupler translates
instantaneously, so r_A dphi = r_B dpsi and psi ~ (A0A / B0B) phi.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class LeverFourBar:
    """Seed 003 linkage; lengths in m (the seed's unit), angles in rad."""

    r_a: float = 60.0
    r_b: float = 40.0
    l_ab: float = 59.91
    theta_ref: float = np.radians(80.0)

    @property
    def pivot_b(self) -> np.ndarray:
        """B0 from the parallel-crank reference position with a vertical coupler."""
        dr = self.r_a - self.r_b
        return np.array([dr * np.sin(self.theta_ref), self.l_ab - dr * np.cos(self.theta_ref)])


def _crank_direction(t):
    return np.array([np.sin(t), -np.cos(t)])


def solve_output_angle(theta_a, link: LeverFourBar = LeverFourBar(), branch: int = +1):
    """Absolute output angle tB (rad) for input angle tA (rad, array ok); branch +1 or -1.

    NaN where the loop cannot close.
    """
    theta_a = np.asarray(theta_a, dtype=float)
    A = link.r_a * _crank_direction(theta_a)
    d = link.pivot_b.reshape(2, *([1] * theta_a.ndim)) - A
    P = 2 * link.r_b * d[0]
    Q = -2 * link.r_b * d[1]
    R = link.l_ab ** 2 - d[0] ** 2 - d[1] ** 2 - link.r_b ** 2
    disc = P ** 2 + Q ** 2 - R ** 2
    with np.errstate(invalid="ignore"):
        t = 2 * np.arctan2(P + branch * np.sqrt(disc), R + Q)
    return np.where(disc >= 0, t, np.nan)


def select_reference_branch(link: LeverFourBar = LeverFourBar()) -> int:
    """The branch whose output passes through tB = theta_ref at tA = theta_ref."""
    err = {b: abs(np.angle(np.exp(1j * (solve_output_angle(link.theta_ref, link, b) - link.theta_ref))))
           for b in (+1, -1)}
    return min(err, key=err.get)


def compute_loop_residual(theta_a, theta_b, link: LeverFourBar = LeverFourBar()):
    """| |B - A| - AB | for given angles (closure check)."""
    A = link.r_a * _crank_direction(np.asarray(theta_a))
    B = link.pivot_b.reshape(2, *([1] * np.ndim(theta_a))) + link.r_b * _crank_direction(np.asarray(theta_b))
    return np.abs(np.hypot(*(B - A)) - link.l_ab)


def compare_linearisation(phi, link: LeverFourBar = LeverFourBar()) -> dict:
    """Exact vs linearised output for input rotations phi (rad) from the reference position.

    relative_error is |psi - psi_lin| / |psi| on the output rotation psi = tB - theta_ref
    (0 at phi = 0 by the limit); relative_error_absolute_angle is the seed notebook's measure,
    |tB - tB_lin| / |tB| with tB the absolute angle in rad.
    """
    phi = np.asarray(phi, dtype=float)
    branch = select_reference_branch(link)
    theta_b = solve_output_angle(link.theta_ref + phi, link, branch)
    psi = np.unwrap(theta_b - link.theta_ref)
    theta_b = link.theta_ref + psi - 2 * np.pi * np.round(psi[..., :1] / (2 * np.pi))
    ratio = link.r_a / link.r_b
    psi = theta_b - link.theta_ref
    psi_lin = ratio * phi
    with np.errstate(invalid="ignore", divide="ignore"):
        rel = np.where(phi == 0, 0.0, np.abs(psi - psi_lin) / np.abs(psi))
    rel_abs = np.abs(theta_b - (link.theta_ref + psi_lin)) / np.abs(theta_b)
    return {"phi": phi, "theta_b": theta_b, "theta_b_linear": link.theta_ref + psi_lin,
            "relative_error": rel, "relative_error_absolute_angle": rel_abs,
            "ratio": ratio, "branch": branch}


def solve_error_limit(link: LeverFourBar = LeverFourBar(), measure: str = "relative_error",
                      level: float = 0.01, phi_max: float = np.radians(50.0)) -> float:
    """First input rotation (rad) at which the error `measure` reaches `level`, by bracketing on a
    0.25 deg grid and bisection; phi_max if it never does."""
    grid = np.arange(0.0, phi_max + 1e-12, np.radians(0.25))
    err = compare_linearisation(grid, link)[measure]
    above = np.nonzero(err >= level)[0]
    if above.size == 0:
        return float(phi_max)
    k = above[0]
    if k == 0:
        return 0.0
    f = lambda ph: compare_linearisation(np.array([0.0, ph]), link)[measure][1] - level
    return bisect_root(f, grid[k - 1], grid[k], xtol=1e-12)


def bisect_root(f, a: float, b: float, xtol: float = 1e-12) -> float:
    """Root of f on [a, b] (f(a), f(b) of opposite signs) by bisection to ``xtol``."""
    fa = f(a)
    if fa * f(b) > 0:
        raise ValueError(f"no sign change of f on [{a}, {b}]")
    while b - a > xtol:
        m = 0.5 * (a + b)
        fm = f(m)
        if fm == 0:
            return float(m)
        if (fm > 0) == (fa > 0):
            a, fa = m, fm
        else:
            b = m
    return float(0.5 * (a + b))
