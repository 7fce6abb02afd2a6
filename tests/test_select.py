"""``softclose select``: catalog parts ranked over their own tolerance boxes.

The catalog here is written by hand (a dozen springs of the three kinds, two dashpots and a
rotary damper at pivot O). The ranking is checked against an independent verdict: every
corner of every pair's box built here from the catalog's numbers (not by the screen's code)
and simulated by the adaptive reference on a model whose config carries the part's length
limits (so the reference's own range check judges them).
"""

from __future__ import annotations

import itertools
import json
import math
import os
from pathlib import Path

import numpy as np
import pytest

from softclose.cli import main
from softclose.config import default_config

from conftest import run_cli as _run, write_file as _write

SPRINGS = """\
part,kind,rate_N_per_m,free_length_m,preload_N,min_length_m,max_length_m,rate_tolerance,free_length_tolerance_m
C-60-4000,compression,4000,0.060,0,0.030,,0.1,0.0009
C-60-5000,compression,5000,0.060,0,0.030,,0.1,0.0009
C-61-6000,compression,6000,0.061,0,0.030,,0.1,0.0009
C-62-3000,compression,3000,0.062,0,0.030,,0.1,0.0009
C-60-8000,compression,8000,0.060,0,0.030,,0.1,0.0009
C-57-2000,compression,2000,0.057,0,0.030,,0.1,0.0009
C-64-1000,compression,1000,0.064,0,0.054,,0.1,0.0009
E-50-500,extension,500,0.050,5,,0.090,0.1,0.0009
E-45-300,extension,300,0.045,2,,0.056,0.1,0.0009
G-70-F20,gas_strut,300,0.070,20,0.045,,0.05,0.0013
G-70-F60,gas_strut,900,0.070,60,0.050,,0.05,0.0013
G-65-F10,gas_strut,150,0.065,10,0.045,,0.05,0.0013
"""
DAMPERS = """\
part,kind,c,pivot,c_tolerance
D-3000,dashpot,3000,,0.2
D-5000,dashpot,5000,,0.2
R-O-1,rotary,1.0,O,0.2
"""


def _cfg():
    # the catalog's own spreads replace those of k, l0 and c; the lid's mass is held fixed
    # here (8 corners a pair keep the reference's check of every corner of every pair short)
    return default_config().update({"tolerance.mass.lid": 0.0})


def _rows(text):
    lines = text.splitlines()
    head = lines[0].split(",")
    return [dict(zip(head, ln.split(","))) for ln in lines[1:]]


@pytest.fixture(scope="module")
def catalog(tmp_path_factory):
    d = tmp_path_factory.mktemp("catalog")
    s = _write(d, "s.csv", SPRINGS)
    dm = _write(d, "d.csv", DAMPERS)
    cfgfile = _write(d, "cfg.toml", "[tolerance]\n\"mass.lid\" = 0.0\n")
    code, out = _run("select", "--springs", str(s), "--dampers", str(dm), "--config",
                     str(cfgfile), "--samples", "64", "--verify", "3", "--json")
    return {"dir": d, "code": code, "json": json.loads(out)}


