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
    path = rep.save(tmp_path_factory.mktemp("report") / "report.pdf", figs)
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


def pdf_string(data: bytes, key: bytes) -> str:
    """The text of a string of the PDF's document information (/Key (...))."""
    raw = re.search(rb"/" + key + rb" \(((?:\\.|[^\\)])*)\)", data, re.S).group(1)
    raw = re.sub(rb"\\(.)", rb"\1", raw, flags=re.S)
    return raw[2:].decode("utf-16-be") if raw.startswith(b"\xfe\xff") else raw.decode("latin-1")


def test_pdf_has_the_sections_and_the_figures(rep, pdf_bytes, figs):
    assert pdf_bytes.startswith(b"%PDF")
    kw = re.search(rb"/Keywords \((.*?)\)", pdf_bytes).group(1).decode("latin-1")
    assert kw.split("; ") == list(SECTIONS)
    assert pdf_string(pdf_bytes, b"Subject") == rep.message
    assert pdf_string(pdf_bytes, b"Title") == "Sign-off report"
    pages = len(re.findall(rb"/Type /Page\b", pdf_bytes))
    # a title page, one text page per section (the config two) and every figure
    assert pages >= 1 + len(SECTIONS) + len(figs)


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


def test_bad_input_is_one_line_and_exit_2(tmp_path):
    rc, _, err = run_cli(["report", "--format", "doc", "--out", str(tmp_path)])
    assert rc == 2 and len(err.strip().splitlines()) == 1 and "--format" in err
    rc, _, err = run_cli(["report", "--samples", "0", "--out", str(tmp_path)])
    assert rc == 2 and "--samples" in err


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
    from softclose.cli.report import optimiser_json
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
