"""The reference's event search: the cubic Hermite guesses (:mod:`softclose.numerics.roots`)
and what they buy -- the same events from fewer fresh CVODES runs."""

import math

import numpy as np
import pytest

import softclose
from softclose.simulation import reference as ref_mod
from softclose.simulation.reference import Reference
from softclose.numerics.roots import hermite_peak, hermite_root


def _hermite(h, f0, d0, f1, d1):
    """The cubic Hermite interpolant on [0, h] as numpy coefficients (highest first)."""
    A = np.array([[0, 0, 0, 1], [0, 0, 1, 0], [h ** 3, h ** 2, h, 1], [3 * h ** 2, 2 * h, 1, 0]])
    return np.linalg.solve(A, [f0, d0, f1, d1])


@pytest.mark.parametrize("coef", [(1.0, -2.0, 0.3, 0.5), (-4.0, 1.0, -1.0, 0.7),
                                  (0.0, 0.0, -3.0, 1.2), (2.0, -3.0, 0.0, 0.4)])
def test_hermite_root_is_a_cubics_root_exactly(coef):
    """A cubic is its own Hermite interpolant: the guess is its root in (0, h)."""
    h = 1.3
    p = np.poly1d(coef)
    dp = p.deriv()
    t = hermite_root(h, p(0), dp(0), p(h), dp(h))
    assert 0 < t < h
    assert abs(p(t)) < 1e-13
    real = [r.real for r in np.roots(coef) if abs(r.imag) < 1e-12 and 0 < r.real < h]
    assert min(abs(t - r) for r in real) < 1e-12


def test_hermite_peak_is_the_interpolants_maximum():
    h = 0.004
    c = _hermite(h, 2.0, 150.0, 2.1, -90.0)
    t = hermite_peak(h, 2.0, 150.0, 2.1, -90.0)
    grid = np.linspace(0, h, 200001)
    assert abs(t - grid[np.argmax(np.polyval(c, grid))]) < 2 * h / 200000
    assert abs(np.polyval(np.polyder(c), t)) < 1e-9


def test_hermite_root_of_a_sine_is_good_to_fourth_order():
    """On a smooth function the guess's error falls as h^4 (halving h: ~16x)."""
    errs = []
    for h in (0.4, 0.2, 0.1):
        r = 0.37 * h                        # the root of sin(t - r) in (0, h)
        t = hermite_root(h, math.sin(-r), math.cos(-r), math.sin(h - r), math.cos(h - r))
        errs.append(abs(t - r))
    assert errs[0] / errs[1] > 12 and errs[1] / errs[2] > 12


def _counted(overrides=()):
    """A reference whose fresh CVODES runs (``flow`` with tau > 0) are counted."""
    ref = Reference.from_config(softclose.load_config(None, list(overrides)))
    count = {"n": 0}
    flow = ref.flow

    def counting(x0, p, tau):
        if tau > 0:
            count["n"] += 1
        return flow(x0, p, tau)
    ref.flow = counting
    return ref, count


@pytest.mark.parametrize("overrides,most", [((), 5), (("design.damper_c=20000",), 14)])
def test_events_take_few_fresh_runs(overrides, most):
    """Fresh CVODES runs of a stroke's events: the default lid's (the rim, 6 from the
    steps' ends alone) and a stiffly damped lid's, whose peak tip speed lies inside a step
    (20 from the ends alone: the peak's search ran to 1e-14 s in the integrator's noise)."""
    ref, count = _counted(overrides)
    assert ref.simulate().closed
    assert count["n"] <= most, count["n"]


@pytest.mark.parametrize("overrides", [(), ("design.damper_c=20000",),
                                       ("design.end_damper_c=0.5", "design.end_damper_angle_deg=6",
                                        "friction.torque=0.05")])
def test_events_agree_with_the_search_from_the_ends(overrides):
    """The second formulation: the same events located without guesses (each search from
    its step's ends, to 1e-14 s) agree far inside the integrator's tolerance."""
    r = Reference.from_config(softclose.load_config(None, list(overrides))).simulate()
    plain = Reference.from_config(softclose.load_config(None, list(overrides)))
    orig = plain._newton_time

    def no_guess(x0, p, h, residual, lo=0.0, hi=None, x_hi=None, guess=None, width=None):
        return orig(x0, p, h, residual, lo, hi)
    plain._newton_time = no_guess
    q = plain.simulate()
    for k in ("closing_time", "impact_theta_dot", "impact_tip_speed", "peak_tip_speed",
              "engage_time", "engage_theta_dot"):
        a, b = getattr(r, k), getattr(q, k)
        if b is None:
            assert a is None
            continue
        assert abs(a - b) <= 1e-12 * abs(b), (k, a, b)


def test_the_chunks_speeds_are_the_single_calls():
    """The tip speeds of a chunk's nodes, computed in one mapped call, are the bits of a
    call per node."""
    ref = Reference.from_config(softclose.load_config())
    p = ref.model.params()
    x0 = np.array([ref.model.stroke.theta0, 0.0])
    ref._speeds = {}
    ref.step(x0, p, 2e-3)
    assert len(ref._speeds) == ref_mod.CHUNK
    for key, (v, dv) in ref._speeds.items():
        x = np.frombuffer(key[0])
        w, dw = ref._speed_fn(x, p, ref._moving, ref._engaged)
        assert (v, dv) == (float(w), float(dw))


def test_a_ringing_lid_stops_the_reference_with_what_to_change():
    """A torsion spring of 1e5 N m/rad rings the lid at hundreds of turns a second; the
    reference stops at its MAX_TURNS-th turn with one line saying what to change (following
    every turn took tens of seconds a stroke), while an ordinary stroke turns far fewer
    times."""
    from softclose.errors import NumericalError
    ring = Reference.from_config(softclose.load_config(None, ["design.torsion_k=100000.0"]))
    with pytest.raises(NumericalError, match=r"the lid rings: it turned back \d+ times .* "
                                             r"soften the spring or damp it"):
        ring.simulate()
    assert Reference.from_config(softclose.load_config()).simulate().closed
