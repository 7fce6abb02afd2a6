"""The end damper in the optimiser (issue 23, item 2): the two-phase multiple shooting (the
phase switch at the engagement angle, its time free) against the adaptive reference --
its shooting equations' gradients with respect to c_e and theta_e against finite
differences of the reference, its discretisation error's order, the optimum verified with
its engagement, the robust design verified at every corner, the Pareto front."""

import math

import casadi as ca
import numpy as np
import pytest

import softclose
from softclose.config import default_config, load_config
from softclose.errors import ConfigError
from softclose.optimiser.cache import get_model, get_nlp, stroke_simulator
from softclose.optimiser.interval import end_damper_mode, free_of, nlp_elements
from softclose.optimiser.nlp import J_INDEX
from softclose.optimiser.optimiser import claims
from softclose.optimiser.starts import initial_guess
from softclose.problem import PARAM_COLUMNS, agreement_tolerance, params_of, resolve
from softclose.simulation.reference import Reference

#: the default optimum's spring and dashpot with an end damper engaging at 5 deg
DESIGN = {"design.spring_k": 1914.709, "design.spring_rest_length": 0.07925707,
          "design.damper_c": 2087.754, "design.spring_kind": "compression",
          "design.end_damper_c": 1.0, "design.end_damper_angle_deg": 5.0}
#: the end damper free: a barrel damper's range, engaging 1..10 deg above the rim
FREE = {"design.end_damper_c": [0.0, 2.0], "design.end_damper_angle_deg": [1.0, 10.0]}
COMPRESSION = default_config().set("optimise.spring_kinds", ["compression"])
ENGAGE = ("closing_time", "impact_theta_dot", "engage_time", "engage_theta_dot")


def _states(cfg, nodes, substeps, substeps_engaged=None):
    """The two-phase NLP of cfg with its design fixed (bounds lo = hi): Ipopt solves its
    shooting equations alone; (nlp, run, p)."""
    nlp = get_nlp(cfg, nodes, substeps, substeps_engaged)
    assert nlp.two_phase
    sim = stroke_simulator(cfg)
    p = nlp.params(cfg)
    d0 = nlp.full_design(cfg, [cfg.design.spring_k, cfg.design.spring_rest_length,
                               cfg.design.damper_c])
    w0, J0 = initial_guess(nlp, cfg, d0, sim, p, cfg.optimise.closing_time_max)
    p[J_INDEX] = J0
    lbx, ubx, lbg, ubg = nlp.bounds(cfg)
    lbx[:nlp.nd] = ubx[:nlp.nd] = w0[:nlp.nd]
    r = nlp.solve(w0, p, lbx, ubx, lbg, ubg)
    assert r.success, r.status
    return nlp, r, p