def _reference_verdicts():
    """Per pair (spring, damper): the reference's verdict at each of the 8 corners of its box,
    built from the catalog's numbers here."""
    from softclose.model.lid import LidModel
    from softclose.optimiser.verify import Checker, verify
    cfg = _cfg()
    springs, dampers = _rows(SPRINGS), _rows(DAMPERS)
    out = {}
    checkers = {}
    for s in springs:
        kind = s["kind"]
        k, l0, F0 = (float(s[x]) for x in ("rate_N_per_m", "free_length_m", "preload_N"))
        rt, ft = float(s["rate_tolerance"]), float(s["free_length_tolerance_m"])
        limits = {f"design.spring_{n}_length": float(s[f"{n}_length_m"])
                  for n in ("min", "max") if s[f"{n}_length_m"]}
        strut = {}
        if kind == "gas_strut":     # F1 +-10 % (no force_tolerance column), its rate unused;
            stroke = l0 - limits.pop("design.spring_min_length")     # its stroke's end
            strut = {"design.strut_stroke": stroke,
                     "design.strut_progression": 1 + k * stroke / F0}
        for d in dampers:
            c, ct = float(d["c"]), float(d["c_tolerance"])
            pivot = d["pivot"] or "lid"
            base = cfg.update({**limits, **strut, "design.spring_kind": kind,
                               "design.spring_preload": F0, "design.rotary_damper_pivot": pivot})
            key = (s["part"], pivot)
            if key not in checkers:
                checkers[key] = Checker(LidModel.from_config(base, cached=True))   # (its cfg: base's)
            verdicts = []
            for zk, zl, zc in itertools.product((-1, 1), repeat=3):
                cc = c * (1 + zc * ct)
                corner = base.update({
                    **({"design.spring_k": 0.0, "design.spring_preload": F0 * (1 + zk * 0.1)}
                       if strut else {"design.spring_k": k * (1 + zk * rt)}),
                    "design.spring_rest_length": l0 + zl * ft,
                    "design.damper_c": cc if d["kind"] == "dashpot" else 0.0,
                    "design.rotary_damper_c": cc if d["kind"] == "rotary" else 0.0})
                v = verify(corner, {}, checker=checkers[key])
                verdicts.append(v.constraints_ok)
            out[(s["part"], d["part"])] = verdicts
    return out


def test_select_ranks_a_verified_feasible_pair_first(catalog):
    assert catalog["code"] == 0
    d = catalog["json"]
    R = d["ranking"]
    assert d["evaluated"] == 12 * 3 == len(R)
    assert d["seconds"] > 0
    for e in R:
        assert {"spring", "damper", "feasible", "yield", "worst_objective", "design",
                "verified"} <= set(e)
    best = R[0]
    assert best["feasible"] and best["verified"] is True
    ref = best["reference"]
    assert ref["feasible"] and ref["agree"] and len(ref["corners"]) == 8
    assert all(c["ok"] for c in ref["corners"])
    # the reference's worst corner J is the kernel's worst (the kernel's includes samples)
    assert ref["worst_objective"] <= best["worst_objective"] * (1 + 1e-6)
    # no feasible pair of better worst-case J ranked below it
    for e in R[1:]:
        if e["feasible"]:
            assert e["worst_objective"] >= best["worst_objective"]
    # the order: feasible first, then yield, then worst J
    keys = [(not e["feasible"], -e["yield"],
             math.inf if e["worst_objective"] is None else e["worst_objective"]) for e in R]
    assert keys == sorted(keys)
    # a pair that fails says why; one that meets every corner has no reason
    for e in R:
        assert bool(e["reason"]) == (not e["feasible"])
    # both outcomes occur in this catalog (the test would not test much otherwise)
    assert 3 <= sum(e["feasible"] for e in R) <= 30


@pytest.mark.slow
def test_feasibility_agrees_with_the_reference_at_every_corner(catalog):
    ref = _reference_verdicts()
    R = catalog["json"]["ranking"]
    assert len(ref) == len(R)
    for e in R:
        v = ref[(e["spring"], e["damper"])]
        assert e["feasible"] == all(v), (e["spring"], e["damper"], v, e["reason"])
        assert e["corners_feasible"] == sum(v), (e["spring"], e["damper"], v)


def test_reasons_name_the_failure(catalog):
    R = {(e["spring"], e["damper"]): e for e in catalog["json"]["ranking"]}
    # a compression spring 57 mm long: the lid's spring length reaches 58.4 mm
    e = R[("C-57-2000", "D-3000")]
    assert not e["feasible"] and "longer than its free length" in e["reason"]
    assert "theta =" in e["reason"]
    # a strut whose compressed length 54 mm is above the shortest length of the stroke
    e = R[("C-64-1000", "D-3000")]
    assert "shorter than its minimum length" in e["reason"]
    # an extension spring whose maximum length 56 mm is below the longest of the stroke
    e = R[("E-45-300", "D-3000")]
    assert "longer than its maximum length" in e["reason"]


