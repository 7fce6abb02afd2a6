"""The one optimisation core: every NLP of the package (the nominal shooting NLP, the scenario
NLP, the calibration NLP) follows one contract (:class:`softclose.optimiser.base.NLP`),
every Ipopt solver is made in one place and every solve returns one result type."""

import math
import re
from pathlib import Path

import numpy as np
import pytest

from softclose.calibration.nlp import FitNLP
from softclose.config import default_config
from softclose.optimiser import ipopt
from softclose.optimiser.base import NLP
from softclose.optimiser.cache import get_nlp, stroke_simulator
from softclose.optimiser.nlp import J_INDEX, ShootingNLP
from softclose.optimiser.run import Run
from softclose.optimiser.starts import initial_guess
from softclose.robust.nlp import ScenarioNLP

ROOT = Path(__import__("softclose").__file__).resolve().parent


def test_ipopt_solvers_are_made_in_one_place():
    """``nlpsol(`` of CasADi is called in softclose/optimiser/ipopt.py alone."""
    calls = [f"{p.relative_to(ROOT)}:{i + 1}" for p in sorted(ROOT.rglob("*.py"))
             for i, line in enumerate(p.read_text().splitlines())
             if re.search(r"\bca(sadi)?\.nlpsol\(", line)]
    assert calls and all(c.startswith("optimiser/ipopt.py:") for c in calls), calls


def test_every_solver_is_made_by_one_method():
    """``nlpsol(`` is written once in softclose/ (CasADi's call in optimiser/ipopt.py): every
    family's solvers, cold and warm, come from :meth:`Structure.make_solver`."""
    from softclose.optimiser.base import Structure
    from softclose.optimiser.nlp import ShootingStructure
    from softclose.robust.nlp import ScenarioStructure
    hits = [f"{p.relative_to(ROOT)}:{i + 1}" for p in sorted(ROOT.rglob("*.py"))
            for i, line in enumerate(p.read_text().splitlines()) if "nlpsol(" in line]
    assert len(hits) == 1 and hits[0].startswith("optimiser/ipopt.py:"), hits
    for family in (ShootingStructure, ScenarioStructure, FitNLP):
        assert issubclass(family, Structure)


def test_every_family_follows_the_contract():
    for family in (ShootingNLP, ScenarioNLP, FitNLP):
        assert issubclass(family, NLP)
        assert family.blocks is not NLP.blocks
    with pytest.raises(TypeError):
        NLP()                                   # blocks() is the contract's to give


def _nominal():
    cfg = default_config().set("optimise.spring_kinds", ["compression"])
    nlp = get_nlp(cfg, 10, 4)
    p = nlp.params(cfg)
    d0 = nlp.full_design(cfg, [1914.709, 0.07925707, 2087.754])
    w0, J0 = initial_guess(nlp, cfg, d0, stroke_simulator(cfg), p,
                           cfg.optimise.closing_time_max)
    p[J_INDEX] = J0
    return cfg, nlp, w0, p


def test_a_solve_returns_a_run_with_violations_per_block_and_group():
    """The nominal NLP's solve: a Run; its violations one block of every constraint group,
    each the largest violation of the group's rows, 0 at the converged answer; at a start
    that breaks continuity, that group's violation is its largest defect."""
    cfg, nlp, w0, p = _nominal()
    bounds = nlp.bounds(cfg)
    run = nlp.solve(w0, p, *bounds, origin="test")
    assert isinstance(run, Run) and run.success and run.origin == "test"
    assert [list(b) for b in run.violations] == [list(nlp.g_names)]
    assert max(run.violations[0].values()) < 1e-8
    assert run.total_violation == sum(run.violations[0].values())
    w_bad = np.array(run.x)
    w_bad[nlp.iX + 2] += 0.1                    # the second node's angle moved
    _, g = nlp.solver.oracle()(w_bad, p)
    g = np.asarray(g).ravel()
    v = nlp.violations(g, bounds[2], bounds[3])
    rows = dict(nlp.groups())["continuity"]
    assert v[0]["continuity"] == pytest.approx(np.max(np.abs(g[rows])), rel=1e-12)
    assert v[0]["continuity"] > 0.05


def test_a_warm_start_from_the_answer_reconverges_at_once():
    cfg, nlp, w0, p = _nominal()
    bounds = nlp.bounds(cfg)
    cold = nlp.solve(w0, p, *bounds)
    warm = nlp.solve(cold.x, p, *bounds, cold.lam_x, cold.lam_g, warm=True)
    assert warm.success and warm.iterations <= 3
    np.testing.assert_allclose(warm.x, cold.x, rtol=1e-6, atol=1e-9)


class _Failing:
    """A solver whose evaluation fails before Ipopt reports (a NaN in a function)."""

    def __call__(self, **_):
        raise RuntimeError("Error in Function::call for 'nlp_g'\nmore lines")

    def size1_in(self, i):
        return 7


def test_an_evaluation_error_is_a_failed_run_never_an_exception():
    x0 = np.arange(3.0)
    run = ipopt.run(_Failing(), x0, np.zeros(2), -np.ones(3), np.ones(3), np.zeros(4),
                    np.zeros(4), violations=lambda g, lo, hi: [{"all": float(np.inf)}])
    assert not run.success and run.status == "Error: Error in Function::call for 'nlp_g'"
    assert math.isnan(run.f) and run.g.shape == (4,) and np.isnan(run.g).all()
    assert run.iterations == 0 and run.lam_x is None and np.array_equal(run.x, x0)
    assert run.violations == [{"all": math.inf}]
    scalar = ipopt.run(_Failing(), x0, np.zeros(2), -np.ones(3), np.ones(3), 0, 0)
    assert scalar.g.shape == (7,) and scalar.violations == []
