"""``softclose report [--out DIR] [--format html|pdf|both] [--paper a4|letter]``: the sign-off
report of a design."""

from __future__ import annotations

import argparse

from .common import Outcome, add_common, add_out, prepare_out, wrote

DESCRIPTION = """\
The sign-off report of the config's design (e.g. the design.toml of `softclose optimise --out
D`, a robust design, a calibrated config; a four-bar or a hinge lid): one self-contained HTML
page (figures inline, nothing fetched: it opens offline) and a PDF of the same sections to
print (A4 or, with --paper letter, US Letter pages: a title block with the verdict, running
header and footer, tables and vector figures).

At the top, the verdict in one line. Then: the lid and the design (a linkage drawing); the
parts to buy (the spring, with the EN 13906-1 checks of a compression spring, and the
dampers with their coefficients at each operating temperature); the metrics of the stroke
verified by the adaptive reference, with the fixed-step simulator's accuracy; the stroke and
the hand force with its zones at each temperature of operating.temperatures_c; the sign-off
matrix: every constraint of [optimise] at the nominal lid, at each temperature and at the
worst corner of the [tolerance] box (value, limit, margin, pass); the yield with its 95 %
interval per temperature; what limits the design (the optimiser's active constraints with
dJ from the optimise.json or robust.json next to the config file, when its design is the
config's; and the smallest margin); the config
and the software version.

Exit 3 when the design fails a requirement (the report is still written and says which)."""


def register(sub) -> None:
    p = sub.add_parser("report", help="the sign-off report of a design: one self-contained "
                                      "HTML page and a PDF",
                       description=DESCRIPTION,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    add_common(p)
    add_out(p, what="folder for report.html and report.pdf (default: the current folder)",
            figures=False)
    p.add_argument("--format", choices=("html", "pdf", "both"), default="both",
                   help="which files to write (default both)")
    p.add_argument("--samples", metavar="N", type=int, default=None,
                   help="Monte Carlo samples of each yield (default tolerance.samples)")
    p.add_argument("--paper", choices=("a4", "letter"), default="a4",
                   help="the PDF's paper size: A4 or US Letter (default a4)")
    p.set_defaults(run=run)


def run(cfg, args) -> Outcome:
    import time

    from ..errors import ConfigError
    from ..signoff import pdf_unavailable, report
    if args.samples is not None and args.samples < 1:
        raise ConfigError(f"--samples {args.samples}: expected a whole number >= 1")
    out = prepare_out(args.out if args.out is not None else ".",
                      [f"report.{k}" for k in (("html", "pdf") if args.format == "both"
                                                else (args.format,))])
    from ..signoff.build import optimiser_json
    res = report(cfg, optimiser=optimiser_json(args.config, cfg), samples=args.samples)
    payload = res.to_json()
    t0 = time.perf_counter()
    kinds = ("html", "pdf") if args.format == "both" else (args.format,)
    skipped = pdf_unavailable() if "pdf" in kinds else None
    if skipped:                 # the HTML instead: the report is written all the same
        kinds = ("html",)
    files = res.save_all(out, formats=kinds, paper=args.paper, name=args.config)
    payload["files"] = [str(f) for f in files]
    payload["timings"]["files"] = time.perf_counter() - t0
    text = res.text() + wrote(files)
    if skipped:
        payload["skipped"] = {"pdf": skipped}
        text += f"\n  report.pdf skipped: {skipped}"
    if res.success:
        return Outcome(payload, text, 0, tuple(files))
    payload["exit_code"] = 3
    return Outcome(payload, text, 3, tuple(files), error=res.message)
