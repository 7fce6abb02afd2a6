"""``select``: rank the catalog's springs (x dampers) by how the lid closes with them.

The procedure, step by step:

1. **Pairs.** Every spring x every damper; without a damper catalog, every spring with the
   config's dashpot, its coefficient c chosen per spring (:func:`choose_c`: the kernel at
   the corners of the box over a geometric grid of ``optimise.damper_c``'s bounds, then a
   finer grid around the best), made to the ``[tolerance]`` spread of ``design.damper_c``.
2. **Screen** (:mod:`.screen`): each pair at the corners of its own tolerance box, at its
   nominal point and on the same Monte Carlo samples, in the C kernel, chunk by chunk;
   corners first (:mod:`.corners`): the samples only where the corners leave it open. A
   spring whose coil the catalog gives is checked at its working lengths (:mod:`.coil`:
   static stress, fatigue, buckling); one that fails makes its pair infeasible.
3. **Rank**: meets every constraint at every corner first, then yield (the share of samples
   that meet every constraint), then worst-case J (over corners and samples), lower first.
4. **Re-solve** (no damper catalog): the best pairs' c by the robust NLP with the spring
   fixed (:mod:`.nlp`); the pair keeps the NLP's c when it then ranks better.
5. **Verify** (:mod:`.verify`): the best ``verify`` pairs at every corner by the adaptive
   reference. Where the reference's verdict differs from the kernel's, the reference's
   stands, the pairs are ranked again and the new best ones verified in turn.
"""

from __future__ import annotations

import math
import time

import numpy as np

from ..config import Config, check_batch
from ..errors import ConfigError
from ..present.progress import Progress
from .files import Catalog, DamperEntry, as_catalog, read_dampers, read_springs
from .result import SelectResult, pair_entry
from .screen import (RANGE, PairBox, pair_box, range_texts, reason_text, run_pairs,
                     summarise)
from .corners import screen_rows
from .nlp import NLP_SAMPLES, solve_c
from .mounting import parts_fix, place_pair, placement_keys
from . import coil, verify
from ..robust.scenarios import at_reference
from .screen import limiting_temperature
from ..problem import condition_parts

#: rows of the whole box per chunk of pairs (a chunk is the unit of progress and of Ctrl-C;
#: corners first, most of its pairs' samples are not run)
CHUNK_ROWS = 160_000
#: default Monte Carlo samples per pair
SAMPLES = 256
#: default number of best pairs verified by the reference at every corner
VERIFY = 10
#: points of the coarse and of the fine grid of c (continuous damper)
C_GRID, C_FINE = 24, 12


def chunks(n: int, size: int):
    for a in range(0, n, size):
        yield a, min(n, a + size)


def choose_c(cfg: Config, box: PairBox, springs, progress: bool = False) -> list:
    """Per spring, the config's dashpot with c chosen over ``optimise.damper_c``'s bounds:
    the most corners of the box feasible, then the smallest worst corner J (the kernel on a
    geometric grid, then on a finer one between the best point's neighbours)."""
    lo, hi = cfg.optimise.damper_c
    lo = max(lo, hi * 1e-3)
    tol = next((s.half_width(1.0) for s in cfg.tolerance.spreads
                if s.key == "design.damper_c" and s.relative), 0.0)
    corners = box.head()

    def best_of(grids):
        pairs = [(s, DamperEntry("c", "dashpot", float(c), None, tol))
                 for s, g in zip(springs, grids) for c in g]
        cols = run_pairs(cfg, corners, pairs)
        sm = summarise(corners, cols, len(pairs))
        m = len(grids[0])
        count = sm["corner_count"].reshape(-1, m)
        J = np.asarray(sm["worst_objective"], float).reshape(-1, m)
        score = np.where(np.isfinite(J), J, 1e300)
        idx = [int(np.lexsort((score[i], -count[i]))[0]) for i in range(len(grids))]
        return idx
    coarse = np.geomspace(lo, hi, C_GRID)
    bar = Progress(2, "choosing c", enabled=progress, unit="")
    idx = best_of([coarse] * len(springs))
    bar.update(1)
    fine = []
    for i in idx:
        a, b = coarse[max(i - 1, 0)], coarse[min(i + 1, C_GRID - 1)]
        fine.append(np.unique(np.r_[np.geomspace(a, b, C_FINE), coarse[i]]))
    m = max(len(f) for f in fine)
    fine = [np.r_[f, np.full(m - len(f), f[-1])] for f in fine]
    idx = best_of(fine)
    bar.update(2, force=True)
    bar.close()
    return [DamperEntry(None, "dashpot", float(f[i]), None, tol) for f, i in zip(fine, idx)]


