"""The report as one self-contained HTML page: CSS inline, figures inline as SVG (their
namespace and metadata stripped, their ids made unique), no URL of any kind. It sets the
blocks of :func:`.document.document`, as the PDF does."""

from __future__ import annotations

import html as _html
import re

from .document import (Bullets, Cell, Code, Figure, Lines, Paragraph, Subheading, Table,
                       document)

#: the page's styles, every rule under the report's own class (a notebook shows the report
#: inside its page: nothing of the notebook is restyled)
CSS = """
.sc-report{font-family:system-ui,-apple-system,'Segoe UI',sans-serif;max-width:1100px;
margin:2em auto;padding:0 1em;color:#222;line-height:1.4}
.sc-report h1{font-size:1.6em;margin-bottom:.2em}
.sc-report h2{border-bottom:1px solid #ccc;margin-top:1.8em}
.sc-report .verdict{font-size:1.15em;font-weight:600;padding:.6em .9em;border-radius:6px}
.sc-report .pass{background:#e6f4ea;color:#17612d}
.sc-report .fail{background:#fce8e6;color:#a50e0e}
.sc-report table{border-collapse:collapse;margin:.6em 0;font-size:.92em}
.sc-report th,.sc-report td{border:1px solid #ccc;padding:.25em .6em;text-align:left;
vertical-align:top}
.sc-report th{background:#f3f3f3}.sc-report td.ok{background:#eef8f0}
.sc-report td.bad{background:#fdecea}.sc-report .small{font-size:.82em;color:#555}
.sc-report pre{background:#f7f7f7;padding:.8em;overflow-x:auto;font-size:.82em}
.sc-report figure{margin:1em 0}.sc-report svg{max-width:100%;height:auto}
"""


def esc(x) -> str:
    return _html.escape(str(x), quote=True)


def _cell(c: Cell) -> str:
    text = (f"<b>{esc(c.strong)}</b> " if c.strong else "") + esc(c.text)
    if c.notes:
        text += "<br><span class=\"small\">" + "<br>".join(esc(n) for n in c.notes) + "</span>"
    return f"<td class=\"{c.mark}\">{text}</td>" if c.mark else f"<td>{text}</td>"


def table(t: Table) -> str:
    """An HTML table of :class:`~.document.Cell` rows (escaped; a marked cell by its class)."""
    out = ["<table><tr>" + "".join(f"<th>{esc(h)}</th>" for h in t.head) + "</tr>"]
    out += ["<tr>" + "".join(_cell(c) for c in row) + "</tr>" for row in t.rows]
    return "\n".join(out) + "</table>"


_ID = re.compile(r'\bid="([^"]+)"')


def svg_inline(figs: dict, name: str) -> str:
    """Figure ``name`` of ``figs`` as an inline <svg> element: no XML header, doctype,
    metadata or namespace URL; every id prefixed with ``name`` (ids stay unique across the
    page's figures); its text as SVG text in the page's fonts."""
    from .figures import figure_svg
    s = figure_svg(figs, name)
    tag = name
    s = s[s.index("<svg"):]
    s = re.sub(r"<metadata>.*?</metadata>", "", s, flags=re.S)
    s = re.sub(r'\s+xmlns(:\w+)?="[^"]*"', "", s)
    s = _ID.sub(lambda m: f'id="{tag}-{m.group(1)}"', s)
    s = s.replace('href="#', f'href="#{tag}-').replace("url(#", f"url(#{tag}-")
    s = s.replace("xlink:href", "href")
    return s


def render_fragment(r, figures: dict | None = None) -> str:
    """The report ``r`` as an HTML fragment: its styles and one <div> (what a notebook
    shows); ``figures``: the report's figures already drawn (default: drawn and closed
    here)."""
    from .figures import close, report_figures
    figs = figures if figures is not None else report_figures(r)
    try:
        body = _body(document(r), figs)
    finally:
        if figures is None:
            close(figs)
    return f"<style>{CSS}</style>\n<div class=\"sc-report\">\n{body}\n</div>"


def render_html(r, figures: dict | None = None) -> str:
    """The page of the report ``r`` (a :class:`~softclose.signoff.ReportResult`);
    ``figures``: the report's figures already drawn (default: drawn and closed here)."""
    return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            "<title>softclose sign-off report</title></head>\n"
            f"<body>\n{render_fragment(r, figures)}\n</body></html>\n")


def _block(b, figs) -> str:
    if isinstance(b, Table):
        return table(b)
    if isinstance(b, Paragraph):
        return f"<p class=\"small\">{esc(b.text)}</p>" if b.small else f"<p>{esc(b.text)}</p>"
    if isinstance(b, Subheading):
        return f"<h3>{esc(b.text)}</h3>"
    if isinstance(b, Figure):
        if b.name not in figs:
            return ""
        return (f"<figure>{svg_inline(figs, b.name)}<figcaption class=\"small\">"
                f"{esc(b.caption)}</figcaption></figure>")
    if isinstance(b, Bullets):
        return "<ul>" + "".join(f"<li>{esc(x)}</li>" for x in b.items) + "</ul>"
    if isinstance(b, Lines):
        return "<p>" + "<br>".join(esc(x) for x in b.lines) + "</p>"
    if isinstance(b, Code):
        return f"<pre>{esc(b.text)}</pre>"
    raise TypeError(f"not a block of the report: {b!r}")


def _body(doc, figs) -> str:
    out = [f"<h1>{esc(doc.title)}</h1>",
           f"<p class=\"verdict {'pass' if doc.success else 'fail'}\">{esc(doc.verdict)}</p>"]
    if doc.failures:
        out.append("<ul>" + "".join(f"<li>{esc(f)}</li>" for f in doc.failures) + "</ul>")
    for s in doc.sections:
        out.append(f"<h2>{esc(s.title)}</h2>")
        out += [_block(b, figs) for b in s.blocks]
    return "\n".join(x for x in out if x)


__all__ = ["render_html", "render_fragment", "svg_inline", "CSS"]
