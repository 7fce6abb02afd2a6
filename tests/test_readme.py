"""The README as a newcomer reads it: its Python study runs as written and gives the default
answer at the default mass; it has exactly two set-up commands; it links only inside the
repository."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text()


def _block_after(marker: str) -> str:
    m = re.search(re.escape(marker) + r"\s*```[a-z]*\n(.*?)```", README, re.S)
    assert m, f"no code block after {marker}"
    return m.group(1)


def test_two_setup_commands_and_no_links_outside_the_repository():
    assert README.count("<!-- main-command -->") == 1
    assert README.count("<!-- test-command -->") == 1
    assert "pip install ." in _block_after("<!-- main-command -->")
    assert 'pip install ".[test]"' in _block_after("<!-- test-command -->")
    links = re.findall(r"\]\(([^)]+)\)", README)
    assert links, "the README links its docs"
    for link in links:
        assert not link.startswith(("..", "/")), link
        assert (ROOT / link.split("#")[0]).exists(), link


@pytest.mark.slow
def test_python_example_runs_as_written(tmp_path):
    code = _block_after("<!-- python-example -->")
    (tmp_path / "study.py").write_text(code)
    run = subprocess.run([sys.executable, "study.py"], cwd=tmp_path, capture_output=True,
                         text=True, timeout=600)
    assert run.returncode == 0, run.stderr
    assert (tmp_path / "spring_against_lid_mass.png").read_bytes()[:4] == b"\x89PNG"
    rows = [line.split() for line in run.stdout.strip().splitlines()]
    header, body = rows[0], rows[1:]
    assert header[:5] == ["lid_mass", "spring_k", "spring_rest_length", "damper_c", "objective"]
    assert [float(r[0]) for r in body] == [0.4, 0.5, 0.6, 0.75]
    default = body[1]                        # 0.5 kg is the default lid: the default answer
    assert float(default[4]) == pytest.approx(0.0228995, rel=1e-5)
    assert float(default[1]) == pytest.approx(1914.7, rel=1e-4)
    assert all(r[-1] == "True" for r in body)
