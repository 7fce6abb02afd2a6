"""The kernel's contract with Python: the columns of its design rows and of its output, its
status codes (:class:`softclose.simulation.stroke.StrokeStatus`), and the layout string
(:data:`LAYOUT`) that ``sc_layout()`` of ``_kernel.c`` must return -- the element registry's parameters, the coefficient table's columns,
the pose and range widths -- so that a kernel built from other sources is refused, never read
wrongly."""

from __future__ import annotations

import numpy as np

from ...model import elements
from ...model.dynamics import COEFFS, COORDINATE_COEFFS
from .table import NPOSE, NX, POINT_NAMES, POSE

#: output columns of the kernel, in order
OUT_FIELDS = ("status", "closing_time", "impact_theta_dot", "impact_tip_speed",
              "peak_tip_speed", "min_spring_length", "max_spring_length", "steps",
              "energy_rise", "theta_min", "theta_dot_max", "theta_max",
              "stop_reason", "stop_theta", "stop_time", "engage_time", "engage_theta_dot")
#: the optional point columns after lid_mass (a row's own attachment points, m; NaN: the
#: table's): D, E, F, H of :data:`softclose.simulation.kernel.table.POINT_NAMES`, x and y each
POINT_COLUMNS = tuple(f"{name}_{xy}" for name in POINT_NAMES for xy in "xy")
NPT = len(POINT_COLUMNS)
#: the design-row columns, in order: the parameter vector (SI), then energy_tol, the
#: optional lid_mass and the optional point columns
DESIGN_COLUMNS = tuple(q.name.removesuffix("_deg") for q in elements.PARAMS) + (
    "energy_tol", "lid_mass") + POINT_COLUMNS
#: the SI factor of each parameter column (an angle given in degrees: pi/180)
SI = np.array([q.si for q in elements.PARAMS])
#: version of the exported C signatures; a built extension reporting another is not used
KERNEL_ABI = 6
#: every layout constant this module shares with the kernel (``sc_layout()`` must equal it)
LAYOUT = (f"abi={KERNEL_ABI};meta=ncell,lo,h,m0,{','.join(elements.KERNEL_META)};"
          f"cc={','.join(COEFFS)};mass={','.join(COEFFS[:4])};"
          f"xcc={','.join(COORDINATE_COEFFS + ('-',) * (NX - len(COORDINATE_COEFFS)))};"
          f"pose={','.join(POSE + ('-',) * (NPOSE - len(POSE)))};"
          f"row={','.join(DESIGN_COLUMNS)};out={','.join(OUT_FIELDS)};nrng=18")


#: the generated C header of this layout, next to ``_kernel.c``
HEADER_NAME = "_layout.h"


def _c_name(prefix: str, name: str) -> str:
    return f"{prefix}_{name.upper()}"


def header() -> str:
    """The C header ``_kernel.c`` includes: the ABI, the design-row, coefficient, extra,
    pose and output columns as enums named after this module's names (``D_SPRING_K``,
    ``C_M``, ``O_CLOSING_TIME`` ...), and :data:`LAYOUT` as the string ``sc_layout()``
    returns. Written by ``python -m softclose.simulation.kernel --write``; a test
    holds the file to this text, so the kernel's layout always comes from the registry."""
    row = DESIGN_COLUMNS[:len(DESIGN_COLUMNS) - NPT]

    def enum(prefix, names, count=None):
        items = [_c_name(prefix, n) for n in names] + ([count] if count else [])
        lines, cur = [], "enum {"
        for i, it in enumerate(items):
            piece = f" {it}" + ("," if i < len(items) - 1 else " };")
            if len(cur) + len(piece) > 95:
                lines.append(cur)
                cur = "      " + piece
            else:
                cur += piece
        return "\n".join(lines + [cur])

    layout = []
    for part in LAYOUT.split(";"):        # a line a part; long parts wrapped after commas
        text, cur = part + ";", ""
        for piece in text.split(","):
            if cur and len(cur) + len(piece) > 80:
                layout.append(cur + ",")
                cur = piece
            else:
                cur = f"{cur},{piece}" if cur else piece
        layout.append(cur)
    layout[-1] = layout[-1].removesuffix(";")
    return "\n".join([
        "/* The stroke kernel's layout, generated from the element registry and",
        " * softclose/simulation/kernel/layout.py by",
        " *     python -m softclose.simulation.kernel --write",
        " * Do not edit: tests/test_kernel_layout.py holds this file to the generator. */",
        "#ifndef SOFTCLOSE_KERNEL_LAYOUT_H",
        "#define SOFTCLOSE_KERNEL_LAYOUT_H",
        "",
        f"#define KERNEL_ABI {KERNEL_ABI} /* bumped when the exported signatures or outputs change */",
        "/* the design-row columns: the elements' parameters (the registry's order), e_tol, m_lid */",
        enum("D", row, "NDESIGN"),
        "/* the table's coefficients, and those that depend on the lid's mass (the first NMASS) */",
        f"#define NC {len(COEFFS)}",
        f"#define NMASS {len(COEFFS[:4])}",
        enum("C", COEFFS),
        "/* the coordinate table's element columns (NX per power) */",
        f"#define NX {NX}",
        enum("X", COORDINATE_COEFFS),
        "/* the pose table's columns (NPOSE per power) */",
        f"#define NPOSE {NPOSE}",
        enum("P", POSE, "P_USED"),
        "/* the outputs per design row */",
        enum("O", OUT_FIELDS, "NOUT"),
        "/* every layout constant above, as one string: checked by Python when it loads the kernel */",
        "static const char LAYOUT[] =",
        "\n".join(f'    "{part}"' for part in layout) + ";",
        "",
        "#endif",
        ""])

