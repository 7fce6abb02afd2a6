"""The sign-off report (softclose.report, ``softclose report``): its HTML is one valid,
self-contained page; its numbers are those of the commands it summarises; its sign-off
matrix flags a design that fails cold; its PDF holds the same sections; its figures render."""

from __future__ import annotations

import contextlib
import dataclasses
import io
import json
import re
import time
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest

from softclose.cli import main
from softclose.config import load_config
from softclose.problem import at_temperature
from softclose.signoff import SECTIONS, report

ROOT = Path(__file__).resolve().parents[1]
#: the default optimum (softclose optimise's design.toml) with silicone-oil dampers
OPTIMUM = ['design.spring_kind="compression"', "design.spring_k=1914.709221447523",
           "design.spring_rest_length=0.07925707423802691", "design.damper_c=2087.7541030385964"]
COLD = OPTIMUM + ["design.damper_temperature_coeff=-0.005",
                  "operating.temperatures_c=[0.0, 23.0, 40.0]"]
SAMPLES = 2000


def run_cli(argv) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = main(argv)
    return rc, out.getvalue(), err.getvalue()


@pytest.fixture(scope="module")
def cold_cfg():
    return load_config(None, COLD)


@pytest.fixture(scope="module")
def rep(cold_cfg):
    return report(cold_cfg, samples=SAMPLES)


@pytest.fixture(scope="module")
def figs(rep):
    from softclose.signoff.figures import close
    f = rep.figures()
    yield f
    close(f)


@pytest.fixture(scope="module")
def page(rep, figs):
    return rep.html(figs)


@pytest.fixture(scope="module")
def pdf_bytes(rep, figs, tmp_path_factory):
    path = rep.save(tmp_path_factory.mktemp("report") / "report.pdf", figs, name="cold.toml")
    return path.read_bytes()


class Balance(HTMLParser):
    """Every opened element closed in order (void elements excepted); every attribute."""

    VOID = {"meta", "br", "img", "hr", "link", "input", "col", "source", "wbr"}

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.stack, self.errors, self.attrs, self.tags = [], [], [], set()

    def handle_starttag(self, tag, attrs):
        self.tags.add(tag)
        self.attrs += attrs
        if tag not in self.VOID:
            self.stack.append(tag)

    def handle_startendtag(self, tag, attrs):
        self.tags.add(tag)
        self.attrs += attrs

    def handle_endtag(self, tag):
        if tag in self.VOID:
            return
        if not self.stack or self.stack[-1] != tag:
            self.errors.append(f"</{tag}> closes {self.stack[-1:] or 'nothing'}")
        else:
            self.stack.pop()


def test_html_is_one_balanced_page_that_fetches_nothing(page):
    p = Balance()
    p.feed(page)
    p.close()
    assert p.errors == [] and p.stack == []
    assert {"html", "head", "body", "style", "svg", "table"} <= p.tags
    css = page.split("<style>")[1].split("</style>")[0]       # every rule the report's own
    selectors = [x.strip() for chunk in re.split(r"\{[^}]*\}", css) for x in chunk.split(",")]
    assert all(x.startswith(".sc-report") for x in selectors if x) and len(selectors) > 10
    assert not ({"script", "link", "img", "iframe", "object"} & p.tags)
    assert re.search(r"(?i)\b(https?|file|ftp):", page) is None
    assert "url(" not in page.replace("url(#", "")        # only ids of the page itself
    srcs = [v for k, v in p.attrs if k == "src"]
    hrefs = [v for k, v in p.attrs if k in ("href", "xlink:href")]
    assert srcs == [] and all(h.startswith("#") for h in hrefs)
    ids = [v for k, v in p.attrs if k == "id"]
    assert len(ids) == len(set(ids)) > 0                   # unique across the figures
    # the sections in order, the verdict first
    at = [page.index(f"<h2>{s}</h2>") for s in SECTIONS]
    assert at == sorted(at) and page.index("class=\"verdict fail\"") < at[0]


