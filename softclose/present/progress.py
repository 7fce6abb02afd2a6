"""Progress on a terminal: one stderr line, redrawn at most five times a second.

Library functions take ``progress=False``; with ``progress=True`` they draw this line when
stderr is a terminal (``force=True`` draws it anyway, for logs). Nothing is printed
otherwise, so scripts and ``--json`` runs stay quiet.
"""

from __future__ import annotations

import math
import sys
import time


class Progress:
    """``label [#####-----] done/total  rate  time left  note`` on stderr."""

    def __init__(self, total: int, label: str, enabled: bool = True, force: bool = False,
                 unit: str = "designs"):
        self.total, self.label, self.unit = max(int(total), 0), label, unit
        self.enabled = bool(enabled) and (force or sys.stderr.isatty())
        self.t0 = time.perf_counter()
        self.last = -math.inf
        self.drawn = False

    def update(self, done: int, note: str = "", force: bool = False) -> None:
        if not self.enabled:
            return
        now = time.perf_counter()
        if not force and now - self.last < 0.2:
            return
        self.last = now
        el = max(now - self.t0, 1e-9)
        frac = done / self.total if self.total else 1.0
        n = int(24 * min(frac, 1.0))
        rate = done / el
        left = (self.total - done) / rate if rate > 0 else math.inf
        eta = f"  {left:,.0f} s left" if math.isfinite(left) and done < self.total else ""
        speed = f"  {rate:,.0f} {self.unit}/s" if self.unit and rate >= 1 else ""
        line = (f"\r  {self.label} [{'#' * n}{'-' * (24 - n)}] {done}/{self.total}"
                f"{speed}{eta}  {note}")
        sys.stderr.write(line[:160].ljust(60))
        sys.stderr.flush()
        self.drawn = True

    def close(self) -> None:
        if self.enabled and self.drawn:
            sys.stderr.write("\n")
            sys.stderr.flush()
        self.drawn = False

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False
