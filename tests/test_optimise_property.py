"""Property (issue 12 item 1): whatever the weights (either may be zero) and the closing-time
window, every number ``optimise`` reports is the adaptive reference's, or agrees with it
within its stated tolerance -- or the answer is reported as not verified (exit 3), naming
the number. The reference is run here again, independently of the optimiser's own
verification (its own model, the default 2 ms output grid).
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, Phase, example, given, settings
from hypothesis import strategies as st

from softclose.config import default_config
from softclose.model.lid import LidModel
from softclose.optimiser import optimise
from softclose.problem import (DESIGN_KEYS, ERROR_KEYS, METRIC_KEYS, VERIFY_RTOL,
                               agreement_tolerance, target)
from softclose.simulation.reference import Reference

CFG = default_config()
_REFS: dict = {}


def weights():
    w = st.one_of(st.just(0.0), st.floats(0.02, 5.0))
    return st.tuples(w, w).filter(lambda ab: ab[0] > 0 or ab[1] > 0)


def window(t_max_hi: float):
    return st.floats(0.3, t_max_hi).flatmap(
        lambda hi: st.tuples(st.one_of(st.just(0.0), st.floats(0.0, 0.7 * hi)), st.just(hi)))


def check(w, win, starts=2):
    (wi, wp), (lo, hi) = w, win
    cfg = CFG.replace(optimise={"weight_impact": wi, "weight_peak_tip": wp,
                                "closing_time_min": lo, "closing_time_max": hi})
    r = optimise(cfg, starts=starts)
    if r.design is None:           # no optimum at all: reported, nothing to compare
        assert not r.success and r.message
        return r
    ver = r.verification
    assert ver is not None and ver.error is None
    if "ref" not in _REFS:
        _REFS["ref"] = Reference(LidModel.from_config(CFG))
    p = np.r_[[r.design[k] for k in DESIGN_KEYS], cfg.design.rotary_damper_c]
    ref = _REFS["ref"].simulate(p)
    # the reported metrics are the reference's (to its own accuracy: the output grids differ)
    for k in METRIC_KEYS:
        a, b = r.metrics[k], getattr(ref, k)
        if k == "closed" or b is None:
            assert a == b, k
        else:
            tol = target(k, b) if k in ERROR_KEYS else 1e-9 * max(abs(b), 1e-3)
            assert abs(a - b) <= tol, (k, a, b)
    # the optimiser's own numbers agree with them, or the answer says which do not
    for k in METRIC_KEYS[1:]:
        a, b = r.optimiser[k], getattr(ref, k)
        if b is None or abs(a - b) > agreement_tolerance(k, b) * (1 + 1e-6):
            assert not r.success and k in r.message, (k, a, b, r.message)
    Jref = cfg.optimise.weight_impact * ref.impact_theta_dot ** 2 + \
        cfg.optimise.weight_peak_tip * ref.peak_tip_speed ** 2
    if abs(r.objective - Jref) > VERIFY_RTOL * Jref * (1 + 1e-6):
        assert not r.success and "objective" in r.message
    if not r.success:
        assert r.message.startswith("the answer is not confirmed")
    return r


#: each example is an optimisation (~0.5-2 s): no shrinking (a failure prints its example)
PHASES = [Phase.explicit, Phase.reuse, Phase.generate]


@settings(max_examples=10, deadline=None, derandomize=True, phases=PHASES,
          suppress_health_check=[HealthCheck.too_slow])
@given(weights(), window(1.5))
@example((1.0, 0.0), (0.0, 1.0))        # issue 12: the peak was the free epigraph variable
def test_reported_numbers_are_verified(w, win):
    r = check(w, win)
    # these problems are well posed: the optimiser finds and verifies their optimum
    assert r.success, r.message


@pytest.mark.slow
@settings(max_examples=12, deadline=None, phases=PHASES,
          suppress_health_check=[HealthCheck.too_slow])
@given(weights(), window(3.0))
def test_reported_numbers_are_verified_wide(w, win):
    check(w, win, starts=3)
