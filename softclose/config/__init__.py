"""Configuration: every key one record, TOML file + ``--set`` overrides -> a validated Config.

- :mod:`.schema` -- the key records (the linkage's here, each element's in its unit) and the
  views derived from them (kinds and defaults, admissible ranges, default spreads, the
  section classes);
- :mod:`.values` -- checking one value against its key;
- :mod:`.tolerance` -- the ``[tolerance]`` section;
- :mod:`.load` -- :class:`Config`, loading, ``--set`` overrides, the work budgets;
- :mod:`.write` -- a config written back as TOML (read back to the same config);
- :mod:`.docs` -- the key tables of docs/model.md, generated from the records.
"""

from ..errors import ConfigError
from .load import (BATCH_STEP_BUDGET, NLP_BUDGET, STEP_BUDGET, TRAJECTORY_BUDGET, Config,
                   apply_override, check_batch, default_config, from_dict, load_config,
                   parse_value, read_toml, steps_per_stroke, to_dict)
from .schema import (DEFAULT_SPREADS, HESSIANS, INTEGRATORS, KEYS, RANGES, SCHEMA, SECTIONS,
                     TOLERANCE_KEYS, TOLERANCE_OPTIONS, TOLERANCE_SECTIONS, Design, Friction,
                     Geometry, Mass, Operating, Optimise, Simulate, Spring, Stroke,
                     numeric_keys)
from .tolerance import MAX_TOLERANCE_SAMPLES, Spread, Tolerance
from .write import to_toml

__all__ = ["ConfigError", "Config", "load_config", "default_config", "from_dict", "to_dict", "to_toml", "parse_value",
           "apply_override", "read_toml", "check_batch", "steps_per_stroke", "numeric_keys",
           "KEYS", "SCHEMA", "RANGES", "SECTIONS", "DEFAULT_SPREADS", "TOLERANCE_KEYS",
           "TOLERANCE_OPTIONS", "TOLERANCE_SECTIONS", "INTEGRATORS", "HESSIANS",
           "STEP_BUDGET", "TRAJECTORY_BUDGET", "NLP_BUDGET", "BATCH_STEP_BUDGET",
           "MAX_TOLERANCE_SAMPLES", "Spread", "Tolerance", "Geometry", "Mass", "Design",
           "Stroke", "Simulate", "Optimise", "Spring", "Operating"]
