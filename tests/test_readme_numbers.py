"""Every number of the documents comes from a command a reader can run: the table of
docs/numbers.md ("Where the numbers come from") names the command of each figure; this test
recomputes the results at the digits quoted, holds the timings (and every row of the speed
table of docs/performance.md) within the stated band (±35 %) of the recorded idle
`softclose bench` run (docs/bench_speed.json), and checks that each figure of the table is
quoted in the text of the README or of a page of the documentation."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from softclose.config import default_config

ROOT = Path(__file__).resolve().parents[1]
NUMBERS = (ROOT / "docs" / "numbers.md").read_text()
PERFORMANCE = (ROOT / "docs" / "performance.md").read_text()
#: the text of the README and of every page of the documentation but the table's own
DOCUMENTS = "\n".join([(ROOT / "README.md").read_text()] + [
    p.read_text() for p in sorted((ROOT / "docs").glob("*.md")) if p.name != "numbers.md"])
RECORD = json.loads((ROOT / "docs" / "bench_speed.json").read_text())
#: the documents' timings lie within this fraction of the recorded bench run
BAND = 0.35
NUMBER = re.compile(r"(?<![\w.])\d[\d,]*(?:\.\d+)?(?:e-?\d+)?")


def _table() -> dict[str, tuple[str, str]]:
    block = NUMBERS.split("<!-- numbers:begin -->")[1].split("<!-- numbers:end -->")[0]
    rows = {}
    for line in block.strip().splitlines()[2:]:
        cells = [c.strip() for c in line.strip().strip("|").split(" | ")]
        rows[cells[0]] = (cells[1], cells[2])
    return rows


TABLE = _table()
PROSE = DOCUMENTS


def _numbers(text: str) -> list[str]:
    return NUMBER.findall(text)


def test_the_table_names_a_command_for_every_figure_and_the_text_quotes_it():
    assert {"optimum", "nominal_yield", "robust", "sobol", "robust_optimise",
            "sweep_cli_40000", "kernel_40000", "cli_simulate"} <= set(TABLE)
    for key, (figure, command) in TABLE.items():
        assert "softclose" in command or "pytest" in command or "python" in command, key
        prose = PROSE.replace("\n", " ")
        for n in _numbers(figure):
            assert n in prose, f"{key}: {n} is in the table but not in the text"


@pytest.fixture(scope="module")
def optimum(default_optimum):
    return default_optimum


def test_optimum(optimum):
    d, m = optimum.design, optimum.metrics
    figure = TABLE["optimum"][0]
    assert (f"spring_k = {d['spring_k']:.7g} N/m, spring_rest_length = "
            f"{d['spring_rest_length']:.7g} m, damper_c = {d['damper_c']:.7g} N s/m, "
            f"J = {optimum.verified_objective:.7g}") in figure
    assert (f"{m['closing_time']:.3f} s, {m['impact_tip_speed']:.3g} m/s, "
            f"{m['peak_tip_speed']:.3g} m/s, {m['holding_moment']:.2g} N m") in figure


def test_the_quoted_digits_reproduce_the_optimum_and_rounder_ones_do_not(optimum):
    """7 digits keep the design within both active limits; the old 3-4 digits do not."""
    from softclose.simulation.simulator import Simulator
    o = default_config().optimise
    quoted = {k: float(f"{v:.7g}") for k, v in optimum.design.items()}
    r = Simulator.from_config(default_config().with_design(**quoted)).run()
    assert r.closing_time <= o.closing_time_max and r.holding_moment >= o.holding_moment_min
    r = Simulator.from_config(default_config().with_design(
        spring_k=1915.0, spring_rest_length=0.0793, damper_c=2088.0)).run()
    assert f"0.0793 m: {r.closing_time:.5g} s, {r.holding_moment:.3g} N m" == \
        TABLE["rounded"][0]


def test_nominal_yield(optimum):
    from softclose.robust import tolerance_analysis
    y = tolerance_analysis(optimum.design_config(), reference=0)
    lo, hi = y.yield_ci
    assert TABLE["nominal_yield"][0] == (f"{100 * y.yield_:.2f} %, {100 * lo:.2f}–"
                                         f"{100 * hi:.2f} %, {y.samples:,} samples")


@pytest.fixture(scope="module")
def robust(default_robust):
    return default_robust


def test_robust(robust):
    d, (lo, hi) = robust.design, robust.yield_ci
    assert TABLE["robust"][0] == (
        f"spring_k = {d['spring_k']:.7g} N/m, spring_rest_length = "
        f"{d['spring_rest_length']:.7g} m, damper_c = {d['damper_c']:.7g} N s/m, "
        f"{100 * robust.yield_:.0f} % ({100 * lo:.2f}–{100 * hi:.0f} %), "
        f"{robust.objective:.3f} instead of {robust.nominal['objective']:.3f}")


def test_sobol(optimum, robust):
    from softclose.robust import sensitivity
    spring = sensitivity(optimum.design_config()).indices["closing_time"]["ST"]
    damper = sensitivity(robust.design_config()).indices["closing_time"]["ST"]
    assert max(spring, key=spring.get) == "design.spring_k"
    assert max(damper, key=damper.get) == "design.damper_c"
    assert TABLE["sobol"][0] == (f"{spring['design.spring_k']:.2f} (the optimum's spring), "
                                 f"{damper['design.damper_c']:.2f} (the robust design's "
                                 "damper)")


def test_catalog(robust):
    """The best pair of the illustrative catalog (studies/catalog_selection.py ranks all
    3,445) over its own box, against the robust optimum, and that optimum made as a part."""
    from softclose.catalog import (DamperEntry, SpringEntry, read_dampers, read_springs,
                                   select, standard_free_length_tolerance)
    cat = ROOT / "examples" / "catalogs"
    springs, dampers = read_springs(cat / "springs.csv"), read_dampers(cat / "dampers.csv")
    assert len(springs) * len(dampers) == 3445
    s = [e for e in springs.parts if e.part == "GS-060-F010"]
    d = [e for e in dampers.parts if e.part == "DP-6000"]
    e = select(default_config(), s, d, verify=1).best
    assert e["feasible"] and e["verified"]
    assert (s[0].spring_kind, s[0].preload, s[0].free_length, s[0].progression, d[0].c) == \
        ("gas_strut", 10.0, 0.060, 1.2, 6000.0)
    ratio = e["worst_objective"] / robust.objective
    r = robust.design
    l0 = r["spring_rest_length"]
    part = SpringEntry("robust", robust.kind, r["spring_k"], l0, 0.0, None, None, 0.1,
                       standard_free_length_tolerance(l0))
    own = select(default_config(), [part], [DamperEntry("c", "dashpot", r["damper_c"], None,
                                                        0.2)], verify=0).best
    assert TABLE["catalog"][0] == (
        f"{len(springs) * len(dampers):,} pairs; 10 N, 60 mm, progression 1.2, 6,000 N s/m; "
        f"{100 * e['yield']:.0f} %, {e['worst_objective']:.3f}; {ratio:.2f}, "
        f"{robust.objective:.4f}; ±{1e3 * part.free_length_tolerance:.1f} mm, "
        f"{100 * own['yield']:.0f} %")


# -- timings: within the band of the recorded idle bench run --------------------------------
#: id -> (the record's quantity, how the documents' figure gives it)
TIMINGS = {"robust_optimise": "median_s", "sweep_cli_40000": "median_s",
           "kernel_40000": "rate", "cli_simulate": "median_s"}


def _value(text: str) -> tuple[float, float]:
    """(low, high) of a quoted figure: 'about 3 s', '1.4–1.7 s', '98,500–108,600 designs/s'."""
    nums = [float(n.replace(",", "")) for n in _numbers(text.split("(")[0])]
    assert nums, text
    return min(nums[:2]), max(nums[:2])


def test_the_record_is_an_idle_run():
    idle = RECORD["idle_load"]
    for key in TIMINGS:
        row = RECORD["rows"][key]
        assert row["median_s"] is not None, key
        assert row["load"] is not None and row["load"] <= idle, \
            f"{key} was recorded at load {row['load']}: record an idle run"


@pytest.mark.parametrize("key", list(TIMINGS))
def test_quoted_timings_lie_within_the_band_of_the_bench_record(key):
    lo, hi = _value(TABLE[key][0])
    measured = RECORD["rows"][key][TIMINGS[key]]
    assert lo * (1 - BAND) <= measured <= hi * (1 + BAND), \
        f"{key}: the documents say {TABLE[key][0]}, the bench record {measured:.4g}"


#: a duration of the performance page's speed table, in seconds
UNITS = {"µs": 1e-6, "ms": 1e-3, "s": 1.0}


def _speed_table() -> dict[str, list[str]]:
    block = PERFORMANCE.split("<!-- speed:begin -->")[1].split("<!-- speed:end -->")[0]
    rows = {}
    for line in block.strip().splitlines()[2:]:
        cells = [c.strip() for c in line.strip().strip("|").split(" | ")]
        rows[cells[0].strip("`")] = cells
    return rows


def test_the_speed_table_is_the_bench_record():
    """docs/performance.md's speed table: a row for every row of the record, each median
    (and rate) within the band of the record's."""
    rows = _speed_table()
    assert set(rows) == set(RECORD["rows"])
    for key, cells in rows.items():
        rec = RECORD["rows"][key]
        value, unit = cells[2].split()
        median = float(value.replace(",", "")) * UNITS[unit]
        assert median == pytest.approx(rec["median_s"], rel=BAND), (key, cells[2])
        if rec["rate"] is not None and rec["unit"]:
            rate = float(_numbers(cells[3])[0].replace(",", ""))
            assert rate == pytest.approx(rec["rate"], rel=BAND), (key, cells[3])