def test_metrics_are_those_of_simulate_and_the_reference(rep, cold_cfg):
    rc, out, _ = run_cli(["simulate", "--json"] + [a for s in COLD for a in ("--set", s)])
    assert rc == 0
    sim = json.loads(out)
    mine = rep.to_json()["metrics"]
    for k in ("closing_time", "impact_tip_speed", "impact_theta_dot", "peak_tip_speed",
              "holding_moment"):
        assert mine["simulate"][k] == sim[k]
        assert mine["accuracy"][k] == sim["accuracy"][k] if k in sim["accuracy"] else True
    # the reference at each temperature (its own grid: the same answer to < 1e-9)
    from softclose.simulation.reference import Reference
    for T in (0.0, 40.0):
        c = at_temperature(cold_cfg, T)
        ref = Reference.from_config(c).simulate()      # (at c's temperature)
        got = rep.strokes[f"{T:g} °C"]["reference"]
        for k in ("closing_time", "impact_tip_speed", "holding_moment"):
            assert got[k] == pytest.approx(getattr(ref, k), rel=1e-8, abs=1e-10)


def test_signoff_matrix_flags_the_cold_closing_time(rep):
    cells = rep.matrix["cells"]["closing_time_max"]
    assert rep.matrix["columns"] == ["nominal", "0 °C", "23 °C", "40 °C", "worst corner"]
    assert cells["nominal"]["ok"] and cells["23 °C"]["ok"] and cells["40 °C"]["ok"]
    cold = cells["0 °C"]
    # the damper 12 % stiffer at 0 °C (exp(0.005 x 23)): the lid closes in 1.172 s > 1 s
    assert not cold["ok"] and 1.17 < cold["value"] < 1.175 and cold["limit"] == 1.0
    assert cold["margin"] == pytest.approx(1.0 - cold["value"])
    assert cells["40 °C"]["value"] == pytest.approx(0.8886, abs=1e-3)
    assert rep.success is False
    assert rep.message.startswith("This design FAILS: closing_time_max at 0 °C is 1.172 s, "
                                  "limit 1 s")
    # the worst corner is named and judged by the reference
    worst = cells["worst corner"]
    assert not worst["ok"] and "at 0 °C" in worst["where"]
    damper = rep.parts["dampers"][0]
    assert damper["at"][0]["coefficient"] == pytest.approx(2087.7541030385964 * np.exp(0.115))


def test_yield_is_that_of_tolerance_analysis_at_each_temperature(rep, cold_cfg):
    from softclose.robust.analysis import tolerance_analysis
    per = rep.yields["per_temperature"]
    assert [p["temperature_c"] for p in per] == [0.0, 23.0, 40.0]
    for p in per[:2]:
        y = tolerance_analysis(at_temperature(cold_cfg, p["temperature_c"]), samples=SAMPLES,
                               reference=0)
        assert p["yield"] == y.yield_ and p["yield_ci"] == list(y.yield_ci)
    # colder is worse (the damper stiffer); jointly no better than the worst
    assert per[0]["yield"] < per[1]["yield"] < per[2]["yield"]
    assert rep.yields["joint"]["yield"] <= per[0]["yield"]


def test_result_is_immutable_and_its_json_strict(rep):
    with pytest.raises(dataclasses.FrozenInstanceError):
        rep.success = True
    text = json.dumps(rep.to_json(), allow_nan=False)
    back = json.loads(text)
    assert back["sections"] == list(SECTIONS) and back["message"] == rep.message
    assert back["limits"]["smallest_margin"]["constraint"] in rep.matrix["cells"]
    frag = rep._repr_html_()                      # a notebook's: styles under its own class
    assert frag.startswith("<style>") and "<body" not in frag and "\nbody{" not in frag
    assert frag.count("<svg") == 6


def pdf_reader(data: bytes):
    import pypdf
    return pypdf.PdfReader(io.BytesIO(data))


