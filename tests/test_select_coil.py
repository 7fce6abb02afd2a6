"""Catalog coil springs checked at their working lengths in ``softclose select``
(softclose.catalog.coil): the catalog's wire and coil columns, a spring that buckles refused
with its margin, the numbers those of softclose.coil_spring's own check of the same spring.

The coils, by hand (EN 10270-1 SH, G = 81500 N/mm^2):
- C-60-4000: d = 2 mm, D = 16 mm, n = 10: R = 81500 * 16 / (8 * 4096 * 10) = 3.9795 N/mm;
- C-60-4000-slim: d = 1.4 mm, D = 8 mm, n = 19: R = 81500 * 3.8416 / (8 * 512 * 19)
  = 4.0231 N/mm; L0/D = 7.6: with both ends pinned it buckles at s_K = 2.98 mm, while the
  lid deflects it by L0 + 0.9 mm - 52.27 mm = 8.63 mm.
"""

from __future__ import annotations

import io
import json
import math
from contextlib import redirect_stdout
from pathlib import Path

import pytest

from softclose.catalog import DamperEntry, read_springs, select
from softclose.coil_spring import CoilSpring, Duty, check
from softclose.coil_spring import standard as en13906
from softclose.optimiser.spring_order import working_lengths
from softclose.config import default_config
from softclose.errors import ConfigError

HEAD = ("part,kind,rate_N_per_m,free_length_m,preload_N,min_length_m,max_length_m,"
        "rate_tolerance,free_length_tolerance_m,wire_d_m,coil_d_m,active_coils,material")
SPRINGS = HEAD + """
C-60-4000,compression,4000,0.060,0,0.024,,0.1,0.0009,0.002,0.016,10,EN10270-1-SH
C-60-4000-slim,compression,4000,0.060,0,0.030,,0.1,0.0009,0.0014,0.008,19,
C-60-4000-plain,compression,4000,0.060,0,0.030,,0.1,0.0009,,,,
E-40-400,extension,400,0.040,2,,0.080,0.1,0.0009,0.0009,0.009,23,EN10270-1-DH
"""
DAMPER = [DamperEntry("D-5000", "dashpot", 5000.0, None, 0.2)]
#: the shipped, illustrative catalog
EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "catalogs" / "springs.csv"


def _cfg():
    return default_config().update({"tolerance.mass.lid": 0.0})


@pytest.fixture(scope="module")
def springs(tmp_path_factory):
    p = tmp_path_factory.mktemp("coil") / "springs.csv"
    p.write_text(SPRINGS)
    return read_springs(p)


@pytest.fixture(scope="module")
def ranked(springs):
    res = select(_cfg(), springs, DAMPER, samples=16, verify=0)
    return {e["spring"]: e for e in res.ranking}


def test_the_coil_columns_are_read(springs):
    c = {p.part: p for p in springs.parts}
    assert not springs.warnings
    s = c["C-60-4000"]
    assert (s.wire_d, s.coil_d, s.active_coils, s.material) == (0.002, 0.016, 10.0,
                                                                "EN10270-1-SH")
    assert s.coil.rate == pytest.approx(81500 * 16 / (8 * 4096 * 10) * 1e3, rel=1e-12)
    assert c["C-60-4000-slim"].material == "EN10270-1-SH"        # the default wire
    assert c["C-60-4000-plain"].coil is None
    assert c["E-40-400"].coil.material == "EN10270-1-DH"
    assert s.to_json()["wire_d_m"] == 0.002 and "wire_d_m" not in \
        c["C-60-4000-plain"].to_json()


def test_bad_coil_rows_are_left_out_by_line_and_column(tmp_path):
    rows = [HEAD,
            "OK,compression,4000,0.060,0,0.024,,0.1,0.0009,0.002,0.016,10,",
            # the coil's rate 3979 N/m is 20 % off the row's 5000 N/m (tolerance 10 %)
            "RATE,compression,5000,0.060,0,0.024,,0.1,0.0009,0.002,0.016,10,",
            "PART,compression,4000,0.060,0,0.024,,0.1,0.0009,0.002,,10,",
            "GAS,gas_strut,300,0.070,20,0.045,,0.05,0.0013,0.002,0.016,10,",
            "WIRE,compression,4000,0.060,0,0.024,,0.1,0.0009,0.002,0.016,10,EN10270-3",
            "INDEX,compression,4000,0.060,0,0.024,,0.1,0.0009,0.001,0.025,1,",
            "FEW,extension,4000,0.060,2,,0.1,0.1,0.0009,0.002,0.01,2.5,"]
    p = tmp_path / "s.csv"
    p.write_text("\n".join(rows) + "\n")
    cat = read_springs(p)
    assert [s.part for s in cat.parts] == ["OK"]
    w = [x.split(": ", 1)[1] for x in cat.warnings]
    assert w[0].startswith("line 3, column rate: the coil's rate G d^4/(8 D^3 n) = 3979.5 N/m "
                           "is -20.4% off the row's 5000 N/m")
    assert w[1].startswith("line 4, column coil_d_m: missing value")
    assert w[2].startswith("line 5, column kind: a gas_strut has no coil")
    assert w[3].startswith("line 6, column material: unknown material 'EN10270-3'")
    assert w[4].startswith("line 7, column coil_d_m: the spring index w = D/d = 25")
    assert w[5].startswith("line 8, column active_coils: n = 2.5 is below EN 13906-2's 3")
    q = tmp_path / "h.csv"
    q.write_text("part,kind,rate_N_per_m,free_length_m,preload_N,min_length_m,max_length_m,"
                 "rate_tolerance,wire_d_m\nA,compression,1000,0.06,0,,,0.1,0.002\n")
    with pytest.raises(ConfigError, match=r"the coil columns come together: missing "
                                          r"coil_d_m or coil_d_mm, active_coils"):
        read_springs(q)


