"""The sign-off report of one design (SPEC §16): :func:`report` judges the design at its
nominal lid, at each operating temperature and at the worst corner of the tolerance box by
the adaptive reference, and returns a :class:`ReportResult` that writes one self-contained
HTML page and a printable PDF document of the same sections (``softclose.report(cfg)``,
``softclose report``)."""

from .build import report
from .pdf import PAPERS, pdf_unavailable
from .result import FORMATS, SECTIONS, ReportResult

__all__ = ["report", "ReportResult", "SECTIONS", "FORMATS", "PAPERS", "pdf_unavailable"]
