"""Every number of the README comes from a command a reader can run (issue 26): its table
"Where the numbers come from" names the command of each figure; this test recomputes the
results at the digits quoted, holds the timings within the stated band (±35 %) of the
recorded idle `softclose bench` run (docs/bench_speed.json), and checks that each figure of
the table is quoted in the README's text."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from softclose.config import default_config

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text()
RECORD = json.loads((ROOT / "docs" / "bench_speed.json").read_text())
#: the README's timings lie within this fraction of the recorded bench run
BAND = 0.35
NUMBER = re.compile(r"(?<![\w.])\d[\d,]*(?:\.\d+)?(?:e-?\d+)?")


def _table() -> dict[str, tuple[str, str]]:
    block = README.split("<!-- numbers:begin -->")[1].split("<!-- numbers:end -->")[0]
    rows = {}
    for line in block.strip().splitlines()[2:]:
        cells = [c.strip() for c in line.strip().strip("|").split(" | ")]
        rows[cells[0]] = (cells[1], cells[2])
    return rows


TABLE = _table()
PROSE = README.split("## Where the numbers come from")[0]


def _numbers(text: str) -> list[str]:
    return NUMBER.findall(text)


def test_the_table_names_a_command_for_every_figure_and_the_text_quotes_it():
    assert {"optimum", "nominal_yield", "robust", "sobol", "robust_optimise",
            "sweep_cli_40000", "kernel_40000", "cli_simulate", "tests"} <= set(TABLE)
    for key, (figure, command) in TABLE.items():
        assert "softclose" in command or "pytest" in command or "python" in command, key
        prose = PROSE.replace("\n", " ")
        for n in _numbers(figure):
            assert n in prose, f"{key}: {n} is in the table but not in the text"


@pytest.fixture(scope="module")
def optimum():
    import softclose
    return softclose.optimise(default_config())


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
    from softclose.simulate import Simulator
    o = default_config().optimise
    quoted = {k: float(f"{v:.7g}") for k, v in optimum.design.items()}
    r = Simulator(default_config().with_design(**quoted)).run()
    assert r.closing_time <= o.closing_time_max and r.holding_moment >= o.holding_moment_min
    r = Simulator(default_config().with_design(
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
def robust():
    import softclose
    return softclose.optimise(default_config(), robust=True)


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
    s = [e for e in springs.parts if e.part == "GS-070-F010"]
    d = [e for e in dampers.parts if e.part == "DP-6000"]
    e = select(default_config(), s, d, verify=1).best
    assert e["feasible"] and e["verified"]
    assert (s[0].preload, s[0].free_length, s[0].rate, d[0].c) == (10.0, 0.070, 150.0, 6000.0)
    ratio = e["worst_objective"] / robust.objective
    r = robust.design
    l0 = r["spring_rest_length"]
    part = SpringEntry("robust", robust.kind, r["spring_k"], l0, 0.0, None, None, 0.1,
                       standard_free_length_tolerance(l0))
    own = select(default_config(), [part], [DamperEntry("c", "dashpot", r["damper_c"], None,
                                                        0.2)], verify=0).best
    assert TABLE["catalog"][0] == (
        f"{len(springs) * len(dampers):,} pairs; 10 N, 70 mm, 150 N/m, 6,000 N s/m; "
        f"{100 * e['yield']:.0f} %, {e['worst_objective']:.3f}; {ratio:.2f}, "
        f"{robust.objective:.4f}; ±{1e3 * part.free_length_tolerance:.1f} mm, "
        f"{100 * own['yield']:.0f} %")


# -- timings: within the band of the recorded idle bench run --------------------------------
#: id -> (the record's quantity, how the README's figure gives it)
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
def test_readme_timings_lie_within_the_band_of_the_bench_record(key):
    lo, hi = _value(TABLE[key][0])
    measured = RECORD["rows"][key][TIMINGS[key]]
    assert lo * (1 - BAND) <= measured <= hi * (1 + BAND), \
        f"{key}: the README says {TABLE[key][0]}, the bench record {measured:.4g}"
