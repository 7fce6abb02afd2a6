"""A root bracketed by a sign change, by Illinois false position (:func:`illinois`): the
reference's events (:mod:`softclose.simulation.reference`) and the opening effort's maximum
(:func:`softclose.simulation.statics.opening_force_exact`) both locate theirs with it. The
reference starts each event's search from a guess: the root (:func:`hermite_root`) or the
maximum (:func:`hermite_peak`) of the cubic Hermite interpolant between two states."""

from __future__ import annotations


def illinois(f, lo: float, hi: float, f_lo: float, f_hi: float, stop, maxit: int) -> float:
    """A root of ``f`` in (lo, hi), where ``f_lo`` and ``f_hi`` (f at the ends) differ in sign.

    False position, with the Illinois rule (the value at an end kept twice in a row is
    halved): superlinear, never stalls at one end. A point outside the bracket (rounding)
    is replaced by its midpoint. ``stop(lo, hi, x, fx)`` ends the search at ``x``; after
    ``maxit`` steps it ends at the bracket's midpoint.
    """
    side = 0
    for _ in range(maxit):
        x = lo - f_lo * (hi - lo) / (f_hi - f_lo) if f_hi != f_lo else 0.5 * (lo + hi)
        if not lo < x < hi:
            x = 0.5 * (lo + hi)
        fx = f(x)
        if stop(lo, hi, x, fx):
            return x
        if (fx > 0) == (f_lo > 0):
            lo, f_lo = x, fx
            if side == -1:
                f_hi *= 0.5
            side = -1
        else:
            hi, f_hi = x, fx
            if side == 1:
                f_lo *= 0.5
            side = 1
    return 0.5 * (lo + hi)


def hermite_root(h: float, f0: float, d0: float, f1: float, d1: float) -> float:
    """The root in (0, h) of the cubic Hermite interpolant of f (values f0, f1 and slopes d0,
    d1 at 0 and h; f0 and f1 of opposite signs): a first guess of an event's time from the
    states at a step's two ends, good to O(h^4). Found by Newton's method on the cubic,
    safeguarded by bisection (no evaluation of f)."""
    def cubic(s):           # value and derivative in s = tau / h
        a = 2 * (f0 - f1) + h * (d0 + d1)
        b = 3 * (f1 - f0) - h * (2 * d0 + d1)
        return ((a * s + b) * s + h * d0) * s + f0, (3 * a * s + 2 * b) * s + h * d0
    lo, hi, s = 0.0, 1.0, f0 / (f0 - f1)
    for _ in range(60):
        v, dv = cubic(s)
        if v == 0:
            break
        if (v > 0) == (f0 > 0):
            lo = s
        else:
            hi = s
        s_new = s - v / dv if dv != 0 else 0.5 * (lo + hi)
        if not lo < s_new < hi:
            s_new = 0.5 * (lo + hi)
        if abs(s_new - s) < 1e-15:
            s = s_new
            break
        s = s_new
    return s * h


def hermite_peak(h: float, f0: float, d0: float, f1: float, d1: float) -> float:
    """Where in (0, h) the cubic Hermite interpolant of f (values f0, f1, slopes d0 > 0 > d1
    at 0 and h) has its maximum: the root of its derivative, a quadratic. A first guess of
    the time of a maximum between two states."""
    a = 3 * (2 * (f0 - f1) + h * (d0 + d1))     # p'(s) = a s^2 + b s + h d0, s = tau / h
    b = 2 * (3 * (f1 - f0) - h * (2 * d0 + d1))
    c = h * d0
    return h * hermite_root(1.0, c, b, a + b + c, 2 * a + b)


__all__ = ["hermite_peak", "hermite_root", "illinois"]
