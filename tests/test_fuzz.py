"""Property-based fuzzing of the command line: every config key of every section, on every
command, with values of every kind and magnitude (issue 15).

Values are drawn by kind -- zero, negative, tiny, huge (1e300), NaN, +-inf, strings, booleans,
vectors of the wrong length, integers beyond the floats, values inside the admissible range,
on its edges and just outside it -- one to three keys per case, and now and then a drawn value
of the command's own options (``--theta-deg``, ``--samples``, ``--closing-times``, a ``--grid``
over any key). Every run must

- end with exit code 0, 2 or 3 (never an exception out of ``main``: a traceback in a shell);
- on exit 2 or 3, say so in exactly one stderr line starting ``softclose: error:``;
- with ``--json``, print one strict JSON object (no NaN / Infinity tokens), carrying
  ``exit_code`` when it failed;
- refuse (exit 2) exactly the configs that :func:`softclose.config.load_config` refuses, before
  any work;
- when not refused, finish within a time proportional to its work (strokes x steps per
  stroke, the optimiser's starts x grid), enforced by an alarm (and a hard faulthandler exit
  if a compiled loop never returns).

Two profiles: the default run draws a fast sample (~670 cases in about 30 s; the costly
commands -- pareto, optimise --robust, bench -- get only values the config refuses, and the
work-size keys are kept to the refused kinds for the optimisers); ``-m fuzz`` runs the long
profile (every kind everywhere, more cases). Cases are counted by kind and outcome; the
counts go to ``fuzz-counts.json`` in pytest's base temp folder (and to the path in the
environment variable ``SOFTCLOSE_FUZZ_COUNTS`` if set; with ``-n``, one file per test process,
the worker's name before the suffix: ``counts-gw0.json``). The issue's three inputs are explicit
examples, and a sample runs as real ``python -m softclose`` processes to check stderr for
tracebacks. The long profile also draws config files of random bytes and encodings, ``--out``
paths colliding with files and folders, and SIGINT or SIGTERM at random moments of
``prepare``, ``optimise --robust`` and ``sweep`` on an empty cache (exit 0, 2, 3 or 130, at
most one error line, no traceback, no process of the command alive a second later, no
temporary file left in the cache or the temporary folder).
"""

from __future__ import annotations

import argparse
import contextlib
import faulthandler
import io
import json
import math
import os
import signal
import subprocess
import sys
import time
import warnings
from collections import Counter, defaultdict
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, Phase, given, reject, settings
from hypothesis import strategies as st

from softclose.cli import build_parser, free_overrides, main
from softclose.config import (SCHEMA, BATCH_STEP_BUDGET, RANGES, TOLERANCE_OPTIONS,
                              load_config, steps_per_stroke)
from softclose.errors import ConfigError

ROOT = Path(__file__).resolve().parents[1]

# -- the commands and how each is run ------------------------------------------------------
#: (command name as registered, argv before the fuzzed --set values, cost class)
#: cost "cheap": every kind of value; "medium": every kind, but the keys that size the work
#: only with refused kinds in the fast profile; "costly": only refused values in the fast
#: profile (a single accepted run takes 8-70 s).
COMMANDS = {
    "state": (["state"], "cheap"),
    "simulate": (["simulate"], "cheap"),
    "sweep": (["sweep", "--out", "{out}"], "cheap"),
    "optimise": (["optimise", "--set", "optimise.starts=2"], "medium"),
    "yield": (["yield"], "medium"),
    "sensitivity": (["sensitivity"], "medium"),
    "pareto": (["pareto", "--set", "optimise.starts=2"], "costly"),
    "optimise --robust": (["optimise", "--robust", "--set", "optimise.starts=2",
                           "--set", "tolerance.samples=500"], "costly"),
    "bench": (["bench", "--quick"], "costly"),
    "docs": (["docs"], "cheap"),
    "select": (["select", "--springs", str(ROOT / "tests" / "data" / "catalog_springs.csv"),
                "--dampers", str(ROOT / "tests" / "data" / "catalog_dampers.csv")], "medium"),
    # the fit of the example record (its data file a drawn positional: see OPTIONS)
    "fit": (["fit", "--free", "design.damper_c", "--free", "mass.inertia_lid", "--out",
             "{out}", "--set", 'design.spring_kind="compression"', "--set",
             "design.spring_k=1914.709", "--set", "design.spring_rest_length=0.07925707"],
            "medium"),
    # compiles the optimiser's NLP in the foreground (~10 s; once per structure and cache)
    "prepare": (["prepare"], "costly"),
    # the coil spring made to order of a compression spring (designed, or checked when the
    # fuzzed [spring] keys give wire, coil diameter and coils)
    "spring": (["spring", "--out", "{out}", "--set", 'design.spring_kind="compression"',
                "--set", "design.spring_k=1914.709", "--set",
                "design.spring_rest_length=0.07925707"], "cheap"),
    # the sign-off report of the default lid, 200 yield samples a temperature (its files:
    # OPTIONS, HTML unless drawn otherwise)
    "report": (["report", "--out", "{out}", "--samples", "200"], "medium"),
}
#: the pairs of the catalog the fuzzed select runs (4 springs x 2 dampers)
SELECT_PAIRS = 8
#: the fit's data files: the examples, and files it must refuse in one line
FIT_DATA = ROOT / "examples" / "data"
BAD_DATA = ROOT / "tests" / "data" / "fit"
#: how a command writes its figures (every command with --out; refused values too)
FIGURE_OPTIONS = {
    "--figure-format": ("png", [(v, True) for v in ("pdf", "svg", "gif", "PNG", "", "jpg")]),
    "--figure-style": ("screen", [(v, True) for v in ("report", "paper", "", "REPORT")]),
}
#: the commands' own options: option -> (default, [(value, cheap)]); ``cheap``: refused, or
#: quick to run (the only values the fast profile draws for the medium and costly commands)
OPTIONS = {
    "simulate": dict(FIGURE_OPTIONS),
    "sweep": dict(FIGURE_OPTIONS),
    "state": {"--theta-deg": ("10", [(v, True) for v in (
                  "0", "-5", "18", "359", "360.5", "-1e300", "1e12", "nan", "inf", "-inf",
                  "abc", "")]),
              "--theta-dot": ("0", [(v, True) for v in (
                  "3", "-1e4", "1e5", "nan", "1e300", "-inf")])},
    "simulate": {"--slow-motion": ("20", [(v, True) for v in (
                     "1", "1000", "2.5", "0.999", "0", "-1", "nan", "inf", "abc", "", "1e300",
                     "1001")])},
    "optimise": {"--slow-motion": ("20", [(v, True) for v in (
                     "1", "1000", "0", "-20", "nan", "abc", "1e9")])},
    # a positional: given as its value alone (see _arg)
    "fit": {"DATA": (str(FIT_DATA / "stroke.csv"), [(str(v), True) for v in (
                FIT_DATA / "gyroscope.csv", FIT_DATA / "nope.csv", FIT_DATA, "",
                *sorted(BAD_DATA.glob("*.csv")))]),
            "--starts": ("1", [(v, True) for v in ("2", "0", "-1", "51", "abc", "", "1e3",
                                                   "9" * 40)] + [("5", False)]),
            **FIGURE_OPTIONS},
    "docs": {"TOPIC": ("keys", [(v, True) for v in (
                 "overview", "keys", "problem", "files", "nope", "KEYS", "", "--keys")])},
    "yield": {"--samples": ("200", [("1", True), ("3", True), ("0", True), ("-5", True),
                                    ("2.5", True), ("abc", True), ("1000000000", True),
                                    (str(10 ** 30), True), ("2000", False)]),
              **FIGURE_OPTIONS},
    "sensitivity": {"--samples": ("16", [("8", True), ("3", True), ("0", True), ("-4", True),
                                         ("abc", True), (str(2 ** 40), True),
                                         ("64", False)]),
                    **FIGURE_OPTIONS},
    "select": {"--samples": ("16", [(v, True) for v in ("0", "1", "-3", "2.5", "abc", "100001",
                                                          str(10 ** 30))] + [("64", False)]),
               "--verify": ("1", [(v, True) for v in ("0", "-1", "x", "1.5")] +
                            [("2", False)]),
               "--seed": ("0", [(v, True) for v in ("7", "-2", "nan", "")]),
               "--springs": (None, [(v, True) for v in (
                   "/nonexistent.csv", str(ROOT / "tests"), str(ROOT / "README.md"),
                   str(ROOT / "tests" / "data" / "catalog_dampers.csv"), "")]),
               "--dampers": (None, [(v, True) for v in (
                   "/nonexistent.csv", str(ROOT / "tests" / "data" / "catalog_springs.csv"),
                   str(ROOT / "pyproject.toml"))]),
               "--free": (None, [(v, True) for v in (
                   "design.spring_preload=0:10", "geometry.lid_e[1]=0.02:0.01",
                   "geometry.lid_e[9]=0:1", "nope=1:2", "geometry.lid_e[1]=abc", "")]
                          + [("geometry.lid_e[1]=0.004:0.024", False)])},
    "prepare": {"--free": (None, [(v, True) for v in (
                    "nope=1:2", "geometry.lid_e[1]=abc", "geometry.lid_e[9]=0:1",
                    "design.spring_k=5:1", "")] + [("geometry.lid_e[1]=0.004:0.024", False)])},
    # the report's files: HTML, or the PDF on a drawn paper (refused values too)
    "report": {"--format": ("html", [(v, True) for v in ("pdf", "both", "doc", "", "HTML")]),
               "--paper": ("a4", [(v, True) for v in ("letter", "A4", "legal", "", "a4 ")])},
    "pareto": {"--closing-times": ("0.4:1:2", [(v, False) for v in (
        "0.4:1:1", "1:0.4:2", "0:1:2", "nan:1:2", "0.4:inf:2", "0.4:1:0", "0.4:1:100000",
        "0.3:3:2:log", "abc", "1e9:1e10:2", "0.4:30:2", "0.4:1:-2", "0.4:1:2.5")])},
}
#: --grid COUNT values of a fuzzed sweep (3 points at most when accepted)
GRID_COUNTS = ("3", "2", "1", "0", "-1", "x", "2.5", str(10 ** 8), str(10 ** 12))
#: keys whose value sizes the work (steps, starts, grid, samples)
WORK_KEYS = ("stroke.t_max", "simulate.step", "optimise.starts", "optimise.nodes",
             "optimise.substeps", "optimise.max_iter", "optimise.closing_time_max",
             "tolerance.samples")