def test_bad_rows_are_reported_by_line_and_column(tmp_path):
    from softclose.catalog import read_dampers, read_springs
    text = SPRINGS.splitlines()
    bad = text[:3] + [
        "X1,compression,-100,0.060,0,0.030,,0.1,0.0009",     # line 4: negative rate
        "X2,torsion,100,0.060,0,0.030,,0.1,0.0009",          # line 5: unknown kind
        "X3,extension,100,0.060,0,,0.050,0.1,0.0009",        # line 6: free length above max
        "X4,compression,,0.060,0,0.030,,0.1,0.0009",         # line 7: missing value
    ]
    p = _write(tmp_path, "bad.csv", "\n".join(bad) + "\n")
    cat = read_springs(p)
    assert [e.part for e in cat.parts] == ["C-60-4000", "C-60-5000"]
    w = cat.warnings
    assert len(w) == 4
    assert "line 4, column rate_N_per_m: negative rate" in w[0]
    assert "line 5, column kind: unknown kind 'torsion'" in w[1]
    assert "line 6, column max_length_m" in w[2] and "above the maximum length" in w[2]
    assert "line 7, column rate_N_per_m: missing value" in w[3]
    # a file with no usable row: exit 2, one line naming the file and the first bad line
    none = _write(tmp_path, "none.csv", "\n".join(bad[:1] + bad[3:]) + "\n")
    dm = _write(tmp_path, "d.csv", DAMPERS)
    code, out = _run("select", "--springs", str(none), "--dampers", str(dm), "--json")
    assert code == 2
    err = json.loads(out)["error"]
    assert "no usable spring" in err and "line 2, column rate_N_per_m" in err
    # a header without a column: exit 2 naming it
    nohead = _write(tmp_path, "nohead.csv", SPRINGS.replace(",rate_tolerance", ",tol"))
    code, out = _run("select", "--springs", str(nohead), "--dampers", str(dm), "--json")
    assert code == 2 and "missing column rate_tolerance" in json.loads(out)["error"]
    # dampers: a rotary damper without a known pivot, a negative c
    dbad = _write(tmp_path, "dbad.csv", DAMPERS + "R-X,rotary,1.0,Q,0.2\nD-neg,dashpot,-5,,0.2\n")
    dc = read_dampers(dbad)
    assert len(dc.parts) == 3
    assert "line 5, column pivot: unknown pivot 'Q'" in dc.warnings[0]
    assert "line 6, column c: the coefficient must be > 0" in dc.warnings[1]


def test_mm_columns_give_the_same_ranking(tmp_path):
    from softclose.catalog import select
    rows = _rows(SPRINGS)
    head = ("part,kind,rate_N_per_mm,free_length_mm,preload_N,min_length_mm,max_length_mm,"
            "rate_tolerance,free_length_tolerance_mm")
    lines = [head]
    for r in rows:
        mm = (lambda v: "" if v == "" else repr(round(float(v) * 1e3, 9)))
        lines.append(",".join([r["part"], r["kind"], repr(float(r["rate_N_per_m"]) / 1e3),
                               mm(r["free_length_m"]), r["preload_N"], mm(r["min_length_m"]),
                               mm(r["max_length_m"]), r["rate_tolerance"],
                               mm(r["free_length_tolerance_m"])]))
    si = _write(tmp_path, "si.csv", SPRINGS)
    mmf = _write(tmp_path, "mm.csv", "\n".join(lines) + "\n")
    dm = _write(tmp_path, "d.csv", DAMPERS)
    a = select(_cfg(), si, dm, samples=32, verify=0)
    b = select(_cfg(), mmf, dm, samples=32, verify=0)
    assert [(e["spring"], e["damper"]) for e in a.ranking] == \
        [(e["spring"], e["damper"]) for e in b.ranking]
    for x, y in zip(a.ranking, b.ranking):
        assert x["feasible"] == y["feasible"] and x["yield"] == y["yield"]
        if x["worst_objective"] is not None:
            assert y["worst_objective"] == pytest.approx(x["worst_objective"], rel=1e-9)


