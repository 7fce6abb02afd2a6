"""Bad input survey: every kind of invalid config and command-line value gets its one-line
error naming the culprit and exit code 2 — in-process through ``softclose.cli.main`` and, for
a few, in a fresh ``python -m softclose`` process. Never a traceback.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from softclose.cli import main

ROOT = Path(__file__).resolve().parents[1]

# (id, config-file text or None, extra argv, substring the message must contain)
# -- kinds of invalid config file content (SPEC §6) --
CONFIG_CASES = [
    ("unknown section", "[geometri]\nlid_length = 0.5\n", "geometri"),
    ("unknown key", "[geometry]\nlid_lenght = 0.5\n", "geometry.lid_lenght"),
    ("section not a table", "geometry = 5\n", "[geometry]"),
    ("string for a number", "[mass]\nlid = \"heavy\"\n", "mass.lid"),
    ("bool for a number", "[design]\nspring_k = true\n", "design.spring_k"),
    ("nan", "[design]\ndamper_c = nan\n", "design.damper_c"),
    ("inf", "[stroke]\nt_max = inf\n", "stroke.t_max"),
    ("zero length", "[geometry]\nlid_length = 0.0\n", "geometry.lid_length"),
    ("negative length", "[geometry]\ncrank_oa = -0.045\n", "geometry.crank_oa"),
    ("negative mass", "[mass]\ncrank_bc = -0.05\n", "mass.crank_bc"),
    ("zero inertia", "[mass]\ninertia_lid = 0\n", "mass.inertia_lid"),
    ("negative gravity", "[mass]\ngravity = -9.81\n", "mass.gravity"),
    ("negative spring", "[design]\nspring_k = -1.0\n", "design.spring_k"),
    ("negative damper", "[design]\ndamper_c = -5.0\n", "design.damper_c"),
    ("zero rest length", "[design]\nspring_rest_length = 0.0\n", "design.spring_rest_length"),
    ("vector too short", "[geometry]\npivot_b = [0.06]\n", "geometry.pivot_b"),
    ("vector of strings", "[geometry]\nlid_c = [\"a\", 0.01]\n", "geometry.lid_c[0]"),
    ("scalar for a vector", "[geometry]\nspring_anchor = 0.06\n", "geometry.spring_anchor"),
    ("assembly of 2", "[geometry]\nassembly = [18.0, 108.0]\n", "geometry.assembly"),
    ("bounds reversed", "[optimise]\nspring_k = [100.0, 0.0]\n", "optimise.spring_k"),
    ("bounds negative", "[optimise]\ndamper_c = [-1.0, 10.0]\n", "optimise.damper_c"),
    ("bounds rest length 0", "[optimise]\nspring_rest_length = [0.0, 0.1]\n",
     "optimise.spring_rest_length"),
    ("unknown integrator", "[simulate]\nintegrator = \"rk45\"\n", "simulate.integrator"),
    ("zero step", "[simulate]\nstep = 0.0\n", "simulate.step"),
    ("step above t_max", "[simulate]\nstep = 10.0\n", "simulate.step"),
    ("zero reference_tol", "[simulate]\nreference_tol = 0\n", "simulate.reference_tol"),
    ("release below closed", "[stroke]\ntheta0_deg = -5.0\n", "stroke.theta0_deg"),
    ("zero t_max", "[stroke]\nt_max = 0\n", "stroke.t_max"),
    ("fractional nodes", "[optimise]\nnodes = 2.5\n", "optimise.nodes"),
    ("zero substeps", "[optimise]\nsubsteps = 0\n", "optimise.substeps"),
    ("unknown hessian", "[optimise]\nhessian = \"bfgs\"\n", "optimise.hessian"),
    ("unknown linear solver", "[optimise]\nlinear_solver = \"pardiso\"\n",
     "optimise.linear_solver"),
    ("closing time window empty", "[optimise]\nclosing_time_min = 2.0\n",
     "optimise.closing_time_min"),
    ("loop cannot close", "[geometry]\ncrank_bc = 0.001\n", "geometry"),
    ("assembly names no side", "[geometry]\nassembly = [18.0, 10.0, 10.0]\n",
     "geometry.assembly"),
    ("toggle inside the stroke",
     "[geometry]\ncrank_bc = 0.0935\nassembly = [18.0, 139.5, 161.9]\n", "toggle"),
    ("not TOML", "[geometry\nlid_length = 0.5\n", "not valid TOML"),
]

# -- kinds of invalid command-line values (SPEC §7) --
CLI_CASES = [
    ("prepare: --free unknown key", ["prepare", "--free", "design.spring_q=0:1"],
     "design.spring_q"),
    ("prepare: --free reversed bounds", ["prepare", "--free", "design.end_damper_c=2:0"],
     "design.end_damper_c"),
    ("prepare: --select missing catalog", ["prepare", "--select", "no-such-springs.csv"],
     "no-such-springs.csv"),
    ("--set without =", ["simulate", "--set", "design.spring_k"], "design.spring_k"),
    ("--set unknown section", ["simulate", "--set", "desing.spring_k=1"], "desing"),
    ("--set unknown key", ["simulate", "--set", "design.spring=1"], "design.spring"),
    ("--set unreadable value", ["simulate", "--set", "design.spring_k=1e4e4"], "1e4e4"),
    ("--set negative value", ["simulate", "--set", "design.damper_c=-3"], "design.damper_c"),
    ("--set wrong type", ["simulate", "--set", "design.damper_c=[1, 2]"], "design.damper_c"),
    ("--set index out of range", ["simulate", "--set", "geometry.pivot_b[2]=0.1"],
     "geometry.pivot_b"),
    ("--set index on a scalar", ["simulate", "--set", "design.spring_k[0]=1"],
     "design.spring_k"),
    ("--set bad integrator", ["simulate", "--set", "simulate.integrator=heun"],
     "simulate.integrator"),
    ("--config missing file", ["simulate", "--config", "/nonexistent/softclose.toml"],
     "/nonexistent/softclose.toml"),
    ("unknown command", ["simulat"], "simulat"),
    ("no command", [], "no command given"),
    ("unknown option", ["simulate", "--colour"], "--colour"),
    ("bench unknown option", ["bench", "--fast"], "--fast"),
    ("state without angle", ["state"], "--theta-deg"),
    ("state angle not a number", ["state", "--theta-deg", "abc"], "--theta-deg"),
    ("state angle nan", ["state", "--theta-deg", "nan"], "--theta-deg"),
    ("state rate inf", ["state", "--theta-deg", "10", "--theta-dot", "inf"], "--theta-dot"),
    ("sweep without grid", ["sweep", "--out", "x"], "--grid"),
    ("sweep without out", ["sweep", "--grid", "design.spring_k=0:100:3"], "--out"),
]


def _check(capsys, argv, key):
    code = main(argv)
    out, err = capsys.readouterr()
    lines = err.strip().splitlines()
    assert code == 2, (code, err)
    assert len(lines) == 1, err
    assert "Traceback" not in err + out
    assert key in lines[0], lines[0]
    return lines[0]


@pytest.mark.parametrize("text,key", [c[1:] for c in CONFIG_CASES], ids=[c[0] for c in CONFIG_CASES])
def test_bad_config_file(capsys, tmp_path, text, key):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    _check(capsys, ["simulate", "--config", str(path)], key)


@pytest.mark.parametrize("argv,key", [c[1:] for c in CLI_CASES], ids=[c[0] for c in CLI_CASES])
def test_bad_command_line(capsys, argv, key):
    _check(capsys, argv, key)


@pytest.mark.parametrize("command", ["state --theta-deg 10", "simulate", "optimise", "bench",
                                     "prepare", "prepare --robust",
                                     "prepare --select examples/catalogs/springs.csv",
                                     "sweep --grid design.spring_k=0:100:3 --out OUT"])
def test_every_command_rejects_a_bad_config(capsys, tmp_path, command):
    """The config is checked before any command runs (no command starts its work)."""
    argv = [a if a != "OUT" else str(tmp_path / "o") for a in command.split()]
    _check(capsys, [*argv, "--set", "mass.lid=0"], "mass.lid")


def test_json_mode_reports_the_error_on_stdout(capsys):
    code = main(["simulate", "--json", "--set", "design.spring_k=-1"])
    out, err = capsys.readouterr()
    assert code == 2
    obj = json.loads(out)
    assert obj["exit_code"] == 2 and "design.spring_k" in obj["error"]
    assert len(err.strip().splitlines()) == 1


@pytest.mark.parametrize("argv,key", [
    (["simulate", "--set", "design.damper_c=-1"], "design.damper_c"),
    (["state", "--theta-deg", "x"], "--theta-deg"),
    (["simulate", "--set", "geometry.crank_bc=0.001"], "geometry"),
    (["bench", "--set", "simulate.integrator=rk45"], "simulate.integrator"),
])
def test_bad_input_in_a_fresh_process(argv, key):
    env = dict(os.environ)
    env["PYTHONPATH"] = str(ROOT) + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH")
                                     else "")
    r = subprocess.run([sys.executable, "-m", "softclose", *argv], capture_output=True,
                       text=True, env=env, timeout=60)
    lines = r.stderr.strip().splitlines()
    assert r.returncode == 2, r.stderr
    assert len(lines) == 1, r.stderr
    assert "Traceback" not in r.stderr + r.stdout
    assert key in lines[0]