def registered_commands() -> set[str]:
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    names = set(sub.choices)
    return {c for c in COMMANDS if c.split()[0] in names}


AVAILABLE = registered_commands()

# -- keys -----------------------------------------------------------------------------------
_VEC_LEN = {"vec2": 2, "vec3": 3, "bounds": 2}


def _keys() -> list[tuple[str, str]]:
    """(full key, kind) of every config key, vector component and tolerance entry."""
    out = []
    for section, fields in SCHEMA.items():
        for key, (kind, _default) in fields.items():
            name = f"{section}.{key}"
            out.append((name, kind))
            if kind in _VEC_LEN:
                n = _VEC_LEN[kind]
                out += [(f"{name}[{i}]", "component") for i in range(n)]
                out.append((f"{name}[{n}]", "component"))          # index out of range
    for key, (kind, _default) in TOLERANCE_OPTIONS.items():
        out.append((f"tolerance.{key}", kind))
    for key in ("design.spring_k", "design.damper_c", "design.end_damper_c", "mass.lid",
                "geometry.pivot_b[0]", "stroke.t_max", "simulate.step"):
        out.append((f"tolerance.{key}", "spread"))
    return out


KEYS = _keys()
KIND_OF = dict(KEYS)


def _base(key: str) -> str:
    """'geometry.pivot_b[1]' -> 'geometry.pivot_b'."""
    return key.split("[", 1)[0]


def _default(key: str):
    section, name = _base(key).split(".", 1)
    if section == "tolerance":
        return TOLERANCE_OPTIONS.get(name, ("", 0.1))[1]
    return SCHEMA[section][name][1]


# -- values ---------------------------------------------------------------------------------
VALUE_KINDS = ("zero", "negative", "tiny", "huge", "nan", "inf", "string", "bool",
               "wrong_length", "big_int", "in_range", "edge", "outside", "scaled")
#: kinds that are often inside the admissible ranges (the command runs)
PLAUSIBLE_KINDS = ("in_range", "edge", "scaled")
#: kinds the config refuses for every key (so a command never starts its work)
REFUSED_KINDS = ("huge", "nan", "inf", "string", "bool", "wrong_length", "big_int")


def toml(x) -> str:
    """A Python value as the TOML text a --set gives."""
    if isinstance(x, bool):
        return "true" if x else "false"
    if isinstance(x, int):
        return str(x)
    if isinstance(x, float):
        if math.isnan(x):
            return "nan"
        if math.isinf(x):
            return "inf" if x > 0 else "-inf"
        return repr(x)
    if isinstance(x, str):
        return json.dumps(x)
    if isinstance(x, (list, tuple)):
        return "[" + ", ".join(toml(v) for v in x) + "]"
    raise TypeError(x)


def _range(key: str):
    return RANGES.get(_base(key))


def _number_in(draw, lo: float, hi: float, integer: bool) -> float | int:
    if integer:
        return draw(st.integers(int(lo), int(min(hi, 10 ** 6))))
    if lo > 0 and hi / lo > 100:           # log-uniform over a wide positive range
        e = draw(st.floats(math.log10(lo), math.log10(hi)))
        return min(max(10.0 ** e, lo), hi)
    return draw(st.floats(lo, hi, allow_nan=False, allow_infinity=False))


@st.composite
def scalar_value(draw, key: str, kind: str, vkind: str):
    """One value of kind ``vkind`` for a scalar-like key (text form for TOML)."""
    integer = kind in ("int+",) or key == "tolerance.samples"
    rng = _range(key)
    default = _default(key)
    if vkind == "zero":
        return draw(st.sampled_from(["0", "0.0", "-0.0"]))
    if vkind == "negative":
        return toml(-draw(st.sampled_from([1, 1.0, 1e-9, 1e300, 0.5, 1e6])))
    if vkind == "tiny":
        return toml(draw(st.sampled_from([1e-9, 1e-300, 5e-324, 1e-12])))
    if vkind == "huge":
        return toml(draw(st.sampled_from([1e300, 1e20, 1.7976931348623157e308, 1e9])))
    if vkind == "nan":
        return draw(st.sampled_from(["nan", "-nan", "+nan"]))
    if vkind == "inf":
        return draw(st.sampled_from(["inf", "-inf", "+inf"]))
    if vkind == "string":
        return draw(st.sampled_from(['"abc"', "abc", '""', '"1.0"', '"rk4"', '"exact"',
                                     '"uniform"', "[\"a\", \"b\"]", "nan_or_what"]))
    if vkind == "bool":
        return draw(st.sampled_from(["true", "false"]))
    if vkind == "wrong_length":
        return draw(st.sampled_from(["[]", "[1.0]", "[1.0, 2.0, 3.0, 4.0]", "[[1.0, 2.0]]",
                                     "[0.1, 0.2]", "[0.1, 0.2, 0.3]"]))
    if vkind == "big_int":
        return "1" + "0" * draw(st.sampled_from([30, 400]))
    if kind.startswith("str:"):                     # the kinds below: a valid choice or not
        choices = kind[4:].split(",")
        return toml(draw(st.sampled_from(choices + ["RK4", "rk45", "bfgs", "pardiso"])))
    if kind.startswith("words:"):                   # a list of the words, or not quite
        choices = kind[6:].split(",")
        words = draw(st.lists(st.sampled_from(choices + ["Linear", "spiral", "gas strut"]),
                              min_size=0, max_size=4))
        return toml(words)
    if vkind in ("in_range", "scaled") and rng is None and kind == "spread":
        return toml(draw(st.sampled_from([0.0, 0.01, 0.1, 0.5, 0.99, 1.0, 2.0])))
    if rng is None:                                  # tolerance options, components of keys
        if key == "tolerance.required_yield":
            return toml(draw(st.floats(0.0, 1.5)))
        if integer:
            return toml(draw(st.integers(-2, 20000)))
        return toml(draw(st.floats(-1.0, 1.0)))
    lo, hi, _unit = rng
    if vkind == "in_range":
        return toml(_number_in(draw, lo, hi, integer))
    if vkind == "edge":
        return toml(draw(st.sampled_from([lo, hi])) if not integer else
                    int(draw(st.sampled_from([lo, hi]))))
    if vkind == "outside":
        if integer:
            return toml(draw(st.sampled_from([int(lo) - 1, int(hi) + 1])))
        below = lo - max(abs(lo) * 1e-6, 1e-12) if lo != 0 else -1e-12
        return toml(draw(st.sampled_from([below, hi * (1 + 1e-6) if hi > 0 else hi + 1e-6])))
    # scaled: the default times a factor (a plausible change)
    d = default if isinstance(default, (int, float)) and not isinstance(default, bool) else 1.0
    if isinstance(d, (list, tuple)):
        d = d[0]
    f = draw(st.sampled_from([0.5, 0.9, 1.1, 2.0, 10.0, 0.1]))
    return toml(max(1, int(d * f)) if integer else float(d) * f)


