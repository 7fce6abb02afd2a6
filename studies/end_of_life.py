"""What does the end of a lid's life cost: a strut that lost gas, a spring that relaxed, dampers that faded?

Three designs are signed off new and at the end of life with the makers' figures
(FIELD NOTES, "End of life"; docs/parts.md): a gas strut at -10 % of its force
(life.strut_force_loss = 0.10), a coil spring at 3 % relaxation (life.spring_relaxation =
0.03), every damper at -15 % (life.damper_change = -0.15). The designs: the nominal optimum of
the default lid, its robust design signed off new and at the end of life (softclose optimise
--robust over every tolerance corner in both states), and the gas-strut chest lid of
examples/lids/chest_lid.toml. For each: the stroke new and old (closing time, impact tip
speed, holding moment, opening force, J) from the adaptive reference, the constraints' margins
in each state, and what the end of life costs in J.

Writes to studies/out/end_of_life/:
  end_of_life.csv       per design and state: closing time, impact tip speed, peak tip speed,
                        holding moment, opening force, J, the margins of closing_time_max and
                        holding_moment_min (and opening_force_max when set), feasible
  end_of_life.png       closing time and J of each design, new against old
  summary.json          each design: its values, J new and old, what the end of life costs,
                        the state that limits it

Usage: python studies/end_of_life.py [--fast] [--json] [--out DIR]
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

import softclose
from softclose.files import write_with
from softclose.present.figures import plt, save
from softclose.present.study import parse, print_json, save_summary, study_options

#: the makers' figures: a strut's force lost over its life, a steel spring's relaxation, the
#: dampers' fade
LIFE = {"life.strut_force_loss": 0.10, "life.spring_relaxation": 0.03,
        "life.damper_change": -0.15}
CHEST = Path(__file__).resolve().parents[1] / "examples" / "lids" / "chest_lid.toml"
COLUMNS = ("closing_time", "impact_tip_speed", "peak_tip_speed", "holding_moment",
           "opening_force", "objective")


def margins(cfg, m: dict) -> dict:
    """The constraints' margins of one stroke (> 0: met with room), in their units."""
    o = cfg.optimise
    out = {"closing_time_max": (o.closing_time_max - m["closing_time"])
           if m["closing_time"] is not None else None,
           "holding_moment_min": m["holding_moment"] - o.holding_moment_min}
    if o.opening_force_max is not None and m.get("opening_force") is not None:
        out["opening_force_max"] = o.opening_force_max - m["opening_force"]
    return out


def in_state(cfg, state: str) -> dict:
    """The adaptive reference's stroke of ``cfg``'s design in ``state``, its J, margins and
    whether it meets every constraint."""
    c = cfg.update({"life.state": state})
    ref = softclose.Reference.from_config(c).simulate()
    m = {k: getattr(ref, k, None) for k in COLUMNS if k != "objective"}
    o = c.optimise
    m["objective"] = (o.weight_impact * ref.impact_theta_dot ** 2
                      + o.weight_peak_tip * ref.peak_tip_speed ** 2) if ref.closed else None
    mg = margins(c, m)
    ok = bool(ref.closed) and all(v is not None and v >= -1e-9 for v in mg.values()) and \
        (ref.closing_time or 0.0) >= o.closing_time_min
    return {**m, "margins": mg, "feasible": ok}


def draw(rows: dict, path: Path) -> Path:
    names = list(rows)
    x = np.arange(len(names))
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 3.8), layout="constrained")
    for k, (state, dx) in enumerate((("new", -0.18), ("end_of_life", 0.18))):
        ct = [rows[n][state]["closing_time"] or np.nan for n in names]
        J = [rows[n][state]["objective"] or np.nan for n in names]
        label = state.replace("_", " ")
        a1.bar(x + dx, ct, 0.36, label=label)
        a2.bar(x + dx, J, 0.36, label=label)
    for ax, what in ((a1, "closing time (s)"), (a2, "J")):
        ax.set_xticks(x, [n.replace("_", " ") for n in names])
        ax.set_ylabel(what)
        ax.legend(fontsize=8)
    fig.suptitle("Each design new and at the end of life (strut -10 %, spring relaxed 3 %, "
                 "dampers -15 %)", fontsize=10)
    return save(fig, path)


def main(argv=None) -> int:
    ap = study_options(__doc__, __file__, fast="2,000 samples in the robust design's yield")
    a = parse(ap, argv)
    base = softclose.default_config()
    if a.fast:
        base = base.update({"tolerance.samples": 2000})
    nominal = softclose.optimise(base)
    robust = softclose.optimise(base.update(LIFE), robust=True)
    chest = softclose.load_config(CHEST)
    designs = {"nominal": nominal.design_config().update(LIFE),
               "robust": robust.design_config().update(LIFE) if robust.design else None,
               "gas_strut_chest": chest.update(LIFE)}
    rows, summary = {}, {"life": LIFE, "designs": {}}
    for name, cfg in designs.items():
        if cfg is None:
            print(f"{name}: no design ({robust.message})", file=sys.stderr)
            continue
        rows[name] = {s: in_state(cfg, s) for s in ("new", "end_of_life")}
        new, old = rows[name]["new"], rows[name]["end_of_life"]
        cost = None if None in (new["objective"], old["objective"]) else \
            old["objective"] - new["objective"]
        limiting = "end_of_life" if new["feasible"] and not old["feasible"] else \
            "new" if not new["feasible"] else None
        d = cfg.design
        summary["designs"][name] = {
            "spring_kind": d.spring_kind, "spring_k": d.spring_k,
            "spring_rest_length": d.spring_rest_length, "spring_preload": d.spring_preload,
            "damper_c": d.damper_c, "new": new, "end_of_life": old,
            "J_cost_of_end_of_life": cost, "fails_only_at_the_end_of_life": limiting ==
            "end_of_life", "limiting_state": limiting}
        if name == "robust":
            summary["designs"][name].update(robust_limiting_state=robust.limiting_state,
                                            robust_objective=robust.objective)
        if not a.json:
            print(f"{name}: J new {new['objective']:.4g}, at the end of life "
                  f"{old['objective']:.4g}" + (f" (+{cost:.4g})" if cost is not None else "")
                  + f"; closes in {new['closing_time']:.4g} s new, "
                  f"{old['closing_time']:.4g} s old; meets every constraint: new "
                  f"{new['feasible']}, old {old['feasible']}")
    files = []

    def csv(p):
        with open(p, "w") as fh:
            fh.write("design,state," + ",".join(COLUMNS)
                     + ",margin_closing_time_max,margin_holding_moment_min,"
                       "margin_opening_force_max,feasible\n")
            for name, by in rows.items():
                for state, r in by.items():
                    mg = r["margins"]
                    vals = [r[k] for k in COLUMNS] + [mg.get("closing_time_max"),
                                                      mg.get("holding_moment_min"),
                                                      mg.get("opening_force_max")]
                    fh.write(f"{name},{state}," + ",".join("" if v is None else repr(float(v))
                                                          for v in vals)
                             + f",{str(r['feasible']).lower()}\n")
    files.append(write_with(a.out / "end_of_life.csv", csv))
    files.append(draw(rows, a.out / "end_of_life.png"))
    save_summary(summary, a.out / "summary.json", files)
    if a.json:
        print_json(summary)
    else:
        print("\n".join(str(f) for f in files))
    return 0


if __name__ == "__main__":
    sys.exit(main())
