"""The self-close constraint ``optimise.self_close_min_deg`` in the optimisers' NLPs (SPEC §13).

The NLP keeps the self-closing moment dV/dtheta - T_fr >= a margin on a grid of
[theta_closed, theta_sc] and between its nodes (Hermite minima); the checks here are
independent of it: the hand-force statics (:func:`softclose.simulation.handforce.hand_force`,
its own grid and root finder on the exact model) for the optimum's self-close angle, the
optimum without the constraint for J, finite differences of J for the active set's price.

The lid: the default one with 1 N m of friction on its rotation and a hand-force curve to
80 deg. Its unconstrained optimum (a compression spring) has a hold-open zone at the rim: it
never closes by itself from rest; an extension spring closes it by itself up to 43.05 deg.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from softclose.cli import main
from softclose import load_config
from softclose.config import default_config
from softclose.optimiser import optimise
from softclose.optimiser.cache import get_nlp
from softclose.optimiser.parameters import SELF_CLOSE_INTERVALS
from softclose.optimiser.cache import get_model
from softclose.problem import params_of, resolve, with_designs
from softclose.simulation.handforce import _parts, hand_force

ROOT = Path(__file__).resolve().parents[1]
FRICTION = {"friction.torque": 1.0, "stroke.theta_open_deg": 80.0}


def _cfg(**kw):
    return default_config().update({**FRICTION, **{f"optimise.{k}": v for k, v in kw.items()}})


def _self_close_deg(cfg, design):
    """The design's self-close angle from the hand-force statics (None: never from rest)."""
    p = with_designs(cfg, [[design[k] for k in ("spring_k", "spring_rest_length",
                                                "damper_c")]])[0]
    return hand_force(get_model(cfg), p, resolve(cfg)).self_close_deg


def test_the_nlp_moment_is_the_statics_one():
    """The NLP's constraint values at the grid's nodes are dV/dtheta - T_fr of the hand-force
    statics (the model's own dV and friction), and the smallest of each interval's nodes and
    Hermite candidate is the true minimum over the interval (to O(h^4))."""
    cfg = _cfg(self_close_min_deg=40.0, spring_kinds=["extension"]).update(
        {"design.spring_kind": "extension", "design.spring_k": 8000.0,
         "design.spring_rest_length": 0.052, "design.damper_c": 100.0})
    nlp = get_nlp(cfg)
    p = params_of(cfg)
    g = nlp.self_close_moments(p, 40.0)
    n = SELF_CLOSE_INTERVALS
    assert g.shape == (2 * n + 1,)
    th = np.linspace(cfg.stroke.theta_closed, np.radians(40.0), n + 1)
    dV, fr, _ = _parts(get_model(cfg), p, th)
    assert fr.min() == pytest.approx(1.0, abs=1e-12)     # the 1 N m of friction
    np.testing.assert_allclose(g[:n + 1], dV - fr, rtol=1e-10, atol=1e-12)
    # per interval: its nodes and its Hermite candidate (an interior minimum, else an end)
    lowest = np.minimum(np.minimum(g[:n], g[1:n + 1]), g[n + 1:])
    fine = np.linspace(th[0], th[-1], 50 * n + 1)
    dVf, frf, _ = _parts(get_model(cfg), p, fine)
    m = dVf - frf
    true_min = np.minimum(m[:-1].reshape(n, 50).min(axis=1), m[50::50])
    np.testing.assert_allclose(lowest, true_min, atol=1e-7)
    assert np.ptp(true_min) > 0.5                   # (the moment varies over the grid)
    # another angle: the same bound NLP, its grid moved (the angle is a parameter)
    g30 = nlp.self_close_moments(p, 30.0)
    th30 = np.linspace(cfg.stroke.theta_closed, np.radians(30.0), n + 1)
    dV30, fr30, _ = _parts(get_model(cfg), p, th30)
    np.testing.assert_allclose(g30[:n + 1], dV30 - fr30, rtol=1e-10, atol=1e-12)


@pytest.mark.slow
def test_the_optimum_closes_by_itself_up_to_the_angle():
    """Unconstrained, the optimum never closes by itself from rest; with
    self_close_min_deg = 40 it does up to at least 40 deg by the hand-force statics, passes
    the verification, and costs J."""
    free = optimise(_cfg())
    assert free.success
    sc_free = _self_close_deg(free.config, free.design)
    assert sc_free is None
    r = optimise(_cfg(self_close_min_deg=40.0))
    assert r.success, r.message
    sc = _self_close_deg(r.config, r.design)
    assert sc is not None and sc >= 40.0
    assert r.verification.constraints["self_close_min_deg"]["ok"]
    assert r.objective >= free.objective
    assert r.objective == pytest.approx(0.02333, rel=2e-3)      # the extension spring's
    assert r.objective > 3 * free.objective


