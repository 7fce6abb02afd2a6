"""The co-design's global first stage (softclose/optimiser/screening.py): the placements
sampled, the pruned screening against judging every pair in every scenario, each
placement's free lengths, and (slow) co-designs on a heavier lid against a grid of fixed
placements each solved by the optimiser."""

import itertools

import numpy as np
import pytest

import softclose
from softclose.optimiser import screening as S
from softclose.optimiser.kinds import free_length_bounds, kind_config, spring_range

BOX4 = (("geometry.spring_anchor[0]", -0.09, -0.03), ("geometry.spring_anchor[1]", -0.01, 0.05),
        ("geometry.lid_e[0]", -0.006, 0.044), ("geometry.lid_e[1]", 0.004, 0.024))


def test_placements_hold_the_box_corners_and_centre():
    V = S.placements(BOX4)
    lo = np.array([b[1] for b in BOX4])
    hi = np.array([b[2] for b in BOX4])
    assert V.shape == (81, 4)
    for corner in itertools.product(*zip(lo, hi)):
        assert np.isclose(V, corner, atol=0).all(axis=1).any()
    assert np.isclose(V, (lo + hi) / 2).all(axis=1).any()
    # five keys: 3^5 > 81 -- the 32 corners, the centre, a Halton fill, all in the box
    box5 = BOX4 + (("geometry.dashpot_lid[0]", 0.0, 0.01),)
    V5 = S.placements(box5)
    lo5, hi5 = np.r_[lo, 0.0], np.r_[hi, 0.01]
    assert V5.shape == (S.MAX_PLACEMENTS, 5)
    assert ((V5 >= lo5) & (V5 <= hi5)).all()
    for corner in itertools.product(*zip(lo5, hi5)):
        assert np.isclose(V5, corner, atol=0).all(axis=1).any()
    assert len(np.unique(V5, axis=0)) == len(V5)


def _analytic_judge(S_count):
    """J = |v - a_s|^2 + |d - b|^2 + s/10 and a violation where d[0] + v[0] > 1.6: a
    worst case over scenarios known exactly."""
    rng = np.random.default_rng(3)
    a = rng.uniform(0, 1, (S_count, 2))

    def judge(V, D, s):
        J = ((V - a[s]) ** 2).sum(axis=1) + ((D[:, :2] - 0.3) ** 2).sum(axis=1) + s / 10
        viol = np.maximum(D[:, 0] + V[:, 0] - 1.6, 0.0)
        return J, viol
    return judge


@pytest.mark.parametrize("worst", [True, False])
def test_pruned_screening_ranks_the_placements_as_judging_everything(worst):
    """The screening judges the other scenarios only where the first's J (a lower bound of
    the worst case) may still matter: its best placements, their designs and J are those of
    judging every pair in every scenario."""
    box = (("a", 0.0, 1.0), ("b", 0.0, 1.0))
    G = np.array(np.meshgrid(np.linspace(0, 1, 7), np.linspace(0, 1, 5), [0.5],
                             indexing="ij")).reshape(3, -1).T
    n_s = 5
    judge = _analytic_judge(n_s)
    scr = S.screen(box, G, judge, n_s, worst=worst, keep=3)
    V = S.placements(box)
    full = np.zeros((len(V), len(G)))
    ok = np.ones((len(V), len(G)), bool)
    for i, v in enumerate(V):
        Js = [judge(np.tile(v, (len(G), 1)), G, s) for s in range(n_s)]
        J = np.array([j for j, _ in Js])
        ok[i] = np.all([viol == 0 for _, viol in Js], axis=0)
        full[i] = J.max(axis=0) if worst else J.mean(axis=0)
    best = np.where(ok, full, np.inf).min(axis=1)
    order = np.argsort(best, kind="stable")[:3]
    assert list(scr.kept) == list(order)
    assert np.allclose(scr.objective[list(scr.kept)], best[order], rtol=1e-14)
    assert scr.best_objective == pytest.approx(best.min(), rel=1e-14)
    for i in scr.kept:
        j = int(np.argmin(np.where(ok[i], full[i], np.inf)))
        assert np.allclose(scr.designs[i], G[j])
    if worst:       # the bound saved strokes
        assert scr.strokes < len(V) * len(G) * n_s
    data = scr.to_json()
    assert data["placements"] == len(V) and data["best_objective"] == scr.best_objective
    assert "placements" in scr.line() and f"{scr.best_objective:.6g}" in scr.line()


def test_each_placement_screens_the_free_lengths_valid_at_its_points():
    """A placement's free lengths are those kind_config gives a config with its points (the
    spring's length over the stroke from the kernel's pose table against the exact model)."""
    from softclose.optimiser.cache import stroke_simulator
    from softclose.optimiser.free_points import placed_config
    cfg = softclose.default_config().set("optimise.free", {k: [lo, hi] for k, lo, hi in BOX4})
    box = S.shared_box(cfg)
    V = S.placements(box)[[0, 40, 80]]
    sim = stroke_simulator(cfg)
    for robust in (False, True):
        c = cfg.set("design.spring_kind", "compression")
        G = S.placement_designs(c, sim.table, box, V, robust=robust)
        for v, g in zip(V, G):
            placed = placed_config(c, dict(zip([b[0] for b in box], v))).set(
                "optimise.free", None)
            k, _ = kind_config(placed, "compression", robust=robust)
            lo, hi = k.optimise.spring_rest_length
            assert g[:, 1].min() == pytest.approx(lo, rel=1e-6)
            assert g[:, 1].max() == pytest.approx(max(hi, lo), rel=1e-6)
            lmin, lmax = spring_range(placed)
            assert free_length_bounds(placed, "compression", lmin, lmax, robust) == \
                pytest.approx((lo, hi))


# -- co-designs on a heavier lid against a grid of fixed placements (slow) --------------
HEAVY = 0.8
#: two free coordinates (the spring anchor's and its lid point's heights): a 3 x 3 grid
BOX2 = {"geometry.spring_anchor[1]": [-0.01, 0.05], "geometry.lid_e[1]": [0.004, 0.024]}


def _grid(fn):
    vals = [np.linspace(lo, hi, 3) for lo, hi in BOX2.values()]
    return [fn(dict(zip(BOX2, v))) for v in itertools.product(*vals)]


@pytest.mark.slow
def test_robust_co_design_of_a_heavier_lid_beats_every_fixed_placement_of_a_grid():
    from softclose.robust import optimise_robust
    base = softclose.default_config().set("mass.lid", HEAVY).set(
        "optimise.spring_kinds", ["compression"])
    r = optimise_robust(base.set("optimise.free", BOX2), samples=200)
    assert r.success
    grid = _grid(lambda pts: optimise_robust(base.update(pts), samples=200))
    best = min(g.objective for g in grid if g.success)
    assert r.objective <= best * (1 + 1e-6)
    scr = r.to_json()["screening"]
    assert scr["placements"] == 9
    assert r.objective <= scr["best_objective"] * (1 + 1e-9)


@pytest.mark.slow
def test_nominal_co_design_of_a_heavier_lid_beats_every_fixed_placement_of_a_grid():
    base = softclose.default_config().set("mass.lid", HEAVY)
    r = softclose.optimise(base.set("optimise.free", BOX2))
    assert r.success
    grid = _grid(lambda pts: softclose.optimise(base.update(pts)))
    best = min(g.objective for g in grid if g.success)
    assert r.objective <= best * (1 + 1e-6)
    scr = r.to_json()["screening"]
    assert scr["placements"] == 9
    assert r.objective <= scr["best_objective"] * (1 + 1e-9)