#: optimise.keep_out: (accepted, refused) polygon lists
POLYGONS = (["[]", "[[[-0.030, 0.0505], [-0.026, 0.0505], [-0.026, 0.0545]]]",
             "[[[-0.1, -0.1], [-0.09, -0.1], [-0.09, -0.09], [-0.1, -0.09]]]",
             "[[[0.0, 0.0], [0.05, 0.0], [0.0, 0.05]], [[-0.05, 0.06], [-0.04, 0.06], "
             "[-0.04, 0.07]]]"],
            ["[[[0, 0], [1, 0], [0.2, 0.2], [0, 1]]]", "[[[0, 0], [1, 1]]]",
             "[[[0, 0], [1, 0], [2, 0]]]", "[[[nan, 0], [1, 0], [0, 1]]]",
             "[[[1e300, 0], [1, 0], [0, 1]]]", "[[0, 0], [1, 0], [0, 1]]", "[[[11, 0], "
             "[12, 0], [12, 1]]]", "[1.0]", "[[[0, 0], [1, 0], [1, 1], [0, 0]]]"])
#: optimise.free: (accepted, refused) tables, attachment points among them
FREE_TABLES = (['{"geometry.lid_e[0]" = [-0.006, 0.044], "geometry.lid_e[1]" = [0.004, 0.024]}',
                '{"geometry.spring_anchor[0]" = [-0.09, -0.03]}',
                '{"geometry.dashpot_anchor[1]" = [-0.02, 0.02], '
                '"geometry.dashpot_lid[0]" = [0.0, 0.03]}',
                '{"design.spring_preload" = [0, 200], "geometry.lid_e[1]" = [0.004, 0.024]}',
                '{"geometry.lid_e[0]" = [0.01, 0.01]}'],
               ['{"geometry.lid_e[0]" = [0.044, -0.006]}', '{"geometry.pivot_b[0]" = [0, 1]}',
                '{"geometry.lid_e[2]" = [0, 1]}', '{"geometry.lid_e[0]" = [nan, 1]}',
                '{"geometry.spring_anchor[1]" = [-1e300, 0]}', '{"geometry.lid_e" = [0, 1]}',
                '{"geometry.lid_e[0]" = [0, 11]}', '{"geometry.lid_e[0]" = 0.01}'])


@st.composite
def value_for(draw, key: str, vkind: str) -> str:
    """The TOML text of a value of kind ``vkind`` for ``key``."""
    kind = KIND_OF[key]
    if kind in ("polygons", "free") and vkind not in ("string", "bool", "big_int", "nan"):
        ok, bad = POLYGONS if kind == "polygons" else FREE_TABLES
        return draw(st.sampled_from(bad if vkind in REFUSED_KINDS else ok + bad))
    if kind == "reals" and vkind in ("in_range", "edge", "outside", "scaled", "nan", "inf",
                                     "tiny", "zero", "negative", "huge"):
        # a list of numbers (one to three) of that kind
        comps = [draw(scalar_value(key, "real", vkind)) for _ in range(draw(st.integers(1, 3)))]
        return "[" + ", ".join(comps) + "]"
    if kind in _VEC_LEN:
        n = _VEC_LEN[kind]
        if vkind in ("in_range", "edge", "outside", "scaled", "nan", "inf", "tiny", "zero",
                     "negative", "huge"):
            # a vector of the right length whose components are of that kind (one of them
            # for the refused kinds, all of them for the rest)
            comps = [draw(scalar_value(key, "real", "in_range" if vkind in REFUSED_KINDS
                                       else vkind)) for _ in range(n)]
            if vkind in ("in_range", "edge", "outside", "scaled", "zero", "tiny", "negative"):
                comps = [draw(scalar_value(key, "real", vkind)) for _ in range(n)]
            else:
                comps[draw(st.integers(0, n - 1))] = draw(scalar_value(key, "real", vkind))
            if kind == "bounds" and vkind in ("in_range", "scaled"):
                nums = sorted(float(c) for c in comps)
                comps = [toml(x) for x in nums]
            return "[" + ", ".join(comps) + "]"
        if vkind == "wrong_length":
            return toml([0.05] * draw(st.sampled_from([0, 1, n + 1])))
        return draw(scalar_value(key, "real", vkind))           # a scalar for a vector
    if kind == "component":
        return draw(scalar_value(key, "real", vkind))
    return draw(scalar_value(key, kind, vkind))


@st.composite
def grid_spec(draw) -> str:
    """One --grid KEY=START:STOP:COUNT of a fuzzed sweep: any key, values of any kind."""
    key = draw(st.sampled_from([k for k, _ in KEYS] + ["design.nope", "mass"]))
    if draw(st.integers(0, 4)) == 0:   # a word key: its words, or anything else
        key = draw(st.sampled_from(["design.spring_kind", "design.damper_one_way"]))
        words = draw(st.lists(st.sampled_from(["linear", "extension", "compression", "gas_strut",
                                               "true", "false", "bogus", "", "1", "-1", "nan",
                                               "[]"]),
                              min_size=1, max_size=3))
        return f"{key}={','.join(words)}" if draw(st.booleans()) else \
            f"{key}=[{', '.join(words)}]"
    kind = KIND_OF.get(key, "real")
    ends = []
    for _ in range(2):
        vkind = draw(st.sampled_from(VALUE_KINDS) | st.sampled_from(PLAUSIBLE_KINDS))
        text = draw(scalar_value(key, "real" if kind in _VEC_LEN or kind == "component"
                                 else kind, vkind)) if key in KIND_OF else "1"
        ends.append(text)
    return f"{key}={ends[0]}:{ends[1]}:{draw(st.sampled_from(GRID_COUNTS))}"


@st.composite
def options(draw, command: str, profile: str) -> list[str]:
    """The command's own options: mostly the defaults, sometimes a drawn value."""
    cost = COMMANDS[command][1]
    argv = []
    for opt, (default, choices) in OPTIONS.get(command, {}).items():
        pool = [v for v, cheap in choices if cheap or profile == "long" or cost == "cheap"]
        if cost == "costly" and profile == "fast":
            pool = []
        value = draw(st.sampled_from(pool)) if pool and draw(st.integers(0, 3)) == 0 \
            else default
        if value is not None:           # (None: the base command line's own)
            argv.append(_arg(opt, value))
    if command == "sweep":
        if draw(st.integers(0, 2)) == 0:
            argv.append(f"--grid={draw(grid_spec())}")
        else:
            argv.append("--grid=design.spring_k=0:2000:3")
    return argv


@st.composite
def cases(draw, cost: str, profile: str):
    """[(key, value kind, TOML text)] for one run: one to three keys."""
    n = draw(st.sampled_from([1, 1, 1, 1, 2, 2, 3]))
    out = []
    for _ in range(n):
        key = draw(st.sampled_from([k for k, _ in KEYS]))
        refused_only = profile == "fast" and (
            cost == "costly" or cost == "medium" and _base(key) in WORK_KEYS)
        if refused_only:
            vkind = draw(st.sampled_from(REFUSED_KINDS))
        else:   # half of the draws plausible (most of the others are refused at once)
            vkind = draw(st.sampled_from(VALUE_KINDS) | st.sampled_from(PLAUSIBLE_KINDS))
        out.append((key, vkind, draw(value_for(key, vkind))))
    return out


# -- running a case -------------------------------------------------------------------------
class FuzzTimeout(BaseException):
    """The run exceeded the time its work allows (BaseException: nothing catches it)."""


@contextlib.contextmanager
def time_limit(seconds: float, what: str):
    """Raise FuzzTimeout after ``seconds`` (re-raised every second: CasADi swallows an
    exception raised inside a solve); a hard exit with all tracebacks 120 s later."""
    def handler(signum, frame):
        raise FuzzTimeout(f"{what}: still running after {seconds:.0f} s")
    previous = signal.signal(signal.SIGALRM, handler)
    signal.setitimer(signal.ITIMER_REAL, seconds, 1.0)
    faulthandler.dump_traceback_later(seconds + 120, exit=True, file=sys.__stderr__)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        faulthandler.cancel_dump_traceback_later()
        signal.signal(signal.SIGALRM, previous)


def _arg(opt: str, value: str) -> str:
    """One option as argv gives it: '--opt=value' ('--opt=-1e300': argparse takes it as a
    value), or the value alone for a positional (an OPTIONS name without dashes)."""
    return f"{opt}={value}" if opt.startswith("-") else value


def _option(argv: list[str], name: str) -> list[str]:
    """Every value of option ``name`` in ``argv`` (given as 'name=value' or 'name value')."""
    out = []
    for i, a in enumerate(argv):
        if a.startswith(name + "="):
            out.append(a[len(name) + 1:])
        elif a == name and i + 1 < len(argv):
            out.append(argv[i + 1])
    return out


