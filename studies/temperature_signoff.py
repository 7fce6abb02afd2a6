"""What does a cold or a hot room do to the nominal optimum, the robust design and a gas strut?

Three designs of the default problem are run from -10 to 50 °C with a silicone-oil damper
(design.damper_temperature_coeff = -0.005 /K: a rotary damper's datasheet, 7.3 s at 0 °C,
6.5 s at 23 °C, 6.0 s at 40 °C): the nominal optimum and the robust design with a steel coil
spring (its rate -2.5e-4 /K), and the nominal optimum with a gas strut instead (its force
follows its gas, about +0.34 %/K, and a 2 N friction band): closing time, impact tip speed,
holding moment and opening force against the temperature, and each design signed off at
-10, 23 and 50 °C (softclose.report: every constraint at each temperature and at the worst
tolerance corner, the hand force and its zones at each). The designs are those of the
reference temperature (the parts' values are given at 23 °C).

Writes to studies/out/temperature_signoff/:
  temperatures.csv      per design and temperature: closing time, impact tip speed,
                        holding moment, opening force, J, feasible
  temperatures.png      closing time and impact tip speed against the temperature, the limits
  nominal_report.html   the nominal optimum signed off at -10, 23 and 50 °C
  robust_report.html    the robust design signed off at -10, 23 and 50 °C
  gas_strut_report.html the gas-strut design signed off at -10, 23 and 50 °C
  summary.json          each design, the temperatures where it breaks a constraint, the
                        reports' verdicts

Usage: python studies/temperature_signoff.py [--fast] [--out DIR]
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

import softclose
from softclose.jsonio import jsonable
from softclose.present.figures import plt, save
from softclose.present.study import parse, study_options

#: the silicone-oil damper's temperature coefficient (1/K) and the sign-off temperatures
BETA = -0.005
SIGN_OFF = [-10.0, 23.0, 50.0]
COLUMNS = ("closing_time", "impact_tip_speed", "holding_moment", "opening_force",
           "objective", "feasible")


def over_temperature(cfg, temps) -> dict:
    """The design of ``cfg`` at every temperature of ``temps``: a sweep over
    operating.temperature_c (each stroke's parts moved to its temperature)."""
    r = softclose.sweep(cfg, {"operating.temperature_c": np.asarray(temps, float)})
    f = r.to_frame()
    return {k: f[k].to_numpy() for k in COLUMNS}


def draw(temps, rows: dict, cfg, path: Path) -> Path:
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 3.8), layout="constrained")
    for name, r in rows.items():
        a1.plot(temps, r["closing_time"], "o-", ms=3, label=name)
        a2.plot(temps, r["impact_tip_speed"], "o-", ms=3, label=name)
    o = cfg.optimise
    a1.axhline(o.closing_time_max, color="tab:red", ls="--", lw=1, label="closing_time_max")
    a1.set_ylabel("closing time (s)")
    a2.set_ylabel("impact tip speed (m/s)")
    for ax in (a1, a2):
        ax.axvline(cfg.operating.reference_temperature_c, color="0.5", ls=":", lw=1)
        ax.set_xlabel("temperature (°C)")
        ax.legend(fontsize=8)
    fig.suptitle(f"The designs at the reference temperature, run from {temps[0]:g} to "
                 f"{temps[-1]:g} °C (damper β = {BETA:g} /K)", fontsize=10)
    return save(fig, path)


def main(argv=None) -> int:
    ap = study_options(__doc__, __file__, json_option=False,
                       fast="2,000 samples in the robust design and 200 in the reports' yields")
    a = parse(ap, argv)
    cfg = softclose.default_config().update({"design.damper_temperature_coeff": BETA})
    nominal = softclose.optimise(cfg)
    robust = softclose.optimise(cfg.update({"tolerance.samples": 2000}) if a.fast else cfg,
                                robust=True)
    strut = softclose.optimise(cfg.update({"optimise.spring_kinds": ["gas_strut"],
                                           "design.strut_friction": 1.0}))
    designs = {"nominal": nominal, "robust": robust, "gas_strut": strut}
    temps = np.arange(-10.0, 50.0 + 1e-9, 5.0)
    rows, summary, files = {}, {}, []
    for name, res in designs.items():
        if res.design is None:
            print(f"{name}: no design ({res.message})", file=sys.stderr)
            continue
        dcfg = res.design_config()
        rows[name] = over_temperature(dcfg, temps)
        signed = softclose.report(dcfg.update({"operating.temperatures_c": SIGN_OFF}),
                                  optimiser=res.to_json(), samples=200 if a.fast else None)
        files.append(signed.save(a.out / f"{name}_report.html"))
        bad = [float(T) for T, ok in zip(temps, rows[name]["feasible"]) if not ok]
        summary[name] = {"design": res.design, "objective": res.objective,
                         "infeasible_at_c": bad, "report": signed.message}
        where = ", ".join(f"{T:g}" for T in bad) + " °C" if bad else "no temperature"
        print(f"{name}: the nominal lid breaks a constraint at {where}; {signed.message}",
              file=sys.stderr)
    path = a.out / "temperatures.csv"
    with open(path, "w") as fh:
        fh.write("design,temperature_c," + ",".join(COLUMNS) + "\n")
        for name, r in rows.items():
            for i, T in enumerate(temps):
                fh.write(f"{name},{T:g}," + ",".join(str(r[k][i]) for k in COLUMNS) + "\n")
    files.append(path)
    files.append(draw(temps, rows, cfg, a.out / "temperatures.png"))
    path = a.out / "summary.json"
    path.write_text(json.dumps(jsonable(summary), indent=1, allow_nan=False))
    files.append(path)
    print("\n".join(str(f) for f in files))
    return 0


if __name__ == "__main__":
    sys.exit(main())