def test_damper_c_optimised_without_a_damper_catalog(tmp_path):
    """Without dampers, c is chosen per spring: at the best spring's c the box is feasible
    at every corner, and 10 % more c breaks a corner or 10 % less raises the worst J."""
    from softclose.catalog import read_springs, select
    from softclose.catalog.files import DamperEntry
    from softclose.catalog.screen import pair_box, run_pairs, summarise
    cfg = _cfg()
    s = read_springs(_write(tmp_path, "s.csv", SPRINGS))
    r = select(cfg, s, samples=32, verify=1)
    best = r.best
    assert r.continuous and best["damper"] is None and best["feasible"]
    assert best["verified"] is True
    # the robust NLP re-solved its c with the spring fixed; the better of the two is kept
    n = best["nlp"]
    assert n["kept"] in ("grid", "nlp") and n["c_grid"] > 0
    assert best["design"]["damper_c"] == (n["c"] if n["kept"] == "nlp" else n["c_grid"])
    if n["kept"] == "nlp":  # the NLP's worst scenario is the kernel's worst over the box
        assert n["objective"] == pytest.approx(best["worst_objective"], rel=1e-3)
    c = best["design"]["damper_c"]
    lo, hi = cfg.optimise.damper_c
    assert lo <= c <= hi
    spring = next(e for e in s.parts if e.part == best["spring"])
    box = pair_box(cfg, 0)
    pairs = [(spring, DamperEntry("x", "dashpot", c * f, None, 0.2)) for f in (1 / 1.1, 1, 1.1)]
    sm = summarise(box, run_pairs(cfg, box, pairs), 3)
    assert sm["corners_ok"][1]
    assert sm["worst_objective"][1] == pytest.approx(best["worst_objective"], rel=1e-12)
    assert (not sm["corners_ok"][2]) or sm["worst_objective"][2] > sm["worst_objective"][1]
    assert (not sm["corners_ok"][0]) or sm["worst_objective"][0] > sm["worst_objective"][1]


def test_result_api_out_and_figure(tmp_path, catalog):
    code, out = _run("select", "--springs", str(catalog["dir"] / "s.csv"), "--dampers",
                     str(catalog["dir"] / "d.csv"), "--config", str(catalog["dir"] / "cfg.toml"),
                     "--samples", "16", "--verify", "1", "--out", str(tmp_path / "o"),
                     "--figure-format", "svg")
    assert code == 0
    names = sorted(p.name for p in (tmp_path / "o").iterdir())
    assert names == ["pairs", "select.csv", "select.json", "select.svg"]
    pairs = sorted((tmp_path / "o" / "pairs").iterdir())
    assert len(pairs) == 10 and pairs[0].name.startswith("01_")
    import pandas as pd
    df = pd.read_csv(tmp_path / "o" / "select.csv")
    assert len(df) == 36 and list(df["rank"]) == list(range(1, 37))
    assert "1 " in out and "adaptive reference at its 8 corners" in out
    from softclose.catalog import select
    r = select(_cfg(), catalog["dir"] / "s.csv", catalog["dir"] / "d.csv", samples=16,
               verify=0)
    f = r.to_frame()
    assert f.iloc[0]["spring"] == r.best["spring"] and len(f) == 36
    assert "SelectResult" in repr(r) and "<table" in r._repr_html_()
    fig = r.plot()
    assert fig.axes[0].get_xlabel().startswith("worst-case J")
    with pytest.raises(Exception):
        r.ranking = ()          # immutable


