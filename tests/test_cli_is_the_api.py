"""A command prints what the library returns: every key of a command's ``--json`` (without
``--out``, whose file list is the command's) is a key of the matching API result's
``to_json()``, with the same value, and the command's text is the result's ``text()``."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

import softclose
from softclose.cli import main

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def cli_json(capsys, *argv) -> tuple[int, dict]:
    code = main([*argv, "--json"])
    return code, json.loads(capsys.readouterr().out)


def cli_text(capsys, *argv) -> str:
    main(list(argv))
    return capsys.readouterr().out.rstrip("\n")


def same(cli: dict, api: dict, volatile=()) -> None:
    """Every key of ``cli`` is in ``api`` with the same value (``volatile``: timings)."""
    assert set(cli) <= set(api), sorted(set(cli) - set(api))
    assert {k: v for k, v in cli.items() if k not in volatile} == \
        {k: api[k] for k in cli if k not in volatile}


@pytest.mark.parametrize("overrides", [
    [],
    ["operating.temperatures_c=[-10, 20, 50]"],
    ["design.end_damper_c=0.05", "design.end_damper_angle_deg=80"],
    ["simulate.step=0.2"],
], ids=["default", "temperatures", "end damper from the release", "unstable"])
def test_simulate_prints_the_api_result(capsys, overrides):
    cfg = softclose.load_config(None, overrides)
    res = softclose.simulate(cfg, hand_force=True)
    sets = [a for o in overrides for a in ("--set", o)]
    code, payload = cli_json(capsys, "simulate", *sets)
    same(payload, res.to_json())
    assert code == (0 if res.ok else 3)
    assert cli_text(capsys, "simulate", *sets) == res.text()


def test_simulate_with_the_hand_force_reports_it_and_its_zones():
    cfg = softclose.default_config().set("operating.temperatures_c", [-10, 20, 50])
    plain = softclose.simulate(cfg)
    res = softclose.simulate(cfg, hand_force=True)
    assert plain.hand_force is None and "closing_force" not in plain.to_json()
    assert res.metrics() == plain.metrics()
    j = res.to_json()
    assert j["closing_force"] == res.hand_force.closing_force
    assert j["self_close_deg"] == res.hand_force.self_close_deg
    assert [t["temperature_c"] for t in j["temperatures"]] == [-10.0, 20.0, 50.0]
    assert "hand force: closes by itself" in res.text()


def test_optimise_prints_the_api_result(capsys):
    cfg = softclose.default_config()
    res = softclose.optimise(cfg)
    code, payload = cli_json(capsys, "optimise")
    api = res.to_json()
    assert set(payload) <= set(api), sorted(set(payload) - set(api))
    for k in ("design", "objective", "status", "success", "active", "problem"):
        assert payload[k] == api[k], k
    assert code == 0
    text = cli_text(capsys, "optimise")
    assert text.split("\n")[:4] == res.text().split("\n")[:4]


def test_yield_prints_the_api_result(capsys):
    cfg = softclose.default_config()
    res = softclose.tolerance_analysis(cfg, samples=300)
    code, payload = cli_json(capsys, "yield", "--samples", "300")
    same(payload, res.to_json(), volatile=("time",))
    assert cli_text(capsys, "yield", "--samples", "300") == res.text("design (the defaults)")


def test_fit_prints_the_api_result(capsys):
    cfg = softclose.default_config()
    data = str(EXAMPLES / "data" / "stroke.csv")
    res = softclose.fit(cfg, [data], free=["design.damper_c"])
    code, payload = cli_json(capsys, "fit", data, "--free", "design.damper_c")
    same(payload, res.to_json(), volatile=("seconds", "times", "solve_time"))
    assert code == 0
    assert cli_text(capsys, "fit", data, "--free", "design.damper_c") == res.text()


def test_select_prints_the_api_result(capsys, tmp_path):
    """select's JSON is SelectResult's (a few parts of the example catalogs)."""
    from softclose.catalog import read_dampers, read_springs
    springs, dampers = tmp_path / "springs.csv", tmp_path / "dampers.csv"
    for path, rows in ((springs, 9), (dampers, 4)):
        lines = [ln for ln in (EXAMPLES / "catalogs" / path.name).read_text().splitlines()
                 if not ln.startswith("#")]
        path.write_text("\n".join(lines[:rows]) + "\n")
    cfg = softclose.default_config()
    res = softclose.select(cfg, read_springs(springs), read_dampers(dampers), samples=16,
                           verify=0)
    argv = ["select", "--springs", str(springs), "--dampers", str(dampers), "--samples",
            "16", "--verify", "0"]
    code, payload = cli_json(capsys, *argv)
    same(payload, res.to_json(), volatile=("seconds", "times"))
    assert code == (0 if res.success else 3)
    untimed = lambda s: re.sub(r"\d+\.\d+ s\b", "_ s", s)  # noqa: E731
    assert untimed(cli_text(capsys, *argv)) == untimed(res.text())


def test_yield_at_several_temperatures_prints_the_api_result(capsys):
    from softclose.robust import yield_by_temperature
    sets = ["--set", "operating.temperatures_c=[-10, 20, 50]"]
    cfg = softclose.load_config(None, [sets[1]])
    res = yield_by_temperature(cfg, samples=200)
    code, payload = cli_json(capsys, "yield", "--samples", "200", *sets)
    api = res.to_json()
    assert set(payload) <= set(api), sorted(set(payload) - set(api))
    assert {k: payload[k] for k in ("design", "box", "yield", "success", "message",
                                    "limiting_temperature_c")} == \
        {k: api[k] for k in ("design", "box", "yield", "success", "message",
                             "limiting_temperature_c")}
    assert code == (0 if res.meets_required else 3)
    assert cli_text(capsys, "yield", "--samples", "200", *sets) == \
        res.text("design (the defaults)")


def test_report_prints_the_api_result(capsys, tmp_path):
    """The report's JSON is the result's, and the list of the files the command wrote (it
    always writes them: ``--out`` defaults to the working folder)."""
    cfg = softclose.default_config()
    res = softclose.report(cfg, samples=200)
    code, payload = cli_json(capsys, "report", "--samples", "200", "--out", str(tmp_path))
    api = res.to_json()
    assert set(payload) <= set(api), sorted(set(payload) - set(api))
    assert payload["message"] == api["message"] and payload["matrix"] == api["matrix"]
    assert sorted(Path(f).name for f in payload["files"]) == ["report.html", "report.pdf"]
    text = cli_text(capsys, "report", "--samples", "200", "--out", str(tmp_path))
    strip = lambda s: [x for x in s.split("\n") if not x.startswith("  (")  # noqa: E731
                       and not x.startswith("  wrote")]
    assert strip(text) == strip(res.text())
