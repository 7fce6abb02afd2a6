"""The designs of a sweep: a full-factorial :class:`Grid` or a :class:`Sample` drawn in ranges.

Both number their designs ``0 .. n-1`` (the ``id`` of a row) and give the swept values of
any ids on demand (:meth:`Grid.points`, :meth:`Sample.points`), so a chunk of a sweep -- or
one row of it -- can be recomputed without the rest. Grid ids run in C order over the axes
as given (the last key varies fastest). Sample ids are positions in the sampler's sequence:
Sobol and random points are generated chunk by chunk (the same values whatever the chunk
size); a Latin hypercube is drawn whole (n x d values) on first use.

The string forms (command line) are parsed here too, every error a one-line
:class:`~softclose.errors.ConfigError` naming the option and the culprit:
``KEY=START:STOP:COUNT``, ``KEY=START:STOP:COUNT:log``, ``KEY=[v1, v2, ...]`` (a TOML array)
for grids, ``KEY=LO:HI`` or ``KEY=LO:HI:log`` for sample ranges.
"""

from __future__ import annotations

import math
import re
import tomllib
import warnings
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from ..errors import ConfigError
from ..config import check_batch, numeric_keys
from ..problem import word_code, WORD_PARAMS, word_text

#: samplers of :class:`Sample` (scipy.stats.qmc, or numpy's PCG64 for "random")
SAMPLERS = ("sobol", "lhs", "random")
#: the largest number of designs accepted (ids are int64; part files hold them on disk)
MAX_DESIGNS = 1_000_000_000
#: most values of one grid key (10^7 values: 80 MB; the product is bounded by MAX_DESIGNS)
MAX_AXIS_VALUES = 10_000_000


def readonly(a) -> np.ndarray:
    a = np.array(a, float)
    a.setflags(write=False)
    return a


def check_key(key: str, option: str) -> str:
    """``key`` if it is a numeric config key (see :func:`softclose.config.numeric_keys`)."""
    known = numeric_keys() + list(WORD_PARAMS)
    if key not in known:
        stem = key.split(".")[-1].split("[")[0]
        close = [k for k in known if stem and stem in k]
        hint = f" (did you mean {', '.join(close[:4])}?)" if close else \
            " (numeric keys: section.key or section.key[i], e.g. design.damper_c)"
        raise ConfigError(f"{option}: {key} is not a numeric config key{hint}")
    return key


def check_values(cfg, key: str, values, option: str) -> None:
    """Refuse values the config itself refuses (its smallest and largest are tried)."""
    if cfg is None:
        return
    if key in WORD_PARAMS:          # every word is tried (there are two or three)
        for c in np.unique(values):
            try:
                cfg.update({key: WORD_PARAMS[key].word(float(c))})
            except ConfigError as exc:
                raise ConfigError(f"{option}: {str(exc).splitlines()[0]}") from None
        return
    for v in (float(np.min(values)), float(np.max(values))):
        try:
            cfg.update({key: v})
        except ConfigError as exc:
            raise ConfigError(f"{option}: {str(exc).splitlines()[0]}") from None


# -- grid ----------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class Grid:
    """A full-factorial grid: every combination of the values of each key.

    ``log`` marks the axes given with log spacing (only how their maps are drawn).
    """

    keys: tuple[str, ...]
    values: tuple[np.ndarray, ...]
    log: tuple[bool, ...] = ()

    kind = "grid"

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(len(v) for v in self.values)

    @property
    def n(self) -> int:
        return math.prod(self.shape)

    def points(self, ids) -> np.ndarray:
        """Swept values of designs ``ids``: an array (len(ids), len(keys))."""
        idx = np.unravel_index(np.asarray(ids, np.int64), self.shape)
        return np.column_stack([v[i] for v, i in zip(self.values, idx)]) if self.keys \
            else np.zeros((len(ids), 0))

    def spec(self) -> dict:
        """Plain values that define the grid (for the manifest of a resumable sweep)."""
        logs = self.log or (False,) * len(self.keys)
        return {"kind": "grid", "axes": [{"key": k, "values": v.tolist(), "log": bool(g)}
                                         for k, v, g in zip(self.keys, self.values, logs)]}

    def describe(self) -> list[str]:
        return [f"{k} ({', '.join(word_text(k, x) for x in v)})" if k in WORD_PARAMS else
                f"{k} ({len(v)} values, {v.min():.6g} .. {v.max():.6g}"
                f"{', log' if g else ''})"
                for k, v, g in zip(self.keys, self.values, self.log or (False,) * len(self.keys))]


