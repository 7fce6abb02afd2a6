"""The report as one self-contained HTML page: CSS inline, figures inline as SVG (their
namespace and metadata stripped, their ids made unique), no URL of any kind."""

from __future__ import annotations

import html as _html
import io
import re

from ..present.display import num
from .text import (SECTIONS, config_lines, damper_rows, design_rows, limit_lines, matrix_cell,
                   metric_rows, spring_rows, stroke_rows, yield_rows)

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


def table(head, rows, classes=None) -> str:
    """An HTML table of text cells (escaped); ``classes``: a class per cell (or None)."""
    out = ["<table><tr>" + "".join(f"<th>{esc(h)}</th>" for h in head) + "</tr>"]
    for i, r in enumerate(rows):
        cls = classes[i] if classes else [None] * len(r)
        out.append("<tr>" + "".join(
            f"<td class=\"{c}\">{esc(v)}</td>" if c else f"<td>{esc(v)}</td>"
            for v, c in zip(r, cls)) + "</tr>")
    return "\n".join(out) + "</table>"


_ID = re.compile(r'\bid="([^"]+)"')


def svg_inline(fig, tag: str) -> str:
    """``fig`` as an inline <svg> element: no XML header, doctype, metadata or namespace
    URL; every id prefixed with ``tag`` (ids stay unique across the page's figures); its
    text as SVG text in the page's fonts."""
    from matplotlib import rc_context
    buf = io.StringIO()
    with rc_context({"svg.fonttype": "none"}):    # text as text: searchable, light, fast
        fig.savefig(buf, format="svg", bbox_inches="tight", metadata={"Date": None})
    s = buf.getvalue()
    s = s[s.index("<svg"):]
    s = re.sub(r"<metadata>.*?</metadata>", "", s, flags=re.S)
    s = re.sub(r'\s+xmlns(:\w+)?="[^"]*"', "", s)
    s = _ID.sub(lambda m: f'id="{tag}-{m.group(1)}"', s)
    s = s.replace('href="#', f'href="#{tag}-').replace("url(#", f"url(#{tag}-")
    s = s.replace("xlink:href", "href")
    return s


def _figure(figs, name, caption) -> str:
    if name not in figs:
        return ""
    return (f"<figure>{svg_inline(figs[name], name)}<figcaption class=\"small\">"
            f"{esc(caption)}</figcaption></figure>")


def render_fragment(r, figures: dict | None = None) -> str:
    """The report ``r`` as an HTML fragment: its styles and one <div> (what a notebook
    shows); ``figures``: the report's figures already drawn (default: drawn and closed
    here)."""
    from .figures import close, report_figures
    figs = figures if figures is not None else report_figures(r)
    try:
        body = _body(r, figs)
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


