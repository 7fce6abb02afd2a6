"""The spring kinds solved side by side (forked processes): the same answer as one after the
other, an error in a child raised here as it would have been, a child that dies replaced by
solving its kind here, and no fork where it is unsafe."""

from __future__ import annotations

import os
import threading

import pytest

from softclose.errors import NumericalError
from softclose.optimiser import sidebyside
from softclose.optimiser.sidebyside import KindProcess

pytestmark = pytest.mark.skipif(not hasattr(os, "fork"), reason="needs fork")


def _pair():
    return 41, (lambda: 42)


def _fails():
    raise NumericalError("the optimiser failed (a test); try other optimise.nodes")


def _dies():
    os._exit(3)


def test_a_child_answers_finishes_and_stops():
    with KindProcess(_pair) as child:
        assert child.raw() == 41
        assert child.finish() == 42
    assert child._closed
    with pytest.raises(ChildProcessError):       # reaped: no zombie left
        os.waitpid(child.pid, os.WNOHANG)


def test_a_child_does_the_parents_share_first():
    """``before``: the parent's share (some of the first kind's starts), sent before the
    child's own answer; an error in it is raised here, and the child still answers."""
    with KindProcess(_pair, before=lambda: {4: "start 5", 5: "start 6"}) as child:
        assert child.before() == {4: "start 5", 5: "start 6"}
        assert child.raw() == 41
        assert child.finish() == 42
    with KindProcess(_pair, before=_fails) as child:
        with pytest.raises(NumericalError, match="try other optimise.nodes"):
            child.before()
        assert child.raw() == 41


def test_a_childs_error_is_raised_here():
    with KindProcess(_fails) as child:
        with pytest.raises(NumericalError, match="try other optimise.nodes"):
            child.raw()


def test_a_child_that_dies_is_an_end_of_file():
    with KindProcess(_dies) as child:
        with pytest.raises(EOFError):
            child.raw()


def test_no_fork_with_threads_running_or_when_turned_off(monkeypatch):
    assert sidebyside.available(1) is False
    stop = threading.Event()
    t = threading.Thread(target=stop.wait)
    t.start()
    try:
        assert sidebyside.available(2) is False
    finally:
        stop.set()
        t.join()
    monkeypatch.setenv(sidebyside.ENV, "0")
    assert sidebyside.available(2) is False


# The optimiser's runs go to a fresh interpreter: this test process may hold other tests'
# threads (a Dask cluster's), with which side by side is (rightly) not used.
SCRIPT = r"""
import json, os, sys
import softclose
from softclose.optimiser import sidebyside
cfg = softclose.load_config()
assert sidebyside.available(2), "side by side is not available in a fresh interpreter"
if sys.argv[1] == "dead":
    real = sidebyside.KindProcess
    sidebyside.KindProcess = lambda solve, before=None: real(lambda: os._exit(3))
forked = softclose.optimise(cfg)
os.environ[sidebyside.ENV] = "0"
serial = softclose.optimise(cfg)
print(json.dumps({"same": [forked.objective == serial.objective, forked.design == serial.design,
                           forked.metrics == serial.metrics, forked.kinds == serial.kinds,
                           forked.notes == serial.notes,
                           # every start, the child's share of the first kind's among them
                           [{k: v for k, v in r.items() if k != "solve_time"}
                            for r in forked.starts] ==
                           [{k: v for k, v in r.items() if k != "solve_time"}
                            for r in serial.starts]],
                  "J": forked.objective, "kinds": [[k["kind"], k["objective"]]
                                                   for k in forked.kinds],
                  "success": forked.success and serial.success}))
"""


