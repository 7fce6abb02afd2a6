"""The report as one list of blocks -- headings, paragraphs, tables whose cells say PASS or
FAIL, figures, the config -- that the HTML page (:mod:`.html`) and the PDF (:mod:`.pdf`)
both lay out: the content exists once, each renderer only sets it."""

from __future__ import annotations

from dataclasses import dataclass

from ..present.display import num
from .text import (SECTIONS, config_lines, damper_rows, design_rows, limit_lines, matrix_cell,
                   metric_rows, spring_rows, stroke_rows, yield_rows)


@dataclass(frozen=True)
class Cell:
    """A table cell: ``text``; ``mark``: ``"ok"`` or ``"bad"`` (a passed or failed cell, shaded
    so in both outputs); ``strong``: a word set in bold before the text (PASS, FAIL);
    ``notes``: lines in small type under it."""

    text: str
    mark: str | None = None
    strong: str = ""
    notes: tuple = ()


@dataclass(frozen=True)
class Table:
    """A table: its header cells and rows of :class:`Cell`."""

    head: tuple
    rows: tuple


@dataclass(frozen=True)
class Paragraph:
    """One paragraph (``small``: a note in small type)."""

    text: str
    small: bool = False


@dataclass(frozen=True)
class Lines:
    """Short lines set one under the other in one paragraph."""

    lines: tuple


@dataclass(frozen=True)
class Bullets:
    items: tuple


@dataclass(frozen=True)
class Subheading:
    text: str


@dataclass(frozen=True)
class Figure:
    """The report's figure ``name`` (a key of ``ReportResult.figures()``; a figure that was not
    drawn is left out) with its caption."""

    name: str
    caption: str


@dataclass(frozen=True)
class Code:
    """Preformatted text (the config as TOML)."""

    text: str


@dataclass(frozen=True)
class Section:
    title: str
    blocks: tuple


@dataclass(frozen=True)
class Document:
    """``title``; ``verdict`` and ``success`` (the one-line verdict and whether it passes);
    ``failures``: every failure listed when the verdict names only the first three;
    ``sections``: the eight sections of :data:`~softclose.signoff.SECTIONS`, in order."""

    title: str
    verdict: str
    success: bool
    failures: tuple
    sections: tuple


def _table(head, rows, marks=None) -> Table:
    """A :class:`Table` of text rows; ``marks``: a mark per cell of each row (or None)."""
    return Table(tuple(head), tuple(
        tuple(Cell(str(v), m) for v, m in zip(row, marks[i] if marks else [None] * len(row)))
        for i, row in enumerate(rows)))


def document(r) -> Document:
    """The :class:`Document` of the report ``r`` (a :class:`~softclose.signoff.ReportResult`)."""
    S = SECTIONS
    sections = []

    blocks = [_table(("design value", "value"), design_rows(r)),
              Figure("linkage", "The lid open and closed, with a zoom on its pivots and the "
                                "spring's points."),
              Figure("attachments", "The spring's line D–E and the dashpot's F–H over the "
                                    "stroke, the lid open (faint) and closed.")]
    sections.append(Section(S[0], tuple(blocks)))

    title, rows, checks, note = spring_rows(r)
    blocks = [Subheading(title), _table(("", "value"), rows)]
    if checks:
        blocks.append(_table(("EN 13906-1 check", "value", "relation", "limit", "unit",
                              "result"), checks,
                             [[None] * 5 + ["ok" if c[-1] == "ok" else "bad"] for c in checks]))
    if note:
        blocks.append(Paragraph(note, small=True))
    head, rows, note = damper_rows(r)
    blocks.append(Subheading("Dampers"))
    blocks.append(_table(head, rows) if rows else Paragraph("No damper."))
    blocks.append(Paragraph(note, small=True))
    sections.append(Section(S[1], tuple(blocks)))

    head, rows, note = metric_rows(r)
    sections.append(Section(S[2], (_table(head, rows), Paragraph(note, small=True))))

    head, rows = stroke_rows(r)
    blocks = [Figure("strokes", "θ and the tip speed over the stroke, one line per operating "
                                "temperature."),
              _table(head, rows)]
    blocks += [Figure(f"hand_force_{T:g}C", f"The hand force at the tip at {T:g} °C, its zones "
                                            "shaded.") for T in r.temperatures]
    sections.append(Section(S[3], tuple(blocks)))

    sections.append(Section(S[4], _matrix(r)))

    head, rows, note = yield_rows(r)
    blocks = ([_table(head, rows)] if rows else []) + [Paragraph(note)]
    sections.append(Section(S[5], tuple(blocks)))

    sections.append(Section(S[6], (Bullets(tuple(limit_lines(r))),)))

    facts, toml = config_lines(r)
    sections.append(Section(S[7], (Lines(tuple(facts)), Code(toml))))
    return Document("Sign-off report", r.message, r.success,
                    tuple(r.failures) if len(r.failures) > 3 else (), tuple(sections))


def _matrix(r) -> tuple:
    """The sign-off matrix: a row per constraint (its name and what it asks, its limit), a
    column per judged lid, each cell PASS or FAIL with its value, margin and corner."""
    m = r.matrix
    cols = m["columns"]
    rows = []
    for row in m["rows"]:
        name = row["name"]
        cells = m["cells"][name]
        lim = next(iter(cells.values())).get("limit")
        lim_text = (f"{row['relation']} {num(lim, 6)} {row['unit']}".strip()
                    if lim is not None and not isinstance(lim, bool) else "yes")
        out = [Cell(name, notes=(row["what"],)), Cell(lim_text)]
        for c in cols:
            x = cells.get(c)
            if x is None:
                out.append(Cell("—"))
                continue
            value, margin, verdict, where = matrix_cell(row, x)
            out.append(Cell(value, "ok" if x["ok"] else "bad", verdict,
                            tuple(s for s in (margin, where) if s)))
        rows.append(tuple(out))
    blocks = [Table(("constraint", "limit") + tuple(cols), tuple(rows))]
    cf = m.get("corners") or {}
    if cf.get("corners"):
        blocks.append(Paragraph(
            f"Worst corner: for each constraint the worst of the {cf['corners']} corners of the "
            f"tolerance box ({', '.join(cf['keys'])}) at each temperature, found by "
            f"{cf['kernel_strokes']} strokes of the C kernel and judged by the adaptive "
            f"reference ({cf['reference_checks']} corners checked).", small=True))
    else:
        blocks.append(Paragraph("No tolerance box is set: no worst-corner column.", small=True))
    blocks.append(Paragraph("Every value is the adaptive reference's (CVODES). Margin: how far "
                            "the value lies inside its limit (negative: outside).", small=True))
    return tuple(blocks)


__all__ = ["document", "Document", "Section", "Table", "Cell", "Paragraph", "Lines", "Bullets",
           "Subheading", "Figure", "Code"]