def test_a_spring_that_buckles_is_refused_with_its_margin(ranked):
    e = ranked["C-60-4000-slim"]
    assert e["feasible"] is False
    sc = e["spring_checks"]
    assert sc["ok"] is False and sc["checked"]
    # s_K by hand: EN 13906-1 with nu = 1, L0 = 60.9 mm, D = 8 mm
    g_e = 81500 / 206000
    L0 = 0.0609
    s_k = L0 * 0.5 / (1 - g_e) * (1 - math.sqrt(1 - (1 - g_e) / (0.5 + g_e)
                                                 * (math.pi * 0.008 / L0) ** 2))
    assert s_k == pytest.approx(2.984e-3, abs=1e-6)
    longest, shortest = working_lengths(_cfg())
    s2 = L0 - shortest
    b = {c["name"]: c for c in sc["checks"]}["buckling"]
    assert (b["value"], b["limit"], b["ok"]) == (pytest.approx(s2, rel=1e-12),
                                                 pytest.approx(s_k, rel=1e-12), False)
    assert b["margin"] == pytest.approx((s_k - s2) / s_k, rel=1e-12)
    assert e["reason"].startswith(
        f"spring buckles: deflection {s2 * 1e3:.4g} mm against s_K {s_k * 1e3:.4g} mm, "
        f"margin {100 * (s_k - s2) / s_k:+.1f} % (EN 13906-1)")
    assert "margin -189.3 %" in e["reason"]


def test_the_numbers_are_coil_springs_own_check(ranked, springs):
    """The ranking row's checks of each coil spring are those of coil_spring.check for the
    same spring: the free length at the deflecting end of its tolerance, the stroke's working
    lengths, the config's cycles and seating."""
    cfg = _cfg()
    longest, shortest = working_lengths(cfg)
    for part in ("C-60-4000", "C-60-4000-slim"):
        s = next(p for p in springs.parts if p.part == part)
        coil = CoilSpring(s.wire_d, s.coil_d, s.active_coils)
        duty = Duty(rate=coil.rate, free_length=0.0609, longest_length=longest,
                    shortest_length=shortest, cycles=1e5, seating=1.0)
        own = check(coil, duty)
        sc = ranked[part]["spring_checks"]
        assert sc["stresses"] == pytest.approx(own.stresses, rel=1e-12)
        assert [(c["name"], c["ok"]) for c in sc["checks"]] == \
            [(c.name, c.ok) for c in own.checks]
        for c, o in zip(sc["checks"], own.checks):
            assert c["value"] == pytest.approx(o.value, rel=1e-12), c["name"]
            assert c["limit"] == pytest.approx(o.limit, rel=1e-12), c["name"]
        assert sc["life"] == own.life
    ok = ranked["C-60-4000"]["spring_checks"]
    assert ok["ok"] and "spring" not in ranked["C-60-4000"]["reason"]
    # its stress at solid length by hand: F_c = R (60.9 - 24) mm, tau = 8 F D/(pi d^3)
    R = 81500 * 16 / (8 * 4096 * 10) * 1e3
    assert ok["stresses"]["tau_c"] == pytest.approx(
        en13906.shear_stress(R * (0.0609 - 0.024), 0.002, 0.016), rel=1e-12)
    # in N and mm: 8 * 16 * F_c / (pi * 2^3) = 747.87 MPa, below 0.56 R_m = 1105 MPa
    assert ok["stresses"]["tau_c"] / 1e6 == pytest.approx(8 * 16 * R * 0.0369 / (math.pi * 8),
                                                          rel=1e-12)
    assert ok["stresses"]["tau_c"] / 1e6 == pytest.approx(747.87, abs=0.01)
    assert ok["stresses"]["tau_c_allowed"] / 1e6 == pytest.approx(
        0.56 * (2220 - 820 * math.log10(2)), rel=1e-12)


