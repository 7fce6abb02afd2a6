"""``softclose select``: rank the springs (x dampers) of catalog files.

    softclose select --springs FILE [--dampers FILE] [--samples N] [--seed S] [--verify N]
                     [--free KEY=LO:HI ...] [--dask ADDRESS|local:N] [--json] [--out DIR]

``--out DIR`` writes ``select.csv`` (every pair, best first), ``select.json``, the best
pairs' configs (``pairs/01_<spring>_<damper>.toml``, ...) and the figure
``select.png`` (yield against worst-case J). Exit 0 when the best pair meets every
constraint at every corner of its tolerance box and the reference agrees; 3 when no pair
does (the ranking is still printed and written); 2 for a bad file or option; 130 after
Ctrl-C (the pairs screened so far are ranked and written).
"""

from __future__ import annotations

import argparse
from .common import (Outcome, add_common, add_out, figures, interactive, prepare_out, saved,
                     wrote)

DESCRIPTION = """\
Rank the springs one can buy (extension, compression, gas strut) -- with every damper of
--dampers, or with the config's dashpot whose c is chosen per spring when no damper file
is given -- by how the lid closes with them: each pair over its own tolerance box (the
spring's rate -- a gas strut's force F1 -- and free length, the damper's c, as the catalog
gives them; [tolerance] for
the other keys, e.g. the lid's mass), in the C kernel at every corner and on Monte Carlo
samples. Rank: meets every constraint at every corner first, then yield, then worst-case
J. The best --verify pairs are re-simulated at every corner by the adaptive reference.

Spring columns: part, kind (extension | compression | gas_strut), rate_N_per_m,
free_length_m, preload_N, min_length_m, max_length_m (empty: no limit), rate_tolerance
(relative), optional free_length_tolerance_m (default: the standard grade, ±0.9 mm up to
63 mm, ±1.3 mm up to 100 mm, ±1.5 % beyond); the lengths and rate may be given in mm and
N/mm instead (free_length_mm, rate_N_per_mm, ...). Damper columns: part, kind (dashpot |
rotary), c (N s/m, or N m s/rad for a rotary damper), pivot (rotary: O, B, A, C or lid),
c_tolerance (relative), optional temperature_coeff_per_K (the damper's beta, 1/K: its
design.damper_temperature_coeff, c(T) = c exp(beta (T - T_ref)); empty: the config's).

A gas_strut row is a gas strut (the isothermal gas law, SPEC §12): free_length its extended
length, preload its force F1 at full extension (> 0), min_length its compressed length
(required: the stroke is free_length - min_length); optional columns progression (K = F at
full compression / F1; empty: 1 + rate x stroke / F1 from the rate), friction_band_N (the
datasheet's F3 - F1; the strut's friction is half of it, design.strut_friction) and
force_tolerance (relative spread of F1, default 0.1; a strut's rate_tolerance does not
apply). Rows that cannot be used are reported by line and column and left out.

Optional coil columns of a compression or extension spring: wire_d_m (wire diameter d),
coil_d_m (mean coil diameter D) -- or wire_d_mm, coil_d_mm -- active_coils (n) and material
(an EN 10270 wire as spring.material names it; empty: EN10270-1-SH); all of d, D, n or none,
the coil's rate G d^4/(8 D^3 n) the row's within its rate_tolerance. Such a spring is checked
at its working lengths as `softclose spring` checks one (EN 13906-1; an extension spring's
body by EN 13906-2, its hooks not covered), at the free length's end of its tolerance that
deflects it more, for spring.cycles and spring.seating: a spring that would be overstressed,
fail fatigue or buckle makes its pair infeasible, the reason naming the check and its margin
(each row's spring_checks in --json). Springs without a coil are ranked as before. An illustrative catalog (not real parts):
`python -m softclose.catalog.illustrative DIR`. The robust NLP that re-solves the best
springs' c (no --dampers) is one NLP for every spring, evaluated by CasADi's virtual machine
unless `softclose prepare --select FILE` compiled it (~3x faster solves, the same numbers)."""


def register(sub) -> None:
    p = sub.add_parser("select", help="rank catalog springs and dampers over their tolerances",
                       description=DESCRIPTION,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    add_common(p)
    p.add_argument("--springs", metavar="FILE", required=True,
                   help="spring catalog (CSV: part, kind, rate_N_per_m, free_length_m, "
                        "preload_N, min_length_m, max_length_m, rate_tolerance"
                        "[, free_length_tolerance_m][, wire_d_m, coil_d_m, active_coils"
                        "[, material]][, progression, friction_band_N, force_tolerance]: a "
                        "spring whose coil is given is checked for static stress, fatigue "
                        "and buckling at its working lengths; a gas_strut row is a gas "
                        "strut, F1 its preload, its stroke free - min length)")
    p.add_argument("--dampers", metavar="FILE",
                   help="damper catalog (CSV: part, kind, c, pivot, c_tolerance"
                        "[, temperature_coeff_per_K]); without it the dashpot's c is chosen "
                        "per spring within optimise.damper_c")
    add_out(p, what="write select.csv, select.json, select.png and the best pairs' configs "
                    "(pairs/*.toml) to this folder")
    p.add_argument("--samples", type=int, metavar="N", default=256,
                   help="Monte Carlo samples per pair (default 256)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument("--verify", type=int, metavar="N", default=10,
                   help="how many of the best pairs the adaptive reference checks at every "
                        "corner (default 10)")
    p.add_argument("--no-nlp", dest="nlp", action="store_false",
                   help="without --dampers: keep the c of the kernel's grid (by default the "
                        "--verify best springs' c is re-solved by the robust NLP)")
    p.add_argument("--dask", metavar="ADDRESS|local:N",
                   help="screen the pairs on a Dask cluster (scheduler address or local:N)")
    p.add_argument("--free", action="append", default=[], metavar="KEY=LO:HI",
                   help="an attachment point free within [LO, HI] (repeatable; "
                        "geometry.spring_anchor[i], lid_e[i], dashpot_anchor[i], "
                        "dashpot_lid[i]): the --verify best pairs' points re-optimised per "
                        "part by the robust co-design (~15 s a pair), each pair judged and "
                        "verified at its own points")
    p.set_defaults(run=run)


def _check(args) -> None:
    from ..errors import ConfigError
    if not 0 <= args.samples <= 100_000:
        raise ConfigError(f"--samples {args.samples}: expected 0..100000")
    if args.seed < 0:
        raise ConfigError(f"--seed {args.seed}: must be non-negative")
    if args.verify < 0:
        raise ConfigError(f"--verify {args.verify}: must be non-negative")


def run(cfg, args) -> Outcome:
    from ..catalog import read_dampers, read_springs, select
    _check(args)
    out = prepare_out(args.out, ["select.csv", "select.json", *figures("select"), "pairs/"])
    springs = read_springs(args.springs)
    dampers = read_dampers(args.dampers) if args.dampers else None
    if args.dask:
        from ..catalog.distributed import mapper
        with mapper(args.dask) as m:
            res = select(cfg, springs, dampers, samples=args.samples, seed=args.seed,
                         verify=args.verify, progress=interactive(args), mapper=m,
                         nlp=args.nlp)
    else:
        res = select(cfg, springs, dampers, samples=args.samples, seed=args.seed,
                     verify=args.verify, progress=interactive(args), nlp=args.nlp)
    payload = res.to_json()
    files = saved(res, out, payload, cfg)
    code = 130 if res.interrupted else (0 if res.success else 3)
    return Outcome(payload, res.text() + wrote(files), code, tuple(files),
                   error=None if res.success or res.interrupted else res.message)
