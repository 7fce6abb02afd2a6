"""Seed 003: closed-form four-bar position and the linearised lever ratio."""

import numpy as np
import pytest

from softclose.validation.textbook.linearisation import (LeverFourBar, compare_linearisation, compute_loop_residual,
                                              select_reference_branch, solve_error_limit,
                                              solve_output_angle)

LINK = LeverFourBar()


def _bisect(g, lo, hi, xtol):
    """Plain bisection (independent of the library's root finder)."""
    glo = g(lo)
    while hi - lo > xtol:
        m = 0.5 * (lo + hi)
        if (g(m) > 0) == (glo > 0):
            lo, glo = m, g(m)
        else:
            hi = m
    return 0.5 * (lo + hi)
PHI = np.radians(np.linspace(0.0, 50.0, 201))


def test_reference_position_is_parallel_cranks_with_vertical_coupler():
    A = LINK.r_a * np.array([np.sin(LINK.theta_ref), -np.cos(LINK.theta_ref)])
    B = LINK.pivot_b + LINK.r_b * np.array([np.sin(LINK.theta_ref), -np.cos(LINK.theta_ref)])
    assert B[0] == pytest.approx(A[0], abs=1e-12)
    assert B[1] - A[1] == pytest.approx(LINK.l_ab, abs=1e-12)
    assert np.allclose(LINK.pivot_b, [19.69615506, 56.43703645], atol=1e-8)   # the seed's B0


@pytest.mark.parametrize("branch", [+1, -1])
def test_both_closed_form_branches_close_the_loop(branch):
    tb = solve_output_angle(LINK.theta_ref + PHI, LINK, branch)
    assert np.all(np.isfinite(tb))
    assert np.max(compute_loop_residual(LINK.theta_ref + PHI, tb, LINK)) <= 1e-10


def test_branches_are_distinct_and_reference_branch_passes_80_deg():
    b = select_reference_branch(LINK)
    t_ref = solve_output_angle(LINK.theta_ref, LINK, b)
    t_other = solve_output_angle(LINK.theta_ref, LINK, -b)
    assert np.cos(t_ref - LINK.theta_ref) == pytest.approx(1.0, abs=1e-12)
    assert abs(np.angle(np.exp(1j * (t_other - t_ref)))) > 0.1


def test_closed_form_matches_a_bracketed_root_of_the_loop_equation():
    r = compare_linearisation(PHI, LINK)
    tb = LINK.theta_ref                      # follow the branch from the reference position
    for phi, t_closed in zip(PHI[::10], r["theta_b"][::10]):
        A = LINK.r_a * np.array([np.sin(LINK.theta_ref + phi), -np.cos(LINK.theta_ref + phi)])
        g = lambda t: np.sum((LINK.pivot_b + LINK.r_b * np.array([np.sin(t), -np.cos(t)]) - A) ** 2) - LINK.l_ab ** 2
        lo, hi = tb - 0.05, tb + 0.5           # the output turns forwards by < 0.5 rad per step
        assert g(lo) * g(hi) < 0
        tb = _bisect(g, lo, hi, 1e-14)
        assert np.cos(tb - t_closed) == pytest.approx(1.0, abs=1e-12)


def test_transfer_ratio_is_exact_at_the_reference_position():
    h = 1e-6
    r = compare_linearisation(np.array([0.0, h]), LINK)
    slope = (r["theta_b"][1] - r["theta_b"][0]) / h
    assert slope == pytest.approx(LINK.r_a / LINK.r_b, rel=1e-5)


def test_one_percent_limit_is_where_the_error_first_reaches_one_percent():
    limit = solve_error_limit(LINK, "relative_error")
    err = compare_linearisation(np.linspace(0.0, limit, 400), LINK)["relative_error"]
    assert np.all(err[:-1] < 0.01)
    assert err[-1] == pytest.approx(0.01, abs=1e-9)
    assert compare_linearisation(np.array([0.0, limit + np.radians(0.5)]), LINK)["relative_error"][1] > 0.01


def test_seed_claim_of_30_deg_against_both_measures():
    """Seed 003 says 'less than 1 % up to 30 deg'; by either measure the 1 % limit comes earlier."""
    r = compare_linearisation(np.radians([30.0]), LINK)
    assert r["relative_error"][0] > 0.01
    assert r["relative_error_absolute_angle"][0] > 0.01
    assert solve_error_limit(LINK, "relative_error") < solve_error_limit(LINK, "relative_error_absolute_angle")
