"""Streaming output and resume: a real SIGINT in a subprocess after some chunks, then
``--resume``, gives exactly the table of an uninterrupted run (every id once); a folder of
another sweep is refused without touching it."""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from softclose.cli import main
from softclose.sweeps import store

ROOT = Path(__file__).resolve().parents[1]
GRID = ["--grid", "design.spring_k=500:9500:30",
        "--grid", "design.spring_rest_length=0.05:0.09:25",
        "--grid", "design.damper_c=100:4000:[N]"]


def _grid(n):
    return [g.replace("[N]", str(n)) for g in GRID]


def _cmd(*args):
    return [sys.executable, "-m", "softclose", "sweep", *args]


def _interrupt(argv, out: Path, parts) -> subprocess.CompletedProcess:
    """Run ``argv``, send SIGINT once ``parts(out)`` finished chunks exist, wait for it."""
    p = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                         cwd=ROOT)
    t0 = time.time()
    while parts(out) < 2 and p.poll() is None and time.time() - t0 < 300:
        time.sleep(0.005)
    if p.poll() is None:
        p.send_signal(signal.SIGINT)
    o, e = p.communicate(timeout=300)
    return subprocess.CompletedProcess(argv, p.returncode, o, e)


def _frame(out: Path, fmt: str) -> pd.DataFrame:
    if fmt == "parquet":
        return pd.read_parquet(out / store.DATASET).sort_values("id").reset_index(drop=True)
    text = ("status", "reason")      # empty cells are NaN in number columns, "" in text
    f = pd.read_csv(out / store.CSV, keep_default_na=False, na_values={
        c: [""] for c in pd.read_csv(out / store.CSV, nrows=0).columns if c not in text})
    return f


def _parquet_parts(out: Path) -> int:
    return len(list((out / store.DATASET).glob("part-*.parquet")))


def _csv_progress(wait: float):
    """A CSV run writes its table at the end: count as "2 chunks done" ``wait`` seconds
    after its manifest appeared (the run has started computing by then)."""
    seen = []

    def parts(out: Path) -> int:
        if not (out / store.MANIFEST).exists():
            return 0
        if not seen:
            seen.append(time.time())
        return 2 if time.time() - seen[0] > wait else 0
    return parts


@pytest.mark.parametrize("fmt, count", [("parquet", 12), ("csv", 40)])
def test_sigint_then_resume_equals_an_uninterrupted_run(tmp_path, fmt, count):
    full, cut = tmp_path / "full", tmp_path / "cut"
    n = 30 * 25 * count                                 # chunks of 200 designs
    opts = [*_grid(count), "--chunk", "200", "--format", fmt, "--threads", "1"]
    p = subprocess.run(_cmd(*opts, "--out", str(full), "--json"), capture_output=True,
                       text=True, cwd=ROOT)
    assert p.returncode == 0, p.stderr
    # a CSV run shows no chunk before its end: it is interrupted a while after it started,
    # longer again if on a busy machine no chunk had finished by then (it starts afresh)
    for wait in ((None,) if fmt == "parquet" else (0.5, 1.5, 4.5)):
        parts = _parquet_parts if wait is None else _csv_progress(wait)
        if cut.exists():
            shutil.rmtree(cut)
        r = _interrupt(_cmd(*opts, "--out", str(cut), "--json"), cut, parts)
        if r.returncode == 0:
            pytest.skip("the sweep finished before the signal arrived")
        assert r.returncode == 130, r.stderr
        payload = json.loads(r.stdout)
        if payload["computed"] > 0:
            break
    assert payload["interrupted"] and 0 < payload["computed"] < n
    assert payload["resume"] == f"softclose sweep --resume {cut}"
    assert "Traceback" not in r.stderr
    done = _frame(cut, fmt)
    assert len(done) == payload["computed"] and len(done) % 200 == 0
    assert not list(cut.glob("*.png"))
    # resume: only the missing chunks are computed
    q = subprocess.run(_cmd("--resume", str(cut), "--json"), capture_output=True, text=True,
                       cwd=ROOT)
    assert q.returncode == 0, q.stderr
    again = json.loads(q.stdout)
    assert again["computed"] == n and again["stages"]["resumed"] == payload["computed"]
    assert again["stages"]["evaluated"] == n - payload["computed"]
    a, b = _frame(full, fmt), _frame(cut, fmt)
    assert np.array_equal(b["id"], np.arange(n))              # every id exactly once
    pd.testing.assert_frame_equal(a, b, check_exact=True)
    full_json = json.loads(p.stdout)
    assert again["best"] == full_json["best"]
    assert again["infeasible_reasons"] == full_json["infeasible_reasons"]
    assert sorted(x.name for x in cut.glob("*.png")) == sorted(x.name for x in full.glob("*.png"))
    assert json.loads((cut / store.MANIFEST).read_text())["complete"] is True


