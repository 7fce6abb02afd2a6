"""The report's tables as rows of text, shared by the HTML page and the PDF."""

from __future__ import annotations

from ..present.display import mm, num
from ..problem import METRIC_KEYS, UNITS

#: the report's sections, in order (the HTML's and the PDF's headings)
SECTIONS = ("1. The lid and the design", "2. The parts to buy",
            "3. The metrics of the stroke, verified", "4. The stroke and the hand force",
            "5. The sign-off matrix", "6. Yield", "7. What limits the design",
            "8. The config and the software")


def _u(v, unit: str = "", digits: int = 6) -> str:
    t = num(v, digits)
    return f"{t} {unit}".rstrip() if unit and t != "—" else t


def design_rows(r) -> list:
    d = r.design
    rows = [("mechanism", "hinge lid" if d["mechanism"] == "hinge" else "four-bar linkage"),
            ("spring", d["spring_kind"]),
            ("spring_k", _u(d["spring_k"], "N/m")),
            ("spring_rest_length", _u(d["spring_rest_length"], "m")),
            ("damper_c", _u(d["damper_c"], "N s/m"))]
    if d.get("rotary_damper_c"):
        rows.append(("rotary_damper_c", _u(d["rotary_damper_c"], "N m s/rad")))
    if d.get("end_damper_c"):
        rows.append(("end_damper_c", _u(d["end_damper_c"], "N m s/rad")))
    rows.append(("the parts' values are given at", f"{d['reference_temperature_c']:g} °C"))
    rows.append(("operating temperatures", ", ".join(f"{T:g} °C" for T in r.temperatures)))
    return rows


def spring_rows(r) -> tuple:
    """(title, rows, EN 13906-1 check rows, note)."""
    s = r.parts["spring"]
    kind = s["kind"]
    if kind == "none":
        return "Spring", [("spring", "none (design.spring_k = 0)")], [], ""
    lengths = [("works between", f"{mm(s.get('shortest_length'))} and "
                                  f"{mm(s.get('longest_length'))}")]
    if kind == "gas_strut":
        rows = [("extended length", mm(s["extended_length"])), ("stroke", mm(s["stroke"])),
                ("force F1 at full extension", _u(s["force_f1"], "N")),
                ("progression K", num(s["progression"])),
                ("force F2 at full compression", _u(s["force_f2"], "N")),
                ("friction band F3 - F1", _u(s["friction_band"], "N"))] + lengths
        rows += [(f"F1 at {a['temperature_c']:g} °C", _u(a["force_f1"], "N", 4))
                 for a in s["force_f1_at"]]
        return "Gas strut", rows, [], ""
    rows = [("kind", s["what"]), ("rate", _u(s["rate"], "N/m")),
            ("rest length", mm(s["rest_length"])), ("preload", _u(s["preload"], "N"))]
    rows += lengths
    checks = []
    c = s.get("coil_spring")
    if c:
        rows += [(f"coil spring ({s['mode']})",
                  f"{s['material']}: wire d = {mm(c['wire_d'])}, mean coil D = "
                  f"{mm(c['coil_d'])}, {c['active_coils']:g} active coils of "
                  f"{c['total_coils']:g}"),
                 ("free length / solid length", f"{mm(c['free_length'])} / "
                                                f"{mm(c['solid_length'])}")
                 if c.get("kind") != "extension" else
                 ("free length / closed body", f"{mm(c['free_length'])} / "
                                               f"{mm(c['body_length'])}; hooks: "
                                               f"{c['hooks']}"),
                 ("outer diameter", mm(c["outer_d"])), ("mass", f"{c['mass'] * 1e3:.4g} g")]
        for ch in s.get("checks", ()):
            scale, unit = {"m": (1e3, "mm"), "Pa": (1e-6, "MPa"), "1": (100.0, "%")}.get(
                ch["unit"], (1.0, ch["unit"]))
            lim = "—" if ch["limit"] is None else f"{ch['limit'] * scale:.5g}"
            checks.append((ch["name"], f"{ch['value'] * scale:.5g}", ch["relation"], lim, unit,
                           "ok" if ch["ok"] else "FAILS"))
    note = s.get("note") or (s.get("message") or "")
    if s.get("ok") is False:
        note = "FAILS: " + note
    return "Spring", rows, checks, note


def damper_rows(r) -> tuple:
    """(head, rows, note): each damper's coefficient at each temperature."""
    temps = r.temperatures
    head = ("damper", "key", "coefficient") + tuple(f"at {T:g} °C" for T in temps)
    rows = [(d["what"], d["key"], _u(d["coefficient"], d["unit"]))
            + tuple(_u(a["coefficient"], d["unit"], 5) for a in d["at"])
            for d in r.parts["dampers"]]
    beta = r.parts["damper_temperature_coeff"]
    note = (f"c(T) = c · exp(β (T − T_ref)), β = design.damper_temperature_coeff = {beta:g} "
            f"1/K, T_ref = {r.parts['reference_temperature_c']:g} °C"
            + (" (no temperature dependence)" if not beta else "."))
    return head, rows, note


def metric_rows(r) -> tuple:
    """(head, rows, note): each metric by the reference and by the fixed-step simulator
    with its estimated accuracy (±), and their difference."""
    m = r.metrics
    ref, sim, acc, diff = m["reference"], m["simulate"], m["accuracy"], m["differences"]
    rows = []
    for k in METRIC_KEYS:
        e = acc.get(k)
        rows.append((k, _u(ref.get(k), UNITS[k], 10), _u(sim.get(k), UNITS[k], 10),
                     "—" if e is None else f"± {e:.1e}",
                     "—" if diff.get(k) is None else f"{diff[k]:.1e}"))
    head = ("metric", "adaptive reference", "fixed-step simulate", "estimated accuracy",
            "difference")
    note = (f"At {r.design['temperature_c']:g} °C. Reference: {m['reference_method']}. "
            f"Simulate: {sim.get('method')}, step {num(sim.get('step'))} s; ± is its "
            "estimated distance from the converged answer.")
    return head, rows, note


