"""Regenerate every report figure in one run.

Runs each study script in its own process, in a fixed order -- the seed reproduction, the
spring-damper maps, the Pareto front (``pareto_closing_time.py``), the work-precision
benchmark (``work_precision.py``) and the stress survey (``stress_survey.py``), then any other
``studies/*.py`` -- each in fast mode with ``--fast``. A script that does not exist yet is
listed as missing; one that fails is reported and the others still run.

Writes to studies/out/report_figures/:
  report_figures.json  for each study: exit code, run time, and the figures it left in
                       studies/out/<name>/ (every study writes its own files there)

``--format pdf`` (or svg) writes every figure in that format and in the report style
(``softclose.present.figures``: a 3.5 in column, 8-pt text, vector), through the environment
variables SOFTCLOSE_FIGURE_FORMAT and SOFTCLOSE_FIGURE_STYLE that ``softclose.present.figures.save``
reads; ``--format png`` (the default) keeps the screen style.

Usage: python studies/report_figures.py [--fast] [--format png|pdf|svg] [--only NAME ...]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
OUT = HERE / "out" / "report_figures"
STUDIES_OUT = HERE / "out"
ORDER = ("seed_reproduction", "spring_damper_maps", "pareto_closing_time", "work_precision",
         "stress_survey")


def studies() -> list[str]:
    others = sorted(p.stem for p in HERE.glob("*.py")
                    if p.stem not in ORDER and p.stem != Path(__file__).stem
                    and not p.stem.startswith("_"))
    return list(ORDER) + others


def takes_out(script: Path) -> bool:
    """The study accepts ``--out DIR``."""
    text = script.read_text()
    return '"--out"' in text or "study_options(" in text


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fast", action="store_true", help="every study in its fast mode")
    ap.add_argument("--only", nargs="*", default=None, help="run only these studies")
    ap.add_argument("--timeout", type=float, default=3600.0, help="per study (s)")
    ap.add_argument("--format", choices=("png", "pdf", "svg"), default="png",
                    help="figure format; pdf and svg in the report style (default png)")
    ap.add_argument("--out", type=Path, default=OUT, help=f"folder of the report (default {OUT})")
    ap.add_argument("--studies-out", type=Path, default=STUDIES_OUT,
                    help=f"each study that takes --out writes to DIR/<name> (default {STUDIES_OUT})")
    a = ap.parse_args(argv)
    a.out.mkdir(parents=True, exist_ok=True)
    env = dict(os.environ)
    if a.format != "png":
        env.update(SOFTCLOSE_FIGURE_FORMAT=a.format, SOFTCLOSE_FIGURE_STYLE="report")
    report, failed = {}, 0
    for name in studies():
        if a.only is not None and name not in a.only:
            continue
        script = HERE / f"{name}.py"
        if not script.exists():
            report[name] = {"status": "missing"}
            print(f"{name:22s} missing (not written yet)", flush=True)
            continue
        t0 = time.time()
        where = a.studies_out / name if takes_out(script) else HERE / "out" / name
        cmd = [sys.executable, str(script)] + (["--fast"] if a.fast else []) + \
            (["--out", str(where)] if takes_out(script) else [])
        try:
            p = subprocess.run(cmd, capture_output=True, text=True, timeout=a.timeout, env=env)
            code, err = p.returncode, p.stderr.strip().splitlines()[-1:] if p.returncode else []
        except subprocess.TimeoutExpired:
            code, err = -1, [f"timed out after {a.timeout:.0f} s"]
        dt = time.time() - t0
        figs = sorted(str(f) for f in where.rglob(f"*.{a.format}")
                      if f.stat().st_mtime >= t0 - 1) if where.exists() else []
        report[name] = {"status": "ok" if code == 0 else "failed", "exit_code": code,
                        "seconds": round(dt, 2), "out": str(where), "figures": figs,
                        "error": err}
        failed += code != 0
        print(f"{name:22s} {'ok' if code == 0 else 'FAILED'} in {dt:6.1f} s, "
              f"{len(figs)} figures" + (f"  ({err[0]})" if err else ""), flush=True)
    (a.out / "report_figures.json").write_text(json.dumps(report, indent=1))
    print(f"wrote {a.out / 'report_figures.json'}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
