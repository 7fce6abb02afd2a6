"""Which parts close three hinge lids gently: a toilet seat, a chest lid and a flap?

Each lid of examples/lids/ is optimised as its config asks (the toilet seat: the one-way
rotary damper at its hinge for a 5-8 s close; the chest lid and the flap: a spring and a
dashpot), every reported number verified by the adaptive reference, and the design is
signed off (softclose.report: the sign-off matrix, the hand force and its zones).
With --fast the lids are not optimised: their configs' own designs are signed off.

Writes to studies/out/hinge_lids/:
  lids.csv              per lid: the design, J, closing time, impact tip speed, verified
  lids.json             the same, with each result's message
  *_design.toml         each lid's design as a config (softclose simulate --config ...)
  *_report.html         each lid's sign-off report
  *_report.pdf          the same, to print (A4)

Usage: python studies/hinge_lids.py [--fast] [--out DIR]
"""

from __future__ import annotations

import csv
import json
import sys
from pathlib import Path

import softclose
from softclose.config import to_toml
from softclose.present.study import parse, study_options

ROOT = Path(__file__).resolve().parents[1]
LIDS = ROOT / "examples" / "lids"


def study(name: str, fast: bool) -> tuple[dict, object]:
    """One lid: its design (optimised, or the config's with --fast), the reference's
    stroke, and the design's config."""
    cfg = softclose.load_config(str(LIDS / f"{name}.toml"))
    if fast:
        design_cfg, res = cfg, None
    else:
        res = softclose.optimise(cfg, starts=2)
        design_cfg = res.design_config() if res.design is not None else cfg
    stroke = softclose.simulate(design_cfg)
    row = {"lid": name, "spring_k": design_cfg.design.spring_k,
           "spring_rest_length": design_cfg.design.spring_rest_length,
           "damper_c": design_cfg.design.damper_c,
           "rotary_damper_c": design_cfg.design.rotary_damper_c,
           "objective": None if res is None else res.objective,
           "closing_time": stroke.closing_time, "impact_tip_speed": stroke.impact_tip_speed,
           "optimised": res is not None,
           "verified": None if res is None else bool(res.success),
           "message": "the config's own design (--fast)" if res is None else res.message}
    return row, design_cfg


def main(argv=None) -> int:
    ap = study_options(__doc__, __file__, json_option=False,
                       fast="sign off the configs' own designs (no optimisation), 200 yield "
                            "samples")
    a = parse(ap, argv)
    rows, files = [], []
    for path in sorted(LIDS.glob("*.toml")):
        row, design_cfg = study(path.stem, a.fast)
        rows.append(row)
        toml = a.out / f"{path.stem}_design.toml"
        toml.write_text(to_toml(design_cfg, header=f"{path.stem}: the design of "
                                                   "studies/hinge_lids.py"))
        sign_off = softclose.report(design_cfg, samples=200 if a.fast else None)
        files += [toml, *sign_off.save_all(a.out, stem=f"{path.stem}_report", name=path.name)]
        row["sign_off"] = sign_off.message
        print(f"{path.stem}: closes in {row['closing_time']:.3g} s at "
              f"{row['impact_tip_speed']:.3g} m/s; {sign_off.message}", file=sys.stderr)
    table = a.out / "lids.csv"
    with open(table, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=[k for k in rows[0] if k != "message"])
        w.writeheader()
        w.writerows([{k: v for k, v in r.items() if k != "message"} for r in rows])
    (a.out / "lids.json").write_text(json.dumps(rows, indent=1))
    files += [table, a.out / "lids.json"]
    print("\n".join(str(f) for f in files))
    return 0


if __name__ == "__main__":
    sys.exit(main())
