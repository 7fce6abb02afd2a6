"""The spring kinds solved side by side (forked processes): the same answer as one after the
other, an error in a child raised here as it would have been, a child that dies replaced by
solving its kind here, and no fork where it is unsafe."""

from __future__ import annotations

import os
import threading

import pytest

import softclose
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


def test_side_by_side_gives_the_answer_of_one_after_the_other(monkeypatch):
    """Both default kinds; with side-by-side on (if this machine allows it) and off: the
    same optimum to the last bit, the same rows per kind, the same notes."""
    cfg = softclose.load_config()
    if not sidebyside.available(2):
        pytest.skip("side by side is not available here (one core or threads running)")
    forked = softclose.optimise(cfg)
    monkeypatch.setenv(sidebyside.ENV, "0")
    serial = softclose.optimise(cfg)
    assert forked.success and serial.success
    assert forked.objective == serial.objective == pytest.approx(0.0228995, abs=5e-8)
    assert forked.design == serial.design
    assert forked.metrics == serial.metrics
    assert forked.kinds == serial.kinds
    assert [k["kind"] for k in forked.kinds] == ["compression", "extension"]
    assert forked.kinds[1]["objective"] == pytest.approx(0.2047459, abs=1e-6)
    assert forked.notes == serial.notes


def test_a_dead_kind_process_is_solved_here(monkeypatch):
    """A side-by-side process that dies before answering: its kind is solved in this
    process, and the answer is the same."""
    cfg = softclose.load_config()
    if not sidebyside.available(2):
        pytest.skip("side by side is not available here")
    real = sidebyside.KindProcess

    def dying(solve):
        return real(_dies)
    monkeypatch.setattr(sidebyside, "KindProcess", dying)
    r = softclose.optimise(cfg)
    assert r.success and r.objective == pytest.approx(0.0228995, abs=5e-8)
    assert r.kinds[1]["objective"] == pytest.approx(0.2047459, abs=1e-6)