def test_two_phase_derivatives_match_finite_differences_of_the_reference():
    """d (closing time, impact theta', engagement time, engagement theta') / d (c_e,
    theta_e) of the two-phase NLP -- its shooting equations (continuity, the node on
    theta_e, theta_N = theta_closed) differentiated by CasADi, the states by the implicit
    function theorem, as Ipopt sees them -- against central differences of the adaptive
    reference, which locates the engagement as an event."""
    cfg = default_config().update(DESIGN).set("optimise.free", FREE) \
        .set("optimise.closing_time_max", 3.0)
    nlp, r, p = _states(cfg, 20, 4)
    groups = dict(nlp.groups())
    w = ca.MX.sym("w", nlp.nw)
    _, g = nlp.solver.oracle()(w, ca.DM(p))
    rows = list(range(groups["continuity"].start, groups["continuity"].stop)) + \
        [groups["engagement"].start]
    G = ca.vertcat(g[rows], w[nlp.iX + 2 * (nlp.N - 1)] - cfg.stroke.theta_closed)
    Jw = np.asarray(ca.Function("J", [w], [ca.jacobian(G, w)])(r.x))
    states = list(range(nlp.iT, nlp.nw - 1))          # T, T1, X (s is in none of them)
    dz = -np.linalg.solve(Jw[:, states], Jw[:, :nlp.nd]) / nlp.scales   # per SI unit
    where = {"closing_time": 0, "engage_time": 1,
             "impact_theta_dot": 2 + 2 * (nlp.N - 1) + 1,
             "engage_theta_dot": 2 + 2 * (nlp.nodes - 1) + 1}
    ref = Reference(get_model(cfg), tol=1e-12)
    base = params_of(cfg)
    free = [k for k, _, _ in nlp.free]
    h = 1e-4
    checked = 0
    for key in FREE:
        col = 3 + free.index(key)
        out = []
        for sgn in (1, -1):
            q = base.copy()
            q[PARAM_COLUMNS[key]] += sgn * h
            out.append(ref.simulate(q, resolve(cfg)))
        for m, i in where.items():
            fd = (getattr(out[0], m) - getattr(out[1], m)) / (2 * h)
            ad = dz[i, col]
            if abs(fd) < 1e-6:         # c_e does not move the engagement; theta_e not the
                assert abs(ad) < 1e-6, (key, m, ad, fd)   # creep speed onto the rim
                continue
            assert abs(ad - fd) <= 1e-5 * abs(fd), (key, m, ad, fd)   # measured <= 1e-7
            checked += 1
    assert checked == 5          # (c_e: T, impact; theta_e: T, T1, engagement theta')


def test_two_phase_discretisation_error_is_fourth_order():
    """The design fixed, the NLP's closing time, impact speed, engagement time and speed
    against the reference's as the intervals double (M = 4, M_engaged = 8 per interval): RK4's
    error falls ~16 times per doubling in both phases (the switch is a node, so no step
    straddles it); at the default N = 10 every number is far inside its agreement
    tolerance."""
    cfg = default_config().update(DESIGN).set("optimise.closing_time_max", 2.0)
    ref = Reference(get_model(cfg), tol=1e-12).simulate(params_of(cfg), resolve(cfg))
    errors = []
    for N in (5, 10, 20):
        nlp, r, _ = _states(cfg, N, 4, 8)
        _, own, _ = claims(nlp, cfg, r)
        errors.append([abs(own[k] - getattr(ref, k)) for k in ENGAGE])
        if N == 10:
            for k, e in zip(ENGAGE, errors[-1]):
                assert e < 1e-2 * agreement_tolerance(k, getattr(ref, k)), (k, e)
    errors = np.array(errors)
    ratios = errors[:-1] / errors[1:]
    assert np.all(ratios > 12), ratios           # measured 15.5 .. 23


def test_two_phase_without_end_damper_is_todays_optimum():
    """The end damper free with bounds [0, 0]: the two-phase NLP (a node on the 5 deg
    angle, its time free) finds today's one-phase optimum J = 0.0228995, the same design,
    verified; a fixed c_e = 0 is today's NLP itself (one phase, no end damper carried)."""
    assert end_damper_mode(COMPRESSION) is None
    assert "end_damper" not in [e.name for e in nlp_elements(COMPRESSION)]
    c = COMPRESSION.set("optimise.starts", 3)
    r1 = softclose.optimise(c)
    r2 = softclose.optimise(c.set("optimise.free", {"design.end_damper_c": [0.0, 0.0]}))
    assert r1.success and r2.success, (r1.message, r2.message)
    assert r1.substeps_engaged is None and r2.substeps_engaged == 4
    assert r1.objective == pytest.approx(0.0228995, rel=2e-6)
    assert r2.objective == pytest.approx(0.0228995, rel=2e-5)     # its own discretisation
    assert r2.verified_objective == pytest.approx(r1.verified_objective, rel=1e-6)
    for k in ("spring_k", "spring_rest_length", "damper_c"):
        assert r2.design[k] == pytest.approx(r1.design[k], rel=2e-3)
    assert r2.design["end_damper_c"] == 0.0
    assert "engage_time" not in r2.optimiser          # no damper: no engagement to claim