def test_a_pairs_config_is_its_parts_and_their_tolerances(tmp_path, catalog):
    """pair_config (what select --out writes in pairs/): the pair's nominal stroke is the
    ranking's, its [tolerance] box the parts' own, and its sign-off report judges the pair's
    box as select did (every corner met)."""
    import softclose
    from softclose.catalog import pair_config, select
    from softclose.config import load_config, to_toml
    from softclose.robust.box import box_of
    cfg = load_config(str(catalog["dir"] / "cfg.toml"))
    r = select(cfg, catalog["dir"] / "s.csv", catalog["dir"] / "d.csv", samples=16, verify=1)
    e = r.best
    c = pair_config(cfg, e)
    assert softclose.simulate(c).closing_time == pytest.approx(
        e["nominal"]["closing_time"], rel=1e-12)
    box = box_of(c)
    half = dict(zip(box.keys, box.half))
    part = e["spring_part"]
    if part["kind"] == "gas_strut":     # its force F1 carries its spread, its rate none
        assert "design.spring_k" not in half
        assert half["design.spring_preload"] == pytest.approx(
            part["force_tolerance"] * part["preload_N"], rel=1e-12)
    else:
        assert half["design.spring_k"] == pytest.approx(
            part["rate_tolerance"] * part["rate_N_per_m"], rel=1e-12)
    assert half["design.spring_rest_length"] == pytest.approx(
        e["spring_part"]["free_length_tolerance_m"], rel=1e-12)
    path = tmp_path / "pair.toml"
    path.write_text(to_toml(c))
    rep = softclose.report(load_config(str(path)), samples=64)
    assert e["feasible"] and rep.success, rep.message


def test_ctrl_c_keeps_the_pairs_screened(tmp_path, monkeypatch):
    from softclose.catalog import select as sel_mod
    import softclose.catalog.ranking as S
    calls = {"n": 0}
    real = S.screen_chunk

    def chunk(*a, **k):
        calls["n"] += 1
        if calls["n"] == 3:
            raise KeyboardInterrupt
        return real(*a, **k)
    monkeypatch.setattr(S, "screen_chunk", chunk)
    monkeypatch.setattr(S, "CHUNK_ROWS", 10 * 25)      # 10 pairs a chunk (25 points each)
    s = _write(tmp_path, "s.csv", SPRINGS)
    dm = _write(tmp_path, "d.csv", DAMPERS)
    r = sel_mod(_cfg(), s, dm, samples=16, verify=3)
    assert r.interrupted and not r.success and r.evaluated == 20
    assert "interrupted: 20 of 36" in r.message
    assert all(e["verified"] is None for e in r.ranking)
    keys = [(not e["feasible"], -e["yield"]) for e in r.ranking]
    assert keys == sorted(keys)


def test_dask_local_ranks_as_the_local_run(tmp_path, monkeypatch):
    """``--dask local:2``: the chunks of pairs screened on two worker processes (arriving in
    any order) give the local run's ranking, number for number."""
    pytest.importorskip("distributed")
    import softclose.catalog.ranking as S
    monkeypatch.setattr(S, "CHUNK_ROWS", 6 * 25)        # 6 chunks of 6 pairs
    s = _write(tmp_path, "s.csv", SPRINGS)
    dm = _write(tmp_path, "d.csv", DAMPERS)
    cfgfile = _write(tmp_path, "cfg.toml", "[tolerance]\n\"mass.lid\" = 0.0\n")
    argv = ["select", "--springs", str(s), "--dampers", str(dm), "--config", str(cfgfile),
            "--samples", "16", "--verify", "0", "--json"]
    code_a, out_a = _run(*argv)
    code_b, out_b = _run(*argv, "--dask", "local:2")
    assert code_a == code_b == 0
    a, b = json.loads(out_a)["ranking"], json.loads(out_b)["ranking"]
    assert len(a) == len(b) == 36
    for x, y in zip(a, b):
        for k in ("spring", "damper", "feasible", "yield", "worst_objective", "reason",
                  "corners_feasible"):
            assert x[k] == y[k], k