def pdf_text(data: bytes) -> str:
    """The PDF's text as a reader's tool extracts it, its whitespace made single spaces (a
    table cell's lines, a paragraph's wrapping) and the header's break hints dropped."""
    text = " ".join(p.extract_text() for p in pdf_reader(data).pages)
    return re.sub(r"\s+", " ", text.replace("\u200b", "").replace("\u00a0", " "))


#: A4 and US Letter in points
A4, LETTER = (595.28, 841.89), (612.0, 792.0)


@pytest.fixture(scope="module")
def letter_bytes(rep, figs):
    return rep.pdf(figs, paper="letter", name="cold lid")


def test_pdf_is_a_document_of_a4_pages_with_the_sections_as_its_outline(rep, pdf_bytes, page):
    pdf = pdf_reader(pdf_bytes)
    sizes = {(round(float(p.mediabox.width), 2), round(float(p.mediabox.height), 2))
             for p in pdf.pages}
    assert sizes == {A4} and 6 <= len(pdf.pages) <= 14
    info = pdf.metadata
    assert info.title == "Sign-off report" and info.subject == rep.message
    assert info["/Keywords"].split("; ") == list(SECTIONS)
    # the same section titles in the HTML's headings, the PDF's outline and its text, in order
    html_titles = re.findall(r"<h2>(.*?)</h2>", page)
    assert html_titles == list(SECTIONS) == [o.title for o in pdf.outline]
    text = pdf_text(pdf_bytes)
    at = [text.index(s) for s in SECTIONS]
    assert at == sorted(at)
    # the title block: the design's name, the verdict, the date and the version, first
    first = re.sub(r"\s+", " ", pdf.pages[0].extract_text())
    assert first.startswith("Sign-off report cold.toml ")
    assert re.search(rf"\d{{4}}-\d\d-\d\d · softclose {re.escape(rep.version)}", first)
    assert rep.message in first
    # every page's footer: the design's name and "page n of N"
    n = len(pdf.pages)
    for i, p in enumerate(pdf.pages):
        assert re.search(rf"cold\.toml · .*page {i + 1} of {n}", p.extract_text(), re.S)
    # the figures are vector graphics: no raster image in the document, their text is text
    assert all(len(p.images) == 0 for p in pdf.pages)
    assert "The closing stroke at each operating temperature" in text


def test_pdf_pages_hold_what_the_docs_list(pdf_bytes):
    """docs/report.md's page list of this report: each section's heading on its page."""
    pages = [re.sub(r"\s+", " ", p.extract_text()) for p in pdf_reader(pdf_bytes).pages]
    assert len(pages) == 9
    first = {s: next(i + 1 for i, t in enumerate(pages) if s in t) for s in SECTIONS}
    assert list(first.values()) == [1, 2, 3, 4, 6, 7, 7, 7]
    assert "EN 13906-1 check" in pages[2] and "Hand force at 0 °C" in pages[4]
    assert "Hand force at 23 °C" in pages[4] and "Hand force at 40 °C" in pages[5]
    assert "[tolerance]" in pages[8]


def test_letter_pages_with_the_option(letter_bytes, pdf_bytes):
    pdf = pdf_reader(letter_bytes)
    assert {(float(p.mediabox.width), float(p.mediabox.height)) for p in pdf.pages} == {LETTER}
    assert "cold lid" in pdf.pages[0].extract_text()
    assert pdf_text(letter_bytes).count("PASS") == pdf_text(pdf_bytes).count("PASS")


