"""Fixed-step integrators: what a method is, and the ones softclose offers.

A method is a Butcher tableau (``A``, ``b``, ``c``) plus a ``kind`` and its stated
``order``. The same tableau drives both implementations:

- the C kernel (:mod:`softclose.simulation.kernel.binding`), which integrates whole strokes for batches of
  designs on the tabulated coefficients of the equation of motion;
- :func:`casadi_step`, a CasADi Function of one step of the exact equation of motion
  (tests compare it with the kernel's step; the optimiser has its own RK4 sub-step on
  Chebyshev series of the geometry, :mod:`softclose.optimiser.nlp`).

Kinds: ``explicit`` (A strictly lower triangular), ``implicit`` (full A, solved by
Newton's method), ``symplectic_euler`` (Euler-Cromer: velocity first, then position with
the new velocity -- a partitioned method with no single tableau).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import casadi as ca
import numpy as np

KIND_CODES = {"explicit": 0, "implicit": 1, "symplectic_euler": 2}


@dataclass(frozen=True)
class Method:
    name: str
    kind: str
    order: int
    A: tuple
    b: tuple
    c: tuple
    description: str
    #: largest |h lambda| on the negative real axis that is stable (inf: A-stable)
    real_stability: float

    @property
    def stages(self) -> int:
        return len(self.b)

    def packed(self) -> np.ndarray:
        """(kind, s, A row-major, b, c) as the C kernel reads it."""
        s = self.stages
        return np.concatenate([[KIND_CODES[self.kind], s], np.asarray(self.A, float).ravel(),
                               self.b, self.c]).astype(float)


_r3, _r6 = math.sqrt(3.0), math.sqrt(6.0)

RK4 = Method(
    "rk4", "explicit", 4,
    A=((0, 0, 0, 0), (0.5, 0, 0, 0), (0, 0.5, 0, 0), (0, 0, 1, 0)),
    b=(1 / 6, 1 / 3, 1 / 3, 1 / 6), c=(0, 0.5, 0.5, 1),
    description="classical Runge-Kutta, explicit, order 4", real_stability=2.785293563405282)

EULER_CROMER = Method(
    "euler_cromer", "symplectic_euler", 1,
    A=((0.0,),), b=(1.0,), c=(0.0,),
    description="symplectic (semi-implicit) Euler, the seed notebook's method, order 1",
    real_stability=2.0)

GAUSS4 = Method(
    "gauss4", "implicit", 4,
    A=((0.25, 0.25 - _r3 / 6), (0.25 + _r3 / 6, 0.25)),
    b=(0.5, 0.5), c=(0.5 - _r3 / 6, 0.5 + _r3 / 6),
    description="Gauss-Legendre, 2 stages, implicit, A-stable and symplectic, order 4",
    real_stability=math.inf)

RADAU5 = Method(
    "radau5", "implicit", 5,
    A=(((88 - 7 * _r6) / 360, (296 - 169 * _r6) / 1800, (-2 + 3 * _r6) / 225),
       ((296 + 169 * _r6) / 1800, (88 + 7 * _r6) / 360, (-2 - 3 * _r6) / 225),
       ((16 - _r6) / 36, (16 + _r6) / 36, 1 / 9)),
    b=((16 - _r6) / 36, (16 + _r6) / 36, 1 / 9), c=((4 - _r6) / 10, (4 + _r6) / 10, 1.0),
    description="Radau IIA, 3 stages, implicit, L-stable (for stiff damping), order 5",
    real_stability=math.inf)

METHODS = {m.name: m for m in (RK4, EULER_CROMER, GAUSS4, RADAU5)}
#: the seed notebook's method and step (Euler-Cromer at 1 kHz; the benchmark marks it)
SEED = ("euler_cromer", 1e-3)


def get_method(name: str) -> Method:
    try:
        return METHODS[name]
    except KeyError:
        raise ValueError(f"unknown integrator {name!r}; choose one of {', '.join(METHODS)}") \
            from None


def casadi_step(method: Method, ode: ca.Function) -> ca.Function:
    """One step ``x1 = F(x0, p, h)`` of ``method`` on ``ode(x, p)``, as a CasADi Function
    (x and p of the sizes ``ode`` takes).

    Implicit methods solve their stage equations with a CasADi Newton rootfinder.
    """
    nx, np_ = ode.size1_in(0), ode.size1_in(1)
    x0, p, h = ca.SX.sym("x0", nx), ca.SX.sym("p", np_), ca.SX.sym("h")
    if method.kind == "symplectic_euler":
        a = ode(x0, p)[1]
        v1 = x0[1] + h * a
        x1 = ca.vertcat(x0[0] + h * v1, v1)
        return ca.Function(f"step_{method.name}", [x0, p, h], [x1], ["x0", "p", "h"], ["x1"])
    s = method.stages
    if method.kind == "explicit":
        K = []
        for i in range(s):
            xi = x0 + h * sum((method.A[i][j] * K[j] for j in range(i)), ca.SX.zeros(nx))
            K.append(ode(xi, p))
        x1 = x0 + h * sum(method.b[i] * K[i] for i in range(s))
        return ca.Function(f"step_{method.name}", [x0, p, h], [x1], ["x0", "p", "h"], ["x1"])
    # implicit: residual in the stage derivatives K (nx*s unknowns), Newton rootfinder
    Kv = ca.SX.sym("K", nx * s)
    K = [Kv[nx * i:nx * (i + 1)] for i in range(s)]
    res = []
    for i in range(s):
        xi = x0 + h * sum(method.A[i][j] * K[j] for j in range(s))
        res.append(K[i] - ode(xi, p))
    G = ca.Function("G", [Kv, ca.vertcat(x0, p, h)], [ca.vertcat(*res)])
    solver = ca.rootfinder("stages", "newton", G, {"abstol": 1e-14, "max_iter": 50,
                                                     "error_on_fail": False})
    x0m, pm, hm = ca.MX.sym("x0", nx), ca.MX.sym("p", np_), ca.MX.sym("h")
    guess = ca.repmat(ode(x0m, pm), s, 1)
    Ks = solver(guess, ca.vertcat(x0m, pm, hm))
    x1 = x0m + hm * sum(method.b[i] * Ks[nx * i:nx * (i + 1)] for i in range(s))
    return ca.Function(f"step_{method.name}", [x0m, pm, hm], [x1], ["x0", "p", "h"], ["x1"])


def amplification(method: Method, hJ: np.ndarray) -> np.ndarray:
    """Step matrix of a Runge-Kutta ``method`` on the linear system x' = J x (hJ = h J).

    None where the step is not defined: hJ not finite, or (implicit methods) h J meets an
    eigenvalue of A^-1, where the stage equations have no unique solution.
    """
    I2 = np.eye(2)
    s = method.stages
    A = np.asarray(method.A, float)
    if not np.all(np.isfinite(hJ)):
        return None
    big = np.eye(2 * s) - np.kron(A, hJ)
    rhs = np.kron(np.ones((s, 1)), hJ)
    try:
        K = np.linalg.solve(big, rhs)  # h K_i = (hJ)(x + sum a_ij h K_j)
    except np.linalg.LinAlgError:
        return None
    S = I2 + sum(method.b[i] * K[2 * i:2 * i + 2] for i in range(s))
    return S if np.all(np.isfinite(S)) else None


def spectral_radius(method: Method, J: np.ndarray, h: float) -> float:
    """Spectral radius of the step matrix at step h; inf where the step is not defined
    (see :func:`amplification`), so that such a step never counts as stable."""
    with np.errstate(over="ignore", invalid="ignore"):
        if method.kind == "symplectic_euler":
            a, b = J[1]
            S = np.array([[1 + h * h * a, h * (1 + h * b)], [h * a, 1 + h * b]])
        else:
            S = amplification(method, h * J)
        if S is None or not np.all(np.isfinite(S)):
            return math.inf
        return float(np.max(np.abs(np.linalg.eigvals(S))))
