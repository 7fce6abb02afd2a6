"""How results show in a notebook: a short repr and an HTML table with the numbers, their
units and accuracies, the limits, the yield with its interval and failures in plain words
(softclose.present.display)."""

from __future__ import annotations

import html as html_module
import math
import re

import numpy as np
import pytest

import softclose
from softclose.present.display import MAX_ROWS, Display, Table, interval, num, percent, pm, to_html


def text(html: str) -> str:
    """The visible text of an HTML fragment (tags dropped, entities read)."""
    return html_module.unescape(re.sub(r"\s+", " ", re.sub(r"<[^>]+>", " ", html)))


@pytest.fixture(scope="module")
def optimum(default_optimum):
    return default_optimum


def test_formatting_helpers():
    assert num(None) == "—" and num(float("nan")) == "—" and num(np.bool_(True)) == "yes"
    assert num(np.int64(1234567)) == "1,234,567" and num(0.1234567891) == "0.123457"
    assert pm(0.99999, 1.2e-8, "s") == "0.99999 s ± 1.2e-08"
    assert pm(None, 1e-3, "s") == "—"
    assert percent(0.432) == "43.2 %" and percent(0.9996) == "99.96 %"
    assert interval((0.4221, 0.4423)) == "42.2–44.2 %" and interval((0.9996, 1.0)) == "99.96–100 %"


def test_num_with_a_format_spec():
    """num(v, spec=...): the column format of the bench's and the stress survey's tables and
    the sweep maps' titles -- the number as the spec gives it (an integer too, no thousands
    separator), a word as it is, "—" for no value and for any value that is not finite."""
    assert num(2.345678, spec=".2f") == "2.35" and num(3, spec=".2f") == "3.00"
    assert num(12000, spec=".4g") == "1.2e+04" and num(np.float64(0.000123), spec=".1e") == "1.2e-04"
    assert num(True, spec=".4g") == "1" and num("coil", spec=".4g") == "coil"
    assert [num(v, spec=".2f") for v in (None, float("nan"), math.inf, -math.inf)] == ["—"] * 4
    assert num(math.inf) == "∞"           # (without a spec: an infinity is shown as one)


def test_html_escapes_text_and_cuts_long_tables():
    d = Display("a <b> & c", False, "x < y", (("k", "<v>"),),
                (Table("t", ("c",), [(i,) for i in range(MAX_ROWS + 5)]),))
    h = to_html(d)
    assert "<b>" not in h and "a &lt;b&gt; &amp; c" in h and "a <b> & c" in text(h)
    assert "&lt;v&gt;" in h and "x &lt; y" in h
    # one fact, the table's header and MAX_ROWS rows; the rest counted
    assert h.count("<tr>") == 1 + 1 + MAX_ROWS and "(5 more rows)" in h


def test_stroke_result(sim):
    res = sim.run()
    r = repr(res)
    assert r.startswith("<StrokeResult (rk4, step 0.002 s") and "\n" not in r and len(r) < 250
    t = text(res._repr_html_())
    assert f"{res.closing_time:.7g} s ± {res.accuracy['closing_time']:.1e}" in t
    assert f"{res.impact_tip_speed:.7g} m/s" in t and "holding_moment" in t and "N m" in t
    assert "estimated distance from the converged answer" in t


def test_stroke_result_that_fails_says_why(cfg):
    res = softclose.simulate(cfg.set("simulate.step", 0.2).set("design.spring_k", 1e4)
                             .set("design.damper_c", 5000.0))
    assert not res.ok
    t = text(res._repr_html_())
    assert res.message.split(";")[0] in t and "✗" in t


def test_optimise_result_shows_design_units_limits_and_verification(optimum):
    res = optimum
    h = res._repr_html_()
    t = text(h)
    assert "verified optimum" in t and "✓" in t
    for k, unit in (("spring_k", "N/m"), ("spring_rest_length", "m"), ("damper_c", "N s/m")):
        assert f"{k} {res.design[k]:.6g} {unit}" in t         # the facts: value and unit
    # verified metrics beside the optimiser's own, with the difference and its allowance
    ct = res.verification.agreement["closing_time"]
    assert f"{res.metrics['closing_time']:.7g} s" in t
    assert f"{ct['difference']:.1e} (allowed {ct['tolerance']:.1e})" in t
    # what limits it, in words, with dJ
    names = {a.name for a in res.active}
    assert {"closing_time_max", "holding_moment_min"} <= names
    for a in res.active:
        assert a.describe(res.objective) in t
    r = repr(res)
    assert "\n" not in r and len(r) <= 200 and f"{res.design['spring_k']:.6g} N/m" in r
    assert "OptimiseResult(" not in r      # not the 7,000-character dataclass dump


def test_optimise_failure_in_plain_words(cfg):
    res = softclose.optimise(cfg.set("optimise.closing_time_max", 0.05), starts=1)
    assert not res.success
    t = text(res._repr_html_())
    assert "✗" in t and res.message.split(";")[0][:60] in t
    assert repr(res).startswith("<OptimiseResult: no verified optimum")