def make_grid(axes: dict, cfg=None, option: str = "axes") -> Grid:
    """A :class:`Grid` from ``{config key: values}`` (1-D, finite, at least one value)."""
    if not isinstance(axes, dict) or not axes:
        raise ConfigError(f"{option}: give at least one config key and its values, e.g. "
                          "{'design.spring_k': np.linspace(500, 9500, 40)}")
    keys, values, log = [], [], []
    for key, vals in axes.items():
        check_key(key, f"{option} {key}")
        try:
            v = _codes(key, vals) if _is_word_key(key) else \
                np.asarray(vals, float).ravel() if np.ndim(vals) <= 1 else None
        except ValueError as exc:
            if _is_word_key(key):
                raise ConfigError(f"{option} {key}: {exc}") from None
            v = None
        except TypeError:
            v = None
        if v is None:
            raise ConfigError(f"{option} {key}: expected a 1-D sequence of numbers")
        if v.size == 0:
            raise ConfigError(f"{option} {key}: no values")
        if not np.all(np.isfinite(v)):
            raise ConfigError(f"{option} {key}: values must be finite")
        if len(np.unique(v)) != len(v):
            raise ConfigError(f"{option} {key}: a value is repeated")
        check_values(cfg, key, v, f"{option} {key}")
        keys.append(key)
        values.append(readonly(v))
        log.append(_geometric(v) and not _is_word_key(key))
    grid = Grid(tuple(keys), tuple(values), tuple(log))
    if grid.n > MAX_DESIGNS:
        raise ConfigError(f"{option}: {grid.n} designs is more than {MAX_DESIGNS}; "
                          "use fewer values or --sample")
    return grid


def _is_word_key(key: str) -> bool:
    return key in WORD_PARAMS


def _codes(key: str, words) -> np.ndarray:
    """The numbers p holds for a word key's values (words, or the numbers themselves)."""
    if isinstance(words, (str, bool)):
        words = [words]
    out = []
    for w in words:
        if isinstance(w, (int, float, np.number)) and not isinstance(w, bool):
            if float(w) not in WORD_PARAMS[key].codes.values():
                word_code(key, w)             # refused, naming the words
            out.append(float(w))
        else:
            out.append(word_code(key, w))
    return np.array(out, float)


def _parse_words(key: str, rhs: str, spec: str, option: str) -> np.ndarray:
    """A word key's values: ``[compression, extension]``, ``compression,extension`` or a
    TOML array of strings (or booleans)."""
    text = rhs.strip()
    if text.startswith("[") and text.endswith("]"):
        text = text[1:-1]
    words = [w.strip().strip("'\"") for w in text.split(",")]
    if not words or not all(words):
        raise ConfigError(f"{option} {spec!r}: expected {key}=WORD,WORD,... or "
                          f"{key}=[WORD, ...]")
    try:
        v = _codes(key, words)
    except ValueError as exc:
        raise ConfigError(f"{option} {spec!r}: {exc}") from None
    if len(np.unique(v)) != len(v):
        raise ConfigError(f"{option} {spec!r}: a value is repeated")
    return v


def _geometric(v: np.ndarray) -> bool:
    """True for log-spaced values (drawn on log axes): positive, a constant ratio that is
    not also a constant difference."""
    if len(v) < 3 or not np.all(v > 0):
        return False
    d, r = np.diff(v), np.diff(np.log(v))
    return bool(np.allclose(r, r[0], rtol=1e-9, atol=0) and not np.allclose(d, d[0], rtol=1e-6))


_NUM = r"[^:\[\]]+"
_LINEAR = re.compile(rf"^({_NUM}):({_NUM}):({_NUM})(?::(\w+))?$")


def _number(text: str, what: str, spec: str, option: str) -> float:
    try:
        x = float(text)
    except ValueError:
        raise ConfigError(f"{option} {spec!r}: {what} must be a number, got {text.strip()!r}") \
            from None
    if not math.isfinite(x):
        raise ConfigError(f"{option} {spec!r}: {what} must be finite")
    return x


