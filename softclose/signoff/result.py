"""The sign-off report as an immutable result: its numbers (``to_json``), its HTML
(``html``, ``_repr_html_``), its PDF (``pdf``) and its files (``save``)."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from ..errors import ConfigError
from ..files import write_bytes, write_text
from .text import SECTIONS
#: the report's file formats (by a path's suffix)
FORMATS = ("html", "pdf")


@dataclass(frozen=True, repr=False)
class ReportResult:
    """The sign-off report of one design (SPEC §16).

    ``success``: the design meets every requirement (every cell of the sign-off matrix, the
    parts, the required yield); ``message``: the one-line verdict; ``failures``: each failed
    requirement in words. The sections' numbers are plain JSON values; ``drawing`` holds
    what the figures are drawn from (not compared, not in the JSON); ``files``: the files
    the report was written to (``softclose report`` lists those :meth:`save_all` wrote;
    none in a result just made).
    """

    success: bool
    message: str
    failures: tuple
    version: str
    temperatures: tuple
    design: dict
    parts: dict
    metrics: dict
    strokes: dict
    matrix: dict
    yields: dict
    limits: dict
    config_toml: str
    problem: dict
    time: float = 0.0
    timings: dict = field(default_factory=dict)
    drawing: dict = field(default_factory=dict, compare=False)
    files: tuple = ()
    #: the states the design is signed off in (SPEC §17) and the one that limits it: the
    #: state of every failed column when only the end of life fails, else of the smallest
    #: margin (None with the new lid alone)
    states: tuple = ("new",)
    limiting_state: str | None = None

    def to_json(self) -> dict:
        """Every number of the report as plain JSON values, by section."""
        return {"success": self.success, "message": self.message,
                "failures": list(self.failures), "version": self.version,
                "sections": list(SECTIONS), "temperatures": list(self.temperatures),
                "design": self.design, "problem": self.problem, "parts": self.parts,
                "metrics": self.metrics, "strokes": self.strokes, "matrix": self.matrix,
                "yield": self.yields, "limits": self.limits, "config": self.config_toml,
                "time": self.time, "timings": self.timings, "states": list(self.states),
                "limiting_state": self.limiting_state, "files": [str(f) for f in self.files]}

    def figures(self) -> dict:
        """The report's figures (matplotlib Figures), by name, in the order shown."""
        from .figures import report_figures
        return report_figures(self)

    def text(self) -> str:
        """What ``softclose report`` prints: the verdict, the sign-off matrix in short."""
        from .text import report_text
        return report_text(self.to_json())

    def html(self, figures: dict | None = None) -> str:
        """The report as one self-contained HTML page (figures inline as SVG, CSS inline,
        nothing fetched); ``figures``: :meth:`figures` already drawn."""
        from .html import render_html
        return render_html(self, figures)

    def _repr_html_(self) -> str:
        """The report inside a notebook's page (its styles apply to the report only)."""
        from .html import render_fragment
        return render_fragment(self)

    def __repr__(self) -> str:
        return f"ReportResult({self.message})"

    def pdf(self, figures: dict | None = None, *, paper: str = "a4",
            name: str | None = None) -> bytes:
        """The report as a printable PDF document (its bytes): ``paper`` ``"a4"`` or
        ``"letter"``; ``name``: the design's name on its title block and in its running
        footer (default: what the design is); ``figures``: :meth:`figures` already drawn."""
        from .pdf import write_pdf
        return write_pdf(self, figures, paper=paper, name=name)

    def save(self, path, figures: dict | None = None, *, paper: str = "a4",
             name: str | None = None) -> Path:
        """Write the report as ``path``: HTML (``.html``) or PDF (``.pdf``, on ``paper``
        ``"a4"`` or ``"letter"``, with the design's ``name``: see :meth:`pdf`); ``figures``:
        :meth:`figures` already drawn (to write both formats drawing them once)."""
        from .pdf import check_paper
        check_paper(paper)
        path = Path(path)
        kind = path.suffix.lower().lstrip(".")
        if kind not in FORMATS:
            raise ConfigError(f"{path}: a report is written as .html or .pdf, not "
                              f"'{path.suffix or 'no suffix'}'")
        if kind == "html":
            write_text(path, self.html(figures))
        else:
            write_bytes(path, self.pdf(figures, paper=paper, name=name))
        return path

    def save_all(self, folder, *, stem: str = "report", formats=FORMATS, paper: str = "a4",
                 name: str | None = None) -> list[Path]:
        """Write the report in each of ``formats`` as ``folder/stem.html`` and
        ``folder/stem.pdf``, its figures drawn once; a PDF this machine cannot make
        (:func:`~softclose.signoff.pdf_unavailable` says why) is left out. Returns the files
        written."""
        from .figures import close
        from .pdf import check_paper, pdf_unavailable
        check_paper(paper)
        kinds = [k for k in formats if k != "pdf" or not pdf_unavailable()]
        figs = self.figures()
        try:
            return [self.save(Path(folder) / f"{stem}.{k}", figs, paper=paper, name=name)
                    for k in kinds]
        finally:
            close(figs)

__all__ = ["ReportResult", "SECTIONS", "FORMATS"]
