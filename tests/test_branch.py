"""Branch choice by the side of the configuration (issue 12 item 4).

``geometry.assembly`` selects the branch by the sign of sin(gamma - phi) (which side of
crank OA crank BC points), not by how close its angles are to a solution. So changed crank
lengths keep their branch without a new assembly; a geometry that cannot assemble, or
meets a toggle on the way to or inside the stroke, is refused in one line naming the keys.

Independent checks: the loop solved by a plain-numpy root scan (conftest.np_closure_all),
the closing condition as the triangle inequality |l2 - l3| <= |w| <= l2 + l3 (no acos), and
every stroke against the adaptive reference (CVODES).
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from conftest import cross2, np_closure_all, wrap_deg
from softclose.model import kinematics as kin
from softclose.config import default_config, from_dict
from softclose.errors import ConfigError
from softclose.model.lid import LidModel
from softclose.simulation.reference import Reference
from softclose.simulation.simulator import Simulator

DEFAULT_ASSEMBLY = (18.0, 108.6655, 146.8855)


def _cfg(**geometry):
    return from_dict({"geometry": geometry})


def _side_roots(theta, geo, side):
    """The numpy solutions of the loop at theta whose cranks lie on ``side`` (sign of
    sin(gamma - phi))."""
    roots = np_closure_all(theta, geo.crank_oa, geo.crank_bc, geo.pivot_b, geo.lid_c)
    return [r for r in roots if np.sign(math.sin(r[1] - r[0])) == side]


def _w(theta, geo):
    c, s = math.cos(theta), math.sin(theta)
    x, y = geo.lid_c
    return np.array([c * x - s * y - geo.pivot_b[0], s * x + c * y - geo.pivot_b[1]])


def _triangle_margin(theta, geo):
    """> 0 where the loop closes: min(|w| - |l2 - l3|, l2 + l3 - |w|) (no closed form)."""
    n = float(np.hypot(*_w(theta, geo)))
    l2, l3 = geo.crank_oa, geo.crank_bc
    return min(n - abs(l2 - l3), l2 + l3 - n)


def _edge(geo, a, b):
    """The angle between a (loop closes) and b (does not) where it stops closing."""
    assert _triangle_margin(a, geo) > 0 >= _triangle_margin(b, geo)
    for _ in range(80):
        m = 0.5 * (a + b)
        a, b = (m, b) if _triangle_margin(m, geo) > 0 else (a, m)
    return 0.5 * (a + b)


# -- changed crank lengths keep the branch of the default assembly ---------------------
@pytest.mark.parametrize("crank_bc", [0.07, 0.075, 0.08, 0.085, 0.09])
def test_crank_bc_family_builds_and_closes_like_the_reference(crank_bc):
    cfg = _cfg(crank_bc=crank_bc)            # geometry.assembly left at its default
    assert cfg.geometry.assembly == DEFAULT_ASSEMBLY
    model = LidModel.from_config(cfg)
    side = 1.0   # sin(146.8855 - 108.6655) > 0: the default assembly's side
    assert model.sigma == -1
    st = cfg.stroke
    worst = 0.0
    for th in np.linspace(st.theta_closed, st.theta0, 7):
        roots = _side_roots(th, cfg.geometry, side)
        assert len(roots) == 1      # exactly one solution on each side
        phi_np, gamma_np = roots[0]
        phi, gamma = model.closure(th)
        worst = max(worst, abs(wrap_deg(math.degrees(phi - phi_np))),
                    abs(wrap_deg(math.degrees(gamma - gamma_np))))
    assert worst < 1e-8   # deg
    if crank_bc in (0.07, 0.09):   # these were refused by the old 10-degree distance rule
        phi18 = _side_roots(math.radians(18.0), cfg.geometry, side)[0][0]
        assert abs(wrap_deg(math.degrees(phi18) - DEFAULT_ASSEMBLY[1])) > 10.0
    res = Simulator.from_config(cfg, model).run()
    ref = Reference(model).simulate()
    assert res.closed and ref.closed
    assert abs(res.closing_time - ref.closing_time) < 1e-6
    assert abs(res.impact_theta_dot - ref.impact_theta_dot) < 1e-5


def test_default_geometry_spec8_angles():
    model = LidModel.from_config(default_config())
    phi, gamma = (math.degrees(v) for v in model.closure(math.radians(18.0)))
    assert abs(phi - 108.665505) <= 0.5e-6
    assert abs(gamma - 146.885531) <= 0.5e-6


# -- the sign that names the branch ----------------------------------------------------
def test_side_is_invariant_and_equals_minus_sigma(geometry_case):
    """D = A x (C - B) = l2 l3 sin(gamma - phi) = -sigma l2 |w| sqrt(1 - u^2): never zero,
    one sign, over the whole tabulated range (kinematics module docstring)."""
    cfg, model = geometry_case
    geo = model.geo
    lo, hi = model.theta_range
    for th in np.linspace(lo, hi, 301):
        k = model.kin(np.array([th, 0.0]))
        phi, gamma = float(k[0]), float(k[1])
        A, C = np.asarray(k[5]).ravel(), np.asarray(k[6]).ravel()
        D = float(cross2(A, C - np.asarray(geo.pivot_b)))
        w = _w(th, geo)
        n = float(np.hypot(*w))
        u = (geo.crank_bc ** 2 - geo.crank_oa ** 2 - n * n) / (2 * geo.crank_oa * n)
        assert D == pytest.approx(-model.sigma * geo.crank_oa * n * math.sqrt(1 - u * u),
                                  rel=1e-12, abs=1e-18)
        assert float(kin.crank_cross(phi, gamma, geo)) == pytest.approx(D, rel=1e-12)
        assert kin.branch_of(phi, gamma) == model.sigma


def test_other_side_gives_the_other_solution():
    cfg0 = default_config()
    th18 = math.radians(18.0)
    (phi_o, gamma_o), = _side_roots(th18, cfg0.geometry, -1.0)
    asm = [18.0, math.degrees(phi_o), math.degrees(gamma_o)]
    cfg = from_dict({"geometry": {"assembly": asm}})
    model, model0 = LidModel.from_config(cfg), LidModel.from_config(cfg0)
    assert model.sigma == -model0.sigma == 1
    for th in np.linspace(cfg.stroke.theta_closed, cfg.stroke.theta0, 5):
        (phi_np, gamma_np), = _side_roots(th, cfg.geometry, -1.0)
        phi, gamma = model.closure(th)
        assert abs(wrap_deg(math.degrees(phi - phi_np))) < 1e-8
        assert abs(wrap_deg(math.degrees(gamma - gamma_np))) < 1e-8
        assert abs(wrap_deg(math.degrees(phi - model0.closure(th)[0]))) > 90.0
    # the default chain is Grashof with the coupler shortest: the other assembly closes too
    res, ref = Simulator.from_config(cfg, model).run(), Reference(model).simulate()
    assert res.closed and ref.closed
    assert abs(res.closing_time - ref.closing_time) < 1e-6


@pytest.mark.parametrize("phi_gamma,sigma", [((10.0, 40.0), -1), ((10.0, 300.0), 1),
                                              ((200.0, 100.0), 1)])
def test_assembly_angles_far_from_both_solutions_select_by_side(phi_gamma, sigma):
    """phi, gamma only name the side: far from both solutions is accepted, by its sign."""
    model = LidModel.from_config(from_dict({"geometry": {"assembly": [18.0, *phi_gamma]}}))
    assert model.sigma == sigma
    (phi_np, _), = _side_roots(math.radians(18.0), model.geo, -sigma)
    assert abs(wrap_deg(math.degrees(model.closure(math.radians(18.0))[0] - phi_np))) < 1e-8


def test_cranks_in_line_name_no_branch():
    cfg = from_dict({"geometry": {"assembly": [18.0, 10.0, 190.0]}})
    with pytest.raises(ConfigError) as exc:
        LidModel.from_config(cfg)
    msg = str(exc.value)
    assert "\n" not in msg and msg.startswith("geometry.assembly")
    # the message offers both solutions at 18 deg: they are the numpy ones
    offered = [tuple(map(float, m)) for m in re.findall(r"\(([-0-9.]+), ([-0-9.]+)\)", msg)]
    roots = np_closure_all(math.radians(18.0), cfg.geometry.crank_oa, cfg.geometry.crank_bc,
                           cfg.geometry.pivot_b, cfg.geometry.lid_c)
    assert len(offered) == len(roots) == 2
    for p, g in offered:
        assert min(abs(wrap_deg(p - math.degrees(r[0]))) + abs(wrap_deg(g - math.degrees(r[1])))
                   for r in roots) < 2e-4


# -- refusals ----------------------------------------------------------------------------
def test_cannot_assemble_names_where_the_loop_closes():
    """crank_bc = 0.1 does not close at the assembly's 18 deg; the message says where it
    does (one interval across the +-180 seam) and which keys to change."""
    cfg = _cfg(crank_bc=0.1)
    with pytest.raises(ConfigError) as exc:
        LidModel.from_config(cfg)
    msg = str(exc.value)
    assert "\n" not in msg
    for key in ("geometry.assembly", "crank_bc", "crank_oa"):
        assert key in msg
    (a, b), = re.findall(r"(-?[0-9.]+)\.\.(-?[0-9.]+)", msg)
    geo = cfg.geometry
    lo = _edge(geo, math.radians(90.0), math.radians(0.0))
    hi = _edge(geo, math.radians(200.0), math.radians(300.0))
    assert abs(float(a) - math.degrees(lo)) < 0.1 and abs(float(b) - math.degrees(hi)) < 0.1


def test_closes_nowhere():
    with pytest.raises(ConfigError, match=r"^geometry: the loop cannot close at any lid angle"):
        LidModel.from_config(_cfg(crank_bc=0.2))


def test_toggle_inside_the_stroke_is_named():
    """crank_bc = 0.0935: assembled at 18 deg, the loop stops closing near 2 deg, inside the
    0..18 deg stroke. The named angle is that toggle (3 decimals, rounded to its far side)."""
    cfg = _cfg(crank_bc=0.0935)
    with pytest.raises(ConfigError) as exc:
        LidModel.from_config(cfg)
    msg = str(exc.value)
    assert "\n" not in msg and "toggle" in msg and "inside the stroke" in msg
    for key in ("crank_bc", "stroke.theta0_deg"):
        assert key in msg
    named = float(re.search(r"theta = (-?[0-9.]+) deg", msg).group(1))
    toggle = math.degrees(_edge(cfg.geometry, math.radians(10.0), math.radians(0.0)))
    assert 0.0 <= toggle - named < 1e-3
    assert _triangle_margin(math.radians(named), cfg.geometry) < 0


def test_toggle_between_locates_the_edge():
    """crank_bc = 0.09 closes down to about -18 deg: the scan from the release angle finds
    the edge to bisection accuracy (the angle 'state --theta-deg' reports)."""
    cfg = _cfg(crank_bc=0.09)
    model = LidModel.from_config(cfg)
    found = model.toggle_between(cfg.stroke.theta0, math.radians(-40.0))
    edge = _edge(cfg.geometry, math.radians(-10.0), math.radians(-30.0))
    assert abs(found - edge) < 1e-9
    assert model.toggle_between(cfg.stroke.theta0, math.radians(-10.0)) is None
