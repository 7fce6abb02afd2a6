"""Parts from a catalog: rank the springs and dampers one can buy (``softclose select``).

- :mod:`.files` -- the catalog files (SPEC §10): springs (extension, compression, gas strut)
  and dampers (dashpot, rotary at a pivot), SI or mm in the header, bad rows reported by line
  and column;
- :mod:`.screen` -- every pair over its own tolerance box in the C kernel;
- :mod:`.coil` -- a catalog spring whose coil is given, checked at its working lengths
  (EN 13906-1/-2: static stress, fatigue, buckling);
- :mod:`.verify` -- the adaptive reference at every corner of the best pairs' boxes;
- :mod:`.ranking` -- the procedure (:func:`select`); :mod:`.result` -- :class:`SelectResult`.
"""

from .files import (Catalog, DamperEntry, SpringEntry, read_dampers, read_springs,
                    standard_free_length_tolerance)
from .result import SelectResult, pair_config
from .ranking import select

__all__ = ["select", "SelectResult", "pair_config", "read_springs", "read_dampers", "Catalog",
           "SpringEntry", "DamperEntry", "standard_free_length_tolerance"]
