"""The report as a PDF (matplotlib's PdfPages): text and table pages in the order of the
HTML, the figures after their section's text. The document's metadata names the verdict
(Subject) and the section titles (Keywords)."""

from __future__ import annotations

import textwrap

from ..present.figures import plt
from .text import (SECTIONS, config_lines, damper_rows, design_rows, limit_lines, matrix_cell,
                   metric_rows, spring_rows, stroke_rows, yield_rows)

#: the figures of the first section (the others follow section 4's text)
FIRST = ("linkage", "attachments")
#: A4 portrait (in), lines of text a page holds, characters a line holds
PAGE = (8.27, 11.69)
LINES = 78
WIDTH = 140
#: the text's size (pt): WIDTH characters of Courier fill the page's width
FONT = 6.2


def columns(head, rows) -> list[str]:
    """Rows of text cells aligned in columns (a monospace table)."""
    if not rows:
        return []
    table = [tuple(map(str, head))] + [tuple(map(str, r)) for r in rows]
    w = [max(len(r[i]) for r in table) for i in range(len(table[0]))]
    line = lambda r: "  ".join(c.ljust(w[i]) for i, c in enumerate(r)).rstrip()  # noqa: E731
    return [line(table[0]), "-" * min(WIDTH, sum(w) + 2 * (len(w) - 1))] + \
        [line(r) for r in table[1:]]


def wrap(text: str) -> list[str]:
    return textwrap.wrap(text, WIDTH) or [""]


#: the characters outside Latin-1 the text pages spell out (their fonts are the PDF's own)
PLAIN = str.maketrans({"≤": "<=", "≥": ">=", "θ": "theta", "–": "-", "−": "-", "β": "beta",
                       "·": "*", "—": "-", "±": "+/-"})
#: the text pages in the PDF's standard fonts (Courier, Helvetica: nothing to embed or lay
#: out glyph by glyph; 10x faster than a TrueType font)
TEXT_RC = {"pdf.use14corefonts": True, "font.family": "sans-serif",
           "font.sans-serif": ["Helvetica"], "font.monospace": ["Courier"]}


def plain(text: str) -> str:
    """``text`` in Latin-1 (what the standard fonts hold)."""
    return text.translate(PLAIN).encode("latin-1", "replace").decode("latin-1")


def _text_pages(pdf, title: str, lines: list[str]) -> int:
    """Write ``lines`` under ``title`` on as many pages as they need; returns the pages."""
    with plt.rc_context(TEXT_RC):
        return _pages(pdf, plain(title), [plain(x) for x in lines])


def _pages(pdf, title: str, lines: list[str], table_width: int = 200) -> int:
    """The pages of ``lines``: a table up to ``table_width`` characters wide is set in a
    smaller font to keep its columns; longer lines are wrapped."""
    pages = 0
    longest = max((len(x) for x in lines if len(x) <= table_width), default=0)
    size = FONT * min(1.0, WIDTH / max(longest, 1))
    width = int(WIDTH * FONT / size)
    lines = [w for x in lines for w in (textwrap.wrap(x, width, subsequent_indent="    ")
                                        if len(x) > width else [x])]
    chunks = [lines[i:i + LINES - 3] for i in range(0, max(len(lines), 1), LINES - 3)]
    for k, chunk in enumerate(chunks):
        fig = plt.figure(figsize=PAGE)
        fig.text(0.06, 0.965, title + (" (continued)" if k else ""), fontsize=13,
                 weight="bold", va="top")
        fig.text(0.06, 0.935, "\n".join(chunk), family="monospace", weight="medium",
                 fontsize=size, va="top")
        pdf.savefig(fig, bbox_inches=None)     # a whole page (tight would draw it twice)
        plt.close(fig)
        pages += 1
    return pages


def _matrix_lines(r) -> list[str]:
    m = r.matrix
    head = ("constraint", "limit") + tuple(m["columns"])
    rows, notes = [], []
    for row in m["rows"]:
        cells = m["cells"][row["name"]]
        lim = next(iter(cells.values())).get("limit")
        lim_text = (f"{row['relation']} {lim:.6g} {row['unit']}".strip()
                    if isinstance(lim, (int, float)) and not isinstance(lim, bool) else "yes")
        out = [row["name"], lim_text]
        for c in m["columns"]:
            x = cells.get(c)
            if x is None:
                out.append("—")
                continue
            value, margin, verdict, where = matrix_cell(row, x)
            out.append(f"{verdict} {value}")
            if where:
                notes.append(f"{row['name']}, worst corner: {where}")
        rows.append(out)
    return columns(head, rows) + [""] + [w for n in notes for w in wrap(n)]


def write_pdf(r, path, figures: dict | None = None) -> None:
    """Write the report ``r`` as the PDF ``path`` (``figures``: already drawn, else drawn
    and closed here)."""
    from matplotlib.backends.backend_pdf import PdfPages
    from .figures import close, report_figures
    figs = figures if figures is not None else report_figures(r)
    S = SECTIONS
    try:
        with PdfPages(path) as pdf:
            info = pdf.infodict()
            info.update(Title="Sign-off report", Subject=r.message,
                        Keywords="; ".join(S), Creator=f"softclose {r.version}")
            _text_pages(pdf, "Sign-off report", wrap(r.message) + [""]
                        + [w for f in r.failures for w in wrap("- " + f)])
            _text_pages(pdf, S[0], columns(("design value", "value"), design_rows(r)))
            for name in FIRST:
                if name in figs:
                    pdf.savefig(figs[name])
            title, rows, checks, note = spring_rows(r)
            lines = [title] + columns(("", "value"), rows) + [""]
            if checks:
                lines += columns(("EN 13906-1 check", "value", "rel.", "limit", "unit",
                                  "result"), checks) + [""]
            lines += wrap(note) + ["", "Dampers"]
            head, drows, dnote = damper_rows(r)
            lines += (columns(head, drows) if drows else ["No damper."]) + wrap(dnote)
            _text_pages(pdf, S[1], lines)
            head, rows, note = metric_rows(r)
            _text_pages(pdf, S[2], columns(head, rows) + [""] + wrap(note))
            head, rows = stroke_rows(r)
            _text_pages(pdf, S[3], columns(head, rows))
            for name, fig in figs.items():
                if name not in FIRST:
                    pdf.savefig(fig)
            _text_pages(pdf, S[4], _matrix_lines(r))
            head, rows, note = yield_rows(r)
            _text_pages(pdf, S[5], columns(head, rows) + [""] + wrap(note))
            _text_pages(pdf, S[6], [w for x in limit_lines(r) for w in wrap(x)])
            facts, toml = config_lines(r)
            _text_pages(pdf, S[7], facts + [""] + toml.splitlines())
    finally:
        if figures is None:
            close(figs)


__all__ = ["write_pdf"]
