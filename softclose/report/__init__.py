"""The sign-off report of one design (SPEC §16): :func:`report` judges the design at its
nominal lid, at each operating temperature and at the worst corner of the tolerance box by
the adaptive reference, and returns a :class:`ReportResult` that writes one self-contained
HTML page and a PDF of the same sections.

``softclose.report(cfg)`` is this package's :func:`report` whether the name is the function
(the package root's lazy API) or this package (once imported, Python binds the package's name
on its parent): the package is callable."""

import sys
import types

from .build import report
from .result import FORMATS, SECTIONS, ReportResult


class _CallablePackage(types.ModuleType):
    """This package, callable as :func:`report`."""

    def __call__(self, *args, **kwargs) -> ReportResult:
        return report(*args, **kwargs)


sys.modules[__name__].__class__ = _CallablePackage

__all__ = ["report", "ReportResult", "SECTIONS", "FORMATS"]
