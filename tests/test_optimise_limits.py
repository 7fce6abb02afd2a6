"""Bounded work and clean failures (issue 15, issue 12 item 8): a closing-time limit beyond
stroke.t_max is clamped (and said so), grids beyond the limit are refused with the key
named, exceptions out of CasADi/Ipopt become one-line NumericalErrors, and long runs show
their progress on a terminal (never with --json)."""

from __future__ import annotations

import json
import sys

import pytest

from softclose.cli import main
from softclose.errors import ConfigError, NumericalError
from softclose.optimiser import H_MAX, MAX_STEPS, discretisation, optimise


def test_closing_time_beyond_t_max_is_clamped(cfg):
    c = cfg.replace(optimise={"closing_time_max": 50.0})
    d = discretisation(c)
    assert d.t_limit == cfg.stroke.t_max == 5.0
    assert d.t_limit / d.steps <= H_MAX and d.t_limit / (d.steps / 2) > H_MAX
    assert any("beyond stroke.t_max" in n for n in d.notes)
    # the same grid as a limit of t_max itself
    same = discretisation(cfg.replace(optimise={"closing_time_max": 5.0}))
    assert (same.nodes, same.substeps) == (d.nodes, d.substeps)
    # and the NLP's bound on T is t_max
    from softclose.optimiser import get_nlp
    nlp = get_nlp(c, d.nodes, d.substeps)
    assert nlp.bounds(c)[1][3] == 5.0


def test_grids_beyond_the_limit_are_refused(cfg):
    with pytest.raises(ConfigError, match="optimise.nodes"):       # by the config
        cfg.replace(optimise={"nodes": 500, "substeps": 8})
    with pytest.raises(ConfigError, match="optimise.nodes"):       # asked for directly
        discretisation(cfg, nodes=500, substeps=8)
    long = cfg.replace(stroke={"t_max": 60.0}, optimise={"closing_time_max": 60.0})
    with pytest.raises(ConfigError, match="closing_time_max") as e:
        discretisation(long)
    assert str(MAX_STEPS) in str(e.value)


def test_cli_refusals_are_one_line(capsys):
    for args, key in ((["--set", "stroke.t_max=60", "--set", "optimise.closing_time_max=60"],
                       "closing_time_max"),
                      (["--set", "optimise.weight_impact=0", "--set",
                        "optimise.weight_peak_tip=0"], "weight_impact")):
        assert main(["optimise", *args]) == 2
        err = capsys.readouterr().err
        assert err.startswith("softclose: error: ") and key in err
        assert len(err.strip().splitlines()) == 1


def test_starts_are_bounded(cfg):
    with pytest.raises(ConfigError, match="starts"):
        optimise(cfg, starts=10_000)
    with pytest.raises(ConfigError, match="starts"):
        optimise(cfg, starts=0)


def test_casadi_exception_becomes_numerical_error(cfg, monkeypatch, capsys):
    from softclose.optimiser import optimiser

    def broken(*a, **k):
        raise RuntimeError("Error in Function::call for 'softclose_ms' [IpoptInterface]")
    monkeypatch.setattr(optimiser, "get_nlp", broken)
    with pytest.raises(NumericalError, match="the optimiser failed"):
        optimise(cfg)
    assert main(["optimise"]) == 3
    err = capsys.readouterr().err
    assert err.startswith("softclose: error: the optimiser failed") and "Traceback" not in err
    assert "optimise.hessian" in err


def test_unavailable_linear_solver_is_named(capsys):
    code = main(["optimise", "--set", 'optimise.linear_solver="ma97"',
                 "--set", "optimise.starts=1"])
    if code == 0:
        pytest.skip("this Ipopt build has the HSL solvers")
    assert code == 2
    assert "optimise.linear_solver" in capsys.readouterr().err


def test_progress_on_a_terminal_only(cfg, monkeypatch, capsys):
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True, raising=False)
    r = optimise(cfg, starts=2, progress=True)
    err = capsys.readouterr().err
    assert r.success
    assert "start 1 of 2" in err and "start 2:" in err and "verifying" in err
    assert optimise(cfg, starts=2).success          # progress=False: silent
    assert capsys.readouterr().err == ""
    assert main(["optimise", "--json", "--set", "optimise.starts=2"]) == 0
    captured = capsys.readouterr()
    assert captured.err == "" and json.loads(captured.out)["success"] is True


@pytest.mark.parametrize("solver", ["ma86", "ma97"])
def test_missing_hsl_solver_is_refused_in_a_real_process(solver):
    """Ipopt's failed load of ma86/ma97 used to crash the process at exit (signal 11): the
    solver is refused before Ipopt is called, and the process ends with exit 2."""
    import subprocess
    import sys
    from softclose.optimiser.nlp import check_linear_solver
    try:
        check_linear_solver(solver)
        pytest.skip("the HSL library is installed here")
    except Exception:
        pass
    run = subprocess.run([sys.executable, "-m", "softclose", "optimise", "--set",
                          f'optimise.linear_solver="{solver}"'], capture_output=True, text=True,
                         timeout=120)
    assert run.returncode == 2, run.stderr
    assert run.stderr.strip().splitlines() == [
        f'softclose: error: optimise.linear_solver: "{solver}" needs the HSL library (libhsl '
        'or libcoinhsl), which is not installed here; use "mumps"']
