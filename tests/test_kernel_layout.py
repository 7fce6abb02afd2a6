"""The kernel's layout comes from the element registry: ``_layout.h`` (the design-row,
coefficient, pose and output columns, the ABI and the layout string ``sc_layout()``
returns) is what the generator writes, and ``_kernel.c`` states none of it by hand."""

from __future__ import annotations

import re

from softclose.model import elements
from softclose.simulation.kernel import layout, library


def test_the_header_is_generated_from_the_registry():
    assert library.HEADER.read_text() == layout.header(), \
        "run: python -m softclose.simulation.kernel --write"


def test_the_row_enum_follows_the_registry():
    text = layout.header()
    row = re.search(r"enum \{ (D_SPRING_K.*?) \};", text, re.S).group(1)
    names = [n.strip() for n in row.split(",")]
    assert names[:len(elements.PARAMS)] == [
        "D_" + q.name.removesuffix("_deg").upper() for q in elements.PARAMS]
    assert names[-3:] == ["D_ENERGY_TOL", "D_LID_MASS", "NDESIGN"]
    assert f'#define KERNEL_ABI {layout.KERNEL_ABI} ' in text


def test_the_c_source_states_no_layout_by_hand():
    src = library.SOURCE.read_text()
    assert '#include "_layout.h"' in src
    assert "static const char LAYOUT" not in src and "#define KERNEL_ABI" not in src
    assert not re.search(r"enum \{ (D_(?!PT = NDESIGN)|O_STATUS|C_M\b|P_AX|X_PSI)", src)


def test_the_loaded_kernel_reports_the_generated_layout():
    lib = library.load()
    assert lib.sc_layout().decode() == layout.LAYOUT
