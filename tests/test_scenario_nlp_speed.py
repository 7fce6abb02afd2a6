"""The robust optimiser's scenario NLP, faster and the same: its shooting intervals evaluated
in threads give the same solve bit for bit; using a scenario NLP builds it and compiles
nothing (compiling is asked for: softclose.robust.nlp.prepare, in the foreground); the
compiled library solves to the same point in the same iterations, and a damaged one is
dropped, never an error."""

from __future__ import annotations

import importlib
import os
import shutil

import numpy as np
import pytest

from softclose import buildcache
from softclose.optimiser import compiled

rnlp = importlib.import_module("softclose.robust.scenario_cache")
maps = importlib.import_module("softclose.optimiser.interval")    # the interval maps

#: a small problem: 2 scenarios of the default box, 4 intervals of 2 sub-steps (the
#: compiled library of it takes a few seconds)
NODES, SUBSTEPS = 4, 2


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv(buildcache.ENV_FOLDER, str(tmp_path))
    rnlp.forget()
    yield tmp_path
    rnlp.forget()


def _problem(cfg):
    from softclose.robust.box import box_of
    from softclose.robust.scenarios import initial_scenarios
    from softclose.robust.solve import Problem
    design = [cfg.design.spring_k, cfg.design.spring_rest_length, cfg.design.damper_c]
    scen = initial_scenarios(box_of(cfg), cfg, [design], 1.0)
    assert len(scen) >= 2
    return Problem(cfg, 1.0, scen[:2], NODES, SUBSTEPS), design


def _solve(cfg):
    problem, design = _problem(cfg)
    x0, J_ref = problem.initial(design)
    return problem, problem.solve(x0, J_ref)


def test_threads_give_the_same_solve(cache, cfg, monkeypatch):
    monkeypatch.setattr(maps, "MAX_MAP_THREADS", 1)
    assert maps.map_threads() == 1
    _, one = _solve(cfg)
    rnlp.forget()
    monkeypatch.setattr(maps, "MAX_MAP_THREADS", 4)
    monkeypatch.setattr(maps, "map_threads", lambda: 3)     # threads even on one core
    _, three = _solve(cfg)
    assert one.success and three.success
    assert three.r.iterations == one.r.iterations
    assert np.array_equal(three.r.x, one.r.x)
    assert np.array_equal(three.J, one.J) and np.array_equal(three.peaks, one.peaks)


def test_using_a_scenario_nlp_compiles_nothing(cache, cfg, monkeypatch):
    """Built symbolically on use, twice (another process), and nothing compiled or started:
    compiling is only done when asked for."""
    import subprocess
    compiled.toolchain(compiled.SCENARIO_CFLAGS)   # (the compiler's --version, asked once)
    started = []
    monkeypatch.setattr(subprocess, "Popen", lambda *a, **k: started.append(a))
    first, _ = _problem(cfg)
    rnlp.forget()
    again, _ = _problem(cfg)
    assert not started and again.nlp.library is None
    assert not list(cache.glob("*/nlp-*.so")) and not list(cache.glob("*/seen-*"))


def test_the_co_designs_first_stage_is_never_compiled(cache, cfg, monkeypatch):
    """A scenario NLP with free attachment points (the co-design's first stage) stays in
    CasADi's virtual machine even when compiling is asked for (``softclose prepare``): its C
    evaluates the derivatives more slowly (docs/bench_structures.json measures both). The
    scenario NLP of the same box without free points is one ``prepare`` compiles."""
    placed = cfg.set("optimise.free", {"geometry.spring_anchor[0]": [-0.09, -0.03]})
    monkeypatch.setattr(compiled, "compile_nlp",
                        lambda *a, **k: pytest.fail("a placed scenario NLP was compiled"))
    problem, _ = _problem(placed)
    assert problem.nlp.placed and not problem.nlp.structure.prepared
    before = len(compiled.interpreted)
    lib = rnlp.prepare(placed, problem.model_cfgs, NODES, SUBSTEPS,
                       placed.tolerance.robust_objective, problem.M_engaged)
    assert lib is None and not list(cache.glob("*/nlp-*.so"))
    # (what `softclose prepare` reports as left to the virtual machine)
    assert [w.endswith(", the points free)") for w in compiled.interpreted[before:]] == [True]
    rnlp.forget()
    plain, _ = _problem(cfg)
    assert plain.nlp.structure.prepared


