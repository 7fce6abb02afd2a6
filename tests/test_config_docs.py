"""The docs' key tables are the key records: docs/model.md holds exactly what
``python -m softclose.config.docs`` generates, and every record is complete."""

from __future__ import annotations

from pathlib import Path

import pytest

from softclose.model import elements
from softclose.config import KEYS, RANGES, SCHEMA, TOLERANCE_KEYS, default_config, docs
from softclose.config.free import config_value

ROOT = Path(__file__).resolve().parents[1]


def test_model_md_key_tables_are_generated_from_the_records():
    text = (ROOT / "docs" / "model.md").read_text()
    assert docs.replace_block(text) == text, (
        "docs/model.md's key tables differ from the key records; run "
        "`python -m softclose.config.docs --write docs/model.md`")


@pytest.mark.parametrize("key", KEYS + TOLERANCE_KEYS, ids=lambda k: k.full)
def test_every_key_is_documented_and_ranged(key):
    assert key.doc, f"{key.full}: no doc line"
    if key.kind in ("pos", "nonneg", "real", "vec2", "vec3", "bounds"):
        assert key.range is not None, f"{key.full}: a number without an admissible range"
        assert key.unit or key.section in ("optimise", "tolerance", "simulate"), key.full
    if key.default is None and key.derive is not None:
        assert key.derived, f"{key.full}: a derived default the docs do not state"
    if key.default is None and key.derive is None:      # optional: the doc says what none is
        assert "none:" in key.doc, f"{key.full}: optional, but its doc does not say so"


def test_element_keys_are_in_the_config_and_its_tables():
    cfg = default_config()
    table = docs.tables()
    for e in elements.ELEMENTS:
        for k in e.keys:
            assert k.name in SCHEMA[k.section]
            assert hasattr(getattr(cfg, k.section), k.name)
            assert f"| `{k.name}` |" in table
            if k.range:
                assert RANGES[k.full] == k.range
    # every parameter of p is a config key with its default
    for q in elements.PARAMS:
        assert config_value(cfg, q.key, number=False) == next(k.default for k in KEYS if k.full == q.key)
