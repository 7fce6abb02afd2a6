"""Five-precision-point synthesis (seed 004) by homotopy continuation with Bertini 2 (optional)."""

import numpy as np
import pytest

pytest.importorskip("bertini", reason="optional dependency bertini2 is not installed")

from softclose.validation.textbook.synthesis import (GENERIC_SOLUTION_COUNT, PIVOT_A, PROBLEM7_POINTS,  # noqa: E402
                                          classify_solutions, evaluate_equations, locate_poses,
                                          solve_precision_points)


@pytest.fixture(scope="module")
def random_case():
    d = np.random.default_rng(0).uniform(-1.0, 1.0, (5, 2))
    r = solve_precision_points(d, PIVOT_A, seed=1)
    return r, classify_solutions(r)


@pytest.fixture(scope="module")
def problem7():
    r = solve_precision_points(PROBLEM7_POINTS, PIVOT_A, seed=1)
    return r, classify_solutions(r)


def _distinct(Z, tol=1e-6):
    for i in range(len(Z)):
        for j in range(i):
            if np.max(np.abs(Z[i] - Z[j])) < tol:
                return False
    return True


@pytest.mark.slow
def test_generic_count_is_36(random_case):
    r, flags = random_case
    assert r.n_paths == 96                            # 6-homogeneous Bezout number
    assert flags["n_finite"] == GENERIC_SOLUTION_COUNT == 36
    assert r.n_at_infinity == r.n_paths - 36
    assert _distinct(r.solutions)


@pytest.mark.slow
def test_every_solution_satisfies_the_equations(random_case, problem7):
    for r, flags in (random_case, problem7):
        res = [np.max(np.abs(evaluate_equations(z, r.points, r.pivot_a))) for z in r.solutions]
        assert max(res) <= 1e-8
        assert flags["max_residual"] <= 1e-8


def test_problem7_counts_from_the_literature(problem7):
    r, flags = problem7
    assert flags["n_finite"] == 33                    # seed 004: 33 solutions, 15 real
    assert flags["n_real"] == 15
    assert _distinct(r.solutions)
    assert flags["n_valid"] >= 1


def test_valid_designs_keep_their_link_lengths_through_the_five_points(problem7):
    r, flags = problem7
    for z in r.solutions[flags["valid"]].real:
        P, Q = locate_poses(z, r.points)
        crank = np.linalg.norm(P, axis=1)
        rocker = np.linalg.norm(Q - r.pivot_a, axis=1)
        coupler = np.linalg.norm(Q - P, axis=1)
        to_point = np.linalg.norm(r.points - P, axis=1)
        for lengths in (crank, rocker, coupler, to_point):
            assert np.ptp(lengths) <= 1e-9 * max(1.0, lengths.max())
