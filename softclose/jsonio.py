"""The one JSON sanitiser: whatever softclose reports becomes strict JSON.

numpy scalars and arrays become Python numbers and lists, NaN and infinities become null
(JSON has no such tokens: ``json.dumps(..., allow_nan=False)`` then never fails), tuples
become lists, enums their text, and objects with ``to_json()`` their JSON form.
"""

from __future__ import annotations

import dataclasses
import enum
import json
import math
from pathlib import Path
from typing import Any

import numpy as np


def jsonable(x: Any) -> Any:
    """``x`` as plain JSON values (see the module docstring)."""
    if isinstance(x, dict):
        return {str(k): jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [jsonable(v) for v in x]
    if isinstance(x, np.ndarray):
        return [jsonable(v) for v in x.tolist()]
    if isinstance(x, enum.Enum):
        return getattr(x, "text", x.name.lower())
    if isinstance(x, (bool, np.bool_)):
        return bool(x)
    if isinstance(x, (np.integer,)):
        return int(x)
    if isinstance(x, (float, np.floating)):
        x = float(x)
        return x if math.isfinite(x) else None
    if isinstance(x, Path):
        return str(x)
    if hasattr(x, "to_json") and callable(x.to_json):
        return jsonable(x.to_json())
    if dataclasses.is_dataclass(x) and not isinstance(x, type):
        return jsonable(dataclasses.asdict(x))
    if hasattr(x, "_asdict") and not isinstance(x, type):     # a config section
        return jsonable(x._asdict())
    return x


def dumps(x: Any, **kw) -> str:
    """Strict JSON text of ``x`` (no NaN/Infinity tokens)."""
    return json.dumps(jsonable(x), allow_nan=False, **kw)
