"""``softclose spring [--out DIR]``: the design's compression or extension spring made to order
(SPEC §14)."""

from __future__ import annotations

import argparse

from .common import Outcome, add_common, add_out, figures, prepare_out, saved, wrote

DESCRIPTION = """\
The design's compression spring (design.spring_kind = "compression", EN 13906-1) or extension
spring ("extension", EN 13906-2: its body) as a part a spring maker can coil: wire, mean coil
diameter and active coils, checked for the lengths it works at as the lid turns between
stroke.theta_closed_deg and stroke.theta0_deg.

With spring.wire_d, spring.coil_d and spring.active_coils all given, that spring is checked;
otherwise one is designed: preferred EN 10270 wire diameters (or the spring.wire_d given),
mean coil diameters on a 0.1 mm grid within spring.max_outer_d / spring.min_inner_d (or the
spring.coil_d given), the active coils rounded to a quarter coil for design.spring_k, every
check met for spring.cycles strokes, the lightest first.

Checks: the rate within the quarter-coil rounding; the shortest working length keeps the
minimum coil gaps S_a; the stress at solid length tau_c <= 0.56 R_m; the stroke stress under
the wire's Goodman line at spring.cycles; buckling (seating spring.seating); the space; the
wire's temperatures. The EN 15800 tolerances are those of spring.grade.

An extension spring (free length design.spring_rest_length with the body closed, initial
tension design.spring_preload): the rate; the closed body (n + 1) d within the free length,
leaving at least 0.8 D_i for each hook; the initial tension stress within the preferred range
at its index; the stress at the largest working force tau_2 <= 0.45 R_m (EN 13906-2); the
body's stroke stress under the unpeened wire's Goodman line; the space; the temperatures.
It does not buckle. Its hooks are not covered (EN 13906-2 §11 and Annex A: ask the maker).

Exit 3 when the spring checked fails a check, or no spring meets them all (the nearest miss
is shown). With --out: spring.json, the checks (spring_checks.csv) and the candidates
(spring_candidates.csv), and spring.png: the force and the stress over the spring's length
with the working range and the limits."""


def register(sub) -> None:
    p = sub.add_parser("spring", help="the design's compression or extension spring made to "
                                      "order (EN 13906-1/-2 checks, EN 15800 tolerances)",
                       description=DESCRIPTION,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    add_common(p)
    add_out(p, what="also write spring.json, the checks and candidates as CSV and the "
                    "figure of the spring's force and stress over its length to this folder")
    p.set_defaults(run=run)


def run(cfg, args) -> Outcome:
    from ..optimiser.spring_order import order_spring
    out = prepare_out(args.out, ["spring.json", "spring_checks.csv", "spring_candidates.csv",
                                 *figures("spring")])
    res = order_spring(cfg)
    payload = res.to_json()
    files = saved(res, out, payload)
    text = res.text() + wrote(files)
    if res.success:
        return Outcome(payload, text, 0, tuple(files))
    payload["exit_code"] = 3
    return Outcome(payload, text, 3, tuple(files), error=res.message)
