"""``python -m softclose.simulation.kernel [--write]``: print, or write next to ``_kernel.c``,
the kernel's layout header generated from the element registry
(:func:`softclose.simulation.kernel.layout.header`)."""

import argparse
from pathlib import Path

from .layout import HEADER_NAME, header


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m softclose.simulation.kernel",
                                description="print (or --write) the kernel's layout header")
    p.add_argument("--write", action="store_true", help=f"write {HEADER_NAME} next to _kernel.c")
    a = p.parse_args(argv)
    text = header()
    if a.write:
        Path(__file__).with_name(HEADER_NAME).write_text(text)
    else:
        print(text, end="")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
