"""The figures as a report reader looks at them (issue 26): the stroke figures' labels touch
no curve, the yield histograms' legend covers no bar, a sweep map's axes stay within the
grid, the animation shows the default stroke in at least 60 frames, and the bench says what a
"—" in its fitted orders means and under which load a target was missed."""

from __future__ import annotations

import os

import numpy as np
import pytest

from softclose.config import default_config
from softclose.present.figures import _curve_points, label_extent, plt
from softclose.simulation.simulator import Simulator

OPTIMUM = {"spring_k": 1914.709221517871, "spring_rest_length": 0.07925707423701318,
           "damper_c": 2087.754103066556}
DESIGNS = {"no spring, no damper": {}, "the optimum": OPTIMUM,
           "a lid that swings open": {"spring_k": 3000.0, "spring_rest_length": 0.1,
                                      "damper_c": 500.0}}


def _clear(fig, labels, twins=()):
    """Each label inside its axes and touching no line (curves, markers, the event line)."""
    renderer = fig.canvas.get_renderer()
    for ann in labels:
        ax = ann.axes
        box = label_extent(ann, renderer)
        frame = ax.get_window_extent(renderer)
        assert frame.x0 <= box.x0 and box.x1 <= frame.x1, ann.get_text()
        assert frame.y0 <= box.y0 and box.y1 <= frame.y1, ann.get_text()
        pts = np.concatenate([_curve_points(a) for a in (ax, *twins)])
        inside = ((pts[:, 0] >= box.x0) & (pts[:, 0] <= box.x1) & (pts[:, 1] >= box.y0)
                  & (pts[:, 1] <= box.y1))
        assert not inside.any(), f"{ann.get_text()!r} lies on a curve"
        for other in labels:
            if other is not ann and other.axes is ax:
                assert not box.overlaps(label_extent(other, renderer))


@pytest.mark.parametrize("design", list(DESIGNS.values()), ids=list(DESIGNS))
def test_stroke_figure_labels_sit_off_the_curves(design):
    from softclose.present.figures.stroke import plot_time_histories
    res = Simulator.from_config(default_config().with_design(**design)).run(trajectory=True)
    fig = plot_time_histories(res)
    assert len(fig.labels) == (3 if res.closed else 1)
    _clear(fig, fig.labels)
    plt.close(fig)


def test_optimum_figure_labels_sit_off_the_curves(default_optimum):
    r = default_optimum
    fig = r.plot()
    assert [a.get_text().split()[0] for a in fig.labels] == ["peak", "impact"]
    _clear(fig, fig.labels, twins=[a for a in fig.axes if a is not fig.labels[0].axes
                                   and a.get_ylabel().startswith("lid angle")])
    plt.close(fig)


def test_yield_legend_covers_no_bar():
    from matplotlib.patches import Rectangle

    from softclose.robust import tolerance_analysis
    r = tolerance_analysis(default_config().with_design(**OPTIMUM), samples=3000,
                           reference=0)
    fig = r.plot()
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    for ax in fig.axes:
        legend = ax.get_legend().get_window_extent(renderer)
        bars = [p for p in ax.patches if isinstance(p, Rectangle) and p.get_height() > 0]
        assert bars
        assert not any(legend.overlaps(b.get_window_extent(renderer)) for b in bars)
        assert not legend.overlaps(ax.get_window_extent(renderer))   # below the panel
    plt.close(fig)


def test_sweep_map_axes_stay_within_the_grid():
    """The issue's map: damper_c = [100, 1000, 4000] ran from -350 to 5500 N s/m."""
    from softclose.present.figures.sweep import plot_maps
    from softclose.sweeps import sweep
    res = sweep(default_config(), {"design.spring_k": np.linspace(500, 9500, 7),
                                   "design.damper_c": [100.0, 1000.0, 4000.0]})
    figs = plot_maps(res)
    fig = figs["map_design_spring_k__design_damper_c"]
    panels = [a for a in fig.axes if a.get_title()]
    assert len(panels) == 4
    for ax in panels:
        assert ax.get_xlim() == (500.0, 9500.0)
        assert ax.get_ylim() == (100.0, 4000.0)
    for f in figs.values():
        plt.close(f)
    res = sweep(default_config(), {"design.damper_c": [100.0, 1000.0, 4000.0]})
    fig = plot_maps(res)["profile_design_damper_c"]
    assert all(ax.get_xlim() == (100.0, 4000.0) for ax in fig.axes)
    plt.close(fig)


