"""The tolerance box of one design: which config values vary, around what, by how much.

``[tolerance]`` gives each toleranced key a spread (relative to its value, or absolute).
Around a design the box is ``nominal ± half_width`` per key; a relative spread of a design
key follows the design (the optimiser moves it), every other key's nominal is its config
value.

Samples are drawn in *unit coordinates* z (z = ±1 at the faces of the box) and mapped onto
a design's box afterwards, so two designs judged "on the same samples" see the same relative
deviations of their springs and dampers and the same lid masses:

- ``uniform``: z ~ U(-1, 1) in each key, independently;
- ``normal``: z ~ N(0, 1/3²) (the spread is 3 sigma), truncated where the key would leave its
  admissible range (a mass or a length <= 0, a negative stiffness): such draws are redrawn.
  With a relative spread below 1 that is beyond 3 sigma, so it removes < 0.14 % of the draws.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np

from ..config import Config, Tolerance
from ..config.free import config_value
from ..errors import ConfigError
from ..problem import DESIGN_KEYS


@dataclass(frozen=True)
class Box:
    """Nominal values and half-widths of the toleranced keys around one design."""

    keys: tuple[str, ...]
    nominal: np.ndarray          # (d,) values of the keys at the design
    half: np.ndarray             # (d,) half-widths: the box is nominal ± half
    z_min: np.ndarray            # (d,) smallest admissible unit coordinate (range of the key)
    relative: tuple[bool, ...]
    spreads: tuple[float, ...]   # as the config gives them
    distribution: str

    @property
    def dim(self) -> int:
        return len(self.keys)

    @property
    def lo(self) -> np.ndarray:
        return self.nominal - self.half

    @property
    def hi(self) -> np.ndarray:
        return self.nominal + self.half

    def values(self, z) -> np.ndarray:
        """Key values at unit coordinates ``z`` (n, d) (clipped to each key's range)."""
        z = np.atleast_2d(np.asarray(z, float))
        return self.nominal + self.half * np.maximum(z, self.z_min)

    def corners(self) -> np.ndarray:
        """Unit coordinates of the 2^d corners, (2^d, d): all sign patterns, -1 first."""
        if not self.dim:
            return np.zeros((1, 0))
        return np.array(list(itertools.product((-1.0, 1.0), repeat=self.dim)))

    def draw(self, n: int, seed: int = 0, distribution: str | None = None) -> np.ndarray:
        """``n`` unit-coordinate samples (n, d) of the configured (or given) distribution."""
        dist = distribution or self.distribution
        rng = np.random.default_rng(seed)
        if dist == "uniform":
            return rng.uniform(-1.0, 1.0, (n, self.dim))
        z = rng.standard_normal((n, self.dim)) / 3.0
        for _ in range(100):                    # redraw what leaves a key's range
            bad = np.any(z <= self.z_min, axis=1)
            if not bad.any():
                return z
            z[bad] = rng.standard_normal((int(bad.sum()), self.dim)) / 3.0
        raise ConfigError("tolerance: the normal distribution leaves the admissible range of "
                          "a key too often; use smaller spreads")

    def label(self, z) -> str:
        """A short name of the point ``z``: ``spring_k +10 %, damper_c -20 %, mass.lid +5 %``."""
        z = np.asarray(z, float)
        if not self.dim:
            return "nominal"
        if np.all((np.abs(z) < 1e-12) | (self.half == 0)):
            return "nominal"
        parts = []
        for key, zi, h, v, rel in zip(self.keys, z, self.half, self.nominal, self.relative):
            if h == 0:
                continue
            name = key.removeprefix("design.")
            if rel and v != 0:
                parts.append(f"{name} {100 * zi * h / abs(v):+.3g} %")
            else:
                parts.append(f"{name} {zi * h:+.4g}")
        return ", ".join(parts)


def box_of(cfg: Config, design: dict | None = None, tolerance: Tolerance | None = None,
           scale: float = 1.0) -> Box:
    """The tolerance box of ``cfg``'s design (``design`` overrides it), spreads x ``scale``.

    A relative spread of a design value that is zero and stays zero -- an element the design
    does not have (``design.end_damper_c`` = 0, a default spread) and the optimiser does not
    choose (not k, l0, c, nor in ``optimise.free``) -- spans nothing: it is left out, so it
    adds no corners and no sample columns (the box of a lid without an end damper is the
    box without its key)."""
    tol = tolerance or cfg.tolerance
    free = {k for k, _, _ in (cfg.optimise.free or ())}
    keys, nominal, half, z_min, rel, spreads = [], [], [], [], [], []
    for s in tol.spreads:
        v = config_value(cfg, s.key)
        name = s.key.removeprefix("design.")
        if design is not None and name in design:
            v = float(design[name])
        if (s.relative and v == 0.0 and s.key.startswith("design.")
                and name not in DESIGN_KEYS and s.key not in free):
            continue
        h = scale * s.half_width(v)
        keys.append(s.key)
        nominal.append(v)
        half.append(h)
        rel.append(s.relative)
        spreads.append(s.value * scale)
        # the key's admissible range in unit coordinates: pos > 0, nonneg >= 0
        if s.kind in ("pos", "nonneg") and h > 0:
            zm = -v / h
            z_min.append(zm + (1e-12 if s.kind == "pos" else 0.0))
        else:
            z_min.append(-math.inf)
    return Box(tuple(keys), np.array(nominal), np.array(half), np.array(z_min), tuple(rel),
               tuple(spreads), tol.distribution)