def _rank_key(e: dict):
    J = e["worst_objective"]
    return (not e["feasible"], -(e["yield"] if e["yield"] is not None else -1.0),
            J if J is not None else math.inf, e["spring"], e["damper"] or "")


def select(cfg: Config, springs, dampers=None, *, samples: int = SAMPLES, seed: int = 0,
           verify: int = VERIFY, progress: bool = False, mapper=None,
           nlp: bool = True, every_sample: bool = False) -> SelectResult:
    """Rank every spring (x damper) of the catalogs by how the lid closes with it, each
    over its own tolerance box and ``[tolerance]`` for the other keys (module docstring).

    ``springs``, ``dampers``: catalog files (:mod:`softclose.catalog.files`), read
    :class:`Catalog` objects or lists of entries; ``dampers=None`` chooses the dashpot's c
    per spring. ``samples``: Monte Carlo samples per pair; ``verify``: how many of the best
    pairs the adaptive reference checks at every corner; ``nlp`` (without dampers): those
    pairs' c re-solved first by the robust NLP (:mod:`.nlp`; kept when it ranks better than
    the grid's). ``mapper``: run chunks elsewhere
    (``softclose.catalog.distributed``). ``every_sample``: every pair's samples run (by
    default corners first, :mod:`.corners`: the samples of the pairs the corners leave
    open; the same ranking where the constraints are monotone over the boxes). Ctrl-C
    between chunks keeps the pairs screened
    (``result.interrupted``). Returns a :class:`SelectResult`; never raises for a part
    that fails (it is ranked with the reason).
    """
    t0 = time.perf_counter()
    cfg = at_reference(cfg)         # (every row at its sign-off temperature: screen.py)
    if isinstance(samples, bool) or not isinstance(samples, (int, np.integer)) \
            or not 0 <= samples <= 100_000:
        raise ConfigError(f"samples: expected a whole number 0..100000, got {samples!r}")
    if isinstance(verify, bool) or not isinstance(verify, (int, np.integer)) or verify < 0:
        raise ConfigError(f"verify: expected a whole number >= 0, got {verify!r}")
    cfg, fixed = parts_fix(cfg)       # (a config's free part values: the parts')
    placed = placement_keys(cfg)      # (refuses free keys other than attachment points)
    spr: Catalog = as_catalog(springs, read_springs)
    dmp: Catalog | None = as_catalog(dampers, read_dampers)
    box = pair_box(cfg, samples, seed)
    n_pairs = len(spr) * (len(dmp) if dmp is not None else 1)
    check_batch(cfg, n_pairs * box.points + (0 if dmp is not None else
                                             len(spr) * (C_GRID + C_FINE + 1) * box.corners),
                "select: the pairs' strokes")
    warnings = fixed + list(spr.warnings) + (list(dmp.warnings) if dmp is not None else [])
    times = {}
    interrupted = False
    found: dict = {}            # pair index -> its ranking entry
    kernel: dict = {}           # pair index -> (corner verdicts, corner J)
    pairs: list = []
    try:
        if dmp is None:
            tc = time.perf_counter()
            dampers_of = choose_c(cfg, box, spr.parts, progress)
            pairs = list(zip(spr.parts, dampers_of))
            times["choose_c"] = time.perf_counter() - tc
        else:
            pairs = [(s, d) for s in spr.parts for d in dmp.parts]
        ts = time.perf_counter()
        size = max(1, CHUNK_ROWS // box.points)
        bar = Progress(len(pairs), "select", enabled=progress, unit="pairs")
        try:
            tasks = ((a, pairs[a:b]) for a, b in chunks(len(pairs), size))
            results = mapper(cfg, box, tasks, every_sample) if mapper is not None else \
                (screen_chunk(cfg, box, a, chunk, every_sample) for a, chunk in tasks)
            for a, rows in results:       # (chunks may arrive out of order)
                for i, (entry, corners) in enumerate(rows):
                    found[a + i] = entry
                    kernel[a + i] = corners
                bar.update(len(found))
        finally:
            bar.update(len(found), force=True)
            bar.close()
        times["screen"] = time.perf_counter() - ts
    except KeyboardInterrupt:
        interrupted = True
    entries = found
    order = sorted(entries, key=lambda i: _rank_key(entries[i]))
    if dmp is None and nlp and not interrupted and verify:
        tn = time.perf_counter()
        try:
            order = _resolve_c(cfg, box, pairs, entries, kernel, order, verify,
                               every_sample)
        except KeyboardInterrupt:
            interrupted = True
        times["nlp"] = time.perf_counter() - tn
    cfgs: dict = {}             # pair index -> the config at the pair's own points
    if placed and not interrupted and verify:
        tp = time.perf_counter()
        try:
            order = _place_best(cfg, box, pairs, entries, kernel, order, verify, cfgs,
                                samples, progress, every_sample)
        except KeyboardInterrupt:
            interrupted = True
        times["placement"] = time.perf_counter() - tp
    tv = time.perf_counter()
    checked: dict = {}
    if not interrupted and verify:
        try:
            order = _verify_best(cfg, box, pairs, entries, kernel, order, verify, checked,
                                 cfgs)
        except KeyboardInterrupt:
            interrupted = True
    times["verify"] = time.perf_counter() - tv
    ranking = tuple(entries[i] for i in order)
    seconds = time.perf_counter() - t0
    times["total"] = seconds
    best = ranking[0] if ranking else None
    if interrupted:
        msg = (f"interrupted: {len(entries)} of {len(pairs) or '?'} pairs screened"
               + ("" if checked else ", none verified by the reference"))
    elif best is None:
        msg = "no pair was screened"
    elif not best["feasible"]:
        msg = ("no pair meets every constraint at every corner of its tolerance box; the "
               f"best, {best['spring']}" + (f" with {best['damper']}" if best['damper'] else "")
               + f", fails: {best['reason']}")
    elif best.get("verified") is False:
        msg = ("the kernel's verdict on the best pair differs from the reference's at "
               f"{', '.join(best['reference']['differ'])}; the reference's stands (every "
               "corner meets every constraint)")
    else:
        msg = ""
    success = not interrupted and best is not None and bool(best["feasible"])
    return SelectResult(
        success=success, message=msg, ranking=ranking, evaluated=len(entries),
        pairs=len(pairs), seconds=seconds, interrupted=interrupted,
        warnings=tuple(warnings), samples=samples, seed=seed, corners=box.corners,
        box=_box_json(box), continuous=dmp is None, verified_count=len(checked),
        screening=_screening(entries, box, every_sample), times=times, springs=spr.path,
        dampers=None if dmp is None else dmp.path)


def _verify_best(cfg, box, pairs, entries, kernel, order, n, checked: dict,
                 cfgs: dict | None = None) -> list:
    """The adaptive reference at every corner of the best ``n`` pairs (``checked`` gets each
    pair's :func:`.verify.verify_pair`; ``cfgs``: a pair's own config, at its own attachment
    points); where its verdict differs from the kernel's, the reference's stands and the
    pairs are ranked again, until the best ``n`` are all checked (at most 5 rounds). Returns
    the new order."""
    cfgs = cfgs or {}
    for _ in range(5):
        todo = [i for i in order[:n] if i not in checked]
        if not todo:
            break
        for i in todo:
            F, J = kernel[i]
            v = verify.verify_pair(cfgs.get(i, cfg), box, *pairs[i], F, J)
            checked[i] = v
            e = entries[i]
            e["verified"] = v["agree"]
            e["reference"] = {k: v[k] for k in ("feasible", "agree", "differ",
                                                "worst_objective", "reason", "seconds")}
            e["reference"]["corners"] = [
                {k: c[k] for k in ("label", "ok", "reason", "objective", "kernel_feasible",
                                   "kernel_objective")} for c in v["corners"]]
            if not v["agree"]:                 # the reference's verdict stands
                e["kernel_reason"] = e["reason"]
                e["feasible"] = v["feasible"]
                e["reason"] = "" if v["feasible"] else f"the reference: {v['reason']}"
                coil.apply(e, e.get("spring_checks"))     # (the spring's checks stand too)
        order = sorted(entries, key=lambda i: _rank_key(entries[i]))
    return order


def _place_best(cfg, box, pairs, entries, kernel, order, n, cfgs: dict, samples: int,
                progress: bool, every_sample: bool = False) -> list:
    """The best ``n`` pairs' attachment points re-optimised (:mod:`.place`); a pair screened
    again at its points keeps them when it ranks better there (``cfgs`` gets its config).
    Returns the new order."""
    best = order[:n]
    bar = Progress(len(best), "placing", enabled=progress, unit="pairs")
    with bar:
        for j, i in enumerate(best):
            s, d = pairs[i]
            info = place_pair(cfg, s, d, max(samples, NLP_SAMPLES))
            kept = "config"
            if info["values"]:
                c_i = cfg.update(info["values"])
                _, rows = screen_chunk(c_i, box, i, [(s, d)], every_sample)
                e2, corners2 = rows[0]
                if _rank_key(e2) < _rank_key(entries[i]):
                    e2["design"].update({k.removeprefix("geometry."): v
                                         for k, v in info["values"].items()})
                    entries[i], kernel[i], cfgs[i] = e2, corners2, c_i
                    kept = "placed"
            info["kept"] = kept
            entries[i]["placement"] = info
            bar.update(j + 1, f"{s.part}: {kept}", force=True)
    return sorted(entries, key=lambda i: _rank_key(entries[i]))


def _resolve_c(cfg, box, pairs, entries, kernel, order, n, every_sample: bool = False
               ) -> list:
    """The best ``n`` springs' c re-solved by the robust NLP (:mod:`.nlp`); the pair is
    screened again with the NLP's c and keeps whichever c ranks better. Returns the new
    order."""
    from dataclasses import replace
    for i in order[:n]:
        s, d = pairs[i]
        info = solve_c(cfg, s, d)
        info["c_grid"] = d.c
        kept = "grid"
        if info["c"] is not None and info["c"] != d.c:
            d2 = replace(d, c=info["c"])
            _, rows = screen_chunk(cfg, box, i, [(s, d2)], every_sample)
            e2, corners2 = rows[0]
            if _rank_key(e2) < _rank_key(entries[i]):
                entries[i], kernel[i], pairs[i] = e2, corners2, (s, d2)
                kept = "nlp"
        info["kept"] = kept
        entries[i]["nlp"] = info
    return sorted(entries, key=lambda i: _rank_key(entries[i]))


def screen_chunk(cfg: Config, box: PairBox, a: int, chunk: list,
                 every_sample: bool = False) -> tuple[int, list]:
    """Screen one chunk of pairs, corners first (:mod:`.corners`; ``every_sample``: every
    pair's samples run): (its first index, [(ranking entry, (corner verdicts, corner J))
    per pair]); an entry's ``sampled`` says whether its corners left it open (its samples
    run), ``samples_run`` how many were run."""
    cols, sampled, runs = screen_rows(cfg, box, chunk, every_sample)
    sm = summarise(box, cols, len(chunk))
    n, nc = box.points, box.corners
    rng = [p for p, r in enumerate(sm["reason"]) if r == RANGE]
    where = dict(zip(rng, range_texts(cfg, box, [(*chunk[p], sm["fail_row"][p])
                                                  for p in rng]))) if rng else {}
    out = []
    lengths = coil.working_lengths(cfg) if any(s.coil is not None for s, _ in chunk) \
        else None
    for p, (s, d) in enumerate(chunk):
        reason = sm["reason"][p]
        text = "" if not reason else reason_text(box, cols, p, sm["fail_row"][p], reason,
                                                 s, d, where.get(p, ""))
        e = pair_entry(s, d, bool(sm["corners_ok"][p]), float(sm["yield"][p]),
                       float(sm["worst_objective"][p]), text,
                       int(sm["corner_count"][p]), nc,
                       {k: float(v[p]) for k, v in sm["nominal"].items()})
        e["sampled"], e["samples_run"] = bool(sampled[p]), int(runs[p])
        coil.apply(e, coil.spring_checks(cfg, s, lengths))
        if len(box.temperatures) > 1:      # (each sign-off temperature, in each state)
            T, state = condition_parts(limiting_temperature(box, cols, cfg.optimise, p,
                                                            sm["fail_row"][p]))
            e["limiting_temperature_c"] = T
            if any(condition_parts(c)[1] for c in box.temperatures):
                e["limiting_state"] = state or "new"
        F = cols["feasible"][p * n:p * n + nc].copy()
        J = np.asarray(cols["objective"][p * n:p * n + nc], float).copy()
        out.append((e, (F, J)))
    return a, out


def _screening(entries: dict, box: PairBox, every_sample: bool) -> dict:
    """How the pairs were screened: corners first or every sample; how many pairs their
    corners decided (met at every one, failed at every one) and how many were sampled."""
    met = sum(1 for e in entries.values() if not e["sampled"] and e["corners_feasible"])
    decided = sum(1 for e in entries.values() if not e["sampled"])
    rows = sum(e["samples_run"] for e in entries.values())
    return {"method": "every sample" if every_sample or not box.samples else "corners first",
            "decided_by_corners": decided, "met_every_corner": met,
            "failed_every_corner": decided - met, "sampled": len(entries) - decided,
            "sample_rows_run": rows,
            "sample_rows_every": len(entries) * (box.points - box.corners - 1)}


def _box_json(box: PairBox) -> dict:
    other = {k: {"spread": s, "relative": r} for k, s, r in
             zip(box.other.keys, box.other.spreads, box.other.relative)}
    return {"parts": "each part's own: rate ± rate_tolerance (a gas strut: F1 ± "
                     "force_tolerance), free length ± free_length_tolerance, c ± c_tolerance",
            "other": other, "distribution": box.other.distribution}