def _int_option(argv: list[str], name: str, default: int) -> int | None:
    """The integer value of ``name`` in ``argv`` (None if it is not a whole number)."""
    values = _option(argv, name)
    if not values:
        return default
    try:
        return int(values[-1])
    except ValueError:
        return None


def _grid_points(argv: list[str]) -> int | None:
    """Points of the sweep's grids (None when a COUNT is not a whole number)."""
    n = 1
    for spec in _option(argv, "--grid"):
        if ":" not in spec:          # a word key's list of words
            n *= spec.count(",") + 1
            continue
        try:
            n *= max(int(spec.rsplit(":", 1)[-1]), 0)
        except ValueError:
            return None
    return n


def strokes_of(command: str, cfg, argv: list[str]) -> int:
    """How many strokes a batch command asks for (0 for the others)."""
    if command == "yield":
        n = _int_option(argv, "--samples", cfg.tolerance.samples)
        return max(n or 0, 0)
    if command == "sensitivity":
        n = _int_option(argv, "--samples", 1024)
        return max(n or 0, 0) * (len(cfg.tolerance.spreads) + 2)
    if command == "sweep":
        return _grid_points(argv) or 0
    if command == "report":       # a yield's samples (at each temperature: one batch each)
        n = _int_option(argv, "--samples", cfg.tolerance.samples)
        return max(n or 0, 0)
    if command == "select":       # every pair at its corners, the nominal point, the samples
        n = _int_option(argv, "--samples", 256)      # (corners and samples at each sign-off T)
        temps = max(1, len(cfg.operating.temperatures_c or ()))
        return SELECT_PAIRS * (temps * (2 ** (3 + _select_axes(cfg)) + max(n or 0, 0)) + 1)
    return 0


def _select_axes(cfg) -> int:
    """The [tolerance] keys a select box adds to a pair's own (rate, free length, c)."""
    owned = ("design.spring_k", "design.spring_rest_length", "design.damper_c",
             "design.rotary_damper_c")
    return sum(1 for s in cfg.tolerance.spreads if s.key not in owned)


def _refinement_seconds(o) -> float:
    """The optimiser's refinement at the same cost per grid step: when the answer disagrees
    with its simulation it re-solves with the sub-steps doubled, up to MAX_REFINE times and
    within MAX_STEPS steps (softclose.optimiser.polish.refine). A degenerate geometry (a
    lid 0.1 mm long) takes all of them: 70-80 s at 10 nodes x 4 sub-steps, bounded."""
    from softclose.optimiser.discretisation import MAX_STEPS
    from softclose.optimiser.polish import MAX_REFINE
    seconds, m = 0.0, o.substeps
    for _ in range(MAX_REFINE):
        if 2 * o.nodes * m > MAX_STEPS:
            break
        m *= 2
        seconds += o.nodes * m * 0.1
    return seconds


def _nlp_steps(cfg) -> int:
    """RK4 steps of cfg's NLP: nodes x substeps, and with an end damper engaging inside the
    stroke phase 2's too (its sub-steps raised for RK4's stability on the end damper)."""
    from softclose.optimiser.discretisation import discretisation
    try:
        return max(discretisation(cfg).steps, cfg.optimise.nodes * cfg.optimise.substeps)
    except Exception:                # refused when the run starts (exit 2, at once)
        return cfg.optimise.nodes * cfg.optimise.substeps


def work_seconds(command: str, cfg, argv: list[str]) -> float:
    """Seconds a run of ``command`` on ``cfg`` may take: a floor for start-up plus its work
    at generous per-step costs (the machine is shared; the point is to catch a run whose
    length the input makes unbounded, not a 2x slowdown)."""
    steps = steps_per_stroke(cfg)
    o = cfg.optimise
    stroke = 3e-6 * steps                          # h and h/2 for the estimate, radau5 worst
    grid = o.starts * _nlp_steps(cfg) * 0.1        # an NLP: ~10 ms a grid step a start
    refine = _refinement_seconds(o)                # (`optimise`'s polish of its answer)
    batch = strokes_of(command, cfg, argv) * stroke
    if command == "state":
        return 30.0
    if command == "simulate":
        return 30.0 + 3 * stroke
    if command == "sweep":
        return 60.0 + 2 * batch
    if command == "optimise":
        return 60.0 + grid + refine + 20 * stroke
    if command == "pareto":
        spec = (_option(argv, "--closing-times") or ["0.3:3:10"])[-1].split(":")
        count = spec[2] if len(spec) > 2 else "10"
        return 90.0 + (int(count) if count.isdigit() else 10) * (grid + 20 * stroke)
    if command in ("yield", "sensitivity"):
        return 60.0 + 2 * batch
    temps = max(1, len(cfg.operating.temperatures_c or ()))   # (sign-off temperatures)
    if command == "optimise --robust":  # every corner, the search and the yield at each T
        return 300.0 + 10 * grid + 500 * stroke * temps
    if command == "bench":
        return 400.0
    if command == "docs":
        return 30.0
    if command == "prepare":      # one NLP compiled (-O1; the points free: a larger one)
        return 120.0 + (240.0 if _option(argv, "--free") else 0.0) + 0.1 * _nlp_steps(cfg)
    if command == "spring":       # a model (its spring's lengths), then < 1 s of design
        return 30.0
    if command == "report":       # per temperature: strokes, the reference, corners, a yield
        return 60.0 + temps * (30.0 + 2 * batch + 500 * stroke)
    if command == "select":       # the kernel's batch, a model per distinct geometry, the
        # reference at every corner of the verified pairs (0.5 s each)
        d = 3 + _select_axes(cfg)
        verify = max(_int_option(argv, "--verify", 10) or 0, 0)
        placing = 120.0 * min(verify, SELECT_PAIRS) if _option(argv, "--free") else 0.0
        return 60.0 + 2 * batch + (0.2 * SELECT_PAIRS * 2 ** d
                                   + min(verify, SELECT_PAIRS) * 2 ** d * 0.5) * temps \
            + 200 * stroke + placing
    if command == "fit":    # ~1 s a start at the default step; the step halved when needed
        return 60.0 + 3e3 * stroke * int((_option(argv, "--starts") or ["1"])[-1]
                                         if (_option(argv, "--starts") or ["1"])[-1].isdigit()
                                         else 1)
    raise AssertionError(command)


#: a case whose work would take longer than this is not run (the ranges allow it; a test
#: cannot wait for it): it is drawn again
MAX_CASE_SECONDS = 900.0
#: a refusal must come this fast
REFUSAL_SECONDS = 15.0


def _reject_constant(name):
    raise ValueError(f"non-strict JSON token {name}")


COUNTS: dict = {"cases": defaultdict(Counter), "values": defaultdict(Counter),
                "commands": defaultdict(Counter), "warnings": Counter(), "seconds": Counter()}


def _count(command: str, values, outcome: str, seconds: float, warned) -> None:
    kind = values[0][1] if len(values) == 1 else \
        f"combination of {len(values)}" if values else "command options only"
    COUNTS["cases"][kind][outcome] += 1
    for _, vkind, _ in values:
        COUNTS["values"][vkind][outcome] += 1
    COUNTS["commands"][command][outcome] += 1
    COUNTS["seconds"][command] += seconds
    for w in warned:
        COUNTS["warnings"][f"{command}: {w.category.__name__}: {str(w.message)[:80]}"] += 1


def run_inprocess(argv: list[str], limit: float, shown: str):
    """(exit code, stdout, stderr, warnings) of ``main(argv)`` in this process."""
    out, err = io.StringIO(), io.StringIO()
    with warnings.catch_warnings(record=True) as warned:
        warnings.simplefilter("always")
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            try:
                with time_limit(limit, shown):
                    rc = main(argv)
            except FuzzTimeout as exc:
                pytest.fail(f"{exc} (its work allows {limit:.0f} s)")
            except BaseException as exc:  # noqa: BLE001 -- in a shell this is a traceback
                import traceback
                tb = "".join(traceback.format_exception(exc))
                pytest.fail(f"{shown}\nraised {type(exc).__name__} (a traceback in a "
                            f"shell):\n{tb[-3000:]}")
    return rc, out.getvalue(), err.getvalue(), list(warned)


def run_subprocess(argv: list[str], limit: float, shown: str):
    """(exit code, stdout, stderr, warnings) of ``python -m softclose argv``, killed after
    ``limit`` s (for runs that may sit in a compiled loop an alarm cannot stop)."""
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    try:
        proc = subprocess.run([sys.executable, "-m", "softclose", *argv], capture_output=True,
                              text=True, timeout=limit, env=env)
    except subprocess.TimeoutExpired:
        pytest.fail(f"{shown}: still running after {limit:.0f} s")
    return proc.returncode, proc.stdout, proc.stderr, []


