"""The largest value of a cubic Hermite interpolant over one sub-step: how the NLP's peak
tip speed sees between its sub-steps (:func:`hermite_max`, CasADi expressions)."""

from __future__ import annotations

import casadi as ca


def hermite_max(va, ma, vb, mb):
    """Maximum over one sub-step of the cubic Hermite interpolant of the tip speed.

    ``va, vb`` are the speeds at the ends, ``ma, mb`` their time derivatives times the step.
    The interior maximum (p' = 0, p'' < 0) is clipped into [0, 1]; by the envelope theorem
    the value is C1 in the data where it matters (the sub-step holding the peak).
    """
    a3 = 2 * va + ma - 2 * vb + mb
    a2 = -3 * va - 2 * ma + 3 * vb - mb
    a1 = ma
    D = a2 * a2 - 3 * a3 * a1
    # every operation is kept finite (with finite derivatives) in the branch not taken:
    # reverse-mode AD multiplies a zero seed by the untaken branch's partials
    pos = D > 0
    r = ca.sqrt(ca.if_else(pos, D, 1.0))
    den1 = r - a2                                # > 0 when a2 <= 0 (and D > 0)
    use1 = a2 <= 0
    ok1 = den1 > 0
    s1 = a1 / ca.if_else(ok1, den1, 1.0)
    ok2 = a3 != 0
    s2 = (-a2 - r) / ca.if_else(ok2, 3 * a3, 1.0)
    sig = ca.if_else(use1, ca.if_else(ok1, s1, 0.0), ca.if_else(ok2, s2, 0.0))
    sig = ca.if_else(pos, ca.fmin(ca.fmax(sig, 0), 1), 0)
    return ((a3 * sig + a2) * sig + a1) * sig + va


__all__ = ["hermite_max"]
