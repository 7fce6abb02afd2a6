"""Every number unchanged: the outputs of a fixed set of designs against the file written
before the element registry (tests/data/make_golden.py, run at commit b33652c).

Kernel strokes (every method, with and without per-row lid masses), holding moments, single
strokes with their error estimates and a trajectory, the adaptive reference, Newton-Euler
states and the NLP's Chebyshev series, on two geometries: the same to 1e-12 relative (most
are the same bit for bit; the tolerance admits a reordered sum). The optimiser's and the
robust optimiser's answers: to their own convergence tolerance (1e-8 relative).
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


def _same(a, b, rtol):
    a, b = np.asarray(a, float), np.asarray(b, float)
    assert a.shape == b.shape
    nan = np.isnan(a)
    assert np.array_equal(nan, np.isnan(b))
    scale = np.maximum(np.abs(a), np.abs(b))
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
            _same(now[key], golden[key], 1e-12)
        except AssertionError as exc:
            raise AssertionError(f"{key}: {exc}") from None
        if key.endswith(("rk4", "euler_cromer", "gauss4", "radau5", "rk4_masses")):
            # status, steps and stop reasons: exactly
            assert np.array_equal(now[key][:, [0, 7, 12]], golden[key][:, [0, 7, 12]]), key