@pytest.mark.slow
def test_end_damper_co_design_is_verified_where_it_engages(tmp_path):
    """c_e and theta_e free: a verified optimum well below today's J, its engagement node
    (time and theta') equal to the reference's located event within the agreement
    tolerance, reported in the JSON, the text and the table, and handed on in design.toml:
    the file's config, re-simulated by the reference, gives the verified J."""
    r = softclose.optimise(COMPRESSION.set("optimise.free", FREE).set("optimise.starts", 4))
    assert r.success, r.message
    assert r.substeps_engaged is not None and r.verification.ok
    assert r.objective < 0.0228995 * 0.85           # measured 0.017414 (-24 %)
    for k, (lo, hi) in FREE.items():
        assert lo - 1e-9 <= r.design[k.split(".")[1]] <= hi + 1e-9
    ver = r.verification
    for k in ("engage_time", "engage_theta_dot"):
        a = ver.agreement[k]
        assert a["ok"] and abs(a["difference"]) <= agreement_tolerance(k, a["reference"])
        assert abs(a["difference"]) < 1e-2 * a["tolerance"]      # measured ~1e-4 of it
        assert r.metrics[k] == a["reference"] == getattr(ver.stroke, k)
    j = r.to_json()
    assert j["engage_time"] == r.metrics["engage_time"] and j["engage_theta_dot"] < 0
    assert j["solver"]["phases"][1]["substeps"] == r.substeps_engaged
    assert "engage_time" in r.text() and "end damper engages" in r._repr_html_()
    r.save(tmp_path)
    c = load_config(tmp_path / "design.toml")
    assert c.design.end_damper_c == r.design["end_damper_c"]
    assert c.design.end_damper_angle_deg == r.design["end_damper_angle_deg"]
    ref = Reference(get_model(c)).simulate(params_of(c), resolve(c))
    J = c.optimise.weight_impact * ref.impact_theta_dot ** 2 \
        + c.optimise.weight_peak_tip * ref.peak_tip_speed ** 2
    assert J == pytest.approx(r.verified_objective, rel=1e-9)
    assert ref.engage_time == pytest.approx(r.metrics["engage_time"], rel=1e-9)


def test_end_damper_keys_are_checked():
    """An angle free without a damper, bounds outside the stroke, a free damper that never
    engages: refused with the key named; an angle at or above the release angle is one
    phase (a damper on the lid all the way); a free angle's bounds are clipped into the
    stroke by 1 % of it."""
    cfg = default_config()
    with pytest.raises(ConfigError, match="end_damper_angle_deg is free but"):
        end_damper_mode(cfg.set("optimise.free", {"design.end_damper_angle_deg": [1, 10]}))
    with pytest.raises(ConfigError, match="outside the stroke"):
        end_damper_mode(cfg.set("optimise.free", {"design.end_damper_c": [0, 2],
                                                  "design.end_damper_angle_deg": [20, 30]}))
    with pytest.raises(ConfigError, match="never acts"):
        end_damper_mode(cfg.set("design.end_damper_angle_deg", -1.0)
                        .set("optimise.free", {"design.end_damper_c": [0, 2]}))
    assert end_damper_mode(cfg.set("design.end_damper_c", 1.0)) == "two-phase"
    assert end_damper_mode(cfg.set("design.end_damper_c", 1.0)
                           .set("design.end_damper_angle_deg", 30.0)) == "always"
    never = cfg.set("design.end_damper_c", 1.0).set("design.end_damper_angle_deg", -1.0)
    assert end_damper_mode(never) is None
    assert "end_damper" not in [e.name for e in nlp_elements(never)]
    wide = cfg.set("optimise.free", {"design.end_damper_c": [0, 2],
                                     "design.end_damper_angle_deg": [-5, 40]})
    (_, lo, hi), = [x for x in free_of(wide) if x[0] == "design.end_damper_angle_deg"]
    assert (lo, hi) == pytest.approx((0.18, 17.82))