def run_case(command: str, values, out_dir: Path, as_json: bool,
             opts: list[str] = (), defaults: bool = True) -> int:
    """Run one case and check everything the module docstring promises (``defaults``: the
    command's options not in ``opts`` get the values of OPTIONS)."""
    base, _cost = COMMANDS[command]
    opts = list(opts)
    for opt, (default, _) in OPTIONS.get(command, {}).items():
        given = _option(opts, opt) if opt.startswith("-") else \
            [a for a in opts if not a.startswith("-")]
        if defaults and not given and default is not None:
            opts.append(_arg(opt, default))
    if command == "sweep" and not _option(opts, "--grid"):
        opts.append("--grid=design.spring_k=0:2000:3")
    argv = [a.replace("{out}", str(out_dir)) for a in base] + opts
    for key, _, text in values:
        argv += ["--set", f"{key}={text}"]
    if as_json:
        argv.append("--json")
    shown = "softclose " + " ".join(argv)
    overrides = [argv[i + 1] for i, a in enumerate(argv) if a == "--set"]
    try:   # the command line is read first (its --free options too), then the config
        args = build_parser().parse_args(argv)
        cfg = load_config(None, overrides + free_overrides(args))
        refused = None
    except ConfigError as exc:
        cfg, refused = None, str(exc)
    over_budget = False
    if cfg is None:
        limit = REFUSAL_SECONDS
    else:
        over_budget = strokes_of(command, cfg, argv) * steps_per_stroke(cfg) > BATCH_STEP_BUDGET
        limit = REFUSAL_SECONDS if over_budget else work_seconds(command, cfg, argv)
        if limit > MAX_CASE_SECONDS:
            reject()
    t0 = time.perf_counter()
    runner = run_subprocess if over_budget else run_inprocess
    rc, stdout, stderr, warned = runner(argv, limit, shown)
    seconds = time.perf_counter() - t0
    outcome = {0: "exit 0", 2: "exit 2", 3: "exit 3"}.get(rc, f"exit {rc}")
    _count(command, values, outcome, seconds, warned)

    assert rc in (0, 2, 3), f"{shown}: exit code {rc}\n{stderr[-2000:]}"
    assert "Traceback" not in stderr, f"{shown}: traceback on stderr\n{stderr[-2000:]}"
    if rc in (2, 3):
        lines = [ln for ln in stderr.splitlines() if ln.strip()]
        assert len(lines) == 1 and lines[0].startswith("softclose: error: "), \
            f"{shown}: exit {rc} must say why in one line, got:\n{stderr[-2000:]}"
    if refused is not None:
        assert rc == 2, f"{shown}: the input is refused ({refused}) but the exit code is {rc}"
        assert stderr.strip() == f"softclose: error: {refused}", \
            f"{shown}: expected the refusal {refused!r}, got {stderr.strip()!r}"
    if over_budget:
        assert rc == 2, (f"{shown}: {strokes_of(command, cfg, argv)} strokes of up to "
                         f"{steps_per_stroke(cfg)} steps exceed the batch budget "
                         f"({BATCH_STEP_BUDGET:g} steps) and must be refused")
    if as_json:
        try:
            payload = json.loads(stdout, parse_constant=_reject_constant)
        except ValueError as exc:
            pytest.fail(f"{shown}: --json output is not strict JSON ({exc}):\n{stdout[:2000]}")
        assert isinstance(payload, dict), f"{shown}: --json must print one object"
        if rc != 0:
            assert payload.get("exit_code") == rc or "error" in payload or \
                payload.get("success") is False, \
                f"{shown}: a failed --json run must say so: {stdout[:500]}"
    return rc


# -- profiles -------------------------------------------------------------------------------
#: examples per command: (fast default run, long "-m fuzz" run); the long profile is sized to
#: run in about five minutes on 2 cores (an accepted prepare compiles an NLP: 10-120 s)
EXAMPLES = {"state": (100, 400), "simulate": (400, 1000), "sweep": (60, 200),
            "optimise": (25, 80), "yield": (25, 100), "sensitivity": (15, 60),
            "pareto": (10, 30), "optimise --robust": (10, 15), "bench": (10, 5),
            "docs": (30, 100), "select": (25, 60), "fit": (25, 60),
            "prepare": (10, 6), "spring": (60, 150), "report": (4, 12)}


@pytest.fixture(scope="module")
def out_root(tmp_path_factory):
    return tmp_path_factory.mktemp("fuzz-out")


@pytest.fixture(scope="module", autouse=True)
def _counts_file(tmp_path_factory):
    """Write the counts of the module's cases when it ends (nothing is printed)."""
    yield
    data = {name: ({k: dict(v) for k, v in table.items()} if isinstance(table, defaultdict)
                   else dict(table)) for name, table in COUNTS.items()}
    data["total"] = sum(sum(c.values()) for c in COUNTS["commands"].values())
    text = json.dumps(data, indent=1, sort_keys=True)
    (tmp_path_factory.getbasetemp() / "fuzz-counts.json").write_text(text)
    if os.environ.get("SOFTCLOSE_FUZZ_COUNTS"):
        path = Path(os.environ["SOFTCLOSE_FUZZ_COUNTS"])
        worker = os.environ.get("PYTEST_XDIST_WORKER")   # (-n: one file per test process)
        if worker:
            path = path.with_name(f"{path.stem}-{worker}{path.suffix}")
        path.write_text(text)


@pytest.fixture(scope="module", autouse=True)
def _warm():
    """Import and compile once, outside the timed runs."""
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        main(["simulate", "--json"])


def _fuzz(command: str, profile: str, out_root: Path) -> None:
    """Draw and run the profile's examples of ``command`` (hypothesis)."""
    n = [0]

    # both profiles draw the same cases on every run, so that CI is reproducible; set
    # SOFTCLOSE_FUZZ_RANDOM=1 to explore new draws (a failure prints its reproduce blob)
    @settings(max_examples=EXAMPLES[command][0 if profile == "fast" else 1],
              derandomize=not os.environ.get("SOFTCLOSE_FUZZ_RANDOM"), database=None,
              deadline=None,
              suppress_health_check=list(HealthCheck), print_blob=True,
              phases=(Phase.explicit, Phase.generate))
    @given(data=st.data())
    def fuzz(data):
        values = data.draw(cases(COMMANDS[command][1], profile), label="values")
        opts = data.draw(options(command, profile), label="options")
        as_json = data.draw(st.booleans(), label="json")
        n[0] += 1
        run_case(command, values, out_root / f"{command.split()[0]}-{profile}-{n[0]}", as_json,
                 opts)

    fuzz()


