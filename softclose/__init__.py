"""softclose: design soft-closing paper-bin lids on a four-bar linkage.

The public entry points: :func:`load_config`, :class:`LidModel`, :func:`simulate` /
:class:`Simulator`, :class:`Reference`; the optimiser and sweeps live in
:mod:`softclose.optimise` and :mod:`softclose.sweep`.
"""

from .config import Config, load_config
from .errors import ConfigError, NumericalError
from .model import LidModel
from .reference import Reference
from .simulate import Simulator, StrokeResult, simulate

__all__ = ["Config", "load_config", "ConfigError", "NumericalError", "LidModel", "Reference",
           "Simulator", "StrokeResult", "simulate"]
__version__ = "0.1.0"