@pytest.mark.slow
def test_robust_end_damper_meets_every_corner():
    """optimise --robust with c_e and theta_e free: every scenario re-simulated by the
    reference meets every constraint and agrees with the scenario NLP (its engagement
    too), no corner of the box (16, the end damper's +-20 % among them) breaks a
    constraint in the kernel, and the worst case is far below the robust optimum without
    an end damper (0.12548)."""
    from softclose.robust import optimise_robust
    r = optimise_robust(COMPRESSION.set("optimise.free", FREE), samples=2000)
    assert r.success, r.message
    assert r.verification["ok"]
    assert r.verification["scenarios_verified"] == r.verification["scenarios"]
    assert r.corner_check["corners"] == 16 and r.corner_check["violating"] == 0
    assert r.objective < 0.12548 * 0.7                  # measured 0.067628 (-46 %)
    for k, (lo, hi) in FREE.items():
        assert lo - 1e-9 <= r.design[k.split(".")[1]] <= hi + 1e-9
    for s in r.scenarios:
        a = s["agreement"]["engage_time"]
        assert a["ok"] and a["reference"] is not None, s["label"]
    assert any("end_damper_c" in s["label"] for s in r.scenarios)
    c = r.design_config()
    assert c.design.end_damper_c == pytest.approx(r.design["end_damper_c"])
    assert not c.optimise.free
    assert r.to_json()["engage_time"] == r.metrics["engage_time"]


def test_pareto_front_with_the_end_damper_is_verified():
    """The front carries the two phases from point to point: each point verified with its
    engagement, J falling as the closing time allowed grows, each below the front without
    an end damper."""
    base = COMPRESSION.set("optimise.starts", 2)
    fr = softclose.front(base.set("optimise.free", FREE), [0.6, 1.0], starts=2)
    fr0 = softclose.front(base, [0.6, 1.0], starts=2)
    assert fr.success, fr.message
    Js = [p.objective for p in fr.points]
    assert Js[1] < Js[0]
    for p, p0 in zip(fr.points, fr0.points):
        assert p.objective < p0.objective
        assert p.verification.agreement["engage_time"]["ok"]
        assert not math.isnan(p.metrics["engage_theta_dot"])


def test_the_starts_end_damper_refined_on_its_own_finer_grid():
    """Each start's end damper moves to the best point of its 9 x 9 grid by the sweep's own
    measure (never worse than its sweep point), starts that become one are solved once, and
    an extension spring's starts of no rate (the same stroke at any free length) are one."""
    from softclose.optimiser.kinds import kind_config
    from softclose.optimiser.starts import END_REFINE, _measure, sweep_starts
    base = default_config().set("optimise.free", FREE)
    t = base.optimise.closing_time_max
    for kind, most in (("compression", 6), ("extension", 1)):
        cfg, why = kind_config(base, kind)
        assert why is None
        sim = stroke_simulator(cfg, 1.05 * t + 0.05)
        starts, _ = sweep_starts(cfg, 6, t, sim)
        assert 1 <= len(starts) <= most
        assert len({tuple(r) for r in starts}) == len(starts)
        for c_e, angle in starts[:, 3:5]:        # on the finer grid of each key's bounds
            for v, (lo, hi) in ((c_e, FREE["design.end_damper_c"]),
                                (angle, FREE["design.end_damper_angle_deg"])):
                step = (hi - lo) / (END_REFINE - 1)
                assert abs((v - lo) / step - round((v - lo) / step)) < 1e-9
        keys = (("design.end_damper_c", 0, 0), ("design.end_damper_angle_deg", 0, 0))
        viol, J, _ = _measure(cfg, sim, starts, keys, t)     # (columns 3, 4: c_e, angle)
        if kind == "compression":                # the feasible starts of the default lid
            assert np.all(viol == 0) and np.all(np.isfinite(J))
    # the answer is the one every start reached before (docs/optimise.md)
    res = softclose.optimise(base)
    assert res.objective == pytest.approx(0.0174136, rel=1e-6) and res.verification.ok
