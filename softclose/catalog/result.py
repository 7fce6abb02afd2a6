"""The result of ``select``: the ranked pairs, each with its verdicts and why it fails, and
the files ``select --out`` writes of it."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

from ..present.display import Display, Displayed, Table, num, percent
from ..files import write_text, write_with
from ..jsonio import jsonable



def pair_entry(spring, damper, feasible: bool, yld: float, worst: float, reason: str,
               corners_ok: int, corners: int, nominal: dict) -> dict:
    """One ranked pair: SPEC §10's keys, then why it fails (``reason``, "" if it does not),
    how many corners meet every constraint, the nominal point's metrics, the parts;
    ``spring_checks`` (None: the catalog gives no coil) the coil spring's checks at its
    working lengths (:func:`softclose.catalog.coil.spring_checks`)."""
    design = {**spring.design(),    # (a gas strut's compressed length: its stroke's end)
              "spring_min_length": None if spring.is_strut else spring.min_length,
              "spring_max_length": spring.max_length}
    design.update({"damper_c": 0.0, "rotary_damper_c": 0.0})
    design.update(damper.design())
    return {"spring": spring.part, "damper": damper.part, "feasible": feasible,
            "yield": yld, "worst_objective": worst if math.isfinite(worst) else None,
            "design": design, "verified": None, "reason": reason,
            "corners_feasible": corners_ok, "corners": corners, "nominal": nominal,
            "spring_part": spring.to_json(), "damper_part": damper.to_json(),
            "reference": None, "spring_checks": None}


def pair_config(cfg, entry: dict):
    """The config of a ranked pair (an entry of :attr:`SelectResult.ranking`) in ``cfg``: its
    parts as the design, their own tolerances as ``[tolerance]`` (the rate's -- a gas
    strut's force tolerance as the spread of ``design.spring_preload`` -- and the damper's
    relative, the free length's absolute): what ``softclose report`` signs off."""
    spring, damper = entry["spring_part"], entry["damper_part"]
    values = {f"design.{k}": v for k, v in entry["design"].items() if v is not None}
    c_key = "design.damper_c" if damper["kind"] == "dashpot" else "design.rotary_damper_c"
    if spring["kind"] == "gas_strut":
        own = {"tolerance.design.spring_preload": spring["force_tolerance"]}
    else:
        own = {"tolerance.design.spring_k": spring["rate_tolerance"]}
    values.update({**own, "tolerance.design.spring_rest_length":
                   {"absolute": spring["free_length_tolerance_m"]},
                   f"tolerance.{c_key}": damper["c_tolerance"]})
    return cfg.update(values)


@dataclass(frozen=True, repr=False)
class SelectResult(Displayed):
    """The ranked pairs (``ranking``, best first: feasible at every corner of its box, then
    yield, then worst-case J) and how they were judged.

    ``success``: the best pair meets every constraint at every corner of its box (by the
    reference, where it was checked); ``verified`` of a pair: the adaptive reference's
    verdict at every corner of its box is the kernel's (None: not checked, outside the best
    ``verify``; False: they differ, and the reference's verdict is the pair's).
    """

    success: bool
    message: str
    ranking: tuple
    evaluated: int
    pairs: int
    seconds: float
    interrupted: bool = False
    warnings: tuple = ()
    samples: int = 0
    seed: int = 0
    corners: int = 0
    box: dict = field(default_factory=dict)
    continuous: bool = False
    verified_count: int = 0
    #: how the pairs were screened (:mod:`softclose.catalog.corners`): ``method``,
    #: ``decided_by_corners`` (``met_every_corner`` + ``failed_every_corner``), ``sampled``
    screening: dict = field(default_factory=dict)
    times: dict = field(default_factory=dict)
    springs: str = ""
    dampers: str | None = None

    @property
    def best(self) -> dict | None:
        return self.ranking[0] if self.ranking else None

    def save(self, folder, cfg, figure_format: str = "png", figure_style: str | None = None
             ) -> list:
        """The ranking in ``folder`` (what ``softclose select --out`` writes): select.csv,
        select.json, its figure and the best pairs' configs made from ``cfg``; the paths."""
        return save_selection(self, folder, cfg, figure_format, figure_style)

    def text(self, top: int = 15) -> str:
        """What ``softclose select`` prints (the ``top`` pairs of the ranking)."""
        from .text import select_text
        return select_text(self, top)

    def to_json(self) -> dict:
        return jsonable({
            "ranking": [dict(e) for e in self.ranking], "evaluated": self.evaluated,
            "seconds": self.seconds, "pairs": self.pairs, "success": self.success,
            "message": self.message, "interrupted": self.interrupted,
            "warnings": list(self.warnings), "samples": self.samples, "seed": self.seed,
            "corners": self.corners, "box": self.box,
            "damper_c_optimised": self.continuous, "verified_pairs": self.verified_count,
            "screening": self.screening, "times": self.times, "springs": self.springs,
            "dampers": self.dampers})

    def to_frame(self):
        """One row per pair, best first: rank, the parts, the verdicts, why it fails,
        ``spring_ok`` (its coil spring's checks met; empty without a coil), the nominal
        metrics and the design values."""
        import pandas as pd
        rows = []
        for r, e in enumerate(self.ranking, 1):
            row = {"rank": r, "spring": e["spring"], "damper": e["damper"],
                   "feasible": e["feasible"], "yield": e["yield"],
                   "worst_objective": e["worst_objective"], "verified": e["verified"],
                   "corners_feasible": e["corners_feasible"], "corners": e["corners"],
                   "reason": e["reason"],
                   "spring_ok": None if e.get("spring_checks") is None
                   else e["spring_checks"]["ok"]}
            row.update({f"nominal_{k}": v for k, v in e["nominal"].items()})
            row.update(e["design"])
            rows.append(row)
        return pd.DataFrame(rows)

    def plot(self):
        """Yield against worst-case J for every pair, the chosen one marked (a Figure)."""
        from ..present.figures.select import plot_select
        return plot_select(self)

    def _display(self) -> Display:
        b = self.best
        facts = [("pairs", f"{self.evaluated} of {self.pairs} screened in "
                           f"{self.seconds:.3g} s")]
        if b is not None:
            with_ = (f" + {b['damper']}" if b["damper"] else
                     f" + c = {b['design']['damper_c']:.4g} N s/m")
            facts.append(("best", f"{b['spring']}{with_}"))
            facts.append(("yield", percent(b["yield"])))
            facts.append(("worst J", num(b["worst_objective"])))
        feas = sum(1 for e in self.ranking if e["feasible"])
        facts.append(("feasible at every corner", f"{feas} pairs"))
        rows = [(i + 1, e["spring"], e["damper"] or "c optimised", num(e["feasible"]),
                 percent(e["yield"]), num(e["worst_objective"]),
                 {None: "—", True: "yes", False: "DIFFERS"}[e["verified"]],
                 e["reason"] or "") for i, e in enumerate(self.ranking)]
        table = Table("ranking (feasible at every corner, then yield, then worst-case J)",
                      ("#", "spring", "damper", "feasible", "yield", "worst J", "verified",
                       "why not"), rows)
        return Display("SelectResult: catalog parts ranked over their tolerance boxes",
                       self.success, self.message, tuple(facts), (table,),
                       tuple(self.warnings[:5]))


def save_selection(res, folder, cfg, figure_format: str = "png",
                   figure_style: str | None = None) -> list[Path]:
    """``select.csv``, ``select.json``, ``select.png`` (a finished ranking) and the best pairs'
    configs (``pairs/``, made from ``cfg``, the config the catalogs were screened for) in
    ``folder``; the paths."""
    from ..present.figures import save
    out = Path(folder)
    files = [write_with(out / "select.csv", lambda p: res.to_frame().to_csv(p, index=False)),
             write_text(out / "select.json",
                        json.dumps(jsonable(res.to_json()), indent=1, allow_nan=False))]
    if res.ranking and not res.interrupted:
        files.append(save(res.plot(), out / f"select.{figure_format}", figure_style))
    return files + save_pair_configs(res, cfg, out)


#: the ranked pairs whose config ``--out`` writes (the best first)
PAIR_CONFIGS = 10


def save_pair_configs(res, cfg, out) -> list:
    """The best pairs' configs, ``pairs/01_<spring>_<damper>.toml`` (softclose report
    --config signs one off)."""
    import re
    from ..config import to_toml
    if not res.ranking:
        return []
    folder = out / "pairs"
    folder.mkdir(exist_ok=True)
    files = []
    for rank, e in enumerate(res.ranking[:PAIR_CONFIGS], 1):
        name = re.sub(r"[^\w.-]+", "-", f"{rank:02d}_{e['spring']}_{e['damper']}")
        path = folder / f"{name}.toml"
        write_text(path, to_toml(pair_config(cfg, e), header=(
            f"softclose select: pair {rank}, {e['spring']} + {e['damper']}: its parts and "
            "their own tolerances")))
        files.append(path)
    return files