def parse_grid_spec(spec: str, cfg=None) -> tuple[str, np.ndarray, bool]:
    """``KEY=START:STOP:COUNT[:log]`` or ``KEY=[v1, v2, ...]`` -> (key, values, log)."""
    option = "--grid"
    form = "expected KEY=START:STOP:COUNT, KEY=START:STOP:COUNT:log or KEY=[v1, v2, ...]"
    if "=" not in spec:
        raise ConfigError(f"{option} {spec!r}: {form}, e.g. design.spring_k=0:2000:41")
    key, rhs = (s.strip() for s in spec.split("=", 1))
    check_key(key, f"{option} {spec!r}")
    log = False
    if _is_word_key(key):
        v = _parse_words(key, rhs, spec, option)
    elif rhs.startswith("["):
        try:
            vals = tomllib.loads(f"v = {rhs}")["v"]
        except tomllib.TOMLDecodeError:
            raise ConfigError(f"{option} {spec!r}: the values are not a TOML array of numbers "
                              "(e.g. [100, 1000, 4000])") from None
        if not vals or not all(isinstance(x, (int, float)) and not isinstance(x, bool)
                               for x in vals):
            raise ConfigError(f"{option} {spec!r}: expected a non-empty array of numbers")
        v = np.array(vals, float)
        if not np.all(np.isfinite(v)):
            raise ConfigError(f"{option} {spec!r}: values must be finite")
        if len(np.unique(v)) != len(v):
            raise ConfigError(f"{option} {spec!r}: a value is repeated")
    else:
        m = _LINEAR.match(rhs)
        if not m:
            raise ConfigError(f"{option} {spec!r}: {form}")
        a, b, n, mode = m.groups()
        start = _number(a, "START", spec, option)
        stop = _number(b, "STOP", spec, option)
        if not re.fullmatch(r"\s*\d+\s*", n) or int(n) < 1:
            raise ConfigError(f"{option} {spec!r}: COUNT must be a positive integer, "
                              f"got {n.strip()!r}")
        count = int(n)
        if count > MAX_AXIS_VALUES:   # before any array is built
            raise ConfigError(f"{option} {spec!r}: COUNT = {count} is more than "
                              f"{MAX_AXIS_VALUES:,} values of one key; use fewer")
        if mode not in (None, "log"):
            raise ConfigError(f"{option} {spec!r}: the fourth field may only be 'log', "
                              f"got {mode!r}")
        if count == 1 and start != stop:
            raise ConfigError(f"{option} {spec!r}: COUNT = 1 needs START = STOP")
        if count > 1 and start == stop:
            raise ConfigError(f"{option} {spec!r}: START = STOP gives {count} equal values")
        log = mode == "log"
        if log:
            if not (start > 0 and stop > 0):
                raise ConfigError(f"{option} {spec!r}: log spacing needs START > 0 and "
                                  "STOP > 0 (a log range cannot reach or cross zero)")
            v = np.geomspace(start, stop, count)
            v[0], v[-1] = start, stop
        else:
            v = np.linspace(start, stop, count)
    check_values(cfg, key, v, f"{option} {spec!r}")
    return key, v, log


def parse_grid(specs: list[str], cfg=None) -> Grid:
    """A :class:`Grid` from ``--grid`` strings (one per key)."""
    if not specs:
        raise ConfigError("--grid: give at least one KEY=START:STOP:COUNT")
    keys, values, logs = [], [], []
    for spec in specs:
        key, v, log = parse_grid_spec(spec, cfg)
        if key in keys:
            raise ConfigError(f"--grid {spec!r}: {key} is swept twice")
        keys.append(key)
        values.append(readonly(v))
        logs.append(log)
    grid = Grid(tuple(keys), tuple(values), tuple(logs))
    if grid.n > MAX_DESIGNS:
        raise ConfigError(f"--grid: {grid.n} designs is more than {MAX_DESIGNS}; use fewer "
                          "values, or --sample N with --range for many keys")
    return grid


