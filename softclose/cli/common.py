"""What every command shares: the outcome type, the common options, the output folder check,
the metrics table and the writing of a result's table and figure."""

from __future__ import annotations

import argparse
import os
import sys
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import ConfigError
from ..files import check_targets, write_text, write_with


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


#: the file an optimiser's --out writes its design to
DESIGN_FILE = "design.toml"


def stroke_files(stem: str) -> list[str]:
    """The files :func:`softclose.cli.files.write_stroke_outputs` writes for ``stem``."""
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


def format_metrics(m: dict) -> str:
    """The stroke metrics as an aligned table (with accuracy where known)."""
    from ..problem import METRIC_KEYS, UNITS
    acc = m.get("accuracy") or {}
    out = []
    for key in METRIC_KEYS:
        v = m.get(key)
        if key == "closed":
            out.append(f"  {key:<19} {'yes' if v else 'no'}")
        elif v is None:
            out.append(f"  {key:<19} —")
        else:
            e = acc.get(key)
            err = f"  (± {e:.1e})" if e is not None else ""
            out.append(f"  {key:<19} {v:.7g} {UNITS[key]}{err}")
    # the end damper's first engagement, where the lid reaches it (StrokeResult.engage_time)
    for key, unit in (("engage_time", "s"), ("engage_theta_dot", "rad/s")):
        if m.get(key) is not None:
            e = acc.get(key)
            err = f"  (± {e:.1e})" if e is not None else ""
            out.append(f"  {key:<19} {m[key]:.7g} {unit}{err}")
    if m.get("reason"):
        why = "invalid design" if m.get("status") == "invalid design" else "why not closed"
        out.append(f"  {why}: {m['reason']}")
    if "method" in m and m.get("step") is not None:
        out.append(f"  ({m['method']}, step {m['step']:g} s, {m['steps']} steps; "
                   "± = estimated distance from the converged answer)")
    return "\n".join(out)


def write_outputs(out: Path, csv_name: str, frame, fig_name: str, plot) -> list[Path]:
    """Write a result's table and figure in ``out``: ``frame`` (a pandas DataFrame, e.g.
    the result's ``to_frame()``) as ``out/csv_name`` without the index, then the figure
    ``plot()`` draws as ``out/fig_name`` (:func:`softclose.present.figures.save`). Returns the two
    paths, table first.

    The figure is drawn only once the table is on disk, so that a failure or a Ctrl-C while
    matplotlib draws still leaves the numbers.
    """
    table = Path(out) / csv_name
    write_with(table, lambda p: frame.to_csv(p, index=False))
    return [table, save_figure(plot(), Path(out) / fig_name)]


def metrics_line(m: dict | None, J: float | None) -> str:
    """The metrics a design file's header quotes (one line)."""
    if not m or not m.get("closed"):
        return "does not close" if m else ""
    return (f"closes in {m['closing_time']:.7g} s, impact tip speed "
            f"{m['impact_tip_speed']:.4g} m/s, peak tip speed {m['peak_tip_speed']:.4g} m/s, "
            f"holding moment {m['holding_moment']:.7g} N m"
            + (f", the end damper engages at {m['engage_time']:.7g} s at theta' = "
               f"{m['engage_theta_dot']:.5g} rad/s" if m.get("engage_time") is not None
               else "")
            + (f"; J = {J:.7g}" if J is not None else ""))


def write_design(path, cfg, what: str, lines=()) -> Path:
    """Write ``cfg`` (a config whose [design] is the design handed on) as a TOML config
    file every command takes with ``--config`` (:func:`softclose.config.to_toml`: the whole
    config, read back to the same config), with a header saying what it is."""
    from ..config import to_toml
    from ..version import __version__
    path = Path(path)
    d = cfg.design
    head = [f"softclose {__version__}: {what}",
            f"design: spring_k = {d.spring_k!r} N/m, spring_rest_length = "
            f"{d.spring_rest_length!r} m, damper_c = {d.damper_c!r} N s/m"
            + (f", end_damper_c = {d.end_damper_c!r} N m s/rad below end_damper_angle_deg = "
               f"{d.end_damper_angle_deg!r} deg" if d.end_damper_c else ""),
            *[x for x in lines if x],
            f"Every command takes this file: softclose yield --config {path.name}, "
            f"softclose sensitivity --config {path.name}, softclose simulate --config "
            f"{path.name} (add --set KEY=VALUE to change a key).",
            "The whole config follows, each key with its unit; a derived key left as a "
            "comment keeps following the keys it derives from."]
    return write_text(path, to_toml(cfg, "\n".join(head)))


def wrote(files) -> str:
    return ("\n  wrote " + ", ".join(str(f) for f in files)) if files else ""