def test_pdf_text_holds_the_verdict_every_constraint_and_the_numbers_of_the_json(rep,
                                                                                 pdf_bytes):
    from softclose.signoff.text import matrix_cell
    text = pdf_text(pdf_bytes)
    assert rep.message in text and all(f in text for f in rep.failures)
    m = rep.matrix
    for row in m["rows"]:                           # every constraint, every cell's value
        assert row["name"] in text and row["what"] in text
        for col, x in m["cells"][row["name"]].items():
            value, margin, verdict, where = matrix_cell(row, x)
            assert f"{verdict} {value}" in text, (row["name"], col)
            assert margin in text and where in text
    cells = [x for row in m["cells"].values() for x in row.values()]
    assert text.count("PASS ") >= sum(x["ok"] for x in cells)
    assert text.count("FAIL ") >= sum(not x["ok"] for x in cells)
    # the design's numbers as the JSON has them (to the digits the table shows)
    d = rep.to_json()["design"]
    design = text[text.index(SECTIONS[0]):text.index(SECTIONS[1])]
    for key in ("spring_k", "spring_rest_length", "damper_c"):
        got = float(re.search(rf"\b{key} ([-\d.e+]+)", design).group(1))
        assert got == pytest.approx(d[key], rel=1e-5)
    # the verified metrics to ten digits, by the reference and by simulate
    ref, sim = rep.metrics["reference"], rep.metrics["simulate"]
    for key in ("closing_time", "impact_tip_speed", "peak_tip_speed"):
        metrics = text[text.index(SECTIONS[2]):text.index(SECTIONS[3])]
        a, b = re.search(rf"\b{key} ([-\d.e+]+) \S+ ([-\d.e+]+)", metrics).groups()
        assert float(a) == pytest.approx(ref[key], rel=1e-9)
        assert float(b) == pytest.approx(sim[key], rel=1e-9)
    # the yield per temperature and the config
    for p in rep.yields["per_temperature"]:
        assert f"{p['temperature_c']:g} °C {100 * p['yield']:.4g} %" in text
    assert "spring_k = 1914.709221447523" in text


def test_pdf_pages_rendered_keep_their_content_within_the_margins(pdf_bytes):
    """Each page drawn at 1 px a point: nothing outside the margins but the running header
    and footer, something inside them; the verdict box and the matrix's PASS and FAIL cells
    in the HTML's colours."""
    import pypdfium2
    from softclose.signoff.html import CSS
    from softclose.signoff.pdf import BOTTOM, CELL_FILL, FAIL_FILL, MARGIN, TOP
    mm = 72 / 25.4
    doc = pypdfium2.PdfDocument(pdf_bytes)
    colours = set()
    try:
        for i in range(len(doc)):
            img = np.asarray(doc[i].render(scale=1).to_pil().convert("RGB")).astype(int)
            h, w, _ = img.shape
            ink = (img < 245).any(axis=2)
            left, right = int(MARGIN * mm) - 1, w - int(MARGIN * mm) + 1
            assert not ink[:, :left].any() and not ink[:, right:].any(), f"page {i + 1}"
            body = ink[int((TOP - 2) * mm):h - int(BOTTOM * mm)]
            assert body.sum() > 2000, f"page {i + 1} is nearly blank"
            assert ink[:int(6 * mm)].sum() == 0 and ink[h - int(4 * mm):].sum() == 0
            colours |= set(map(tuple, img.reshape(-1, 3)[::7]))
    finally:
        doc.close()
    for fill in (CELL_FILL["ok"], CELL_FILL["bad"], FAIL_FILL):
        assert fill in colours
    css = {k: tuple(int(v[j:j + 2], 16) for j in (0, 2, 4))
           for k, v in re.findall(r"td\.(ok|bad)\{background:#(\w{6})\}", CSS)}
    assert css == CELL_FILL                     # the cells shaded as in the HTML


def test_pdf_that_cannot_be_made_is_refused_in_one_line(rep, monkeypatch, tmp_path):
    import sys

    from softclose.errors import ConfigError
    from softclose.signoff.pdf import PdfUnavailable
    with pytest.raises(ConfigError, match="paper: 'legal'"):
        rep.save(tmp_path / "report.pdf", paper="legal")
    monkeypatch.setitem(sys.modules, "fpdf", None)          # fpdf2 missing
    with pytest.raises(PdfUnavailable, match="fpdf2 cannot be imported"):
        rep.pdf()
    assert not (tmp_path / "report.pdf").exists()


