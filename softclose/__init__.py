"""softclose: design soft-closing paper-bin lids on a four-bar linkage.

The public API (each takes a :class:`Config` and plain Python values, writes no file, prints
nothing unless ``progress=True``, and returns an immutable result with ``.success``,
``.message``, ``.to_frame()``, ``.to_json()`` and ``.plot()``):

- :func:`simulate` -- one closing stroke, every metric with its estimated accuracy;
- :func:`optimise` -- the soft-close design (multiple shooting + Ipopt), verified by an
  independent adaptive simulation; ``robust=True`` designs for the ``[tolerance]`` box;
- :func:`front` -- the verified Pareto front of the objective against ``closing_time_max``;
- :func:`sweep` -- metrics over a grid (or sample) of any numeric config keys;
- :func:`tolerance_analysis`, :func:`sensitivity` -- Monte Carlo yield and Sobol indices;
- :func:`load_config`, :func:`default_config`, :meth:`Config.set` -- configs.

Lower layers for scripts that need them: :class:`LidModel`, :class:`Simulator`,
:class:`Reference`, :mod:`softclose.problem`.
"""

from .config import Config, default_config, load_config
from .errors import ConfigError, NumericalError, SoftcloseError
from .model import LidModel
from .optimiser import front, optimise
from .reference import Reference
from .simulate import Simulator, simulate
from .stroke import StrokeResult, StrokeStatus

__all__ = ["simulate", "optimise", "front", "load_config", "default_config", "Config", "StrokeResult",
           "StrokeStatus", "ConfigError", "NumericalError", "SoftcloseError", "LidModel",
           "Reference", "Simulator"]
__version__ = "0.2.0"