def test_front_result(cfg):
    fr = softclose.front(cfg, [0.8, 1.2])
    t = text(fr._repr_html_())
    assert "closing_time_max [s]" in t and "spring_k [N/m]" in t
    for p in fr.points:
        assert f"{p.design['damper_c']:.6g}" in t
    assert "points = 2, 2 verified" in repr(fr)


def test_yield_and_sensitivity(cfg, optimum):
    c = cfg.with_design(**optimum.design)
    y = softclose.tolerance_analysis(c, samples=2000, reference=0)
    t = text(y._repr_html_())
    assert f"yield {percent(y.yield_)} (95 % interval {interval(y.yield_ci)}" in t
    assert "below the required 99 %" in t            # the nominal optimum's yield is ~43 %
    assert "tolerance box" in t and "±10 %" in t and "±20 %" in t
    for reason, n in y.failures.items():
        assert f"{reason} {num(n)}" in t
    assert repr(y).startswith("<YieldResult") and f"yield = {percent(y.yield_)}" in repr(y)
    s = softclose.sensitivity(c, samples=256)
    t = text(s._repr_html_())
    k = max(s.keys, key=lambda k: s.indices["closing_time"]["ST"][k])
    st = s.indices["closing_time"]
    assert f"{k} {st['S1'][k]:.3f} ± {st['S1_conf'][k]:.3f} {st['ST'][k]:.3f} ± " \
           f"{st['ST_conf'][k]:.3f}" in t
    assert f"closing_time driven by = {k}" in repr(s)


def test_sweep_shows_size_and_best_rows_never_every_row(cfg):
    axes = {"design.spring_k": np.linspace(500, 9500, 40),
            "design.spring_rest_length": np.linspace(0.05, 0.09, 30),
            "design.damper_c": np.linspace(100, 4000, 25)}
    res = softclose.sweep(cfg, axes)
    h = res._repr_html_()
    t = text(h)
    assert "30,000" in t and f"feasible {res.feasible:,}" in t
    assert len(h) < 12000                     # 30,000 rows, a few kilobytes of HTML
    best = res.best_rows()
    assert len(best) == 5
    df = res.to_frame()
    top = df[df.feasible].nsmallest(5, "objective")
    assert [r["id"] for r in best] == top["id"].tolist()
    assert f"{best[0]['objective']:.6g}" in t and str(best[0]["id"]) in t
    for reason, n in res.reasons.items():
        assert f"{reason} {n:,}" in t
    assert repr(res).startswith("<SweepResult: grid of 30,000 designs")


def test_robust_result_shows_both_yields(cfg):
    from softclose.robust.result import RobustResult
    from softclose.robust.analysis import YieldResult
    y = YieldResult(True, "", {"spring_k": 1.0}, ("design.spring_k",), "uniform", 100, 0, 0.97,
                    (0.915, 0.9938), 0.99, {"too slow": 3}, {"closing_time":
                                                            {"p1": 0.5, "p50": 0.8, "p99": np.inf}},
                    {"design.spring_k": {"nominal": 1.0, "low": 0.9, "high": 1.1,
                                         "spread": 0.1, "relative": True}})
    r = RobustResult(True, "", "Solve_Succeeded", {"spring_k": 1e4, "spring_rest_length": 0.056,
                                                   "damper_c": 5e3}, 0.1, "worst",
                     None, [], None, y, {"design": {"spring_k": 1914.7}}, y, {}, 1.0, [], {}, {})
    t = text(r._repr_html_())
    assert "yield 97 % (95 % interval 91.5–99.38 %, 100 samples)" in t
    assert "nominal optimum's yield 97 %" in t
    assert "closing_time [s] 0.5 0.8 not closed" in t     # +inf: a lid that did not close
    assert "objective (worst case) = 0.1" in repr(r)


def test_optimal_grid_result(cfg):
    from softclose.sweeps.optimal import optimise_grid
    res = optimise_grid(cfg, {"mass.lid": [0.4, 0.6]})
    t = text(res._repr_html_())
    assert "points 2 (2 over mass.lid)" in t and "verified 2" in t
    assert "mass.lid [kg]" in t and "spring_k [N/m]" in t
    assert f"{res.columns['spring_k'][1]:.6g}" in t and " yes" in t
    assert repr(res).startswith("<OptimalGridResult: the optimum at every grid point: ok")


def test_bench_result_names_missed_targets():
    from softclose.bench.benchmark import BenchResult
    from softclose.bench.timing import speed_row
    from softclose.bench.precision import WorkPrecision
    wp = WorkPrecision((), {}, {}, {}, {}, {"method": "rk4", "step": 0.002, "confirmed": True,
                                             "meets_targets": True, "failing_designs": []}, ())
    rows = (speed_row("run", "Simulator.run(p, estimate_error=False)", 130e-6, 300),
            speed_row("cli_simulate", "simulate start-up", 0.4, 9))
    b = BenchResult("AMD EPYC", "2026-11-25", "abc1234", False, wp, rows, (), "", 3.0,
                    load=(0.3, 0.4))
    t = text(b._repr_html_())
    assert "Simulator.run(p, estimate_error=False) 130 µs ≤ 500 µs yes" in t
    assert "simulate start-up 400 ms ≤ 300 ms NO" in t
    assert "targets missed: simulate start-up" in t and "0.30 → 0.40" in t
    assert "confirmed" in repr(b)
