"""The opening effort (statics over a fine grid of angles, a fifth of a screen's time) is
computed where it is a constraint or reported, and only there: a column left out is NaN, the
other columns are the same bits; a catalog screen reports it at each pair's nominal row as
a full evaluation does; the reference leaves it out when asked, its metrics unchanged."""

from __future__ import annotations

import numpy as np

from softclose.config import default_config
from softclose.robust.evaluate import evaluate
from softclose.simulation.reference import Reference

KEYS = ["design.spring_k", "design.damper_c", "mass.lid"]


def _rows(cfg, n=40, seed=3):
    rng = np.random.default_rng(seed)
    base = np.array([cfg.design.spring_k, cfg.design.damper_c, cfg.mass.lid])
    return base * (1 + 0.2 * rng.uniform(-1, 1, (n, len(KEYS))))


def test_evaluate_without_the_opening_effort_is_the_same_otherwise():
    cfg = default_config()
    X = _rows(cfg)
    full, part = evaluate(cfg, KEYS, X), evaluate(cfg, KEYS, X, opening=False)
    assert np.isfinite(full["opening_force"]).all() and (full["opening_force"] > 0).all()
    assert np.isnan(part["opening_force"]).all()
    for k, v in full.items():
        if k != "opening_force":
            assert np.array_equal(np.asarray(v), np.asarray(part[k])), k


def test_a_bounded_opening_effort_is_never_left_out():
    """Where ``optimise.opening_force_max`` bounds it, ``opening=False`` computes it anyway
    (as ``verify`` does): the same bits as asking for it."""
    cfg = default_config().set("optimise.opening_force_max", 50.0)
    X = _rows(cfg, 2)
    a, b = evaluate(cfg, KEYS, X), evaluate(cfg, KEYS, X, opening=False)
    assert np.isfinite(b["opening_force"]).all()
    assert np.array_equal(a["opening_force"], b["opening_force"])


def test_a_screen_reports_the_nominal_opening_effort(tmp_path):
    from softclose.catalog import read_dampers, read_springs
    from softclose.catalog.screen import pair_box, run_pairs
    from pathlib import Path
    data = Path(__file__).parent / "data"
    springs = read_springs(data / "catalog_springs.csv").parts[:3]
    dampers = read_dampers(data / "catalog_dampers.csv").parts[:2]
    cfg = default_config()
    box = pair_box(cfg, 8)
    pairs = [(s, d) for s in springs for d in dampers]
    cols = run_pairs(cfg, box, pairs)
    bounded = run_pairs(cfg.set("optimise.opening_force_max", 1e6), box, pairs)
    nominal = np.arange(len(pairs)) * box.points + box.corners
    F, G = cols["opening_force"], bounded["opening_force"]
    assert np.isfinite(G).all() and np.isfinite(F[nominal]).all()
    assert np.allclose(F[nominal], G[nominal], rtol=1e-13, atol=0)
    others = np.setdiff1d(np.arange(len(F)), nominal)
    assert np.isnan(F[others]).all()
    for k in ("closing_time", "peak_tip_speed", "holding_moment", "objective"):
        assert np.array_equal(cols[k], bounded[k], equal_nan=True), k


def test_the_reference_leaves_the_opening_effort_out_when_asked():
    cfg = default_config()
    from softclose.model.lid import LidModel
    ref = Reference(LidModel.from_config(cfg))
    a, b = ref.simulate(), ref.simulate(opening=False)
    assert a.opening_force is not None and a.opening_force > 0 and b.opening_force is None
    for k in ("closing_time", "impact_theta_dot", "peak_tip_speed", "holding_moment",
              "min_spring_length", "max_spring_length"):
        assert getattr(a, k) == getattr(b, k), k
