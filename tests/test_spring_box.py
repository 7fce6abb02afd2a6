"""``optimise --robust`` with a compression spring made to order: the answer holds for its
spring's own EN 15800 box (SPEC §14; softclose.robust.spring_box)."""

from __future__ import annotations

import numpy as np
import pytest

from softclose.coil_spring import tolerances as en15800
from softclose.coil_spring.materials import material
from softclose.config import default_config
from softclose.problem import PARAM_KEYS, params_of
from softclose.robust import optimise_robust
from softclose.robust.box import box_of
from softclose.robust.spring_box import PRELOAD, RATE, made_to_order
from softclose.robust.stats import margins
from softclose.simulation.simulator import Simulator

#: the default problem with a spring made to order
MADE = {"spring.material": "EN10270-1-SH"}


@pytest.fixture(scope="module")
def made():
    return optimise_robust(default_config().update(MADE))


def _own(spring: dict, grade: int) -> tuple[float, float, float]:
    """EN 15800 of a spring recomputed from its d, D, n: the rate R = G d^4 / (8 D^3 n), the
    free length's tolerance A_L0 (m) and the relative force part 1.5 Q %."""
    d, D, n = spring["wire_d"], spring["coil_d"], spring["active_coils"]
    R = material(spring["material"]).G * d ** 4 / (8 * D ** 3 * n)
    return R, en15800.free_length_tolerance(d, D, n, R, grade), 0.015 * en15800.QUALITY[grade]


def test_only_a_material_given_makes_the_spring_to_order():
    assert made_to_order(default_config().update({"spring.material": "EN10270-1-DH"}))
    assert not made_to_order(default_config())
    assert not made_to_order(default_config().update({"spring.grade": 1}))


@pytest.mark.slow
def test_the_spreads_used_are_the_springs_own_en15800_tolerances(made):
    assert made.success, made.message
    st = made.to_json()["spring_tolerance"]
    assert st["holds"] and st["grade"] == 2
    assert st["source"] == {RATE: "EN 15800", PRELOAD: "EN 15800"}
    used_k = st["spreads"][RATE]["relative"]
    used_f = st["spreads"][PRELOAD]["absolute"]
    # the box solved with is the EN 15800 box of the spring of the round before (the larger
    # of the rounds' boxes), recomputed here from d, D, n
    before = st["rounds"][st["round"] - 2]["spring"]
    R, A_L0, frac = _own(before, 2)
    assert R == pytest.approx(before["rate"], rel=1e-12)
    # the free length's tolerance as the force it makes at the spring's rate (no preload)
    assert made.design.get("spring_preload", 0.0) == 0.0
    assert used_f == pytest.approx(R * A_L0, rel=1e-12) and used_k == pytest.approx(0.015)
    # the reported spring's own box lies within it
    R, A_L0, frac = _own(st["spring"], 2)
    assert R * A_L0 <= used_f * (1 + 1e-9) and frac <= used_k * (1 + 1e-12)
    assert st["own"][PRELOAD] == pytest.approx(R * A_L0, rel=1e-12)
    assert st["free_length"] == pytest.approx(used_f / R, rel=1e-12)
    # ... and the box reproduces EN 15800's force tolerance at every working length:
    # R A_L0 + 1.5 Q % F = A_F
    s = st["spring"]
    for F in (1.0, 10.0, 40.0):
        A_F = en15800.force_tolerance(s["wire_d"], s["coil_d"], s["active_coils"], F, 2)
        assert R * A_L0 + frac * F == pytest.approx(A_F, rel=1e-12)
    # the reported spring is the design's: its rate and free length
    assert s["rate"] == pytest.approx(made.design["spring_k"], rel=0.125 / s["active_coils"])
    assert s["free_length"] == pytest.approx(made.design["spring_rest_length"], rel=1e-9)
    # the result's box carries these spreads
    assert made.box[RATE] == {"spread": used_k, "relative": True}
    assert made.box[PRELOAD] == {"spread": used_f, "relative": False}


