"""The report as a printable PDF document (fpdf2): A4 or US Letter pages with margins, a title
block on the first page (the design's name, the verdict, the date and the version), a running
header and footer (the design's name, page n of N), the eight sections with real headings,
real tables (the sign-off matrix's cells shaded PASS or FAIL as in the HTML) and the figures
as vector graphics at the text width. It sets the same blocks as the HTML page
(:func:`.document.document`); nothing of the content is written twice.

fpdf2 is pure Python (its wheels install with pip on Linux, macOS and Windows, beside the
Pillow and fontTools that matplotlib brings); the text is set in the DejaVu fonts that
matplotlib ships, embedded as subsets (every character of the report, ° θ ± ≤ included)."""

from __future__ import annotations

import datetime as _dt
import io
import re
from pathlib import Path

from ..errors import ConfigError
from .document import (Bullets, Cell, Code, Figure, Lines, Paragraph, Subheading, Table,
                       document)
from .text import SECTIONS

#: the paper sizes (``--paper``) and fpdf2's name of each
PAPERS = {"a4": "A4", "letter": "Letter"}
#: the page's margins (mm): left and right, top (under the running header), bottom
MARGIN = 18.0
TOP = 20.0
BOTTOM = 18.0
#: type sizes (pt)
BODY, SMALL, TABLE, CODE = 9.0, 7.5, 8.0, 7.2
#: a table's type is made smaller down to this size before its columns wrap inside words
TABLE_MIN = 6.5
#: the colours of the HTML's styles (.pass/.fail verdict, td.ok/td.bad cells, th, pre, .small)
PASS_FILL, PASS_TEXT = (0xe6, 0xf4, 0xea), (0x17, 0x61, 0x2d)
FAIL_FILL, FAIL_TEXT = (0xfc, 0xe8, 0xe6), (0xa5, 0x0e, 0x0e)
CELL_FILL = {"ok": (0xee, 0xf8, 0xf0), "bad": (0xfd, 0xec, 0xea)}
HEAD_FILL, CODE_FILL, RULE, GREY = (0xf3, 0xf3, 0xf3), (0xf7, 0xf7, 0xf7), (0xcc,) * 3, (0x55,) * 3
#: the fpdf2 release the layout needs (its tables, SVG images and fonts)
FPDF_MIN = (2, 8)
#: a figure drawn wider than this many times the text width (the linkage's two panels) is
#: laid out again at that width for the PDF, so that its lettering is not shrunk
WIDE = 1.15
#: a cell's padding (mm)
PAD = 1.0
PT = 25.4 / 72.0            # mm per point
#: where a header's long names may wrap: after an underscore (a zero-width space)
ZWSP = "\u200b"
NBSP = "\u00a0"


def pdf_unavailable() -> str | None:
    """Why this machine cannot write the PDF (fpdf2 missing or too old), or None."""
    try:
        import fpdf
    except ImportError as exc:
        return f"fpdf2 cannot be imported ({exc}); pip install 'fpdf2>={FPDF_MIN[0]}.{FPDF_MIN[1]}'"
    version = getattr(fpdf, "FPDF_VERSION", "0")
    got = tuple(int(x) for x in re.findall(r"\d+", version)[:2])
    if got < FPDF_MIN:
        return (f"fpdf2 {version} is older than {FPDF_MIN[0]}.{FPDF_MIN[1]}; "
                f"pip install -U 'fpdf2>={FPDF_MIN[0]}.{FPDF_MIN[1]}'")
    return None


def check_paper(paper: str) -> str:
    if paper not in PAPERS:
        raise ConfigError(f"paper: {paper!r}; expected one of {', '.join(PAPERS)}")
    return paper


def design_name(r) -> str:
    """A design without a name (no config file) called by what it is."""
    d = r.design
    what = "hinge lid" if d["mechanism"] == "hinge" else "four-bar lid"
    from ..present.display import num
    return (f"{what}, {d['spring_kind']} spring k = {num(d['spring_k'], 4)} N/m, "
            f"damper c = {num(d['damper_c'], 4)} N s/m")


#: the font families (as matplotlib's SVG names them) and styles the PDF embeds, and their
#: files in matplotlib's data (a figure whose text needs another is drawn with its text as
#: outlines)
SANS, MONO = "DejaVu Sans", "DejaVu Sans Mono"
FONTS = {(SANS, ""): "DejaVuSans.ttf", (SANS, "B"): "DejaVuSans-Bold.ttf",
         (SANS, "I"): "DejaVuSans-Oblique.ttf", (MONO, ""): "DejaVuSansMono.ttf"}
