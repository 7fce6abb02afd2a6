"""The key tables of docs/model.md, generated from the key records.

``python -m softclose.config.docs`` prints them; ``--write docs/model.md`` replaces the block
between the markers ``<!-- keys:begin -->`` and ``<!-- keys:end -->`` with them, and a test
(tests/test_config_docs.py) fails when the file and the records differ.
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

from ..model.keys import Key
from .schema import DEFAULT_SPREADS, KEYS, SECTIONS, TOLERANCE_KEYS

BEGIN, END = "<!-- keys:begin -->", "<!-- keys:end -->"


def _num(x) -> str:
    """A number with every digit it has (the shortest repr), without a trailing .0."""
    if isinstance(x, bool):
        return "true" if x else "false"
    if isinstance(x, int):
        return str(x)
    if x and abs(x) >= 1e6 and float(x).is_integer():       # 1e7, not 10000000
        m, e = f"{x:e}".split("e")
        return f"{float(m):g}e{int(e)}"
    text = repr(float(x))
    return text[:-2] if text.endswith(".0") else text


def default_text(k: Key) -> str:
    """The default as the tables show it: a number, a list, a quoted word, or its rule."""
    if k.default is None:
        return k.derived or "none"
    if isinstance(k.default, str):
        return f'`"{k.default}"`'
    if isinstance(k.default, tuple):
        return "[" + ", ".join(f'"{x}"' if isinstance(x, str) else _num(x)
                               for x in k.default) + "]"
    return _num(k.default)


def range_text(k: Key) -> str:
    """The admissible range (both ends included), its unit, and the key's note."""
    if k.lo is None:
        text = ", ".join(f"`{c}`" for c in k.choices) if k.choices else "—"
    else:
        text = f"{_num(k.lo)} .. {_num(k.hi)}"
    return text + (f"; {k.note}" if k.note else "")


def _row(k: Key) -> str:
    unit = k.unit or "—"
    spread = f" (default tolerance ±{k.spread:.0%})" if k.spread else ""
    return f"| `{k.name}` | {default_text(k)} | {unit} | {range_text(k)} | {k.doc}{spread} |"


def section_table(section: str) -> str:
    rows = [f"### `[{section}]`", "", "| key | default | unit | admissible | meaning |",
            "|---|---|---|---|---|"]
    rows += [_row(k) for k in KEYS if k.section == section]
    return "\n".join(rows)


def tolerance_table() -> str:
    rows = ["### `[tolerance]`", "",
            "| key | default | unit | admissible | meaning |", "|---|---|---|---|---|"]
    for full, spread in DEFAULT_SPREADS.items():
        rows.append(f'| `"{full}"` | {spread:g} | relative | ≥ 0 | ±{spread:.0%} '
                    f"manufacturing spread of `{full}` |")
    rows.append("| any other numeric key | — | relative, or `{absolute = x}` | ≥ 0 | its "
                "spread |")
    rows += [_row(k) for k in TOLERANCE_KEYS]
    return "\n".join(rows)


def tables() -> str:
    """Every key table, in the order of the sections, then [tolerance]."""
    return "\n\n".join([section_table(s) for s in SECTIONS] + [tolerance_table()])


def replace_block(text: str) -> str:
    """``text`` with the block between the markers replaced by :func:`tables`."""
    pattern = re.compile(re.escape(BEGIN) + r".*?" + re.escape(END), re.S)
    if not pattern.search(text):
        raise ValueError(f"no {BEGIN} ... {END} block")
    return pattern.sub(lambda _: f"{BEGIN}\n{tables()}\n{END}", text)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m softclose.config.docs",
                                 description="print the config key tables, or write them into "
                                             "a Markdown file between its key markers")
    ap.add_argument("--write", metavar="FILE", type=Path)
    args = ap.parse_args(argv)
    if args.write is None:
        print(tables())
        return 0
    args.write.write_text(replace_block(args.write.read_text()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