def test_the_reference_verdict_stands_where_it_differs(tmp_path, monkeypatch):
    """Where the reference's verdict at a corner differs from the kernel's, the pair takes
    the reference's and the pairs are ranked again: the next best is then verified too (the
    reference stood in for here by one that fails the kernel's best pair at one corner)."""
    import softclose.catalog.verify as V
    from softclose.catalog import select
    s = _write(tmp_path, "s.csv", SPRINGS)
    dm = _write(tmp_path, "d.csv", DAMPERS)
    plain = select(_cfg(), s, dm, samples=16, verify=0)
    first = (plain.ranking[0]["spring"], plain.ranking[0]["damper"])
    real = V.verify_pair

    def verify_pair(cfg, box, spring, damper, F, J):
        v = real(cfg, box, spring, damper, F, J)
        if (spring.part, damper.part) == first:
            v = dict(v, feasible=False, agree=False, differ=[v["corners"][0]["label"]],
                     reason="too slow (stand-in)")
        return v
    monkeypatch.setattr(V, "verify_pair", verify_pair)
    r = select(_cfg(), s, dm, samples=16, verify=2)
    demoted = next(e for e in r.ranking if (e["spring"], e["damper"]) == first)
    assert demoted["verified"] is False and not demoted["feasible"]
    assert demoted["reason"] == "the reference: too slow (stand-in)"
    assert demoted["kernel_reason"] == ""
    assert (r.ranking[0]["spring"], r.ranking[0]["damper"]) != first
    assert r.ranking[0]["verified"] is True and r.ranking[1]["verified"] is True
    assert r.success and r.verified_count == 3


def _interrupted_select(tmp_path, monkeypatch, interrupt, *options) -> tuple[int, str]:
    """``softclose select`` on SPRINGS x DAMPERS (12 pairs a chunk), ``interrupt()`` called
    as the second chunk starts: (exit code, stdout)."""
    import softclose.catalog.ranking as S
    calls = {"n": 0}
    real = S.screen_chunk

    def chunk(*a, **k):
        calls["n"] += 1
        if calls["n"] == 2:
            interrupt()
        return real(*a, **k)
    monkeypatch.setattr(S, "screen_chunk", chunk)
    monkeypatch.setattr(S, "CHUNK_ROWS", 12 * 25)      # 12 pairs a chunk
    s = _write(tmp_path, "s.csv", SPRINGS)
    dm = _write(tmp_path, "d.csv", DAMPERS)
    cfgfile = _write(tmp_path, "cfg.toml", "[tolerance]\n\"mass.lid\" = 0.0\n")
    return _run("select", "--springs", str(s), "--dampers", str(dm), "--config",
                str(cfgfile), "--samples", "16", *options)


def test_ctrl_c_on_the_command_line_writes_what_was_ranked(tmp_path, monkeypatch):
    """Exit 130, and --out holds the pairs screened before the interruption, ranked."""
    def interrupt():
        raise KeyboardInterrupt
    code, out = _interrupted_select(tmp_path, monkeypatch, interrupt,
                                    "--out", str(tmp_path / "o"))
    assert code == 130
    import pandas as pd
    df = pd.read_csv(tmp_path / "o" / "select.csv")
    assert len(df) == 12 and df["verified"].isna().all()
    assert "interrupted: 12 of 36 pairs screened" in out


def test_a_real_ctrl_c_prints_what_was_ranked(tmp_path, monkeypatch):
    """SIGINT itself (the command line's handler notes it, then raises): with --json and no
    --out the pairs screened before it are still printed, ranked, and the exit code is
    130."""
    import signal
    code, out = _interrupted_select(tmp_path, monkeypatch,
                                    lambda: signal.raise_signal(signal.SIGINT), "--json")
    assert code == 130
    payload = json.loads(out)
    assert payload["interrupted"] is True
    assert len(payload["ranking"]) == 12
    assert all(e["verified"] is None for e in payload["ranking"])