# explicit examples: the issue's inputs, and what the fuzzing found (fixed since)
ISSUE_CASES = [
    ("optimise", [("geometry.lid_length", "huge", "1e300")], []),
    ("simulate", [("mass.inertia_lid", "in_range", "2"), ("design.spring_k", "huge", "1e300")],
     []),
    ("optimise", [("optimise.closing_time_max", "huge", "1e9")], []),
    ("optimise", [("optimise.closing_time_max", "in_range", "30.0")], []),  # past t_max
    ("simulate", [("stroke.theta0_deg", "huge", "1e300")], []),
    ("simulate", [("design.spring_k", "big_int", "1" + "0" * 400)], []),
    ("simulate", [("simulate.step", "edge", "1e-07"), ("stroke.t_max", "edge", "60.0")], []),
    ("state", [], ["--theta-deg=1e12"]),
    ("state", [], ["--theta-dot=1e300"]),
    ("simulate", [("geometry.spring_anchor", "bool", "false"),
                  ("geometry.spring_anchor[1]", "scaled", "2.0")], []),
    ("optimise", [("optimise.starts", "big_int", "1" + "0" * 400)], []),
    # a lid of 0.37 mm: exit 3, and CasADi must not add its own warnings to the one line
    ("optimise", [("geometry.lid_length", "in_range", "0.00036890193232696903")], []),
    # the fit: an accepted run, a lid of another mass, two starts, a bad file, a gyroscope
    ("fit", [], []),
    ("fit", [("mass.lid", "in_range", "0.6")], ["--starts=2"]),
    ("fit", [], [str(BAD_DATA / "backwards.csv")]),
    ("fit", [("geometry.crank_oa", "in_range", "0.03")], [str(FIT_DATA / "gyroscope.csv")]),
    # the end damper (issue 23): engaging inside the stroke, from the release (its angle at
    # or above theta0), never (at or below the rim), stiff enough that rk4 is unstable
    # (exit 3 with the step: its crossings must not chatter without time passing), refused
    # values, a grid over both keys, the state below the angle
    ("simulate", [("design.end_damper_c", "in_range", "0.8"),
                  ("design.end_damper_angle_deg", "in_range", "10.0")], []),
    ("simulate", [("design.end_damper_c", "in_range", "2.0"),
                  ("design.end_damper_angle_deg", "edge", "360.0")], []),
    ("simulate", [("design.end_damper_c", "in_range", "2.0"),
                  ("design.end_damper_angle_deg", "edge", "-360.0")], []),
    ("simulate", [("design.end_damper_c", "edge", "100000.0")], []),
    ("simulate", [("design.end_damper_c", "negative", "-1.0")], []),
    ("simulate", [("design.end_damper_angle_deg", "outside", "360.5")], []),
    ("simulate", [("design.end_damper_angle_deg", "string", '"low"')], []),
    ("sweep", [], ["--grid=design.end_damper_angle_deg=-10:30:3",
                   "--grid=design.end_damper_c=0:1e5:3"]),
    ("state", [("design.end_damper_c", "in_range", "1.0")], ["--theta-deg=2", "--theta-dot=-3"]),
    # the optimiser with the end damper (issue 23 item 2): its two phases with both keys
    # free; an angle free without a damper (refused at the run); a damper so stiff that
    # phase 2's RK4 steps exceed the NLP's budget (refused, naming the end damper)
    ("optimise", [], ["--free=design.end_damper_c=0:2", "--free=design.end_damper_angle_deg=1:10"]),
    ("optimise", [], ["--free=design.end_damper_angle_deg=1:10"]),
    ("optimise", [("design.end_damper_c", "edge", "100000.0")], []),
    # the self-close constraint in the optimiser: an angle it meets; one below the rim (the
    # rim alone); one above the open angle (exit 2); with free attachment points (refused)
    ("optimise", [("optimise.self_close_min_deg", "in_range", "10.0")], []),
    ("optimise", [("optimise.self_close_min_deg", "edge", "-360.0")], []),
    ("optimise", [("optimise.self_close_min_deg", "edge", "360.0")], []),
    ("optimise", [("optimise.self_close_min_deg", "in_range", "10.0")],
     ["--free=geometry.spring_anchor[0]=-0.09:-0.03"]),
    # the coil spring made to order: designed; checked (fails buckling and the rate: exit 3);
    # an index outside 4..20, coils without the wire, a wire the material lacks (exit 2);
    # no room at all (exit 3); a free length shorter than the stroke's longest (exit 2)
    ("spring", [], []),
    ("spring", [("spring.wire_d", "in_range", "0.002"), ("spring.coil_d", "in_range", "0.016"),
                ("spring.active_coils", "in_range", "17.0")], []),
    ("spring", [("spring.wire_d", "in_range", "0.001"), ("spring.coil_d", "in_range", "0.03")],
     []),
    ("spring", [("spring.active_coils", "in_range", "5.0")], []),
    ("spring", [("spring.wire_d", "in_range", "0.0002")], []),
    ("spring", [("spring.max_outer_d", "edge", "0.0001")], []),
    ("spring", [("design.spring_rest_length", "in_range", "0.05")], []),
    ("spring", [("design.spring_kind", "string", '"extension"')], []),
    # an extension spring made to order (EN 13906-2's body): designed, its figure drawn
    ("spring", [("design.spring_kind", "string", '"extension"'),
                ("design.spring_rest_length", "in_range", "0.045"),
                ("design.spring_preload", "in_range", "2.0")], []),
    # temperature as a scenario dimension: the robust design and select at 0, 23 and 40 °C
    # with a silicone-oil damper, a stroke temperature alone (its one sign-off temperature),
    # a sweep over the stroke's temperature
    ("optimise --robust", [("operating.temperatures_c", "in_range", "[0.0, 23.0, 40.0]"),
                           ("design.damper_temperature_coeff", "in_range", "-0.005")], []),
    ("optimise --robust", [("operating.temperature_c", "in_range", "-10.0")], []),
    ("select", [("operating.temperatures_c", "in_range", "[0.0, 23.0, 40.0]"),
                ("design.damper_temperature_coeff", "in_range", "-0.005")], []),
    ("sweep", [("design.damper_temperature_coeff", "in_range", "-0.005")],
     ["--grid=operating.temperature_c=-60:150:4"]),
    # the end of life (SPEC §17): a stroke at it, a sweep over the state, the yield and the
    # robust design signed off new and at the end of life, a value at its strict end
    ("simulate", [("life.strut_force_loss", "in_range", "0.1"),
                  ("life.damper_change", "in_range", "-0.15"),
                  ("life.state", "string", '"end_of_life"')], []),
    ("simulate", [("life.strut_force_loss", "edge", "1.0")], []),
    ("sweep", [("life.damper_change", "in_range", "-0.15")],
     ["--grid=life.state=[new, end_of_life]"]),
    ("yield", [("life.damper_change", "in_range", "-0.15"),
               ("life.spring_relaxation", "in_range", "0.03")], []),
    ("optimise --robust", [("life.spring_relaxation", "in_range", "0.03"),
                           ("life.damper_change", "in_range", "-0.15")], []),
]


#: explicit cases of 10-30 s each, run with the slow tests (a faster case covers each command)
SLOW_ISSUE_CASES = {"fit mass.lid=0.6 --starts=2", "optimise optimise.closing_time_max=30.0",
                    "optimise --free=design.end_damper_c=0:2 --free=design.end_damper_angle_deg=1:10",
                    "optimise --robust operating.temperatures_c=[0.0, 23 "
                    "design.damper_temperature_coeff=-0.005",
                    "optimise --robust operating.temperature_c=-10.0",
                    "optimise --robust life.spring_relaxation=0.03 life.damper_change=-0.15"}
ISSUE_IDS = [f"{c} " + " ".join([f"{k}={t[:8]}" for k, _, t in v] + o) for c, v, o in ISSUE_CASES]


@pytest.mark.parametrize("command,values,opts", [
    pytest.param(*case, marks=pytest.mark.slow) if name in SLOW_ISSUE_CASES else case
    for case, name in zip(ISSUE_CASES, ISSUE_IDS)], ids=ISSUE_IDS)
def test_issue_inputs(command, values, opts, out_root):
    """The inputs of the issue (and what the fuzzing found) end with a one-line error or an
    answer; the three of the issue are refused naming the key, its value and its range."""
    if command not in AVAILABLE:
        pytest.skip(f"softclose {command} is not registered in this build")
    rc = run_case(command, values, out_root / "issue", as_json=False, opts=opts)
    if values and values[-1][2] in ("1e300", "1e9"):
        assert rc == 2


#: batches within every other bound whose strokes x steps exceed the batch budget: at the
#: smallest step (5e7 steps a stroke), or the largest [tolerance] sample count at a small step
_SMALLEST_STEP = [("simulate.step", "edge", "1e-07")]
BUDGET_CASES = [
    ("sweep", ["--grid", "design.spring_k=0:2000:5000", "--grid", "design.damper_c=0:2000:4000"],
     _SMALLEST_STEP),
    ("yield", ["--samples", "10000000"], _SMALLEST_STEP),
    ("sensitivity", ["--samples", str(2 ** 20)], _SMALLEST_STEP),
    ("yield", [], [("tolerance.samples", "edge", "10000000"), ("simulate.step", "edge", "1e-06")]),
    ("optimise --robust", [], [("tolerance.samples", "edge", "10000000"),
                               ("simulate.step", "edge", "1e-06")]),
]


@pytest.mark.parametrize("command,opts,values", BUDGET_CASES,
                         ids=[f"{c} {' '.join(o)} {v[0][0]}={v[0][2]}"[:70]
                              for c, o, v in BUDGET_CASES])
def test_batch_budget(command, opts, values, out_root):
    """Designs x steps per stroke is bounded: these batches would run for days; they must be
    refused at once, naming what to change (run in a subprocess, killed after 15 s)."""
    if command not in AVAILABLE:
        pytest.skip(f"softclose {command} is not registered in this build")
    if command == "optimise --robust":   # samples of the yield estimate: also a batch
        cfg = load_config(None, [f"{k}={t}" for k, _, t in values])
        assert cfg.tolerance.samples * steps_per_stroke(cfg) > BATCH_STEP_BUDGET
        rc, _, stderr, _ = run_subprocess(
            ["optimise", "--robust", *[a for k, _, t in values for a in ("--set", f"{k}={t}")]],
            REFUSAL_SECONDS, f"softclose optimise --robust {values}")
        assert rc == 2, stderr
        return
    assert run_case(command, values, out_root / f"budget-{command}", as_json=False,
                    opts=opts, defaults=False) == 2


#: the fast profile's costliest commands (10-45 s each) run with the slow tests
SLOW_FUZZ = {"sweep", "optimise", "fit"}


@pytest.mark.parametrize("command", [pytest.param(c, marks=pytest.mark.slow) if c in SLOW_FUZZ
                                     else c for c in COMMANDS])