def _body(r, figs) -> str:
    S = SECTIONS
    out = ["<h1>Sign-off report</h1>",
           f"<p class=\"verdict {'pass' if r.success else 'fail'}\">{esc(r.message)}</p>"]
    if len(r.failures) > 3:
        out.append("<ul>" + "".join(f"<li>{esc(f)}</li>" for f in r.failures) + "</ul>")
    out.append(f"<h2>{esc(S[0])}</h2>")
    out.append(table(("design value", "value"), design_rows(r)))
    out.append(_figure(figs, "linkage", "The lid open and closed, with a zoom on its "
                                        "pivots and the spring's points."))
    out.append(_figure(figs, "attachments", "The spring's line D–E and the dashpot's F–H "
                                            "over the stroke, the lid open (faint) and "
                                            "closed."))
    out.append(f"<h2>{esc(S[1])}</h2>")
    title, rows, checks, note = spring_rows(r)
    out.append(f"<h3>{esc(title)}</h3>")
    out.append(table(("", "value"), rows))
    if checks:
        out.append(table(("EN 13906-1 check", "value", "relation", "limit", "unit", "result"),
                         checks, [[None] * 5 + ["ok" if c[-1] == "ok" else "bad"]
                                  for c in checks]))
    if note:
        out.append(f"<p class=\"small\">{esc(note)}</p>")
    head, rows, note = damper_rows(r)
    out.append("<h3>Dampers</h3>")
    out.append(table(head, rows) if rows else "<p>No damper.</p>")
    out.append(f"<p class=\"small\">{esc(note)}</p>")
    out.append(f"<h2>{esc(S[2])}</h2>")
    head, rows, note = metric_rows(r)
    out.append(table(head, rows))
    out.append(f"<p class=\"small\">{esc(note)}</p>")
    out.append(f"<h2>{esc(S[3])}</h2>")
    out.append(_figure(figs, "strokes", "θ and the tip speed over the stroke, one line per "
                                        "operating temperature."))
    head, rows = stroke_rows(r)
    out.append(table(head, rows))
    for T in r.temperatures:
        out.append(_figure(figs, f"hand_force_{T:g}C",
                           f"The hand force at the tip at {T:g} °C, its zones shaded."))
    out.append(f"<h2>{esc(S[4])}</h2>")
    out.append(_matrix(r))
    out.append(f"<h2>{esc(S[5])}</h2>")
    head, rows, note = yield_rows(r)
    out.append(table(head, rows) if rows else "")
    out.append(f"<p>{esc(note)}</p>")
    out.append(f"<h2>{esc(S[6])}</h2>")
    out.append("<ul>" + "".join(f"<li>{esc(x)}</li>" for x in limit_lines(r)) + "</ul>")
    out.append(f"<h2>{esc(S[7])}</h2>")
    facts, toml = config_lines(r)
    out.append("<p>" + "<br>".join(esc(x) for x in facts) + "</p>")
    out.append(f"<pre>{esc(toml)}</pre>")
    return "\n".join(x for x in out if x)


def _matrix(r) -> str:
    m = r.matrix
    cols = m["columns"]
    out = ["<table><tr><th>constraint</th><th>limit</th>"
           + "".join(f"<th>{esc(c)}</th>" for c in cols) + "</tr>"]
    for row in m["rows"]:
        name = row["name"]
        cells = m["cells"][name]
        first = next(iter(cells.values()))
        lim = first.get("limit")
        lim_text = (f"{row['relation']} {num(lim, 6)} {row['unit']}".strip()
                    if lim is not None and not isinstance(lim, bool) else "yes")
        tds = []
        for c in cols:
            x = cells.get(c)
            if x is None:
                tds.append("<td>—</td>")
                continue
            value, margin, verdict, where = matrix_cell(row, x)
            sub = "<br>".join(esc(s) for s in (margin, where) if s)
            tds.append(f"<td class=\"{'ok' if x['ok'] else 'bad'}\"><b>{esc(verdict)}</b> "
                       f"{esc(value)}" + (f"<br><span class=\"small\">{sub}</span>" if sub
                                          else "") + "</td>")
        out.append(f"<tr><td>{esc(name)}<br><span class=\"small\">{esc(row['what'])}</span>"
                   f"</td><td>{esc(lim_text)}</td>" + "".join(tds) + "</tr>")
    out.append("</table>")
    cf = m.get("corners") or {}
    if cf.get("corners"):
        out.append(f"<p class=\"small\">Worst corner: for each constraint the worst of the "
                   f"{cf['corners']} corners of the tolerance box ({', '.join(cf['keys'])}) "
                   f"at each temperature, found by {cf['kernel_strokes']} strokes of the C "
                   f"kernel and judged by the adaptive reference ({cf['reference_checks']} "
                   "corners checked).</p>")
    else:
        out.append("<p class=\"small\">No tolerance box is set: no worst-corner column.</p>")
    out.append("<p class=\"small\">Every value is the adaptive reference's (CVODES). Margin: "
               "how far the value lies inside its limit (negative: outside).</p>")
    return "\n".join(out)


__all__ = ["render_html", "render_fragment", "svg_inline", "CSS"]
