"""The example notebooks (examples/*.ipynb): committed without outputs, and each runs from
top to bottom in a fresh kernel in its FAST mode (nbclient + ipykernel, as a user's Jupyter
would run it); the explorer's update function, without a browser."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import softclose

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
NOTEBOOKS = sorted(EXAMPLES.glob("*.ipynb"))


def test_there_are_the_four_examples():
    assert [p.name for p in NOTEBOOKS] == ["01_first_design.ipynb", "02_lid_masses.ipynb",
                                           "03_robust_and_yield.ipynb", "04_sweep_map.ipynb"]


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_committed_without_outputs(path):
    nbformat = pytest.importorskip("nbformat")
    nb = nbformat.read(path, as_version=4)
    nbformat.validate(nb)
    for cell in nb.cells:
        if cell.cell_type == "code":
            assert cell.outputs == [] and cell.execution_count is None, \
                f"{path.name}: a cell has outputs; clear them before committing"
    params = [c for c in nb.cells if "parameters" in c.metadata.get("tags", [])]
    assert len(params) == 1 and "FAST = False" in params[0].source


@pytest.mark.slow
@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_notebook_runs(path, tmp_path):
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    pytest.importorskip("ipykernel")
    nb = nbformat.read(path, as_version=4)
    for cell in nb.cells:
        if "parameters" in cell.metadata.get("tags", []):
            cell.source = cell.source.replace("FAST = False", "FAST = True")
    client = nbclient.NotebookClient(nb, timeout=300, kernel_name="python3",
                                     resources={"metadata": {"path": str(tmp_path)}})
    client.execute()
    html = [o for c in nb.cells if c.cell_type == "code" for o in c.outputs
            if "text/html" in o.get("data", {})]
    assert html, "no result displayed as a table"
    if path.stem == "01_first_design":    # the optimum shows as a table with units
        assert "N/m" in html[0]["data"]["text/html"] and "verified" in html[0]["data"]["text/html"]
        assert any("application/vnd.jupyter.widget-view+json" in o.get("data", {})
                   for o in nb.cells[-1].outputs)
    if path.stem == "04_sweep_map":
        assert (tmp_path / "sweep_map.pdf").read_bytes()[:4] == b"%PDF"


@pytest.fixture(scope="module")
def explorer(cfg):
    from softclose.notebook.explorer import Explorer
    return Explorer(cfg.with_design(spring_k=1914.7, spring_rest_length=0.07926,
                                    damper_c=2087.8), n=9)


def test_explorer_update_is_the_stroke_of_the_sliders(explorer, cfg):
    d = explorer.update(1914.7, 0.07926, 2087.8, 0.5)
    ref = softclose.simulate(explorer.cfg, trajectory=True)
    m = d["metrics"]
    assert m["closing_time"] == ref.closing_time and m["peak_tip_speed"] == ref.peak_tip_speed
    assert m["holding_moment"] == pytest.approx(ref.holding_moment, rel=1e-9)
    assert np.array_equal(d["theta"], ref.trajectory["theta"])
    assert np.array_equal(d["tip_speed"], ref.trajectory["tip_speed"])
    assert np.array_equal(d["spring_length"], ref.trajectory["spring_length"])
    # the map: n x n around the design, its centre the design itself
    assert d["J"].shape == (9, 9) and d["k"][4] == pytest.approx(1914.7)
    assert d["J"][4, 4] == pytest.approx(m["objective"], rel=1e-12)


def test_explorer_lid_mass_moves_the_stroke_as_a_new_config(explorer, cfg):
    d = explorer.update(1914.7, 0.07926, 2087.8, 0.6)
    ref = softclose.simulate(explorer.cfg.set("mass.lid", 0.6))
    assert d["metrics"]["closing_time"] == pytest.approx(ref.closing_time, abs=1e-9)
    assert d["metrics"]["impact_theta_dot"] == pytest.approx(ref.impact_theta_dot, rel=1e-7)


def test_explorer_widget_redraws_when_a_slider_moves(explorer):
    pytest.importorskip("ipywidgets")
    box = explorer.widget()
    title = box.view.fig.axes[0].get_title()
    box.sliders["damper_c"].value = 3000.0
    assert box.view.fig.axes[0].get_title() != title
    assert "1.480 s" in box.view.fig.axes[0].get_title()
    assert box.sliders["spring_k"].min == explorer.cfg.optimise.spring_k[0]