@pytest.mark.slow
def test_free_points_are_re_optimised_per_part(capsys):
    """``select --free``: a pair's attachment points by the robust co-design with the parts
    fixed; the pair is screened and checked by the reference at its own points, where its
    worst-case J is lower than at the config's points; the points reported are the ones it
    was judged at (the library's simulate of the nominal lid there gives the row's nominal
    closing time); a gas strut keeps the config's points and says so; free keys other than
    points are refused in one line."""
    import softclose
    from softclose.catalog import read_dampers, read_springs
    data = Path(__file__).resolve().parent / "data"
    springs = read_springs(data / "catalog_springs.csv").parts
    dampers = [d for d in read_dampers(data / "catalog_dampers.csv").parts
               if d.part == "D-3000"]
    ext = [s for s in springs if s.part == "E-50-500"]
    strut = [s for s in springs if s.part == "G-70-F20"]
    cfg = default_config()
    bounds = {"geometry.lid_e[1]": [0.004, 0.024], "geometry.spring_anchor[1]": [-0.01, 0.05]}
    free = cfg.update({f"optimise.free.{k}": v for k, v in bounds.items()})
    plain = softclose.select(cfg, ext, dampers, verify=1)
    placed = softclose.select(free, ext, dampers, verify=1)
    a, b = plain.ranking[0], placed.ranking[0]
    assert b["placement"]["kept"] == "placed" and b["feasible"] and b["verified"] is True
    assert b["reference"]["feasible"] and b["reference"]["worst_objective"] == pytest.approx(
        b["worst_objective"], rel=1e-3)
    # (docs/numbers.md: select_free)
    assert (round(a["worst_objective"], 3), round(b["worst_objective"], 3)) == (1.384, 1.236)
    points = b["placement"]["values"]
    for k, (lo, hi) in bounds.items():
        assert lo - 1e-9 <= points[k] <= hi + 1e-9
        assert b["design"][k.removeprefix("geometry.")] == points[k]
    d = b["design"]
    nominal = cfg.update({**points, "design.spring_kind": d["spring_kind"],
                          "design.spring_k": d["spring_k"],
                          "design.spring_rest_length": d["spring_rest_length"],
                          "design.spring_preload": d["spring_preload"],
                          "design.spring_max_length": d["spring_max_length"],
                          "design.damper_c": d["damper_c"]})
    assert softclose.simulate(nominal).closing_time == pytest.approx(
        b["nominal"]["closing_time"], rel=1e-9)
    # a gas strut's points are co-designed too (the strut's law and friction through them);
    # the pair keeps whichever points rank it better
    s = softclose.select(free, strut, dampers, verify=1).ranking[0]
    assert s["placement"]["kept"] in ("config", "placed") and s["verified"] is True
    assert main(["select", "--springs", str(data / "catalog_springs.csv"), "--free",
                 "design.torsion_k=0:10"]) == 2
    assert "design.torsion_k cannot be free here" in capsys.readouterr().err
    # a value the parts set, free in a config (an example lid's own problem), is theirs
    from softclose.catalog.mounting import parts_fix
    c, warn = parts_fix(free.update({"optimise.free": {"design.rotary_damper_c": [0, 5],
                                                       "geometry.lid_e[1]": [0.004, 0.024]}}))
    assert [k for k, _, _ in c.optimise.free] == ["geometry.lid_e[1]"]
    assert warn == ["optimise.free: design.rotary_damper_c is set by each pair's parts, "
                    "not chosen"]