def _run(mode: str) -> dict:
    import json
    import subprocess
    import sys
    if (os.cpu_count() or 1) < 2:
        pytest.skip("side by side needs two cores")
    out = subprocess.run([sys.executable, "-c", SCRIPT, mode], capture_output=True, text=True,
                         timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_side_by_side_gives_the_answer_of_one_after_the_other():
    """Both default kinds; with side-by-side on and off: the same optimum to the last bit,
    the same rows per kind, the same notes."""
    r = _run("alive")
    assert r["success"] and all(r["same"]), r["same"]
    assert r["J"] == pytest.approx(0.0228995, abs=5e-8)
    assert [k for k, _ in r["kinds"]] == ["compression", "extension"]
    assert r["kinds"][1][1] == pytest.approx(0.2047459, abs=1e-6)


def test_a_dead_kind_process_is_solved_here():
    """Side-by-side processes that die before answering: their kinds are solved in this
    process, and the answer is the same as one after the other."""
    r = _run("dead")
    assert r["success"] and all(r["same"]), r["same"]
    assert r["kinds"][1][1] == pytest.approx(0.2047459, abs=1e-6)


# The robust co-design's stage 1 (robust/placement.py): the nominal co-designs of the spring
# kinds after the first, started side by side before the first kind's stage 1 runs.
STAGE1 = r"""
import json, os, sys, tempfile
os.environ["SOFTCLOSE_CACHE"] = tempfile.mkdtemp()   # a fresh cache, compiling on: the
os.environ["SOFTCLOSE_COMPILE"] = "1"                 # kinds' one NLP is used once here
import softclose
from softclose import buildcache
from softclose.optimiser import sidebyside
from softclose.optimiser.kinds import kind_config
from softclose.robust import placement
cfg = softclose.load_config().set("optimise.free", {   # the README's co-design box
    "geometry.spring_anchor[0]": [-0.09, -0.03], "geometry.spring_anchor[1]": [-0.01, 0.05],
    "geometry.lid_e[0]": [-0.006, 0.044], "geometry.lid_e[1]": [0.004, 0.024]})
configs = [kind_config(cfg, k, robust=True)[0] for k in ("compression", "extension")]
if sys.argv[1] == "dead":
    real = sidebyside.KindProcess
    sidebyside.KindProcess = lambda solve, before=None: real(lambda: os._exit(3))
ahead = placement.nominals_ahead(configs)
assert set(ahead) == {1}, ahead
try:
    forked = placement._nominal(configs[1], ahead[1])
finally:
    ahead[1].close()
here = placement._nominal(configs[1], None)
os.environ[sidebyside.ENV] = "0"
compiling = [p.name for p in buildcache.folder().glob("compiling.lock")]
print(json.dumps({"off": placement.nominals_ahead(configs) == {}, "compiling": compiling,
                  "same": [forked.objective == here.objective, forked.design == here.design,
                           forked.success == here.success],
                  "J": forked.objective}))
"""


def _stage1(mode: str) -> dict:
    import json
    import subprocess
    import sys
    if (os.cpu_count() or 1) < 2:
        pytest.skip("side by side needs two cores")
    out = subprocess.run([sys.executable, "-c", STAGE1, mode], capture_output=True,
                         text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    return json.loads(out.stdout.strip().splitlines()[-1])


@pytest.mark.parametrize("mode", ["alive", "dead"])
def test_the_robust_co_designs_later_kinds_start_side_by_side(mode):
    """Stage 1 of the robust co-design: the extension spring's nominal co-design, solved in
    a process started before the compression spring's stage 1 (or, when that process dies,
    here), is the one solved here to the last bit (J = 0.2047, the bound the README's
    robust co-design compares with); none is started with side by side turned off. The
    kinds' one NLP is built before the fork: built in each process, it would count as a
    second use and start its background compilation beside the first run (7 s slower)."""
    r = _stage1(mode)
    assert all(r["same"]) and r["off"] and r["compiling"] == [], r
    assert r["J"] == pytest.approx(0.204746, abs=1e-6)


def test_the_nlp_loaded_before_a_fork_is_the_one_the_starts_use():
    """What the parent loads before forking (kind_nlp) is the NLP plan_kind gives the starts,
    also with a free point outside its bounds (clipped in, and its value is part of the
    NLP's key): otherwise the parent builds an NLP nobody uses and every process its own."""
    import softclose
    from softclose.optimiser.cache import get_nlp
    from softclose.optimiser.discretise import discretisation
    from softclose.optimiser.optimiser import kind_nlp, plan_kind
    cfg = softclose.load_config().set("optimise.free", {
        "geometry.spring_anchor[0]": [-0.09, -0.08], "geometry.lid_e[1]": [0.004, 0.024]})
    assert not -0.09 <= cfg.geometry.spring_anchor[0] <= -0.08
    nlp = kind_nlp(cfg)
    assert plan_kind(cfg).nlp is nlp
    disc = discretisation(cfg)
    assert get_nlp(cfg, disc.nodes, disc.substeps) is not nlp     # the unclipped one
