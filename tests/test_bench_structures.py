"""The benchmark's NLP-structure rows (`softclose bench --structures`): what an NLP keyed by
its structure carries, and the recorded run the performance page quotes."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from softclose.bench.structures import COMMANDS, measure, structures_of
from softclose.bench.report import structures_markdown
from softclose.config import default_config
from softclose.optimiser import cache as oc
from softclose.optimiser.nlp import NLP_PARAMS

ROOT = Path(__file__).resolve().parents[1]
RECORD = json.loads((ROOT / "docs" / "bench_structures.json").read_text())
PERFORMANCE = (ROOT / "docs" / "performance.md").read_text()


def test_the_default_structure_carries_the_lid_as_parameters():
    """The default optimiser builds one structure; its parameters are the NLP's scalars, the
    time grid of N intervals and the lid vector (the numbers that used to be constants); its
    C is generated without compiling."""
    cfg = default_config()
    built = structures_of(cfg, False, ())
    assert [kind for kind, _ in built] == ["nominal"]
    row = measure(built[0][1], None)
    nlp = next(iter(oc._NLPS.values()))
    N = cfg.optimise.nodes
    assert row["parameters"] == len(NLP_PARAMS) + N + len(nlp.lid_vector)
    assert row["variables"] == nlp.structure.solver.size1_in(0)
    assert row["constraints"] == nlp.structure.solver.size1_out(2)
    assert row["c_mb"] > 1.0 and "compile_s" not in row


def test_the_record_measured_every_command_and_compiled_each_structure():
    commands = {name for name, _, _ in COMMANDS}
    rows = RECORD["rows"]
    assert {r["command"] for r in rows} <= commands and "optimise" in {r["command"] for r in rows}
    assert all(r["compile_s"] > 0 and r["c_mb"] > 0 for r in rows)
    assert {r["flags"] for r in rows if r["nlp"] == "nominal"} == {"-O1"}
    assert {r["flags"] for r in rows if r["nlp"] == "scenarios"} <= {"-O0"}


def test_prepare_compiles_a_structure_only_where_its_c_is_faster():
    """The record times one Hessian and one Jacobian of every structure in CasADi's virtual
    machine and compiled; ``softclose prepare`` compiles exactly the structures whose C was
    faster (the co-design's first-stage scenario NLP is the one it leaves to the virtual
    machine), and the structures built now say the same."""
    rows = RECORD["rows"]
    for r in rows:
        assert r["derivatives_vm_ms"] > 0 and r["derivatives_c_ms"] > 0
        assert r["prepared"] == (r["derivatives_c_ms"] < r["derivatives_vm_ms"]), r
    assert [r["prepared"] for r in rows if r["nlp"] == "scenarios"] == [True, False]
    built = {(k, bool(getattr(st, "placed", False))): st.prepared
             for name, robust, free in COMMANDS if name in ("optimise --robust",)
             for k, st in structures_of(default_config(), robust, free)}
    assert built == {("nominal", False): True, ("scenarios", False): True}


def test_the_performance_page_shows_the_record():
    block = PERFORMANCE.split("<!-- structures:begin -->")[1].split("<!-- structures:end -->")[0]
    assert block.strip() == structures_markdown(RECORD["rows"]).strip()


@pytest.mark.parametrize("rows", [RECORD["rows"][:1]])
def test_the_table_has_a_line_per_structure(rows):
    table = structures_markdown(rows).splitlines()
    assert len(table) == 2 + len(rows)
    assert f"{rows[0]['c_mb']:.2f} MB" in table[2] and f"`{rows[0]['command']}`" in table[2]


def test_a_bench_run_writes_the_structures_record(tmp_path):
    """`softclose bench --structures --out DIR` writes `structures.json` in the record's
    form (docs/bench_structures.json is that file of a run), beside `structures.csv`
    (:func:`softclose.bench.report.write_files` calls ``write_structures``)."""
    from softclose.bench.benchmark import BenchResult
    from softclose.bench.precision import WorkPrecision
    from softclose.bench.report import structures_record, write_structures
    wp = WorkPrecision((), {}, {}, {}, {}, {"method": "rk4", "step": 0.002, "confirmed": True,
                                             "meets_targets": True, "failing_designs": []}, ())
    res = BenchResult("AMD EPYC", "2026-12-06", "abc1234", True, wp, (), (), "", 3.0,
                      load=(0.1, 0.2), structures=tuple(RECORD["rows"]))
    files = write_structures(res, tmp_path)
    written = json.loads((tmp_path / "structures.json").read_text())
    assert tmp_path / "structures.json" in files and (tmp_path / "structures.csv").exists()
    assert written == json.loads(json.dumps(structures_record(res)))
    assert written["rows"] == RECORD["rows"] and written["machine"] == "AMD EPYC"
    assert set(RECORD) <= set(written)
    assert structures_markdown(written["rows"]) == structures_markdown(RECORD["rows"])