@pytest.mark.slow
def test_the_fixed_point_settles_on_the_default_problem(made):
    """In newtons the box does not favour a soft spring: the rounds' springs stay near one
    rate, and the last round's spring is the one solved for."""
    st = made.to_json()["spring_tolerance"]
    rates = [r["spring"]["rate"] for r in st["rounds"] if r["spring"]]
    assert len(rates) >= 2 and max(rates) / min(rates) < 1.2
    assert st["rounds"][-1]["holds"]


@pytest.mark.slow
def test_every_corner_of_the_spring_box_meets_the_constraints_in_the_kernel(made):
    cfg = made.design_config()
    box = box_of(cfg, made.design)
    assert set(box.keys) == {RATE, PRELOAD, "design.damper_c", "mass.lid"}
    sim = Simulator.from_config(cfg)
    p0 = params_of(cfg)
    corners = box.values(box.corners())
    P = np.repeat(p0[None, :], len(corners), axis=0)
    names = list(PARAM_KEYS)                    # params_of's order
    mass = np.full(len(corners), cfg.mass.lid)
    for j, key in enumerate(box.keys):
        if key == "mass.lid":
            mass = corners[:, j]
        else:
            P[:, names.index(key.removeprefix("design."))] = corners[:, j]
    cols = sim.run_batch(P, lid_mass=mass)
    m = margins(cols, cfg.optimise)
    assert len(m) == 16
    assert np.all(m >= -1e-6), (m, [box.label(z) for z in box.corners()])
    # the box is the one the result's own corner check judged
    assert made.corner_check["violating"] == 0


@pytest.mark.slow
def test_the_robust_page_quotes_this_answer(made):
    """docs/robust.md's worked case is this run's: its rounds' springs, force tolerances, J."""
    from pathlib import Path
    page = (Path(__file__).resolve().parents[1] / "docs" / "robust.md").read_text()
    page = " ".join(page.split())
    st = made.to_json()["spring_tolerance"]
    first, last = st["rounds"][0], st["rounds"][-1]
    s = first["spring"]
    assert (f"k = {first['spring']['rate']:.0f} N/m (J = {first['objective']:.4f}), whose "
            f"spring d {s['wire_d'] * 1e3:.2g} × D {s['coil_d'] * 1e3:.3g} × n "
            f"{s['active_coils']:g} has a force tolerance of ±{first['own'][PRELOAD]:.3f} N "
            f"(free length ±{first['own'][PRELOAD] / s['rate'] * 1e3:.3f} mm)") in page
    d = made.design
    assert (f"J = {made.objective:.4f} (k = {d['spring_k']:.0f} N/m, l0 = "
            f"{d['spring_rest_length'] * 1e3:.2f} mm, c = {d['damper_c']:.0f} N s/m)") in page
    second = st["rounds"][1]
    s = second["spring"]
    assert (f"J = {second['objective']:.4f} and a spring d {s['wire_d'] * 1e3:.2g} × D "
            f"{s['coil_d'] * 1e3:.3g} × n {s['active_coils']:g} of "
            f"±{second['own'][PRELOAD]:.3f} N") in page
    geometry = ("wire_d", "coil_d", "active_coils")
    assert [last["spring"][g] for g in geometry] == [s[g] for g in geometry]
    assert len(st["rounds"]) == 3


@pytest.mark.slow
def test_the_design_config_names_the_spring_whose_box_it_holds_for(made):
    """design.toml holds the spring (d, D, n): ``softclose spring`` and the report check that
    one, and it passes every check at the robust design."""
    from softclose.optimiser.spring_order import spring_order
    cfg = made.design_config()
    s = made.to_json()["spring_tolerance"]["spring"]
    assert (cfg.spring.wire_d, cfg.spring.coil_d, cfg.spring.active_coils) == (
        s["wire_d"], s["coil_d"], s["active_coils"])
    check = spring_order(cfg)
    assert check.ok, check.failed
    assert abs(check.rate / made.design["spring_k"] - 1) <= 0.015
