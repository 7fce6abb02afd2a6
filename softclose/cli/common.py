"""What every command shares: the outcome type, the common options, the output folder check,
the metrics table and the writing of a result's table and figure."""

from __future__ import annotations

import argparse
import os
import sys
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import ConfigError
from ..files import check_targets


@dataclass(frozen=True)
class Outcome:
    """What a command reports: a JSON-able payload, its text form, an exit code, the files
    it wrote, and (exit code 3) the one-line error that goes to stderr."""

    payload: dict
    text: str
    exit_code: int = 0
    files: tuple = field(default_factory=tuple)
    error: str | None = None


def add_common(p: argparse.ArgumentParser) -> None:
    """--config, --set and --json (every command)."""
    p.add_argument("--config", metavar="FILE",
                   help="TOML config file, e.g. the design.toml that `softclose optimise "
                        "--out D` writes (every key: `softclose docs keys`)")
    p.add_argument("--set", dest="overrides", action="append", default=[],
                   metavar="SECTION.KEY=VALUE",
                   help="override one config key; the value is read as TOML (repeatable)")
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")


#: the figure formats and styles of the commands (softclose.present.figures.FORMATS / STYLES: not
#: imported here, matplotlib is not needed to parse a command line)
FIGURE_FORMATS = ("png", "pdf", "svg")
FIGURE_STYLES = ("screen", "report")
#: how this command writes its figures (set from its options by :func:`set_figures`)
FIGURES = {"format": "png", "style": None}


def add_out(p: argparse.ArgumentParser, required: bool = False, what: str = "",
            figures: bool = True) -> None:
    p.add_argument("--out", metavar="DIR", required=required,
                   help=what or "folder for the tables and figures (created if missing)")
    if figures:
        add_figures(p)


def add_figures(p: argparse.ArgumentParser) -> None:
    """--figure-format and --figure-style (every command that writes figures)."""
    p.add_argument("--figure-format", choices=FIGURE_FORMATS, default=None,
                   help="file format of the figures (default png; pdf with "
                        "--figure-style report)")
    p.add_argument("--figure-style", choices=FIGURE_STYLES, default=None,
                   help="screen (default) or report: a 3.5 in column (two columns for "
                        "panels side by side), 8-pt text, vector by default")


def set_figures(args) -> None:
    """How this command writes figures, from its options (none: PNG in the current style of
    :mod:`softclose.present.figures`, the screen's unless the environment says otherwise)."""
    st = getattr(args, "figure_style", None)
    fmt = getattr(args, "figure_format", None) or ("pdf" if st == "report" else "png")
    FIGURES.update(format=fmt, style=st)


def figure_path(path) -> Path:
    """``path`` with the suffix of this command's figure format."""
    return Path(path).with_suffix("." + FIGURES["format"])


def save_figure(fig, path) -> Path:
    """Write ``fig`` as ``path`` in this command's figure format and style (the suffix of
    ``path`` is replaced) and close it."""
    from ..present.figures import save
    return save(fig, figure_path(path), style=FIGURES["style"])


def stroke_files(stem: str) -> list[str]:
    """The files :func:`softclose.simulation.folder.write_stroke_outputs` writes for ``stem``."""
    return [f"{stem}_trajectory.csv", f"{stem}_animation.gif",
            *figures(f"{stem}_time", f"{stem}_linkage")]


#: the admissible --slow-motion factors of a stroke's animation
SLOW_MOTION_RANGE = (1.0, 1000.0)


def add_slow_motion(p: argparse.ArgumentParser) -> None:
    """--slow-motion FACTOR: how much slower than the stroke its GIF plays (with --out)."""
    p.add_argument("--slow-motion", metavar="FACTOR", type=str, default=None,
                   help="with --out: the animation plays FACTOR times slower than the stroke "
                        f"({SLOW_MOTION_RANGE[0]:g}..{SLOW_MOTION_RANGE[1]:g}; default: the "
                        "smallest of 1, 2, 5, 10, 20, ... showing at least 60 frames, x20 "
                        "for the default 0.15 s stroke; at most 60 s of animation)")


def slow_motion(args) -> float | None:
    """The --slow-motion factor (None: the default), checked before any work."""
    import math
    text = getattr(args, "slow_motion", None)
    if text is None:
        return None
    lo, hi = SLOW_MOTION_RANGE
    try:
        x = float(text)
    except ValueError:
        raise ConfigError(f"--slow-motion {text}: expected a number (how many times slower "
                          f"than the stroke the animation plays, {lo:g}..{hi:g})") from None
    if not (math.isfinite(x) and lo <= x <= hi):
        raise ConfigError(f"--slow-motion {text}: outside {lo:g}..{hi:g} (1: real time)")
    return x


def figures(*stems: str) -> list[str]:
    """The names of figures ``stems`` in this command's figure format."""
    return [figure_path(s).name for s in stems]


def prepare_out(path: str | os.PathLike | None, files=()) -> Path | None:
    """Check and create the output folder before any work is done.

    A path that names an existing file, lies under a file, or cannot be created or written
    is refused with one line naming it (exit 2), so that no result is computed and then lost;
    so is a name in ``files`` (the files the command writes there; ``NAME/``: a folder) that
    is a folder or cannot be replaced (:func:`softclose.files.check_targets`).
    """
    if path is None:
        return None
    p = Path(path)
    if p.exists() and not p.is_dir():
        raise ConfigError(f"--out {path}: exists and is not a folder; name a folder")
    try:
        p.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ConfigError(f"--out {path}: cannot create the folder "
                          f"({exc.strerror or type(exc).__name__})") from None
    probe = p / f".softclose-write-test-{os.getpid()}"
    try:
        probe.write_bytes(b"")
        probe.unlink()
    except OSError as exc:
        raise ConfigError(f"--out {path}: cannot write in the folder "
                          f"({exc.strerror or type(exc).__name__})") from None
    check_targets(p, files)
    return p


def interactive(args) -> bool:
    """Draw progress: stderr is a terminal and the output is not --json."""
    return (not getattr(args, "json", False)) and sys.stderr.isatty()


def saved(res, out: Path | None, payload: dict, *args) -> list[Path]:
    """With ``--out``: ``res.save(out, *args, figure format, figure style)`` (in this
    command's figure options), its files also listed in ``payload["files"]``; without: no
    file."""
    if out is None:
        return []
    files = res.save(out, *args, FIGURES["format"], FIGURES["style"])
    payload["files"] = [str(f) for f in files]
    return files


def wrote(files) -> str:
    return ("\n  wrote " + ", ".join(str(f) for f in files)) if files else ""