def test_a_figure_of_the_report_renders_to_an_image(figs, tmp_path):
    import matplotlib.image as mpimg
    path = tmp_path / "strokes.png"
    figs["strokes"].savefig(path, dpi=50)
    img = mpimg.imread(path)
    assert img.shape[0] > 100 and img.shape[1] > 100
    assert np.ptp(img[..., :3]) > 0.5                   # drawn, not blank
    assert set(figs) == {"linkage", "attachments", "strokes", "hand_force_0C", "hand_force_23C",
                         "hand_force_40C"}


def test_hinge_lid_report_from_the_command_line(tmp_path):
    rc, out, err = run_cli(["report", "--config", str(ROOT / "examples" / "lids" / "chest_lid.toml"),
                            "--out", str(tmp_path), "--format", "html", "--samples", "200",
                            "--json"])
    payload = json.loads(out)
    assert rc == (0 if payload["success"] else 3)
    assert payload["design"]["mechanism"] == "hinge"
    assert payload["files"] == [str(tmp_path / "report.html")]
    assert "hinge lid" in (tmp_path / "report.html").read_text()
    assert not (tmp_path / "report.pdf").exists()


def test_without_fpdf2_the_command_writes_the_html_and_says_why_not_the_pdf(tmp_path,
                                                                             monkeypatch):
    import sys
    monkeypatch.setitem(sys.modules, "fpdf", None)
    chest = str(ROOT / "examples" / "lids" / "chest_lid.toml")
    rc, out, err = run_cli(["report", "--config", chest, "--out", str(tmp_path), "--format", "pdf",
                            "--samples", "50"])
    assert rc in (0, 3) and "Traceback" not in err
    assert (tmp_path / "report.html").exists() and not (tmp_path / "report.pdf").exists()
    skipped = [ln for ln in out.splitlines() if "report.pdf skipped" in ln]
    assert len(skipped) == 1 and "fpdf2 cannot be imported" in skipped[0]


def test_bad_input_is_one_line_and_exit_2(tmp_path):
    rc, _, err = run_cli(["report", "--format", "doc", "--out", str(tmp_path)])
    assert rc == 2 and len(err.strip().splitlines()) == 1 and "--format" in err
    rc, _, err = run_cli(["report", "--samples", "0", "--out", str(tmp_path)])
    assert rc == 2 and "--samples" in err
    rc, _, err = run_cli(["report", "--paper", "legal", "--out", str(tmp_path)])
    assert rc == 2 and len(err.strip().splitlines()) == 1 and "--paper" in err


def test_without_a_tolerance_box_yield_is_skipped(cold_cfg):
    cfg = cold_cfg.replace(operating={"temperatures_c": []})
    cfg = dataclasses.replace(cfg, tolerance=dataclasses.replace(cfg.tolerance, spreads=()))
    r = report(cfg)
    assert "skipped" in r.yields and "worst corner" not in r.matrix["columns"]
    assert r.matrix["columns"] == ["nominal", "23 °C"] and r.success
    assert r.message == "This design meets every requirement at 23 °C."


@pytest.mark.slow
def test_report_of_the_default_optimum_at_three_temperatures_takes_at_most_10_s(tmp_path,
                                                                                cold_cfg):
    """With its models built (the build cache warm, as after `softclose optimise`; the
    test run's cache starts empty): the report and both files within 10 s."""
    report(cold_cfg, samples=10)
    t0 = time.perf_counter()
    r = report(cold_cfg)
    figs = r.figures()
    r.save(tmp_path / "report.html", figs)
    r.save(tmp_path / "report.pdf", figs)
    assert time.perf_counter() - t0 <= 10.0


