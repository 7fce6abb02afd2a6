"""A catalog selection written to a folder (what ``softclose select --out`` writes): the
ranking as CSV and JSON, its figure and the best pairs' configs."""

from __future__ import annotations

import json
from pathlib import Path

from ..files import write_text, write_with


def save_selection(res, folder, cfg, figure_format: str = "png",
                   figure_style: str | None = None) -> list[Path]:
    """``select.csv``, ``select.json``, ``select.png`` (a finished ranking) and the best pairs'
    configs (``pairs/``, made from ``cfg``, the config the catalogs were screened for) in
    ``folder``; the paths."""
    from ..jsonio import jsonable
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
    from .result import pair_config
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


__all__ = ["save_selection", "save_pair_configs", "PAIR_CONFIGS"]