# -- sample --------------------------------------------------------------------------------
@dataclass(frozen=True)
class Range:
    """The interval a sampled key is drawn in (uniform in the value, or in its log)."""

    key: str
    lo: float
    hi: float
    log: bool = False

    def scale(self, u: np.ndarray) -> np.ndarray:
        """Map unit-interval points ``u`` onto the range."""
        if self.log:
            a, b = math.log(self.lo), math.log(self.hi)
            return np.exp(a + u * (b - a))
        return self.lo + u * (self.hi - self.lo)


@dataclass(frozen=True, eq=False)
class Sample:
    """``n`` designs drawn in ``ranges`` by ``sampler`` (Sobol scrambled, LHS, random)."""

    ranges: tuple[Range, ...]
    n: int
    sampler: str = "sobol"
    seed: int = 0
    _lhs: dict = field(default_factory=dict, repr=False, compare=False)

    kind = "sample"

    @property
    def keys(self) -> tuple[str, ...]:
        return tuple(r.key for r in self.ranges)

    @property
    def shape(self) -> tuple[int]:
        return (self.n,)

    @property
    def log(self) -> tuple[bool, ...]:
        return tuple(r.log for r in self.ranges)

    def unit(self, a: int, b: int) -> np.ndarray:
        """Points ``a .. b-1`` of the sampler's sequence in the unit cube."""
        d = len(self.ranges)
        if self.sampler == "sobol":
            from scipy.stats import qmc
            eng = qmc.Sobol(d, scramble=True, rng=np.random.default_rng(self.seed))
            with warnings.catch_warnings():  # balance needs n a power of 2: see the docs
                warnings.simplefilter("ignore")
                if a:
                    eng.fast_forward(a)
                return eng.random(b - a)
        if self.sampler == "random":
            bits = np.random.PCG64(self.seed)
            bits.advance(a * d)             # one 64-bit draw per double: exact positioning
            return np.random.Generator(bits).random((b - a, d))
        return self._hypercube[a:b]

    @cached_property
    def _hypercube(self) -> np.ndarray:
        from scipy.stats import qmc
        return qmc.LatinHypercube(len(self.ranges), rng=np.random.default_rng(self.seed)) \
            .random(self.n)

    def points(self, ids) -> np.ndarray:
        """Sampled values of designs ``ids``: an array (len(ids), len(keys))."""
        ids = np.asarray(ids, np.int64)
        if ids.size == 0:
            return np.zeros((0, len(self.ranges)))
        a, b = int(ids.min()), int(ids.max()) + 1
        U = self.unit(a, b)[ids - a]
        return np.column_stack([r.scale(U[:, j]) for j, r in enumerate(self.ranges)])

    def spec(self) -> dict:
        return {"kind": "sample", "n": self.n, "sampler": self.sampler, "seed": self.seed,
                "ranges": [{"key": r.key, "lo": r.lo, "hi": r.hi, "log": r.log}
                           for r in self.ranges]}

    def describe(self) -> list[str]:
        return [f"{r.key} in [{r.lo:.6g}, {r.hi:.6g}]{' (log)' if r.log else ''}"
                for r in self.ranges]


def make_range(key: str, lo, hi, log: bool = False, cfg=None, where: str | None = None) -> Range:
    """A validated :class:`Range`; ``where`` starts every error message (default the key)."""
    where = where or f"ranges {key}"
    check_key(key, where)
    _no_range(key, where)
    try:
        lo, hi = float(lo), float(hi)
    except (TypeError, ValueError):
        raise ConfigError(f"{where}: LO and HI must be numbers") from None
    if not (math.isfinite(lo) and math.isfinite(hi)):
        raise ConfigError(f"{where}: LO and HI must be finite")
    if not lo < hi:
        raise ConfigError(f"{where}: LO = {lo:g} must be below HI = {hi:g}")
    if log and not lo > 0:
        raise ConfigError(f"{where}: a log range needs LO > 0 (it cannot reach or "
                          f"cross zero), got LO = {lo:g}")
    check_values(cfg, key, [lo, hi], where)
    return Range(key, lo, hi, bool(log))


def _no_range(key: str, where: str) -> None:
    if _is_word_key(key):
        words = ",".join(word_text(key, c) for c in WORD_PARAMS[key].codes.values())
        raise ConfigError(f"{where}: {key} takes words, not a range: sweep it on a grid "
                          f"(--grid {key}={words})")


