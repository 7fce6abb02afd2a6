"""SPEC §15: single-pivot (hinge) lids."""

import pytest

from softclose.config import from_dict
from softclose.errors import ConfigError


def test_hinge_keys_and_defaults():
    cfg = from_dict({"geometry": {"mechanism": "hinge"}})
    assert cfg.geometry.mechanism == "hinge"
    assert tuple(cfg.geometry.hinge) == (0.0, 0.0)
    assert from_dict({}).geometry.mechanism == "four_bar"


@pytest.mark.parametrize("section,key,value", [
    ("geometry", "crank_oa", 0.05), ("geometry", "pivot_b", [0.1, 0.0]),
    ("geometry", "assembly", [18.0, 100.0, 140.0]), ("mass", "inertia_bc", 1e-4)])
def test_hinge_refuses_crank_keys(section, key, value):
    raw = {"geometry": {"mechanism": "hinge"}}
    raw.setdefault(section, {})[key] = value
    with pytest.raises(ConfigError) as exc:
        from_dict(raw)
    msg = str(exc.value)
    assert "\n" not in msg and msg.startswith(f"{section}.{key}:")


@pytest.mark.parametrize("raw,key", [({"mechanism": "flap"}, "geometry.mechanism"),
                                     ({"mechanism": "hinge", "hinge": [0.0]}, "geometry.hinge"),
                                     ({"mechanism": "hinge", "hinge": [99.0, 0.0]},
                                      "geometry.hinge")])
def test_hinge_bad_values_name_the_key(raw, key):
    with pytest.raises(ConfigError) as exc:
        from_dict({"geometry": raw})
    assert key in str(exc.value) and "\n" not in str(exc.value)