def test_an_extension_spring_is_checked_by_its_body(ranked, springs):
    cfg = _cfg()
    longest, shortest = working_lengths(cfg)
    s = next(p for p in springs.parts if p.part == "E-40-400")
    sc = ranked["E-40-400"]["spring_checks"]
    assert sc["ok"] and sc["standard"].startswith("EN 13906-2")
    assert sc["free_length"] == pytest.approx(0.040 - 0.0009)
    own = check(s.coil, Duty(rate=s.coil.rate, free_length=0.0391, longest_length=longest,
                             shortest_length=shortest, kind="extension", initial_tension=2.0))
    assert sc["stresses"] == pytest.approx(own.stresses, rel=1e-12)
    assert {c["name"] for c in sc["checks"] if c["deciding"]} == {"static", "fatigue"}


def test_springs_without_a_coil_are_unchanged(ranked, springs):
    plain = next(p for p in springs.parts if p.part == "C-60-4000-plain")
    e = ranked["C-60-4000-plain"]
    assert e["spring_checks"] is None
    # the same part without coil columns ranks exactly so; a buckling twin keeps its
    # kernel verdicts and only adds the spring's reason
    again = select(_cfg(), [plain], DAMPER, samples=16, verify=0).best
    for k in ("feasible", "yield", "worst_objective", "reason", "corners_feasible"):
        assert again[k] == e[k], k
    slim = ranked["C-60-4000-slim"]
    assert slim["yield"] == e["yield"] and slim["corners_feasible"] == e["corners_feasible"]
    if e["reason"]:
        assert slim["reason"].endswith("; " + e["reason"])


def test_select_command_shows_the_refusal(tmp_path):
    from softclose.cli import main
    p = tmp_path / "s.csv"
    p.write_text(SPRINGS)
    d = tmp_path / "d.csv"
    d.write_text("part,kind,c,pivot,c_tolerance\nD-5000,dashpot,5000,,0.2\n")
    buf = io.StringIO()
    with redirect_stdout(buf):
        main(["select", "--springs", str(p), "--dampers", str(d), "--samples", "16",
              "--verify", "0", "--json", "--set", "tolerance.mass.lid=0.0"])
    out = json.loads(buf.getvalue())
    rows = {e["spring"]: e for e in out["ranking"]}
    assert set(rows["C-60-4000"]) >= {"spring", "damper", "feasible", "yield",
                                      "worst_objective", "design", "verified",
                                      "spring_checks"}
    assert "spring buckles" in rows["C-60-4000-slim"]["reason"]
    assert rows["C-60-4000-slim"]["feasible"] is False
    assert rows["C-60-4000-plain"]["spring_checks"] is None
    f = select(_cfg(), read_springs(p), DAMPER, samples=4, verify=0).to_frame()
    ok = dict(zip(f["spring"], f["spring_ok"]))
    assert ok["C-60-4000"] is True and ok["C-60-4000-slim"] is False
    assert ok["C-60-4000-plain"] is None


def test_an_overstressed_catalog_spring_by_hand():
    """The shipped catalog's CS-070-02000: d = 1.4 mm, D = 21.6 mm, n = 2 (solid length
    4 * 1.4 = 5.6 mm), free length 70 + 1.3 mm: R = 81500 * 1.4^4 / (8 * 21.6^3 * 2) N/mm,
    tau_c = 8 D R (71.3 - 5.6) / (pi d^3) = 2557 MPa above 0.56 R_m = 1176 MPa."""
    from softclose.catalog import coil
    e = next(p for p in read_springs(EXAMPLE).parts
             if p.part == "CS-070-02000")
    R = 81500 * 1.4 ** 4 / (8 * 21.6 ** 3 * 2)                       # N/mm
    tau_c = 8 * 21.6 * R * (71.3 - 5.6) / (math.pi * 1.4 ** 3)        # MPa
    limit = 0.56 * (2220 - 820 * math.log10(1.4))
    assert round(tau_c) == 2557 and round(limit) == 1176
    sc = coil.spring_checks(default_config(), e)
    st = {c["name"]: c for c in sc["checks"]}["static"]
    assert st["value"] / 1e6 == pytest.approx(tau_c, rel=1e-12)
    assert st["limit"] / 1e6 == pytest.approx(limit, rel=1e-12)
    assert not sc["ok"] and sc["reason"] == (
        f"spring overstressed: stress at solid length {tau_c:.4g} MPa against 0.56 R_m = "
        f"{limit:.4g} MPa, margin {100 * (limit - tau_c) / limit:+.1f} % (EN 13906-1)")
    # the shipped catalog's other coils: two pass at the default lid, the 62 mm one buckles
    ok = {p.part: coil.spring_checks(default_config(), p)["ok"]
          for p in read_springs(EXAMPLE).parts if p.coil is not None}
    assert ok == {"CS-060-04000": True, "CS-062-03150": False, "CS-064-02500": True,
                  "CS-070-02000": False, "ES-040-0400-T2": True}
