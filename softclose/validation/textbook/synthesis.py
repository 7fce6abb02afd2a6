"""Five-precision-point path synthesis of a four-bar (Morgan & Wampler 1990; seed 004).

Ground pivots O = (0, 0) and a; coupler point D passes through d_0 .. d_4.  Unknowns
z = (c1, s1, c2, s2, c3, s3, c4, s4, x1, x2, y1, y2): R_j = [[c_j, -s_j], [s_j, c_j]] rotates the
coupler from position 0 to position j, x (y) is the vector from the coupler point to the crank
pin on the O (a) side in position 0, so the pins in position j are P_j = d_j + R_j x, Q_j = d_j + R_j y.
Constant crank lengths |P_j| = |P_0|, |Q_j - a| = |Q_0 - a| give, for j = 1..4,

    c_j^2 + s_j^2 - 1 = 0
    (d_j^T R_j - d_0^T) x + (|d_j|^2 - |d_0|^2) / 2 = 0
    ((d_j - a)^T R_j - (d_0 - a)^T) y + (|d_j|^2 - |d_0|^2) / 2 - a^T (d_j - d_0) = 0

Twelve equations; the generic number of finite complex solutions is 36.  They are found by
homotopy continuation with Bertini 2 (optional dependency `bertini2`, module `bertini`), with the
six variable groups {c_j, s_j}, {x}, {y}: a 6-homogeneous start system with 6 * 2^4 = 96 paths
instead of the 2^4 * 2^8 = 4096 of the total-degree one.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from fractions import Fraction

import numpy as np

# Problem 7 of Morgan & Wampler (five points on a straight line), pivot a = (1, 0).
PROBLEM7_POINTS = np.array([[0.50, 1.06], [-0.83, -0.27], [-0.34, 0.22], [-0.13, 0.43], [0.22, 0.78]])
PIVOT_A = np.array([1.0, 0.0])
GENERIC_SOLUTION_COUNT = 36


def evaluate_equations(z, d, a=PIVOT_A) -> np.ndarray:
    """The twelve residuals at z (complex allowed)."""
    z = np.asarray(z)
    d = np.asarray(d, float)
    a = np.asarray(a, float)
    c, s = z[0:8:2], z[1:8:2]
    x, y = z[8:10], z[10:12]
    F = np.zeros(12, dtype=np.result_type(z, float))
    for j in range(1, 5):
        cj, sj = c[j - 1], s[j - 1]
        F[j - 1] = cj ** 2 + sj ** 2 - 1
        dj, d0 = d[j], d[0]
        row = np.array([dj[0] * cj + dj[1] * sj, -dj[0] * sj + dj[1] * cj])        # d_j^T R_j
        F[3 + j] = (row - d0) @ x + 0.5 * (dj @ dj - d0 @ d0)
        ej, e0 = dj - a, d0 - a
        row = np.array([ej[0] * cj + ej[1] * sj, -ej[0] * sj + ej[1] * cj])
        F[7 + j] = (row - e0) @ y + 0.5 * (dj @ dj - d0 @ d0) - a @ (dj - d0)
    return F


def _build_bertini_system(bertini, d, a):
    """The same twelve polynomials as a bertini System with six variable groups."""
    coef = lambda v: bertini.coefficient(Fraction(float(v)))   # exact binary value of the double
    c = bertini.variables("c", 4)
    s = bertini.variables("s", 4)
    x = bertini.variables("x", 2)
    y = bertini.variables("y", 2)
    S = bertini.System()
    for j in range(4):
        S.add_variable_group(bertini.VariableGroup([c[j], s[j]]))
    S.add_variable_group(bertini.VariableGroup(x))
    S.add_variable_group(bertini.VariableGroup(y))
    for j in range(4):
        S.add_function(c[j] * c[j] + s[j] * s[j] - 1)
    d0 = d[0]
    for j in range(4):
        dj = d[j + 1]
        r0 = coef(dj[0]) * c[j] + coef(dj[1]) * s[j]
        r1 = coef(dj[1]) * c[j] - coef(dj[0]) * s[j]
        S.add_function((r0 - coef(d0[0])) * x[0] + (r1 - coef(d0[1])) * x[1]
                       + coef(0.5 * (dj @ dj - d0 @ d0)))
    for j in range(4):
        dj = d[j + 1]
        ej, e0 = dj - a, d0 - a
        r0 = coef(ej[0]) * c[j] + coef(ej[1]) * s[j]
        r1 = coef(ej[1]) * c[j] - coef(ej[0]) * s[j]
        S.add_function((r0 - coef(e0[0])) * y[0] + (r1 - coef(e0[1])) * y[1]
                       + coef(0.5 * (dj @ dj - d0 @ d0) - a @ (dj - d0)))
    order = [v for j in range(4) for v in (c[j], s[j])] + x + y
    return S, order


@dataclass
class SynthesisResult:
    """Finite solutions (n x 12 complex, ordered as z) and the solve's bookkeeping."""

    points: np.ndarray
    pivot_a: np.ndarray
    solutions: np.ndarray
    n_paths: int
    n_at_infinity: int
    seconds: float