def stroke_rows(r) -> tuple:
    """(head, rows): the reference's metrics and the hand force at each temperature."""
    keys = (("closing_time", "s"), ("impact_tip_speed", "m/s"), ("peak_tip_speed", "m/s"),
            ("holding_moment", "N m"))
    hand = (("opening_force", "N"), ("closing_force", "N"), ("self_close_deg", "deg"))
    head = ("temperature",) + tuple(k for k, _ in keys + hand) + ("hold-open",)
    rows = []
    for col, s in r.strokes.items():
        ref, h = s["reference"], s.get("hand") or {}
        ho = ", ".join(f"{a:.3g}–{b:.3g} deg" for a, b in h.get("hold_open") or ()) or "none"
        rows.append((col,) + tuple(_u(ref.get(k), u, 6) for k, u in keys)
                    + tuple(_u(h.get(k), u, 4) for k, u in hand) + (ho,))
    return head, rows


def matrix_cell(row: dict, x: dict) -> tuple:
    """(value, margin, PASS/FAIL, where) of one sign-off cell as text."""
    v = x.get("value")
    value = ("yes" if v else "no") if isinstance(v, bool) else _u(v, row["unit"], 6)
    if v is None and x.get("reason"):
        value = x["reason"]
    margin = "" if x.get("margin") is None else f"margin {num(x['margin'], 4)} {row['unit']}"
    return value, margin.strip(), "PASS" if x["ok"] else "FAIL", x.get("where", "")


def yield_rows(r) -> tuple:
    """(head, rows, note)."""
    y = r.yields
    if "skipped" in y:
        return (), [], y["skipped"]
    head = ("temperature", "yield", "95 % interval", "samples", "failures", "required")
    rows = []
    for p in y["per_temperature"]:
        fails = ", ".join(f"{k}: {n}" for k, n in p["failures"].items()) or "none"
        rows.append((f"{p['temperature_c']:g} °C", f"{100 * p['yield']:.4g} %",
                     f"{100 * p['yield_ci'][0]:.4g} – {100 * p['yield_ci'][1]:.4g} %",
                     str(p["samples"]), fails, "met" if p["meets_required"] else "NOT met"))
    j = y["joint"]
    rows.append(("every temperature", f"{100 * j['yield']:.4g} %",
                 f"{100 * j['yield_ci'][0]:.4g} – {100 * j['yield_ci'][1]:.4g} %",
                 str(j["samples"]), "", "met" if j["meets_required"] else "NOT met"))
    note = (f"Monte Carlo over the tolerance box ({', '.join(y['keys'])}; "
            f"{y['distribution']}), the same samples at every temperature; required yield "
            f"{100 * y['required_yield']:.4g} %. Interval: Wilson score, 95 %."
            + (f" Note: {y['note']}." if y.get("note") else ""))
    return head, rows, note


def limit_lines(r) -> list[str]:
    lim = r.limits
    out = []
    for a in lim.get("active", ()):
        dj = a.get("dJ")
        out.append(f"{a['name']} is active at its {a.get('bound', '')} bound "
                   f"{num(a.get('value'))} {a.get('unit') or ''}".rstrip()
                   + (f": dJ = {dj:.4g} (the objective's change per unit change of the "
                      "bound)" if dj is not None else ""))
    if not lim.get("active"):
        out.append("The optimiser's active constraints are not known (no optimise.json or "
                   "robust.json of this design next to the config file): the constraint with "
                   "the smallest margin limits it.")
    sm = lim.get("smallest_margin")
    if sm:
        value = sm["value"]
        value = ("yes" if value else "no") if isinstance(value, bool) else num(value)
        out.append(f"The tightest cell of the sign-off matrix: {sm['constraint']} at "
                   f"{sm['column']}: value {value}, limit {num(sm['limit'])}"
                   + (f", margin {num(sm['margin'], 4)}" if sm["margin"] is not None else
                      " (fails)") + ".")
    return out


def config_lines(r) -> tuple:
    facts = [f"softclose {r.version}",
             f"report computed in {r.time:.2f} s"]
    return facts, r.config_toml


def report_text(payload: dict) -> str:
    """What ``softclose report`` prints of a report's JSON: the verdict, the sign-off matrix
    in short, the time."""
    m = payload["matrix"]
    lines = [payload["message"], "sign-off matrix (PASS/FAIL per column: "
             + ", ".join(m["columns"]) + "):"]
    for row in m["rows"]:
        cells = m["cells"][row["name"]]
        lines.append(f"  {row['name']:<19} " + "  ".join(
            ("PASS" if cells[c]["ok"] else "FAIL") if c in cells else "  — "
            for c in m["columns"]))
    y = payload["yield"]
    if "joint" in y:
        j = y["joint"]
        lines.append(f"  yield at every temperature {100 * j['yield']:.4g} % (95 % interval "
                     f"{100 * j['yield_ci'][0]:.4g}–{100 * j['yield_ci'][1]:.4g} %)")
    lines.append(f"  ({payload['time']:.2f} s)")
    return "\n".join(lines)


__all__ = ["SECTIONS", "report_text", "design_rows", "spring_rows", "damper_rows", "metric_rows", "stroke_rows",
           "matrix_cell", "yield_rows", "limit_lines", "config_lines"]
