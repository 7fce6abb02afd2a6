"""What every study script shares (``studies/*.py``): its options and its JSON.

A study takes ``--fast`` (its smoke-test size, said in ``fast``), ``--json`` (one JSON object
on stdout instead of text) and ``--out DIR`` (its output folder, by default
``studies/out/<the script's name>`` beside the script)::

    parser = study_options(__doc__, __file__, fast="2,000 samples")
    parser.add_argument("--seed", type=int, default=0)      # its own options, if any
    args = parse(parser, argv)                               # the folder exists after it
    ...
    if args.json:
        print_json(summary)
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from ..files import write_text
from ..jsonio import jsonable


def default_out(script) -> Path:
    """A study's default output folder: ``out/<its name>`` beside the script."""
    script = Path(script).resolve()
    return script.parent / "out" / script.stem


def study_options(doc: str, script, fast: str, json_option: bool = True,
                  out: Path | None = None, plots: bool = False) -> argparse.ArgumentParser:
    """The parser of a study: its docstring's first line as the description, ``--fast``
    (``fast`` says what it shrinks), ``--json`` (unless ``json_option`` is false),
    ``--no-plots`` (with ``plots``: the study may skip its figures) and ``--out DIR``
    (default ``out``, or :func:`default_out` of ``script``)."""
    out = Path(out) if out is not None else default_out(script)
    ap = argparse.ArgumentParser(description=(doc or "").strip().splitlines()[0])
    ap.add_argument("--fast", action="store_true", help=fast)
    if json_option:
        ap.add_argument("--json", action="store_true", help="print one JSON object")
    if plots:
        ap.add_argument("--no-plots", action="store_true")
    ap.add_argument("--out", type=Path, default=out, help=f"output folder (default {out})")
    return ap


def parse(parser: argparse.ArgumentParser, argv=None) -> argparse.Namespace:
    """The study's options from ``argv``; its output folder is made."""
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    return args


def add_report(summary: dict, files: list, report, folder, name: str) -> None:
    """A study's sign-off ``report`` (a :class:`softclose.signoff.ReportResult`) written in
    ``folder`` as HTML and PDF with the design's ``name``, its files added to ``files`` and
    its verdict to ``summary["report"]``."""
    files += report.save_all(folder, name=name)
    summary["report"] = report.message


def write_rows(rows: list, path, fields=None) -> Path:
    """``rows`` (dicts) as a CSV table at ``path``: a header of ``fields`` (default the
    first row's keys), then one line per row; the path."""
    import csv
    path = Path(path)
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(fields or rows[0]))
        w.writeheader()
        w.writerows(rows)
    return path


def save_summary(summary: dict, path, files: list) -> Path:
    """Write ``summary`` to ``path`` as strict JSON, add ``path`` to ``files`` and list them
    all in ``summary["files"]`` (for :func:`print_json`). Returns ``path``."""
    path = Path(path)
    files.append(path)
    write_text(path, json.dumps(jsonable(summary), indent=1, allow_nan=False))
    summary["files"] = [str(f) for f in files]
    return path


def save_figure(fig, path) -> str:
    """A study's figure, laid out tight, written as ``path``
    (:func:`softclose.present.figures.save`); the path as text."""
    from .figures import save
    fig.tight_layout()
    return str(save(fig, path))


def print_files(files) -> None:
    """One line per file a study wrote."""
    for f in files:
        print("wrote", f)


def print_json(summary) -> None:
    """``summary`` as one strict JSON object on stdout (no NaN: missing values are null)."""
    print(json.dumps(jsonable(summary), allow_nan=False))


__all__ = ["study_options", "parse", "print_json", "save_summary", "default_out", "save_figure",
           "print_files", "add_report", "write_rows"]
