"""A root bracketed by a sign change, by Illinois false position (:func:`illinois`): the
reference's events (:mod:`softclose.simulation.reference`) and the opening effort's maximum
(:func:`softclose.simulation.statics.opening_force_exact`) both locate theirs with it."""

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


__all__ = ["illinois"]