_STYLE = re.compile(r'style="([^"]*font-family[^"]*)"')


def _fonts_of(svg: str) -> set:
    """The (family, style) of every text of ``svg``."""
    out = set()
    for style in _STYLE.findall(svg):
        family = re.search(r"font-family:\s*'?([^',;]+)", style).group(1).strip()
        bold = re.search(r"font-weight:\s*(bold|[6-9]00)", style) is not None
        italic = re.search(r"font-style:\s*(italic|oblique)", style) is not None
        out.add((family, ("B" if bold else "") + ("I" if italic else "")))
    return out


def _svg(figs: dict, name: str, text_width_in: float) -> bytes:
    """Figure ``name`` as SVG for the PDF: the HTML's SVG (its text as text) when the PDF
    holds every font it names, else with its text as outlines; a constrained-layout figure
    much wider than the text (the linkage's two panels) is drawn again at the text width,
    so that its lettering keeps its size. Font sizes are given in the SVG's own units (its
    px are points: fpdf2 would take them for 3/4 pt)."""
    from .figures import figure_svg
    fig = figs[name]
    width = fig.get_size_inches()[0]
    engine = type(fig.get_layout_engine()).__name__
    scale = (WIDE * text_width_in / width
             if width > WIDE * text_width_in and engine == "ConstrainedLayoutEngine" else 1.0)
    text = figure_svg(figs, name) if scale == 1.0 else _render(fig, "none", scale)
    if not _fonts_of(text) <= set(FONTS):
        text = _render(fig, "path", scale)
    text = re.sub(r"<metadata>.*?</metadata>", "", text, flags=re.S)
    text = re.sub(r"font-size:\s*([\d.]+)px", r"font-size: \1", text)
    return text.encode("utf-8")


def _render(fig, fonttype: str, scale: float) -> str:
    """``fig`` as SVG (``fonttype``: matplotlib's ``svg.fonttype``) drawn at ``scale``
    times its size (then given its size back)."""
    from matplotlib import rc_context
    size = tuple(fig.get_size_inches())
    buf = io.StringIO()
    try:
        fig.set_size_inches(size[0] * scale, size[1] * scale)
        with rc_context({"svg.fonttype": fonttype}):
            fig.savefig(buf, format="svg", bbox_inches="tight", metadata={"Date": None})
    finally:
        fig.set_size_inches(*size)
    return buf.getvalue()


def _clipped_svg():
    """fpdf2's SVG converter, which clips a group (<g clip-path=...>: matplotlib's markers)
    as it clips a path: a marker outside its axes is not drawn, as in matplotlib."""
    from fpdf.svg import SVGObject

    class ClippedSVG(SVGObject):
        def build_group(self, group, pdf_group=None, inherited_style=None):
            out = super().build_group(group, pdf_group, inherited_style)
            m = re.search(r"url\((#[\w-]+)\)", group.attrib.get("clip-path", ""))
            if m and m.group(1) in self.cross_references:
                out.clipping_path = self.cross_references[m.group(1)]
            return out

    return ClippedSVG


def _draw_svg(pdf, svg: bytes, x: float, y: float, w: float, h: float) -> None:
    """Draw ``svg`` as vector graphics into the box (x, y, w, h) of the page (mm), clipped
    to it."""
    from fpdf.drawing import Transform
    _, _, path = _clipped_svg()(svg).transform_to_rect_viewport(
        scale=1, width=w, height=h, ignore_svg_top_attrs=True)
    path.transform = path.transform @ Transform.translation(x, y)
    old = pdf.x, pdf.y
    try:
        with pdf.rect_clip(x, y, w, h):
            pdf.set_xy(0, 0)
            pdf.draw_path(path)
    finally:
        pdf.set_xy(*old)


def _md(text: str) -> str:
    """``text`` with fpdf2's markdown markers escaped (it is set as it reads)."""
    return re.sub(r"(\\|\*\*|__|--|~~)", r"\\\1", text)


def _wrap_names(text: str) -> str:
    return text.replace("_", "_" + ZWSP)