def test_the_optimisers_json_of_the_same_design_says_what_limits_it(tmp_path, cold_cfg):
    from softclose.signoff.build import optimiser_json
    design = {k: getattr(cold_cfg.design, k) for k in ("spring_k", "spring_rest_length",
                                                       "damper_c")}
    active = [{"name": "closing_time_max", "kind": "constraint", "bound": "upper",
               "value": 1.0, "unit": "s", "dJ": -0.031}]
    (tmp_path / "optimise.json").write_text(json.dumps({"design": design, "active": active}))
    config = str(tmp_path / "design.toml")
    assert optimiser_json(config, cold_cfg)["active"] == active
    other = dict(design, damper_c=design["damper_c"] * 1.01)     # a stale file: not used
    (tmp_path / "optimise.json").write_text(json.dumps({"design": other, "active": active}))
    assert optimiser_json(config, cold_cfg) is None


def test_softclose_report_is_the_function_after_the_package_is_imported():
    """softclose.report is the sign-off package's function, also once the package
    (softclose.signoff) is imported."""
    import softclose
    import softclose.signoff as package
    cfg = load_config(str(ROOT / "examples" / "lids" / "chest_lid.toml"))
    assert softclose.report is package.report
    for call in (softclose.report, package.report):
        r = call(cfg, samples=50)
        assert isinstance(r, softclose.ReportResult) and r.design["mechanism"] == "hinge"


def test_the_spring_to_buy_is_that_of_softclose_spring(rep):
    rc, out, _ = run_cli(["spring", "--json"] + [a for s in COLD for a in ("--set", s)])
    spring = json.loads(out)
    part = rep.parts["spring"]
    assert rc == 0 and part["ok"] and part["mode"] == "designed"
    assert part["coil_spring"] == spring["spring"] and part["checks"] == spring["checks"]


def test_pdf_figures_keep_matplotlibs_clipping_and_fonts():
    """A figure's SVG in the PDF: text as text in the embedded fonts (sizes in points, not
    3/4 of them), as outlines in a font the PDF lacks; a marker outside its axes, clipped
    by matplotlib, is not drawn."""
    import matplotlib.pyplot as plt
    import pypdfium2
    from fpdf import FPDF

    from softclose.signoff.figures import Figures
    from softclose.signoff.pdf import _draw_svg, _svg
    fig = plt.figure(figsize=(4, 3))
    ax = fig.add_axes([0.2, 0.2, 0.5, 0.6])
    ax.set_xlim(0, 1)
    ax.set_ylim(0, 1)
    ax.plot([0.5, 1.3], [0.5, 0.5], "s", color="red", ms=12, clip_on=True)
    ax.set_xlabel("x in the sans")
    fig.text(0.98, 0.1, "edge", ha="right")      # (the cropped figure reaches past 1.3)
    other = plt.figure(figsize=(4, 3))
    other.text(0.5, 0.5, "in a serif", family="DejaVu Serif")
    try:
        figs = Figures(plain=fig, serif=other)
        svg = _svg(figs, "plain", 6.8).decode()
        assert "x in the sans" in svg and "font-size: 10;" in svg and "px;" not in svg
        serif = _svg(figs, "serif", 6.8).decode()
        assert "<text" not in serif and "in a serif" not in serif.split("-->")[-1]
        pdf = FPDF(unit="pt", format=(400, 300))
        pdf.add_page()
        _draw_svg(pdf, svg.encode(), 0, 0, 400, 300)
        doc = pypdfium2.PdfDocument(bytes(pdf.output()))
        img = np.asarray(doc[0].render(scale=1).to_pil().convert("RGB")).astype(int)
        doc.close()
    finally:
        plt.close(fig)
        plt.close(other)
    red = (img[..., 0] > 200) & (img[..., 1] < 80) & (img[..., 2] < 80)
    cols = np.nonzero(red.any(axis=0))[0]
    assert red.sum() > 50                                  # the marker inside is drawn
    assert cols.max() - cols.min() < 30                    # and only that one