def parse_range(spec: str, cfg=None) -> Range:
    """``KEY=LO:HI`` or ``KEY=LO:HI:log`` -> :class:`Range`."""
    option = "--range"
    m = re.match(r"^\s*([^=\s]+)\s*=\s*([^:]+):([^:]+)(?::(\w+))?\s*$", spec)
    if not m:
        raise ConfigError(f"{option} {spec!r}: expected KEY=LO:HI or KEY=LO:HI:log, e.g. "
                          "design.damper_c=100:4000")
    key, a, b, mode = m.groups()
    check_key(key, f"{option} {spec!r}")
    _no_range(key, f"{option} {spec!r}")
    if mode not in (None, "log"):
        raise ConfigError(f"{option} {spec!r}: the third field may only be 'log', got {mode!r}")
    lo = _number(a, "LO", spec, option)
    hi = _number(b, "HI", spec, option)
    return make_range(key, lo, hi, mode == "log", cfg, f"{option} {spec!r}")


def make_sample(ranges, n, sampler: str = "sobol", seed: int = 0, cfg=None,
                option: str = "sample") -> Sample:
    """A :class:`Sample` from ranges given as :class:`Range` or ``{key: (lo, hi[, "log"])}``."""
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)):
        raise ConfigError(f"{option}: N must be a whole number, got {n!r}")
    if n <= 0:
        raise ConfigError(f"{option}: N must be positive, got {n}")
    if n > MAX_DESIGNS:
        raise ConfigError(f"{option}: N = {n} is more than {MAX_DESIGNS}")
    if sampler not in SAMPLERS:
        raise ConfigError(f"{option}: unknown sampler {sampler!r} (choose {', '.join(SAMPLERS)})")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ConfigError(f"{option}: the seed must be a non-negative whole number, got {seed!r}")
    if isinstance(ranges, dict):
        rs = []
        for key, r in ranges.items():
            r = tuple(r) if isinstance(r, (list, tuple)) else (r,)
            if len(r) not in (2, 3) or (len(r) == 3 and r[2] not in ("log", "linear")):
                raise ConfigError(f"ranges {key}: expected (lo, hi) or (lo, hi, 'log'), got {r!r}")
            rs.append(make_range(key, r[0], r[1], len(r) == 3 and r[2] == "log", cfg))
        ranges = rs
    ranges = tuple(ranges)
    if not ranges:
        raise ConfigError(f"{option}: give at least one range (--range KEY=LO:HI)")
    keys = [r.key for r in ranges]
    dup = next((k for k in keys if keys.count(k) > 1), None)
    if dup:
        raise ConfigError(f"--range {dup}: given twice")
    return Sample(ranges, int(n), sampler, int(seed))


def check_budget(cfg, space, what: str = "the sweep") -> None:
    """Refuse (ConfigError) a sweep whose strokes could take more fixed steps in all than
    :data:`softclose.config.BATCH_STEP_BUDGET` (designs x t_max / step, at the smallest
    swept step and the longest swept t_max)."""
    if cfg is None:
        return
    values = {}
    for key, pick in (("simulate.step", min), ("stroke.t_max", max)):
        if key in space.keys:
            j = space.keys.index(key)
            v = space.values[j] if space.kind == "grid" else \
                (space.ranges[j].lo, space.ranges[j].hi)
            values[key] = float(pick(v))
    try:
        worst = cfg.update(values) if values else cfg
    except ConfigError:      # e.g. a step above t_max: such designs are refused one by one
        worst = cfg
    check_batch(worst, space.n, what)


def space_from_spec(spec: dict):
    """The :class:`Grid` or :class:`Sample` of a manifest's ``spec()``."""
    if spec.get("kind") == "grid":
        axes = spec["axes"]
        return Grid(tuple(a["key"] for a in axes), tuple(readonly(a["values"]) for a in axes),
                    tuple(bool(a.get("log", False)) for a in axes))
    if spec.get("kind") == "sample":
        return Sample(tuple(Range(r["key"], float(r["lo"]), float(r["hi"]), bool(r["log"]))
                            for r in spec["ranges"]), int(spec["n"]), spec["sampler"],
                      int(spec["seed"]))
    raise ConfigError(f"not a sweep specification: {spec!r}"[:200])
