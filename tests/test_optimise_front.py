"""The Pareto front (issue 12 item 5): ``front`` and ``softclose pareto`` -- every point
verified, the objective falling as the allowed closing time grows, the continuation reaching
the same optimum as a cold multistart, and the table, JSON and figure forms."""

from __future__ import annotations

import csv
import dataclasses
import json

import pytest

from softclose.cli import main
from softclose.errors import ConfigError
from softclose.optimiser import FrontResult, front, optimise
from softclose.problem import METRIC_KEYS

TIMES = (0.5, 1.0, 2.0)


@pytest.fixture(scope="module")
def fr(cfg) -> FrontResult:
    return front(cfg, TIMES)


def test_front_points_are_verified_and_ordered(cfg, fr):
    assert fr.success, fr.message
    assert fr.closing_times == TIMES and len(fr.points) == 3
    for t, p in zip(fr.closing_times, fr.points):
        assert p.verified and p.success
        assert p.problem["closing_time_max"] == t
        assert p.metrics["closing_time"] <= t * (1 + 1e-6)
    J = [p.objective for p in fr.points]
    # more time can only help: the optimal objective falls with closing_time_max
    assert J[0] > J[1] > J[2]
    # the continuation lands on the multistart optimum of the same problem
    assert J[1] == pytest.approx(optimise(cfg).objective, rel=1e-6)


def test_front_forms(fr):
    with pytest.raises(dataclasses.FrozenInstanceError):
        fr.points = ()
    j = fr.to_json()
    json.dumps(j, allow_nan=False)
    assert j["success"] is True and len(j["points"]) == 3
    for t, p in zip(TIMES, j["points"]):
        assert p["closing_time_max"] == t and p["success"] is True
        assert set(p["design"]) == {"spring_k", "spring_rest_length", "damper_c"}
        assert all(k in p for k in METRIC_KEYS) and p["verification"]["ok"] is True
        assert p["closing_time"] == p["verification"]["closing_time"]
    frame = fr.to_frame()
    assert list(frame["closing_time_max"]) == list(TIMES)
    assert {"objective", "verified_objective", *METRIC_KEYS} <= set(frame.columns)
    fig = fr.plot()
    fig.canvas.draw()
    assert len(fig.axes) == 5
    for a in fig.axes:                    # every axis has its unit; the twin shares its x
        assert "[" in a.get_ylabel(), a.get_title()
        assert "[" in a.get_xlabel() or a.get_title() == "", a.get_title()
    import matplotlib.pyplot as plt
    plt.close(fig)


def test_front_refuses_bad_closing_times(cfg):
    for bad in ([], [float("nan")], [0.0], list(range(1, 300))):
        with pytest.raises(ConfigError, match="closing_times"):
            front(cfg, bad)


def test_cli_pareto(tmp_path, capsys):
    code = main(["pareto", "--closing-times", "0.6:1.2:2", "--json", "--out", str(tmp_path)])
    captured = capsys.readouterr()
    out = json.loads(captured.out)
    assert code == 0 and out["success"] is True
    assert [p["closing_time_max"] for p in out["points"]] == [0.6, 1.2]
    for p in out["points"]:
        assert set(p) >= {"closing_time_max", "success", "design", "objective",
                          "verification", *METRIC_KEYS}
    assert captured.err == ""
    rows = list(csv.DictReader(open(tmp_path / "pareto.csv")))
    assert [float(r["closing_time_max"]) for r in rows] == [0.6, 1.2]
    assert float(rows[1]["objective"]) == pytest.approx(out["points"][1]["objective"])
    assert (tmp_path / "pareto.png").stat().st_size > 10000


@pytest.mark.parametrize("arg", ["1:0.5:3", "a:b:3", "0.5:1:0", "0.5:1:1000", "0.5:1",
                                 "0:1:3", "0.5:1:3:lin"])
def test_cli_pareto_bad_closing_times(arg, capsys, tmp_path):
    code = main(["pareto", "--closing-times", arg, "--out", str(tmp_path / "x")])
    err = capsys.readouterr().err
    assert code == 2 and err.startswith("softclose: error: --closing-times")
    assert not (tmp_path / "x" / "pareto.csv").exists()