#: a number and its unit stay on one line in a table's cell (no-break spaces: a PDF
#: reader's text has plain spaces there), and so do a relation or "margin" and its number
#: where the columns allow it
_UNIT = re.compile(r"(?<=\d) (?=[^\s\d])|(?<=\bN) (?=(?:s/m|m)\b)|(?<=\bN m) (?=s/rad)")
_BOUND = re.compile(r"(?<=\bmargin) (?=-?\d)|(?<=[≤≥<>]) (?=-?\d)")


def _keep(text: str, level: int = 2) -> str:
    """``text`` with the spaces it keeps at ``level`` (2: units and bounds, 1: units, 0:
    none) made no-break spaces."""
    if level >= 1:
        text = _UNIT.sub(NBSP, text)
    if level >= 2:
        text = _BOUND.sub(NBSP, text)
    return text


class _Writer:
    """The PDF of one report: fpdf2's document, its running header and footer, the blocks."""

    def __init__(self, r, figs: dict, paper: str, name: str | None, date: str):
        from fpdf import FPDF

        writer = self

        class Doc(FPDF):
            def header(self):
                writer._header()

            def footer(self):
                writer._footer()

        self.r, self.figs = r, figs
        self.name = name or design_name(r)
        self.date = date
        pdf = self.pdf = Doc(orientation="portrait", unit="mm", format=PAPERS[paper])
        pdf.set_margins(MARGIN, TOP, MARGIN)
        pdf.set_auto_page_break(True, margin=BOTTOM)
        import matplotlib
        ttf = Path(matplotlib.get_data_path()) / "fonts" / "ttf"
        for (family, style), file in FONTS.items():
            pdf.add_font(family, style, str(ttf / file))
        pdf.set_title("Sign-off report")
        pdf.set_subject(r.message)
        pdf.set_keywords("; ".join(SECTIONS))
        pdf.set_creator(f"softclose {r.version}")
        pdf.set_author("softclose")
        pdf.set_lang("en")
        pdf.set_display_mode("fullwidth")
        pdf.set_font(SANS, "", BODY)

    # -- the page ---------------------------------------------------------------------------
    def _header(self):
        pdf = self.pdf
        if pdf.page_no() == 1:
            return
        pdf.set_y(9)
        pdf.set_font(SANS, "", 7.5)
        pdf.set_text_color(*GREY)
        head = "Sign-off report · "
        pdf.cell(pdf.epw * 0.75, 4, head + self._fit(self.name, pdf.epw * 0.74
                                                     - pdf.get_string_width(head)), align="L")
        word = "PASS" if self.r.success else "FAILS"
        pdf.set_text_color(*(PASS_TEXT if self.r.success else FAIL_TEXT))
        pdf.set_font(SANS, "B", 7.5)
        pdf.cell(pdf.epw * 0.25, 4, word, align="R")
        pdf.set_draw_color(*RULE)
        pdf.set_line_width(0.2)
        pdf.line(MARGIN, 13.6, pdf.w - MARGIN, 13.6)
        pdf.set_text_color(0)
        pdf.set_y(TOP)

    def _footer(self):
        pdf = self.pdf
        pdf.set_y(-12)
        pdf.set_font(SANS, "", 7.5)
        pdf.set_text_color(*GREY)
        tail = f" · {self.date} · softclose {self.r.version}"
        pdf.cell(pdf.epw * 0.8, 4, self._fit(self.name, pdf.epw * 0.79 - pdf.get_string_width(tail))
                 + tail, align="L")
        pdf.cell(pdf.epw * 0.2, 4, f"page {pdf.page_no()} of {{nb}}", align="R")
        pdf.set_text_color(0)

    def _fit(self, text: str, width: float) -> str:
        """``text`` cut short at its start ("…") to ``width`` mm in the current font (a long
        path keeps its file name)."""
        pdf = self.pdf
        if pdf.get_string_width(text) <= width:
            return text
        while text and pdf.get_string_width("…" + text) > width:
            text = text[1:]
        return "…" + text

    def _room(self, h: float) -> None:
        """A new page unless ``h`` mm fit on this one."""
        if self.pdf.get_y() + h > self.pdf.page_break_trigger:
            self.pdf.add_page()

    # -- the blocks -------------------------------------------------------------------------
    def write(self) -> bytes:
        doc = document(self.r)
        pdf = self.pdf
        pdf.add_page()
        self._title(doc)
        for s in doc.sections:
            self._heading(s.title, s.blocks[0] if s.blocks else None)
            for b, after in zip(s.blocks, s.blocks[1:] + (None,)):
                self._block(b, after)
        return bytes(pdf.output())

    def _title(self, doc):
        pdf = self.pdf
        pdf.set_font(SANS, "B", 20)
        pdf.multi_cell(0, 9, doc.title, new_x="LMARGIN", new_y="NEXT")
        pdf.set_font(SANS, "B", 12)
        pdf.multi_cell(0, 6, self.name, new_x="LMARGIN", new_y="NEXT")
        pdf.set_font(SANS, "", BODY)
        pdf.set_text_color(*GREY)
        pdf.multi_cell(0, 5, f"{self.date} · softclose {self.r.version}", new_x="LMARGIN",
                       new_y="NEXT")
        pdf.set_text_color(0)
        pdf.ln(3)
        fill, ink = (PASS_FILL, PASS_TEXT) if doc.success else (FAIL_FILL, FAIL_TEXT)
        pdf.set_fill_color(*fill)
        pdf.set_text_color(*ink)
        pdf.set_font(SANS, "B", 11)
        pdf.multi_cell(0, 6, doc.verdict, fill=True, padding=(3, 4), align="L",
                       new_x="LMARGIN", new_y="NEXT")
        pdf.set_text_color(0)
        pdf.set_fill_color(255)
        if doc.failures:
            pdf.ln(2)
            self._bullets(doc.failures)
        pdf.ln(2)

    def _heading(self, title: str, first) -> None:
        pdf = self.pdf
        self._room(12 + self._least(first))
        pdf.ln(4)
        pdf.start_section(title, level=0)
        pdf.set_font(SANS, "B", 13)
        pdf.multi_cell(0, 7, title, new_x="LMARGIN", new_y="NEXT")
        pdf.set_draw_color(*RULE)
        pdf.set_line_width(0.3)
        pdf.line(MARGIN, pdf.get_y() + 0.5, pdf.w - MARGIN, pdf.get_y() + 0.5)
        pdf.ln(2.5)
        pdf.set_font(SANS, "", BODY)

    def _least(self, b) -> float:
        """The height (mm) of ``b``'s first lines: what a heading keeps with it."""
        if isinstance(b, Figure) and b.name in self.figs:
            w, h = self._figure_size(b.name)
            return h + 8
        if isinstance(b, Table):
            return self._layout(b)[4]
        return 12

    def _block(self, b, after=None) -> None:
        """Set block ``b`` (``after``: the block that follows it, or None)."""
        pdf = self.pdf
        if isinstance(b, Table):
            # a short table stays on the page with the note under it
            note = isinstance(after, Paragraph) and after.small
            self._table(b, 2 * SMALL * PT * 1.35 + 2 if note else 0.0)
        elif isinstance(b, Paragraph):
            size = SMALL if b.small else BODY
            pdf.set_font(SANS, "", size)
            if b.small:
                pdf.set_text_color(*GREY)
            pdf.multi_cell(0, size * PT * 1.35, b.text, align="L", new_x="LMARGIN",
                           new_y="NEXT")
            pdf.set_text_color(0)
            pdf.ln(1.5)
        elif isinstance(b, Subheading):
            self._room(20)
            pdf.ln(1)
            pdf.set_font(SANS, "B", 10.5)
            pdf.multi_cell(0, 6, b.text, new_x="LMARGIN", new_y="NEXT")
            pdf.ln(0.5)
        elif isinstance(b, Figure):
            self._figure(b)
        elif isinstance(b, Bullets):
            self._bullets(b.items)
        elif isinstance(b, Lines):
            pdf.set_font(SANS, "", BODY)
            for line in b.lines:
                pdf.multi_cell(0, BODY * PT * 1.35, line, align="L", new_x="LMARGIN",
                               new_y="NEXT")
            pdf.ln(1.5)
        elif isinstance(b, Code):
            pdf.set_font(MONO, "", CODE)
            pdf.set_fill_color(*CODE_FILL)
            pdf.multi_cell(0, CODE * PT * 1.3, b.text.rstrip("\n"), fill=True, padding=2,
                           align="L", new_x="LMARGIN", new_y="NEXT")
            pdf.set_fill_color(255)
            pdf.ln(1.5)
        else:
            raise TypeError(f"not a block of the report: {b!r}")
        pdf.set_font(SANS, "", BODY)

    def _bullets(self, items) -> None:
        pdf = self.pdf
        pdf.set_font(SANS, "", BODY)
        h = BODY * PT * 1.35
        for x in items:
            pdf.set_x(MARGIN + 1)
            pdf.cell(4, h, "•")
            pdf.multi_cell(pdf.epw - 5, h, x, align="L", new_x="LMARGIN", new_y="NEXT")
            pdf.ln(0.8)
        pdf.ln(1)

    # -- figures ----------------------------------------------------------------------------
    def _figure_size(self, name: str) -> tuple[float, float]:
        """(width, height) in mm of figure ``name`` set at the text width."""
        svg = self._svgs(name)
        m = re.search(rb'<svg[^>]*\bwidth="([\d.]+)pt"[^>]*\bheight="([\d.]+)pt"', svg)
        w = self.pdf.epw
        return w, w * float(m.group(2)) / float(m.group(1))

    def _svgs(self, name: str) -> bytes:
        cache = self.__dict__.setdefault("_svg_cache", {})
        if name not in cache:
            cache[name] = _svg(self.figs, name, self.pdf.epw / 25.4)
        return cache[name]

    def _figure(self, b: Figure) -> None:
        if b.name not in self.figs:
            return
        pdf = self.pdf
        w, h = self._figure_size(b.name)
        room = pdf.page_break_trigger - pdf.t_margin
        if h + 10 > room:                    # (a figure taller than a page: scaled down)
            w, h = w * (room - 10) / h, room - 10
        self._room(h + 10)
        pdf.set_fill_color(0)               # (what SVG's shapes without a fill inherit)
        pdf.set_draw_color(0)
        _draw_svg(pdf, self._svgs(b.name), MARGIN + (pdf.epw - w) / 2, pdf.get_y(), w, h)
        pdf.set_y(pdf.get_y() + h + 1)
        pdf.set_font(SANS, "", SMALL)
        pdf.set_text_color(*GREY)
        pdf.multi_cell(0, SMALL * PT * 1.35, b.caption, align="L", new_x="LMARGIN",
                       new_y="NEXT")
        pdf.set_text_color(0)
        pdf.set_fill_color(255)
        pdf.ln(3)

    # -- tables -----------------------------------------------------------------------------
    def _widths(self, t: Table, size: float, level: int) -> tuple[list[float], list[float]]:
        """Each column's natural width (its longest line) and least width (its longest
        word), in mm, at type size ``size``."""
        pdf = self.pdf
        n = len(t.head)
        nat, least = [0.0] * n, [0.0] * n
        keep = lambda x: _keep(x, level)     # noqa: E731

        def measure(i, text, style):
            pdf.set_font(SANS, style, size)
            for line in text.split("\n"):
                nat[i] = max(nat[i], pdf.get_string_width(line))
                for word in re.split(rf"[ {ZWSP}]", line):
                    least[i] = max(least[i], pdf.get_string_width(word))

        for i, h in enumerate(t.head):
            measure(i, _wrap_names(str(h)), "B")
        for row in t.rows:
            for i, c in enumerate(row):
                measure(i, keep(c.text), "")
                if c.strong:                 # (a bold word and a space before the text)
                    pdf.set_font(SANS, "B", size)
                    bold = pdf.get_string_width(c.strong + " ")
                    least[i] = max(least[i], bold)
                    pdf.set_font(SANS, "", size)
                    nat[i] = max(nat[i], bold + pdf.get_string_width(keep(c.text).split("\n")[0]))
                for note in c.notes:
                    measure(i, keep(note), "I")
        extra = 2 * PAD + 0.6
        return [x + extra for x in nat], [x + extra for x in least]

    def _layout(self, t: Table) -> tuple:
        """(type size, column widths, whether words stay whole, line height, the height to
        keep on one page) of table ``t``: its natural widths when they fit, else each column
        its longest word and the rest of the width by what it would take; the type smaller
        (down to :data:`TABLE_MIN`) while the words do not fit."""
        cache = self.__dict__.setdefault("_layouts", {})
        if id(t) in cache:
            return cache[id(t)][1]
        pdf = self.pdf
        avail = pdf.epw
        # the type at TABLE, a little smaller, with fewer no-break spaces, down to
        # TABLE_MIN with none, until every column's longest word fits
        sizes = [TABLE - 0.5 * i for i in range(int((TABLE - TABLE_MIN) / 0.5) + 1)]
        tries = [(x, level) for level in (2, 1) for x in sizes[:3]] + [(x, 0) for x in sizes]
        for size, level in tries:
            nat, least = self._widths(t, size, level)
            if sum(least) <= avail:
                break
        whole = sum(least) <= avail
        if sum(nat) <= avail:
            widths = nat
        elif whole:
            slack = [a - b for a, b in zip(nat, least)]
            widths = [b + (avail - sum(least)) * s / sum(slack) for b, s in zip(least, slack)]
        else:                                # (words wrap inside: the type is at its least)
            widths = [b * avail / sum(least) for b in least]
        line = size * PT * 1.3
        height = self._height(t, widths, size, line, level)
        # a table of up to a third of a page is kept whole; a longer one starts with a few rows
        page = pdf.page_break_trigger - pdf.t_margin
        out = (size, widths, whole, line, height if height < page / 3 else line * 6 + 4 * PAD,
               level)
        cache[id(t)] = (t, out)
        return out

    def _table(self, t: Table, then: float = 0.0) -> None:
        from fpdf.fonts import FontFace
        pdf = self.pdf
        avail = pdf.epw
        size, widths, whole, line, keep, level = self._layout(t)
        self._room(keep + then)
        pdf.set_font(SANS, "", size)
        pdf.set_fill_color(255)
        pdf.set_draw_color(*RULE)
        pdf.set_line_width(0.2)
        head_style = FontFace(family=SANS, emphasis="BOLD", fill_color=HEAD_FILL)
        with pdf.table(width=min(sum(widths), avail), col_widths=tuple(widths), align="LEFT",
                       text_align="LEFT", v_align="TOP", markdown=True,
                       headings_style=head_style, line_height=line,
                       padding=PAD, wrapmode="WORD" if whole else "CHAR",
                       repeat_headings=1) as table:
            head = table.row()
            for h in t.head:
                head.cell(_md(_wrap_names(str(h))))
            for r in t.rows:
                row = table.row()
                for c in r:
                    self._cell(row, c, FontFace, level)
        pdf.ln(2.5)
        pdf.set_font(SANS, "", BODY)

    def _height(self, t: Table, widths, size: float, line: float, level: int) -> float:
        """About the height (mm) of table ``t`` with columns ``widths``: its rows' lines."""
        pdf = self.pdf
        pdf.set_font(SANS, "", size)
        total = 0.0
        for row in ((Cell(_wrap_names(str(h))) for h in t.head),) + tuple(t.rows):
            lines = 1
            for c, w in zip(row, widths):
                text = (c.strong + " " if c.strong else "") + _keep(c.text, level)
                n = sum(max(1, -(-pdf.get_string_width(x) // max(w - 2 * PAD, 1.0)))
                        for x in text.split("\n") + [_keep(n, level) for n in c.notes])
                lines = max(lines, n)
            total += lines * line + 2 * PAD
        return total

    @staticmethod
    def _cell(row, c: Cell, FontFace, level: int) -> None:
        text = (f"**{_md(c.strong)}** " if c.strong else "") + _md(_keep(c.text, level))
        if c.notes:
            text += "".join(f"\n__{_md(_keep(n, level))}__" for n in c.notes)
        style = FontFace(fill_color=CELL_FILL[c.mark]) if c.mark else None
        row.cell(text, style=style)


def write_pdf(r, figures: dict | None = None, *, paper: str = "a4", name: str | None = None,
              date: str | None = None) -> bytes:
    """The report ``r`` as the bytes of a PDF on ``paper`` (``"a4"`` or ``"letter"``);
    ``name``: the design's name in the title block and the running footer (default: what
    the design is); ``date``: the date it shows (default today, ISO 8601); ``figures``:
    already drawn, else drawn and closed here."""
    check_paper(paper)
    why = pdf_unavailable()
    if why:
        raise PdfUnavailable(why)
    from .figures import close, report_figures
    figs = figures if figures is not None else report_figures(r)
    try:
        return _Writer(r, figs, paper, name, date or _dt.date.today().isoformat()).write()
    finally:
        if figures is None:
            close(figs)


class PdfUnavailable(RuntimeError):
    """This machine cannot write the PDF (the message says why and what to install)."""


__all__ = ["write_pdf", "pdf_unavailable", "PdfUnavailable", "PAPERS", "check_paper",
           "design_name"]