def solve_precision_points(points, pivot_a=PIVOT_A, seed: int = 1) -> SynthesisResult:
    """All finite solutions by Bertini 2 (adaptive precision, power-series endgame, no records)."""
    import bertini

    d = np.asarray(points, float)
    a = np.asarray(pivot_a, float)
    S, order = _build_bertini_system(bertini, d, a)
    was_recording = bertini.recording()
    bertini.recording(False)
    try:
        bertini.random.set_random_seed(int(seed))
        t0 = time.perf_counter()
        solver = bertini.nag_algorithm.ZeroDimSolver(S, mptype="adaptive")
        result = solver.solve(show_progress=False)
        seconds = time.perf_counter() - t0
    finally:
        bertini.recording(was_recording)
    answer = result.answer
    names = [str(v) for v in S.variable_ordering()] if hasattr(S, "variable_ordering") else None
    wanted = [str(v) for v in order]
    perm = [names.index(n) for n in wanted] if names else list(range(12))
    Z = np.array([[complex(v) for v in sol] for sol in answer.finite], dtype=complex).reshape(-1, 12)
    return SynthesisResult(d, a, Z[:, perm], int(solver.num_paths()), len(answer.at_infinity), seconds)


@dataclass(frozen=True)
class Design:
    """A real solution as a mechanism: ground pivots O, a; pins P0, Q0 and coupler point d0 in position 0."""

    O: np.ndarray
    a: np.ndarray
    P0: np.ndarray
    Q0: np.ndarray
    d0: np.ndarray

    @property
    def lengths(self) -> dict:
        return {"crank_O": float(np.linalg.norm(self.P0 - self.O)),
                "coupler": float(np.linalg.norm(self.Q0 - self.P0)),
                "crank_a": float(np.linalg.norm(self.Q0 - self.a)),
                "ground": float(np.linalg.norm(self.a - self.O))}


def make_design(z, d, a=PIVOT_A) -> Design:
    z = np.real(np.asarray(z))
    d = np.asarray(d, float)
    return Design(np.zeros(2), np.asarray(a, float), d[0] + z[8:10], d[0] + z[10:12], d[0].copy())


def locate_poses(z, d) -> tuple[np.ndarray, np.ndarray]:
    """Pins P_j, Q_j (5 x 2 each) in the five precision positions."""
    z = np.real(np.asarray(z))
    d = np.asarray(d, float)
    P, Q = [d[0] + z[8:10]], [d[0] + z[10:12]]
    for j in range(1, 5):
        c, s = z[2 * j - 2], z[2 * j - 1]
        R = np.array([[c, -s], [s, c]])
        P.append(d[j] + R @ z[8:10])
        Q.append(d[j] + R @ z[10:12])
    return np.array(P), np.array(Q)


def check_coupler_angles_ordered(z) -> bool:
    """Seed criterion: coupler rotations theta_j = atan2(s_j, c_j) in (0, 2 pi) monotone in j."""
    th = np.mod(np.arctan2(np.real(z[1:8:2]), np.real(z[0:8:2])), 2 * np.pi)
    dth = np.diff(th)
    return bool(np.all(dth > 0) or np.all(dth < 0))