def test_one_nlp_serves_every_spring_and_the_re_solve_is_the_robust_design(tmp_path):
    """The best springs' c re-solved by the robust NLP: every coil spring fills one NLP
    structure with its numbers, every gas strut one of its own (none is built per part: a
    further spring of either law adds none), and the re-solve's design, worst-case objective
    and verdict are those of the whole robust design (``report=True``) for the same
    spring."""
    import softclose.robust.scenario_cache as rnlp
    from softclose.catalog import read_springs, select
    from softclose.catalog.nlp import NLP_SAMPLES, solve_c, spring_config
    from softclose.catalog.files import DamperEntry
    from softclose.robust import optimise_robust
    rnlp.forget()
    s = read_springs(_write(tmp_path, "s.csv", SPRINGS))
    r = select(_cfg(), s, samples=16, verify=3)
    solved = [e for e in r.ranking if e.get("nlp")]
    assert len(solved) == 3 and all(e["nlp"]["success"] for e in solved)
    sizes = {key[0] for key in rnlp._STRUCTURES}      # (scenarios of each structure)
    laws = {key[2] for key in rnlp._STRUCTURES}       # (the geometric series: the law)
    kinds = {x.spring_kind for x in s.parts if x.part in {e["spring"] for e in solved}}
    assert kinds == {"compression", "gas_strut"} and len(sizes) == 1
    assert len(laws) == 2, rnlp._STRUCTURES.keys()
    built = len(rnlp._STRUCTURES)
    for part in ("G-65-F10", "C-60-5000"):            # one more of each law: nothing built
        x = next(p for p in s.parts if p.part == part)
        solve_c(_cfg(), x, DamperEntry(None, "dashpot", 4000.0, None, 0.2))
    assert len(rnlp._STRUCTURES) == built
    spring = next(x for x in s.parts if x.part == solved[0]["spring"])
    damper = DamperEntry(None, "dashpot", solved[0]["nlp"]["c_grid"], None, 0.2)
    lean = solve_c(_cfg(), spring, damper)
    full = optimise_robust(spring_config(_cfg(), spring, damper), samples=NLP_SAMPLES,
                           verify=False)
    assert lean["c"] == full.design["damper_c"] == solved[0]["nlp"]["c"]
    assert lean["objective"] == full.objective
    assert lean["success"] == (full.design is not None) and lean["message"] == full.message


@pytest.mark.slow
def test_prepare_select_compiles_the_nlp_and_select_loads_it(tmp_path, monkeypatch, capsys):
    """``softclose prepare --select FILE`` compiles select's NLP (in the foreground, named on
    stderr); select then loads it and ranks with the same numbers as CasADi's virtual
    machine; a bad catalog is exit 2 before anything is built."""
    import shutil
    from softclose import buildcache
    import softclose.robust.scenario_cache as rnlp
    from softclose.catalog import select
    if shutil.which(os.environ.get("CC", "cc")) is None:
        pytest.skip("no C compiler")
    monkeypatch.setenv(buildcache.ENV_FOLDER, str(tmp_path / "cache"))
    s = _write(tmp_path, "s.csv", SPRINGS)
    cfgfile = _write(tmp_path, "cfg.toml", "[tolerance]\n\"mass.lid\" = 0.0\n")
    rnlp.forget()
    vm = select(_cfg(), s, samples=16, verify=2)
    assert all(st.library is None for st in rnlp._STRUCTURES.values())
    rnlp.forget()
    code, out = _run("prepare", "--select", str(s), "--config", str(cfgfile), "--json")
    err = capsys.readouterr().err
    assert code == 0, err
    done = json.loads(out)
    # the first solve's NLP (nominal lid and 8 corners) of each spring law (the coil
    # springs', the gas struts'), and any a search round enlarged or a strut's solve retried
    assert 2 <= len(done["compiled"]) <= 6 and not done["failed"], (done, err)
    assert "building the NLP of the robust optimiser (9 scenarios" in err
    rnlp.forget()
    fast = select(_cfg(), s, samples=16, verify=2)
    assert rnlp._STRUCTURES and all(st.library is not None
                                    for st in rnlp._STRUCTURES.values())
    assert [(e["spring"], e.get("nlp")) for e in fast.ranking] == \
        [(e["spring"], e.get("nlp")) for e in vm.ranking]
    bad = _write(tmp_path, "bad.csv", "part,kind\n")
    assert main(["prepare", "--select", str(bad)]) == 2
    assert "missing column" in capsys.readouterr().err