def test_fuzz(command, out_root):
    """Fast profile (the default run): the module docstring's promises on every command."""
    if command not in AVAILABLE:
        pytest.skip(f"softclose {command} is not registered in this build")
    _fuzz(command, "fast", out_root)


@pytest.mark.fuzz
@pytest.mark.parametrize("command", list(COMMANDS))
def test_fuzz_long(command, out_root, request):
    """Long profile (``pytest -m fuzz``, run by CI): every kind of value everywhere."""
    if "fuzz" not in (request.config.getoption("markexpr") or ""):
        pytest.skip("the long fuzz profile runs with -m fuzz")
    if command not in AVAILABLE:
        pytest.skip(f"softclose {command} is not registered in this build")
    _fuzz(command, "long", out_root)


#: a sample run as real processes: a traceback would reach stderr there
SUBPROCESS_SAMPLE = [
    ["optimise", "--set", "geometry.lid_length=1e300"],
    ["simulate", "--set", "mass.inertia_lid=2", "--set", "design.spring_k=1e300"],
    ["optimise", "--set", "optimise.closing_time_max=1e9"],
    ["state", "--theta-deg=1e12", "--json"],
    ["simulate", "--set", "design.damper_c=nan", "--json"],
    ["simulate", "--set", "design.spring_k=" + "9" * 400],
    ["sweep", "--grid", "design.spring_k=nan:1:3", "--out", "{out}"],
    ["sweep", "--grid=geometry.assembly[0]=2.0:10.0:1000000000000", "--out", "{out}"],
    ["fit", str(BAD_DATA / "binary.csv"), "--free", "design.damper_c"],
    ["fit", str(BAD_DATA / "nan_row.csv"), "--free", "design.damper_c", "--json"],
]


@pytest.mark.parametrize("argv", SUBPROCESS_SAMPLE, ids=[" ".join(a)[:60] for a in
                                                         SUBPROCESS_SAMPLE])