def trace_circuit(design: Design, step: float = 0.01, max_steps: int = 200000):
    """Follow the configuration curve through position 0 once around.

    The curve is f(alpha, beta) = |P(alpha) - Q(beta)|^2 - l_PQ^2 = 0 on the torus of the two crank
    angles; it is followed by pseudo-arclength continuation (predictor along the tangent
    (-f_beta, f_alpha), Newton corrector) until it returns to its start.  Returns the (alpha, beta)
    samples (unwrapped) and the coupler point along the circuit.
    """
    r1, r3 = np.linalg.norm(design.P0 - design.O), np.linalg.norm(design.Q0 - design.a)
    l2 = np.linalg.norm(design.Q0 - design.P0)
    e = lambda t: np.array([np.cos(t), np.sin(t)])
    de = lambda t: np.array([-np.sin(t), np.cos(t)])

    def f_and_grad(u):
        P = design.O + r1 * e(u[0])
        Q = design.a + r3 * e(u[1])
        w = P - Q
        return w @ w - l2 ** 2, np.array([2 * w @ (r1 * de(u[0])), -2 * w @ (r3 * de(u[1]))])

    u0 = np.array([np.arctan2(*(design.P0 - design.O)[::-1]), np.arctan2(*(design.Q0 - design.a)[::-1])])
    u = u0.copy()
    path = [u.copy()]
    _, g = f_and_grad(u)
    tangent = np.array([-g[1], g[0]]) / np.linalg.norm(g)
    for n in range(max_steps):
        v = u + step * tangent
        for _ in range(20):
            f, g = f_and_grad(v)
            v = v - f * g / (g @ g)          # minimum-norm Newton step onto the curve
            if abs(f) < 1e-14 * max(1.0, l2 ** 2):
                break
        _, g = f_and_grad(v)
        t_new = np.array([-g[1], g[0]]) / np.linalg.norm(g)
        if t_new @ tangent < 0:
            t_new = -t_new
        u, tangent = v, t_new
        path.append(u.copy())
        back = np.angle(np.exp(1j * (u - u0)))
        if n > 10 and np.linalg.norm(back) < 0.5 * step:
            break
    path = np.array(path)
    P = design.O + r1 * np.stack([np.cos(path[:, 0]), np.sin(path[:, 0])], axis=1)
    Q = design.a + r3 * np.stack([np.cos(path[:, 1]), np.sin(path[:, 1])], axis=1)
    psi = np.arctan2(*(Q - P).T[::-1]) - np.arctan2(*(design.Q0 - design.P0)[::-1])
    c, s = np.cos(psi), np.sin(psi)
    w = design.d0 - design.P0
    coupler = P + np.stack([c * w[0] - s * w[1], s * w[0] + c * w[1]], axis=1)
    return path, coupler


def check_design_valid(z, d, a=PIVOT_A, step: float = 0.005) -> bool:
    """Real design whose five positions lie on one circuit and are passed in order (either direction)."""
    if np.max(np.abs(np.imag(z))) > 1e-8 * max(1.0, np.max(np.abs(z))):
        return False
    design = make_design(z, d, a)
    if min(design.lengths.values()) < 1e-6:
        return False
    P, Q = locate_poses(z, d)
    angles = np.stack([np.arctan2(*(P - design.O).T[::-1]), np.arctan2(*(Q - design.a).T[::-1])], axis=1)
    path, _ = trace_circuit(design, step=step)
    hits = []
    for j in range(5):
        dist = np.linalg.norm(np.angle(np.exp(1j * (path - angles[j]))), axis=1)
        k = int(np.argmin(dist))
        if dist[k] > 2 * step:
            return False                      # position j is on another circuit
        hits.append(k)
    hits = np.array(hits)
    order = np.argsort(hits)
    n = len(order)
    seq = np.roll(order, -int(np.nonzero(order == 0)[0][0]))
    return bool(np.all(seq == np.arange(n)) or np.all(seq == np.r_[0, np.arange(n - 1, 0, -1)]))


def classify_solutions(result: SynthesisResult, real_tol: float = 1e-8) -> dict:
    """Counts and per-solution flags: finite, real, seed-ordered, valid; max residual."""
    Z = result.solutions
    scale = np.maximum(1.0, np.max(np.abs(Z), axis=1))
    real = np.max(np.abs(Z.imag), axis=1) <= real_tol * scale
    residuals = np.array([np.max(np.abs(evaluate_equations(z, result.points, result.pivot_a))) for z in Z])
    ordered = np.array([bool(r) and check_coupler_angles_ordered(z) for z, r in zip(Z, real)])
    valid = np.array([bool(r) and check_design_valid(z.real, result.points, result.pivot_a)
                      for z, r in zip(Z, real)])
    return {"n_finite": int(len(Z)), "n_real": int(real.sum()), "n_ordered": int(ordered.sum()),
            "n_valid": int(valid.sum()), "max_residual": float(residuals.max(initial=0.0)),
            "real": real, "ordered": ordered, "valid": valid, "residuals": residuals}
