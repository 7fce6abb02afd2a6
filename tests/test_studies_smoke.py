"""Every studies/*.py runs in its fast mode and leaves the files its docstring promises.

A study's docstring states its question and lists what it writes under
``Writes to studies/out/<name>/:`` (one file a line; entries marked "(if ...)" are
conditional; ``*`` is a glob). Each script runs with ``--fast`` in a subprocess.
"""

from __future__ import annotations

import ast
import re
import subprocess
import sys
import time
from pathlib import Path

import pytest

STUDIES = Path(__file__).resolve().parents[1] / "studies"
SCRIPTS = sorted(p for p in STUDIES.glob("*.py") if not p.stem.startswith("_"))


def promised(script: Path) -> tuple[str, list[str]]:
    doc = ast.get_docstring(ast.parse(script.read_text())) or ""
    m = re.search(r"Writes to studies/out/([\w\-]+)/:\n((?:[ \t]+\S.*\n?)+)", doc)
    assert m, f"{script.name}: the docstring must say 'Writes to studies/out/<name>/:'"
    files = []
    for line in m.group(2).splitlines():
        if re.match(r"^ {2}\S", line) and "(if" not in line:
            files.append(line.split()[0])
    return m.group(1), files


@pytest.mark.slow
@pytest.mark.parametrize("script", [s for s in SCRIPTS if s.stem != "report_figures"],
                         ids=lambda p: p.stem)
def test_study_fast_mode(script):
    name, files = promised(script)
    doc = ast.get_docstring(ast.parse(script.read_text()))
    assert "?" in doc.splitlines()[0] or doc.splitlines()[0], "the docstring states a question"
    t0 = time.time()
    p = subprocess.run([sys.executable, str(script), "--fast"], capture_output=True, text=True,
                       timeout=900, cwd=STUDIES.parent)
    assert p.returncode == 0, p.stderr[-2000:]
    out = STUDIES / "out" / name
    assert files, f"{script.name} lists no files"
    for f in files:
        hits = list(out.glob(f)) if "*" in f else [out / f]
        assert hits and all(h.exists() for h in hits), f"{script.name}: {f} missing in {out}"
        assert max(h.stat().st_mtime for h in hits) >= t0 - 1, f"{f} not rewritten"


def test_report_figures_runs_a_study():
    script = STUDIES / "report_figures.py"
    name, files = promised(script)
    p = subprocess.run([sys.executable, str(script), "--fast", "--only", "seed_reproduction"],
                       capture_output=True, text=True, timeout=600, cwd=STUDIES.parent)
    assert p.returncode == 0, p.stderr[-2000:]
    import json
    rep = json.loads((STUDIES / "out" / name / files[0]).read_text())
    assert rep["seed_reproduction"]["status"] == "ok"
    assert any(f.endswith("seed_reproduction.png") for f in rep["seed_reproduction"]["figures"])


def test_seed_reproduction_numbers():
    import json
    p = subprocess.run([sys.executable, str(STUDIES / "seed_reproduction.py"), "--fast", "--json"],
                       capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr
    r = json.loads(p.stdout)
    ref = r["reference"]
    assert abs(ref.closing_time - 0.1491478) < 1e-7          # SPEC §8
    assert abs(ref.impact_theta_dot + 4.155764) < 1e-6
    assert abs(r["rk4_1ms_errors"]["impact_theta_dot"]) < 1e-6   # the default meets the target
    # the seed's Euler-Cromer at 1 kHz is first order and off by ~1e-3 .. 1e-2
    assert 1e-4 < abs(r["seed_errors"]["impact_theta_dot"]) < 5e-2
    assert 0.9 < r["observed_order"]["euler_cromer"] < 1.1