def test_resume_refuses_another_sweep_and_touches_nothing(tmp_path, capsys):
    out = tmp_path / "s"
    argv = ["sweep", "--grid", "design.spring_k=0:2000:5", "--grid", "design.damper_c=0:500:3",
            "--format", "parquet", "--chunk", "4", "--out", str(out)]
    assert main(argv) == 0
    capsys.readouterr()
    before = {p: p.stat().st_mtime_ns for p in out.rglob("*")}
    cases = [
        (["--grid", "design.spring_k=0:2000:6", "--grid", "design.damper_c=0:500:3"],
         "grid values of design.spring_k differ"),
        (["--grid", "design.spring_k=0:2000:5", "--grid", "mass.lid=0.4:0.6:3"], "grid keys"),
        (["--set", "mass.lid=0.6"], "config key mass.lid: 0.5 in the folder, 0.6 here"),
        (["--chunk", "8"], "chunk size: 4 in the folder, 8 here"),
        (["--format", "csv"], "format: 'parquet' in the folder, 'csv' here"),
        (["--sample", "8", "--range", "design.damper_c=1:10"], "a grid in the folder"),
    ]
    for extra, words in cases:
        code = main(["sweep", "--resume", str(out), *extra])
        err = capsys.readouterr().err.strip().splitlines()
        assert code == 2 and len(err) == 1 and words in err[0], (extra, err)
        assert "a different sweep" in err[0]
    assert {p: p.stat().st_mtime_ns for p in out.rglob("*")} == before
    # no sweep there, or another folder
    assert main(["sweep", "--resume", str(tmp_path)]) == 2
    assert "manifest.json missing" in capsys.readouterr().err
    assert main(["sweep", "--resume", str(out), "--out", str(tmp_path)]) == 2
    # a finished sweep resumed: nothing left to compute, the same table
    assert main(["sweep", "--resume", str(out), "--json"]) == 0
    s = json.loads(capsys.readouterr().out)
    assert s["stages"]["evaluated"] == 0 and s["computed"] == 15 and s["stages"]["resumed"] == 15


def test_an_unfinished_sweep_is_not_overwritten(tmp_path, capsys):
    out = tmp_path / "s"
    argv = ["sweep", "--grid", "design.spring_k=0:2000:5", "--format", "parquet", "--chunk",
            "2", "--out", str(out)]
    assert main(argv) == 0
    m = json.loads((out / store.MANIFEST).read_text())
    (out / store.MANIFEST).write_text(json.dumps({**m, "complete": False}))
    (out / store.DATASET / "part-000001.parquet").unlink()       # as after Ctrl-C
    capsys.readouterr()
    assert main(argv) == 2
    assert "holds an unfinished sweep" in capsys.readouterr().err
    assert sorted(p.name for p in (out / store.DATASET).iterdir()) == [
        "part-000000.parquet", "part-000002.parquet"]
    # resume computes the missing chunk only
    assert main(["sweep", "--resume", str(out), "--json"]) == 0
    s = json.loads(capsys.readouterr().out)
    assert s["stages"]["evaluated"] == 2 and s["stages"]["resumed"] == 3
    # a finished sweep is replaced by a new one in its folder
    assert main(["sweep", "--grid", "design.spring_k=0:2000:3", "--format", "parquet",
                 "--out", str(out), "--json"]) == 0
    f = pd.read_parquet(out / store.DATASET)
    assert len(f) == 3


def test_parquet_table_equals_csv_table(tmp_path, capsys):
    g = ["--grid", "design.spring_k=0:3000:7", "--grid", "design.damper_c=[0, 1500, 4000]"]
    assert main(["sweep", *g, "--out", str(tmp_path / "c")]) == 0
    assert main(["sweep", *g, "--format", "parquet", "--chunk", "5", "--out",
                 str(tmp_path / "p")]) == 0
    a = _frame(tmp_path / "c", "csv")
    b = _frame(tmp_path / "p", "parquet")
    pd.testing.assert_frame_equal(a, b, check_exact=True, check_dtype=False)
    assert os.path.getsize(tmp_path / "p" / "map_design_spring_k__design_damper_c.png") > 10_000
