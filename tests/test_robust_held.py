"""A design variable held at one value (its bounds lo = hi, as ``softclose select`` holds a
catalog spring's rate and free length) is a parameter of the scenario NLP, not a variable
its derivatives carry (:func:`softclose.problem.held_design`)."""

import numpy as np
import pytest

import softclose
from softclose.robust import optimise_robust
from softclose.problem import held_design


def _cfg(width: float = 0.0):
    """A catalog compression spring (examples/catalogs/springs.csv, CS-060-03150) held
    (``width`` 0) or bounded to a box of that relative width."""
    cfg = softclose.load_config().set("optimise.spring_kinds", ["compression"])
    return cfg.update({"optimise.spring_k": [3150.0, 3150.0 * (1 + width)],
                       "optimise.spring_rest_length": [0.06, 0.06 * (1 + width)],
                       "design.spring_min_length": 0.024})


def test_held_keys_are_those_bounded_to_one_value():
    assert held_design(_cfg()) == (True, True, False)
    assert held_design(_cfg(1e-12)) == (False, False, False)
    assert held_design(softclose.load_config()) == (False, False, False)


@pytest.fixture(scope="module")
def both():
    return [optimise_robust(_cfg(w), samples=200) for w in (0.0, 1e-12)]


def test_the_held_spring_gives_the_design_of_a_tiny_box(both):
    """The second formulation: the spring's rate and free length as variables bounded to a
    box 1e-12 wide give the same c and worst-case J."""
    held, boxed = both
    assert held.success and boxed.success
    assert held.design["spring_k"] == 3150.0 and held.design["spring_rest_length"] == 0.06
    assert held.design["damper_c"] == pytest.approx(boxed.design["damper_c"], rel=1e-8)
    assert held.objective == pytest.approx(boxed.objective, rel=1e-8)


def test_a_held_bound_is_still_reported_with_its_price(both):
    """What limits the design: the held rate and free length are active bounds with dJ per
    unit relaxation from the NLP's parameter multipliers, as the boxed variables' are from
    their bound multipliers."""
    held, boxed = both
    a = {x.name: x for x in held.active if x.kind == "bound"}
    b = {x.name: x for x in boxed.active if x.kind == "bound"}
    for key in ("spring_k", "spring_rest_length"):
        assert key in a and key in b
        assert a[key].bound == b[key].bound
        assert np.isfinite(a[key].dJ) and a[key].dJ != 0
        assert a[key].dJ == pytest.approx(b[key].dJ, rel=1e-4)


def test_a_held_spring_takes_fewer_directions():
    """The Hessian of the Lagrangian and the constraints' Jacobian of the scenario NLP need
    two directions fewer with the rate and the free length held: nothing depends on their
    variables."""
    from softclose.robust.box import box_of
    from softclose.robust.scenarios import initial_scenarios
    from softclose.robust.solve import Problem

    def directions(cfg):
        box = box_of(cfg)
        scen = initial_scenarios(box, cfg, [[3150.0, 0.06, 2000.0]], 1.0)
        solver = Problem(cfg, 1.0, scen, cfg.optimise.nodes, cfg.optimise.substeps) \
            .nlp.structure.solver
        h = solver.get_function("nlp_hess_l").sparsity_out(0)
        j = solver.get_function("nlp_jac_g").sparsity_out(1)
        return (h + h.T).star_coloring().size2(), j.uni_coloring().size2()

    (h_held, j_held), (h_box, j_box) = directions(_cfg()), directions(_cfg(1e-12))
    assert h_held == h_box - 2 and j_held == j_box - 2
