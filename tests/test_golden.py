"""Every number unchanged: the outputs of a fixed set of designs against the file written
before the element registry (tests/data/make_golden.py, run at commit b33652c).

Kernel strokes (every method, with and without per-row lid masses), holding moments, single
strokes with their error estimates and a trajectory, the adaptive reference, Newton-Euler
states and the NLP's Chebyshev series, on two geometries: the same to 1e-12 relative (most
are the same bit for bit; the tolerance admits a reordered sum: the dashpot's tabulated
(dl_d/dtheta)^2 is now the derivative of its coordinate's length, which rounds differently
from the explicit e_OC . dC/dtheta of b33652c; a series coefficient is compared relative to
its series' largest). The adaptive reference is held to 1e-10, its own accuracy; its entries
were rewritten once, when it began carrying CVODES on through its output grid instead of
starting afresh at every node (they moved by up to 4.9e-9 relative, towards the answer at
tolerance 1e-14: on the seed's spring the closing time's error went from 6.2e-9 s to
4.5e-10 s). The optimiser's and the robust optimiser's answers: to their own convergence
tolerance (1e-8 relative).
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

HERE = Path(__file__).with_name("data")


@pytest.fixture(scope="module")
def golden():
    return dict(np.load(HERE / "golden.npz"))


@pytest.fixture(scope="module")
def now():
    spec = importlib.util.spec_from_file_location("make_golden", HERE / "make_golden.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod.compute()


def _same(a, b, rtol, per=None):
    """a equals b to ``rtol`` relative to each value, or (``per``: the axes to take the
    largest over) relative to the largest value of its series -- for the pieces of a table or
    a Chebyshev series, whose high-order coefficients are rounding-sized."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    assert a.shape == b.shape
    nan = np.isnan(a)
    assert np.array_equal(nan, np.isnan(b))
    scale = np.maximum(np.abs(a), np.abs(b))
    if per is not None:
        scale = np.broadcast_to(scale.max(axis=per, keepdims=True), scale.shape)
    bad = np.abs(a - b) > rtol * scale + 1e-300
    bad &= ~nan
    assert not bad.any(), (f"{int(bad.sum())} values differ, worst relative "
                           f"{float(np.max(np.abs(a - b)[bad] / scale[bad])):.3g}")


def test_every_array_is_compared(golden, now):
    assert set(golden) == set(now)


@pytest.mark.parametrize("key", ["optimise", "robust"])
def test_optimisers_unchanged(golden, now, key):
    _same(now[key], golden[key], 1e-8)


def test_strokes_references_states_unchanged(golden, now):
    for key in sorted(golden):
        if key in ("optimise", "robust"):
            continue
        try:
            per = (1,) if key.endswith("chebyshev") else (0, 2) if key.endswith("cc") else None
            # the adaptive reference: to its own accuracy (CVODES at 1e-12 locates a turning
            # point to ~1e-11: a rounding-sized change of the equation moves it that much)
            _same(now[key], golden[key], 1e-10 if key.endswith("reference") else 1e-12, per)
        except AssertionError as exc:
            raise AssertionError(f"{key}: {exc}") from None
        if key.endswith(("rk4", "euler_cromer", "gauss4", "radau5", "rk4_masses")):
            # status, steps and stop reasons: exactly
            assert np.array_equal(now[key][:, [0, 7, 12]], golden[key][:, [0, 7, 12]]), key