def test_sweep_map_names_each_fixed_key_s_unit():
    from softclose.present.figures.sweep import unit
    assert unit("design.torsion_k") == "N m/rad"
    assert unit("design.torsion_free_angle_deg") == "deg"
    assert unit("geometry.assembly[1]") == "deg" and unit("geometry.pivot_b[0]") == "m"


def test_sweep_map_note_gives_a_word_key_no_unit():
    """A kind held fixed reads "spring_kind = compression", numbers keep their units."""
    from softclose.present.figures.sweep import _views
    from softclose.sweeps import sweep
    cfg = default_config().update({"design.spring_kind": "compression",
                                   "design.spring_rest_length": 0.09})
    res = sweep(cfg, {"design.damper_c": [1000.0, 4000.0]})
    note = _views(res)[0].note.split("not swept: ", 1)[1]
    assert note.endswith("spring_kind = compression") and "compression -" not in note
    assert "spring_k = 0 N/m" in note and "spring_rest_length = 0.09 m" in note


def test_the_default_stroke_shows_at_least_60_frames(tmp_path):
    from PIL import Image

    from softclose.present.figures.stroke import FPS, slow_motion_factor, write_animation
    sim = Simulator.from_config(default_config())
    res = sim.run(trajectory=True)
    assert res.closing_time == pytest.approx(0.1491478, abs=1e-7)
    assert slow_motion_factor(res.closing_time) == 20          # 0.149 s x 20 x 25/s
    path = write_animation(sim.model, res.trajectory, tmp_path / "a.gif")
    gif = Image.open(path)
    assert gif.n_frames == 76 and gif.info["duration"] == 1000 // FPS
    # real time, as before: 4 frames for the stroke and its last instant
    gif = Image.open(write_animation(sim.model, res.trajectory, tmp_path / "b.gif",
                                     slow_motion=1))
    assert gif.n_frames == 5
    # a 1 s stroke needs x5 (125 frames); a long one plays at most 60 s
    assert slow_motion_factor(1.0) == 5 and slow_motion_factor(5.0, 1000) == 12


def test_simulate_slow_motion_option(tmp_path, capsys):
    from PIL import Image

    from softclose import cli
    assert cli.main(["simulate", "--out", str(tmp_path), "--slow-motion", "2"]) == 0
    assert Image.open(tmp_path / "stroke_animation.gif").n_frames == 9
    for bad in ("0.5", "nan", "abc", "2000"):
        assert cli.main(["simulate", "--out", str(tmp_path), "--slow-motion", bad]) == 2
        err = capsys.readouterr()[1].strip()
        assert err.startswith(f"softclose: error: --slow-motion {bad}:"), err


def test_bench_says_why_an_order_is_missing_and_under_which_load():
    from softclose.bench.report import ORDER_DASH, met_text, speed_markdown
    from softclose.bench.timing import speed_row
    row = speed_row("cli_simulate", "cli", 0.31, 3)
    assert row["met"] is False and "load" in row
    assert met_text({**row, "load": 2.04}) == "**no** (loaded: 2.0)"
    assert met_text({**row, "load": 0.2}) == "**no**"
    table = speed_markdown([{**row, "load": 2.04}])
    assert "| **no** (loaded: 2.0) | 2.0 |" in table
    assert "The targets are set for an idle machine (load below 0.5)" in table
    assert ORDER_DASH.startswith("— : no slope fitted.")


def test_bench_load_is_the_other_processes_not_the_bench_s_own():
    """A row's load counts what other processes used while it was measured: the bench's
    own busy loop (or its child's) is not load, another process spinning is (about a core)."""
    import subprocess
    import sys
    import time

    from softclose.bench.timing import OtherLoad

    def spin(seconds):
        t = time.perf_counter()
        while time.perf_counter() - t < seconds:
            pass
    with OtherLoad() as own:
        spin(0.6)
        subprocess.run([sys.executable, "-c", "import time\nt=time.time()\nwhile "
                        "time.time()-t<0.6: pass"], check=True)
    p = subprocess.Popen([sys.executable, "-c", "while True: pass"])
    try:
        time.sleep(0.3)
        with OtherLoad() as other:
            time.sleep(1.0)
    finally:
        p.kill()
        p.wait()
    assert own.value is not None and other.value is not None
    cores = os.cpu_count() or 1
    if own.value > cores - 1.2:     # no free core for the spinner: nothing to tell apart
        pytest.skip(f"the machine is busy ({own.value:.2f} of {cores} cores used by others)")
    assert other.value - own.value >= 0.4, (own.value, other.value)