@pytest.mark.slow
def test_an_active_self_close_angle_and_its_price():
    """Extension springs alone: at 44 deg (the unconstrained extension optimum closes by
    itself to 43.05 deg) the constraint is active, the optimum closes by itself to 44 deg
    and no further (within the margin's worth), and the active set's dJ per degree is the
    finite difference of the optimal J in the angle."""
    base = dict(spring_kinds=["extension"])
    free = optimise(_cfg(**base))
    assert _self_close_deg(free.config, free.design) == pytest.approx(43.05, abs=0.01)
    r = optimise(_cfg(self_close_min_deg=44.0, **base))
    assert r.success, r.message
    sc = _self_close_deg(r.config, r.design)
    assert 44.0 <= sc < 44.001
    assert r.objective > free.objective
    act = {a.name: a for a in r.active}["self_close_min_deg"]
    assert (act.bound, act.value, act.unit) == ("lower", 44.0, "deg")
    assert r.problem["self_close_min_deg"] == 44.0
    lo, hi = (optimise(_cfg(self_close_min_deg=v, **base)).objective for v in (43.95, 44.05))
    assert -act.dJ == pytest.approx((hi - lo) / 0.1, rel=0.02)


@pytest.mark.slow
def test_an_inactive_constraint_changes_nothing():
    """0.3 N m of friction: the unconstrained optimum closes by itself over the whole curve,
    so self_close_min_deg = 40 leaves the design and J as they are (to 1e-8)."""
    base = {"friction.torque": 0.3, "stroke.theta_open_deg": 80.0,
            "optimise.spring_kinds": ["compression"]}
    a = optimise(default_config().update(base))
    b = optimise(default_config().update({**base, "optimise.self_close_min_deg": 40.0}))
    assert _self_close_deg(a.config, a.design) == 80.0
    for k in a.design:
        assert b.design[k] == pytest.approx(a.design[k], rel=1e-8), k
    assert b.objective == pytest.approx(a.objective, rel=1e-8)
    assert "self_close_min_deg" not in {x.name for x in b.active}


@pytest.mark.slow
def test_the_robust_design_closes_by_itself_in_every_scenario():
    """optimise --robust: every scenario of the tolerance box closes by itself up to 43 deg
    (the robust optimum at 40 deg reaches only 42.47 deg in its worst scenario); the limit is
    active in the scenarios of the light lid and the weak spring, priced per degree as the
    finite difference of the worst-case J."""
    from softclose.robust import optimise_robust
    ext = dict(spring_kinds=["extension"])
    r = optimise_robust(_cfg(self_close_min_deg=43.0, **ext))
    assert r.success
    cons = [s["constraints"]["self_close_min_deg"] for s in r.scenarios]
    assert len(cons) == 9 and all(c["ok"] for c in cons)
    worst = min(c["value"] for c in cons)
    assert 43.0 <= worst < 43.001
    act = {a.name: a for a in r.active}["self_close_min_deg"]
    assert act.scenarios and all("spring_k -10 %" in s and "mass.lid -5 %" in s
                                 for s in act.scenarios)
    lo, hi = (optimise_robust(_cfg(self_close_min_deg=v, **ext)).objective
              for v in (42.95, 43.05))
    assert hi > r.objective > lo
    assert -act.dJ == pytest.approx((hi - lo) / 0.1, rel=0.02)


def test_an_angle_above_the_open_angle_is_refused(capsys):
    code = main(["optimise", "--set", "optimise.self_close_min_deg=30"])
    out, err = capsys.readouterr()
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "optimise.self_close_min_deg" in lines[0], err
    assert "stroke.theta_open_deg" in lines[0]


def test_free_attachment_points_are_refused(capsys):
    code = main(["optimise", "--set", "optimise.self_close_min_deg=10",
                 "--free", "geometry.spring_anchor[0]=-0.09:-0.03"])
    out, err = capsys.readouterr()
    assert code == 2, err
    assert "optimise.self_close_min_deg" in err and "attachment points" in err


def test_the_nlp_moment_with_strut_friction():
    """A gas strut with friction along it (the chest lid): T_fr = T_f + F_R |dl/dtheta| varies
    with the angle, and the NLP's moment at the nodes is still the statics' dV/dtheta - T_fr."""
    cfg = load_config(ROOT / "examples" / "lids" / "chest_lid.toml").replace(design={
        "spring_kind": "gas_strut", "spring_rest_length": 0.14, "strut_stroke": 0.05,
        "spring_preload": 300.0, "strut_progression": 1.3, "spring_k": 0.0,
        "strut_friction": 10.0, "damper_c": 0.0}).update({"optimise.self_close_min_deg": 30.0})
    p = params_of(cfg)
    g = get_nlp(cfg).self_close_moments(p, 30.0)
    n = SELF_CLOSE_INTERVALS
    th = np.linspace(cfg.stroke.theta_closed, np.radians(30.0), n + 1)
    dV, fr, _ = _parts(get_model(cfg), p, th)
    assert fr.max() - fr.min() > 0.1             # (the strut's friction moment varies)
    np.testing.assert_allclose(g[:n + 1], dV - fr, rtol=1e-10, atol=1e-12)