def test_subprocess_sample(argv, tmp_path):
    """A sample in fresh ``python -m softclose`` processes: one line on stderr, no traceback."""
    if argv[0] not in {c.split()[0] for c in AVAILABLE}:
        pytest.skip(f"softclose {argv[0]} is not registered in this build")
    argv = [a.replace("{out}", str(tmp_path / "out")) for a in argv]
    rc, stdout, stderr, _ = run_subprocess(argv, 120.0, "softclose " + " ".join(argv))
    assert "Traceback" not in stderr, stderr[-3000:]
    assert rc == 2, f"exit {rc}: {stderr[-2000:]}"
    lines = [ln for ln in stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("softclose: error: "), stderr
    if "--json" in argv:
        payload = json.loads(stdout, parse_constant=_reject_constant)
        assert payload["exit_code"] == 2 and payload["error"] == lines[0][len("softclose: error: "):]


# -- the admissible ranges themselves ---------------------------------------------------------
#: other keys an edge value needs to pass the cross-checks (step < t_max, min < max, budgets)
_COMPANIONS = {
    ("stroke.t_max", "lo"): {"simulate.step": 1e-7},
    ("optimise.nodes", "hi"): {"optimise.substeps": 1},
    ("optimise.substeps", "hi"): {"optimise.nodes": 1},
    ("stroke.theta_closed_deg", "hi"): None,     # must lie below theta0_deg (<= 360)
    ("stroke.theta0_deg", "lo"): None,           # must lie above theta_closed_deg (>= -360)
    ("stroke.theta_open_deg", "lo"): None,       # must lie above theta_closed_deg (>= -360)
    ("optimise.closing_time_min", "hi"): None,   # must lie below closing_time_max (<= 60)
    ("spring.wire_d", "lo"): {"spring.material": "EN10270-1-DH"},   # SH starts at 0.28 mm
    # the coils only with the wire and the coil diameter (4 <= D/d <= 20)
    ("spring.active_coils", "lo"): {"spring.wire_d": 0.002, "spring.coil_d": 0.016},
    ("spring.active_coils", "hi"): {"spring.wire_d": 0.002, "spring.coil_d": 0.016},
}


def _edge_config(key: str, value):
    kind = SCHEMA[key.split(".")[0]][key.split(".")[1]][0]
    n = _VEC_LEN.get(kind, 1 if kind == "reals" else None)
    raw = {key: [value] * n if n else value}
    return raw, kind


@pytest.mark.parametrize("key", list(RANGES))
def test_ranges(key):
    """Every range is enforced with one line naming the key, the value and the range, and
    both of its ends are admissible (with the cross-checked keys set to match)."""
    from softclose.config import default_config
    lo, hi, unit = RANGES[key]
    integer = isinstance(lo, int) and isinstance(hi, int)
    for end, x in (("lo", lo), ("hi", hi)):
        companions = _COMPANIONS.get((key, end), {})
        if companions is None:
            continue
        raw, kind = _edge_config(key, x)
        if key == "optimise.closing_time_min":
            raw["stroke.t_max"] = 60.0
        cfg = default_config().update({**companions, **raw})
        got = getattr(getattr(cfg, key.split(".")[0]), key.split(".")[1])
        assert got == (tuple([float(x)] * len(got)) if isinstance(got, tuple) else x)
    outside = [int(lo) - 1, int(hi) + 1] if integer else \
        [lo - max(abs(lo), 1e-3) * 1e-3, hi + max(abs(hi), 1e-3) * 1e-3]
    for x in outside:
        raw, kind = _edge_config(key, x)
        if kind in ("pos", "int+") and x <= 0 or kind == "nonneg" and x < 0:
            continue                                 # the sign check speaks first
        with pytest.raises(ConfigError) as info:
            default_config().update(raw)
        msg = str(info.value)
        assert "\n" not in msg and msg.startswith(key) and f"{x:g}" in msg
        assert f"{lo:g}..{hi:g}" in msg and "admissible range" in msg


def test_budgets():
    """The step budget (t_max / step) and the NLP budget (nodes x substeps) are enforced
    with one line naming the keys; the defaults and the stress cases' extremes pass."""
    from softclose.config import NLP_BUDGET, STEP_BUDGET, default_config
    cfg = default_config()
    assert steps_per_stroke(cfg) == 2500
    assert steps_per_stroke(cfg.update({"simulate.step": 1e-7})) == STEP_BUDGET   # 5 s
    with pytest.raises(ConfigError, match=r"^simulate\.step: .* steps a stroke, above the "):
        cfg.update({"simulate.step": 1e-7, "stroke.t_max": 5.01})
    cfg.update({"optimise.nodes": NLP_BUDGET // 4, "optimise.substeps": 4})
    with pytest.raises(ConfigError, match=r"^optimise\.nodes x optimise\.substeps: "):
        cfg.update({"optimise.nodes": NLP_BUDGET // 4 + 1, "optimise.substeps": 4})
    with pytest.raises(ConfigError, match=r"^optimise\.closing_time_min: .* stroke\.t_max"):
        cfg.update({"optimise.closing_time_min": 2.0, "optimise.closing_time_max": 3.0,
                    "stroke.t_max": 1.5})
    # a closing-time limit past t_max cannot bind: admitted (the optimiser clamps it)
    assert cfg.update({"optimise.closing_time_max": 30.0}).optimise.closing_time_max == 30.0


def test_stress_designs_admitted():
    """The ranges admit every design of the stress survey (dampers to 1e6 N s/m, springs to
    1e6 N/m, steps from 1e-7 s to 1 s, 60 s strokes): they bound nonsense, not studies."""
    stress = pytest.importorskip("softclose.validation.stress")
    from softclose.config import default_config
    for case in stress.stress_cases(fast=False):
        default_config().replace(**case.overrides)     # raises ConfigError if refused


@pytest.mark.parametrize("sets,rows", [
    (["simulate.step=1e-6", "design.spring_k=2000", "design.spring_rest_length=0.1"],
     "5000002 rows (to stroke.t_max)"),                  # held open: runs to t_max
    (["simulate.step=1e-7"], "1491481 rows (to the closing)"),
])
def test_trajectory_budget(sets, rows, tmp_path):
    """``simulate --out`` keeps one row a step: a trajectory above TRAJECTORY_BUDGET rows is
    refused in one line with the step that fits (5e7 rows would take 40 GB and 30 minutes),
    and that step fits."""
    import re
    argv = ["simulate", "--out", str(tmp_path / "a")]
    for s in sets:
        argv += ["--set", s]
    rc, _, stderr, _ = run_inprocess(argv, 60.0, " ".join(argv))
    assert rc == 2 and f"would have {rows}, above the budget of 1e+06" in stderr, stderr
    step = float(re.search(r"use simulate\.step >= (\S+) s", stderr).group(1))
    # that step fits (checked without writing a million rows): no refusal, and its stroke
    # has at most the budget's rows
    from softclose.config import TRAJECTORY_BUDGET
    from softclose.simulation.simulator import Simulator
    cfg = load_config(None, sets + [f"simulate.step={step}"])
    sim = Simulator.from_config(cfg)
    p = sim.model.params()
    sim._check_trajectory_size(np.r_[p, sim.energy_tol(p[None, :])])
    r = sim.run(estimate_error=False)
    steps = r.steps if r.closed else math.ceil(cfg.stroke.t_max / step)
    assert steps + 2 <= TRAJECTORY_BUDGET


# -- files and signals (the long profile) -----------------------------------------------------
#: encodings a config may come in from an editor
ENCODINGS = ("utf-8", "utf-8-sig", "latin-1", "cp1252", "utf-16", "shift_jis")


@st.composite
def config_bytes(draw) -> bytes:
    """Random bytes, or a config's text (a comment of any characters, then a valid key) in
    one of :data:`ENCODINGS`."""
    if draw(st.booleans()):
        return draw(st.binary(max_size=400))
    comment = draw(st.text(max_size=60)).replace("\r", " ").replace("\n", " ")
    text = f"# {comment}\n[mass]\nlid = 0.5\n"
    return text.encode(draw(st.sampled_from(ENCODINGS)), errors="replace")


@pytest.mark.fuzz
@settings(max_examples=40, deadline=None, database=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=config_bytes())
def test_fuzz_config_files(data, out_root):
    """A config of random bytes or in another encoding: read (exit 0, the same config as its
    UTF-8 text) or refused in one line naming the file (exit 2); never a traceback."""
    path = out_root / "random.toml"
    path.write_bytes(data)
    argv = ["state", "--theta-deg", "30", "--config", str(path)]
    rc, out, err, _ = run_inprocess(argv, 30.0, f"config bytes {data[:40]!r}")
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert rc in (0, 2), err
    if rc == 2:
        assert len(lines) == 1 and lines[0].startswith("softclose: error: "), err
    else:
        assert out.strip()
        text = data.decode("utf-8-sig")          # (read: so it is UTF-8, BOM or not)
        assert "\0" not in text


#: what each command writes in --out (a name that may collide), and a cheap command line
COLLIDING = {
    "simulate": (["simulate", "--set", "stroke.t_max=0.3"],
                 ["stroke_trajectory.csv", "stroke_time.png", "stroke_animation.gif",
                  "hand_force.png"]),
    "optimise": (["optimise"], ["design.toml", "optimise.json", "optimum.png",
                                "optimum_trajectory.csv", "optimum_animation.gif"]),
    "yield": (["yield", "--samples", "50", "--set", "tolerance.design.spring_k=0.05"],
              ["yield_samples.csv", "yield_histograms.png"]),
    "sweep": (["sweep", "--grid", "design.spring_k=0:400:3"], ["sweep.csv", "manifest.json"]),
}


@pytest.mark.fuzz
@settings(max_examples=20, deadline=None, database=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(command=st.sampled_from(sorted(COLLIDING)), what=st.sampled_from(
    ["folder at a file", "out is a file", "out under a file", "nothing"]), pick=st.integers(0, 9))
def test_fuzz_output_collisions(command, what, pick, out_root):
    """An --out folder or a file in it colliding with a file or a folder: exit 2 with one
    line naming it before any work (nothing written), or -- nothing in the way -- exit 0;
    never a traceback, never a temporary file left."""
    import shutil
    import uuid
    argv, names = COLLIDING[command]
    case = out_root / f"collide-{uuid.uuid4().hex[:8]}"
    case.mkdir()
    out = case / "out"
    name = names[pick % len(names)]
    if what == "nothing" and command == "optimise":
        what = "folder at a file"                   # (an optimiser run is not drawn: 10 s)
    if what == "folder at a file":
        (out / name).mkdir(parents=True)
        culprit = name
    elif what == "out is a file":
        out.write_text("a file")
        culprit = str(out)
    elif what == "out under a file":
        case.joinpath("file").write_text("a file")
        out = case / "file" / "out"
        culprit = str(out)
    before = sorted(p.relative_to(case) for p in case.rglob("*"))
    rc, _, err, _ = run_inprocess([*argv, "--out", str(out)], 60.0, f"{command} {what}")
    lines = [ln for ln in err.splitlines() if ln.strip()]
    if what == "nothing":
        assert rc == 0, err
        assert not [p for p in out.iterdir() if p.name.startswith(".")]
    else:
        assert rc == 2 and len(lines) == 1 and culprit in lines[0], err
        assert sorted(p.relative_to(case) for p in case.rglob("*")) == before
    shutil.rmtree(case)


def _marked_processes(mark: str) -> list[str]:
    """Live processes (not zombies) carrying ``mark`` in their environment."""
    found = []
    for d in Path("/proc").iterdir():
        if not d.name.isdigit() or int(d.name) == os.getpid():
            continue
        try:
            if mark.encode() not in (d / "environ").read_bytes():
                continue
            state = (d / "stat").read_text().rsplit(")", 1)[1].split()[0]
            cmd = (d / "cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
        except OSError:
            continue
        if state != "Z":
            found.append(f"{d.name}: {cmd[:120]}")
    return found


def _guarded(pid: int) -> bool:
    """Whether the process ``pid`` handles SIGTERM (its command runs under
    :func:`softclose.interrupt.guard`; before, in the interpreter's start-up, a signal has
    the system's default effect)."""
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return True
    caught = next(int(x.split()[1], 16) for x in status.splitlines() if x.startswith("SigCgt:"))
    return bool(caught & (1 << (signal.SIGTERM - 1)))


#: the commands interrupted at random moments, and the latest moment drawn (s after start;
#: on an empty cache prepare builds its model ~3 s, then compiles ~10 s)
SIGNALLED = {
    "prepare": (["prepare"], 12.0),
    "optimise --robust": (["optimise", "--robust"], 10.0),
    "sweep": (["sweep", "--grid", "design.spring_k=0:5000:300", "--grid",
               "design.damper_c=0:5000:300", "--out", "{out}"], 6.0),
}


@pytest.mark.fuzz
@pytest.mark.skipif(not Path("/proc/self/environ").exists(), reason="scans /proc (Linux)")
@pytest.mark.parametrize("name", list(SIGNALLED))
@settings(max_examples=3, deadline=None, database=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(fraction=st.floats(0.0, 1.0), sig=st.sampled_from([signal.SIGINT, signal.SIGTERM]))
def test_fuzz_signals(name, fraction, sig, tmp_path_factory):
    """SIGINT or SIGTERM to the softclose process alone (as a supervisor sends it) at a random
    moment once the command runs (its handler installed), on an empty cache: exit 0, 2, 3 or
    130, at most one error line starting a line, no traceback; one second after it returns no process of the command is alive, and no
    temporary file is left in the cache or the temporary folder."""
    import uuid
    argv, latest = SIGNALLED[name]
    case = tmp_path_factory.mktemp("signal")
    cache, tmp = case / "cache", case / "tmp"
    tmp.mkdir()
    mark = f"softclose-signal-{uuid.uuid4().hex}"
    env = {**os.environ, "SOFTCLOSE_CACHE": str(cache), "TMPDIR": str(tmp),
           "SOFTCLOSE_TEST_MARK": mark}       # (the installed package: its kernel is built)
    argv = [a.replace("{out}", str(case / "out")) for a in argv]
    proc = subprocess.Popen([sys.executable, "-m", "softclose", *argv], cwd=case, env=env,
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 60
    while not _guarded(proc.pid) and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.01)
    delay = fraction * latest
    try:
        proc.wait(timeout=delay)
    except subprocess.TimeoutExpired:
        proc.send_signal(sig)
    try:
        err = proc.communicate(timeout=60)[1]
    except subprocess.TimeoutExpired:
        proc.kill()
        pytest.fail(f"softclose {name}: still running 60 s after {sig.name}")
    shown = f"softclose {name}, {sig.name} after {delay:.2f} s"
    assert proc.returncode in (0, 2, 3, 130), f"{shown}: exit {proc.returncode}: {err[-2000:]}"
    assert "Traceback" not in err, f"{shown}: {err[-3000:]}"
    errors = [ln for ln in err.splitlines() if "softclose: error:" in ln
              or "softclose: interrupted" in ln]
    assert len(errors) <= 1 and all(ln.startswith("softclose: ") for ln in errors), \
        f"{shown}: {err[-2000:]}"
    time.sleep(1.0)
    left = _marked_processes(mark)
    assert not left, f"{shown}: processes left running: {left}"
    temporaries = [str(p) for p in cache.rglob(".*") if ".tmp" in p.name or
                   p.name.startswith(".build-")] + [str(p) for p in tmp.iterdir()]
    assert not temporaries, f"{shown}: temporary files left: {temporaries}"
