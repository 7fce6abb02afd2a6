"""A spring's kind (and a damper's one-way flag) as sweep keys: the words go in, the kernel
runs each row with its kind's law and valid range, and every table shows the words.

Known answers: each row of a grid over the kinds equals a simulation of that kind alone
(a second code path: one config per row, the simulator's own run); a kind whose spring would
leave its valid range is ``invalid`` with the simulator's own reason; the CSV round-trips.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

import softclose
from softclose.cli import main
from softclose.errors import ConfigError
from softclose.sweeps.space import make_grid, make_range, parse_grid_spec
from softclose.sweeps.store import read_csv, write_csv

KINDS = ["compression", "extension", "linear"]


@pytest.fixture(scope="module")
def base():
    return softclose.load_config().update({"design.damper_c": 3000.0,
                                           "design.spring_preload": 20.0})


@pytest.fixture(scope="module")
def swept(base):
    return softclose.sweep(base, {"design.spring_kind": KINDS,
                                  "design.spring_k": [1000.0, 2500.0],
                                  "design.spring_rest_length": [0.045, 0.07]})


def test_each_row_is_its_kind_simulated_alone(base, swept):
    df = swept.to_frame()
    assert list(df["design.spring_kind"].unique()) == KINDS      # words, in the given order
    statuses = set()
    for _, row in df.iterrows():
        cfg = base.update({"design.spring_kind": row["design.spring_kind"],
                           "design.spring_k": row["design.spring_k"],
                           "design.spring_rest_length": row["design.spring_rest_length"]})
        alone = softclose.simulate(cfg)
        if alone.status.name == "OUT_OF_RANGE":   # out of its valid range: the same reason
            assert row["status"] == "invalid"
            assert row["reason"] == alone.reason and "spring" in alone.reason
            statuses.add("invalid")
            continue
        statuses.add(row["status"])
        assert row["status"] == alone.status.name.lower().replace("_", " ")
        for m in ("closing_time", "impact_theta_dot", "holding_moment", "opening_force"):
            a, b = row[m], alone.metrics()[m]
            assert (np.isnan(a) and (b is None or np.isnan(b))) or a == pytest.approx(b, rel=1e-12)
    # the grid holds each outcome: the preload makes the kinds differ
    assert {"invalid", "closed"} <= statuses
    J = df.groupby("design.spring_kind")["closing_time"].max()
    assert J["compression"] != J["linear"]


def test_the_csv_shows_words_and_reads_back(swept, tmp_path):
    path = write_csv(swept.columns, swept.keys, tmp_path / "sweep.csv")
    first = path.read_text().splitlines()[1]
    assert '"compression"' in first
    back = read_csv(path, list(swept.keys))
    np.testing.assert_array_equal(back["design.spring_kind"], swept.columns["design.spring_kind"])


def test_words_are_checked():
    with pytest.raises(ConfigError, match="takes linear, extension, compression, gas_strut, got 'coil'"):
        parse_grid_spec("design.spring_kind=compression,coil")
    with pytest.raises(ConfigError, match="repeated"):
        parse_grid_spec("design.spring_kind=[linear, linear]")
    with pytest.raises(ConfigError, match="takes words, not a range"):
        make_range("design.spring_kind", 0, 1)
    with pytest.raises(ConfigError, match="takes true, false|takes false, true"):
        make_grid({"design.damper_one_way": ["maybe"]})
    key, v, log = parse_grid_spec("design.damper_one_way=[true, false]")
    assert key == "design.damper_one_way" and list(v) == [1.0, 0.0] and not log


def test_command_line_names_the_best_of_each_kind(tmp_path, capsys):
    out = tmp_path / "s"
    code = main(["sweep", "--grid", "design.spring_kind=compression,extension",
                 "--grid", "design.spring_k=1000:3000:3", "--set", "design.damper_c=3000",
                 "--set", "design.spring_rest_length=0.07", "--out", str(out), "--json"])
    assert code == 0
    payload = json.loads(capsys.readouterr().out)
    assert payload["space"][0] == "design.spring_kind (compression, extension)"
    assert payload["best"]["design.spring_kind"] == "compression"
    assert payload["infeasible_reasons"].get("invalid") == 3     # every extension row
    code = main(["sweep", "--grid", "design.spring_kind=compression,extension",
                 "--grid", "design.spring_k=1000:3000:3", "--set", "design.damper_c=3000",
                 "--set", "design.spring_rest_length=0.07", "--out", str(tmp_path / "s2")])
    text = capsys.readouterr().out
    assert "best objective by design.spring_kind: compression" in text
    assert "extension none feasible (0 feasible)" in text
    assert code == 0
    assert code == main(["sweep", "--range", "design.spring_kind=0:1", "--sample", "8",
                         "--out", str(tmp_path / "t")]) - 2
