"""The robust optimiser's policy: how many corners enter the scenario NLP together, how many
samples each search draws, how many rounds and refinements it takes, when a sample counts
as violating, how often the box is widened -- and where the kernel may cut a stroke in the
searches (:func:`t_end`), and which tolerance boxes it takes at all (:func:`check_keys`).
"""

from __future__ import annotations

from ..config import Config
from ..errors import ConfigError
from ..problem import VERIFY_RTOL
from .evaluate import slow_keys
from ..optimiser.discretisation import discretisation, t_limit

#: most corners of the box that enter the scenario NLP all together (d <= 4 keys). Each
#: scenario adds 2N + 2 variables and a copy of every constraint to the NLP, and one
#: reference re-simulation: with five keys tolerance (33 scenarios) one solve took 2.4 s
#: and a warm re-solve up to 10 s, against 0.5 s for the default nine. Beyond it the NLP
#: starts from the corners that matter (:func:`softclose.robust.scenarios.initial_scenarios`)
#: and every one of the 2^d corners is simulated in the kernel after each solve instead
#: (:func:`softclose.robust.worst_cases.check_corners`: 2^d strokes, milliseconds), the
#: violating ones joining the scenarios.
MAX_CORNERS = 16


def max_corners(cfg: Config) -> int:
    """The corners that enter the scenario NLP all together: :data:`MAX_CORNERS` one-phase
    scenarios' worth of RK4 steps. A two-phase scenario (an end damper engaging inside the
    stroke) costs N (M + M_e) steps instead of N M (M_e: the engaged phase's sub-steps), so
    fewer of its corners enter together (16 M / (M + M_e): 5 at M_e = 2M, with a fourth
    toleranced key's 16 corners the worst-corner start of d > 4); the corner check still
    simulates all 2^d after every solve."""
    disc = discretisation(cfg)
    M, Me = disc.substeps, disc.substeps_engaged
    return MAX_CORNERS if Me is None else int(MAX_CORNERS * M / (M + Me))
#: most toleranced keys that need a model per value (geometry, crank masses, stroke
#: angles): each corner check builds 2^s models (~0.04 s each; 2^8: ~10 s). With the five
#: kernel-column keys (design, rotary damper, lid mass) that bounds d by 13 (8192 corners,
#: ~0.1 s a check)
MAX_SLOW_KEYS = 8
#: Monte Carlo samples of each interior worst-case search (uniform in the box)
CHECK_SAMPLES = 4096
#: the same when a toleranced key needs a model per sample (geometry, crank masses ...)
SLOW_CHECK_SAMPLES = 256
#: most yield samples of the robust optimiser when a key needs a model per sample
SLOW_YIELD_SAMPLES = 2000
#: scenarios added per search round, and the most rounds
ADD_PER_ROUND = 2
MAX_ROUNDS = 6
#: a sample counts as violating when its relative margin is below -MC_TOL (the kernel's
#: closing-time error at the default step is ~1e-7 s) or its objective exceeds the worst
#: scenario's by more than OBJ_RTOL
MC_TOL = 1e-6
OBJ_RTOL = 1e-3
#: the NLP's worst-scenario objective must agree with an accurate simulation to this
REFINE_RTOL = 1e-4
#: and every scenario's own objective, impact speed and peak tip speed to this (half the
#: reference's VERIFY_RTOL, the rest left for the verification's margin)
AGREE_RTOL = VERIFY_RTOL / 2
MAX_REFINE = 3
#: box widening when the yield falls short (normal distribution), and how often
WIDEN = 1.15
MAX_WIDEN = 3
#: samples near the boundary re-simulated by the reference in each yield estimate
YIELD_REFERENCE = 1


def t_end(cfg: Config) -> float:
    """Where the kernel may cut a stroke in the robust searches: anything slower is
    infeasible anyway (the closing window ends before it), with a margin."""
    return 1.05 * t_limit(cfg) + 0.05


def check_keys(cfg: Config) -> None:
    """ConfigError unless the robust optimiser can check every corner of cfg's box in
    reasonable time: at most :data:`MAX_SLOW_KEYS` toleranced keys needing a model per
    value."""
    slow = slow_keys([s.key for s in cfg.tolerance.spreads])
    if len(slow) > MAX_SLOW_KEYS:
        raise ConfigError(f"tolerance: {len(slow)} toleranced keys need a model per value "
                          f"({', '.join(slow[:3])}, ...); optimise --robust checks all 2^d "
                          f"corners of the box and takes at most {MAX_SLOW_KEYS} of them "
                          "(softclose yield and sensitivity take any number)")