@pytest.mark.slow
def test_the_compiled_scenario_nlp_gives_the_same_solve(cache, cfg, monkeypatch):
    if shutil.which(os.environ.get("CC", "cc")) is None:
        pytest.skip("no C compiler")
    vm_problem, vm = _solve(cfg)
    assert vm_problem.nlp.library is None and vm.success
    key = vm_problem.nlp.key
    lib = rnlp.prepare(cfg, vm_problem.model_cfgs, NODES, SUBSTEPS,
                       cfg.tolerance.robust_objective, vm_problem.M_engaged)
    assert lib is not None and lib == compiled.compiled_nlp(key, compiled.SCENARIO_CFLAGS)
    rnlp.forget()
    problem, fast = _solve(cfg)
    assert problem.nlp.library is not None and problem.nlp.build_time < 0.5
    assert fast.r.iterations == vm.r.iterations
    np.testing.assert_allclose(fast.r.x, vm.r.x, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(fast.J, vm.J, rtol=1e-12)
    np.testing.assert_allclose(fast.peaks, vm.peaks, rtol=1e-12)
    assert problem.nlp.g_sizes == vm_problem.nlp.g_sizes
    # the warm solver of the library: a warm start at the answer stays there (the design
    # and every scenario's objective; an epigraph variable nothing pins may move)
    warm = problem.solve(fast.r.x, fast.J_ref, (fast.r.lam_x, fast.r.lam_g))
    # (Ipopt's path to the same point takes 2..7 iterations depending on the machine's
    # floating point: a warm start is far fewer than the cold solve's)
    assert warm.success and warm.r.iterations <= max(8, fast.r.iterations // 2)
    np.testing.assert_allclose(warm.design, fast.design, rtol=1e-7)
    np.testing.assert_allclose(warm.J, fast.J, rtol=1e-7)
    # a library of another NLP (its numbers say other dimensions) is dropped and the NLP
    # built again: the same answer (a damaged file fails the same way, in dlopen)
    meta = dict(buildcache.load("nlpmeta", key))
    meta["nw"] = meta["nw"] + 1
    buildcache.store("nlpmeta", key, meta)
    rnlp.forget()
    problem, again = _solve(cfg)
    assert problem.nlp.library is None
    assert compiled.compiled_nlp(key, compiled.SCENARIO_CFLAGS) is None
    assert np.array_equal(again.r.x, vm.r.x)


def test_threads_give_the_same_nominal_solve(cache, monkeypatch):
    """The optimiser's NLP in the virtual machine maps its intervals in threads
    (optimiser.cache builds it so unless it is compiled): the two-phase end-damper NLP
    solves to the same bits in the same iterations as with one thread."""
    from softclose.config import default_config
    from softclose.optimiser import cache as ocache
    from softclose.optimiser.optimiser import solve
    cfg = default_config().set("optimise.free", {"design.end_damper_c": [0, 2],
                                                 "design.end_damper_angle_deg": [1, 10]})
    runs = []
    for k in (1, 3):
        ocache.forget()
        monkeypatch.setattr(ocache, "map_threads", lambda k=k: k)
        r = solve(cfg, nodes=4, substeps=2)
        st = next(iter(ocache._STRUCTURES.values()))
        assert st.library is None and st.solver is not None
        runs.append(r)
    ocache.forget()
    one, three = runs
    assert one.success and three.success
    assert three.iterations == one.iterations
    assert three.objective == one.objective and three.design == one.design
