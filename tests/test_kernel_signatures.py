"""The ctypes signatures of the kernel's exported functions are those of their C
definitions: every ``sc_*`` function of ``_kernel.c`` is declared in
:func:`softclose.simulation.kernel.library.load`, with the same number of arguments, each
of the same type, and the same return type (a mismatch would pass wrong bits silently)."""

from __future__ import annotations

import ctypes
import re

import pytest

from softclose.simulation.kernel import library

SOURCE = library.SOURCE.read_text()
#: C parameter types -> ctypes
CTYPES = {
    "const double *": ctypes.POINTER(ctypes.c_double),
    "double *": ctypes.POINTER(ctypes.c_double),
    "double": ctypes.c_double,
    "long": ctypes.c_long,
    "long *": ctypes.POINTER(ctypes.c_long),
    "const long *": ctypes.POINTER(ctypes.c_long),
    "int": ctypes.c_int,
    "void": None,
}


def definitions() -> dict[str, tuple]:
    """name -> (return type, [parameter types]) of every exported function with arguments."""
    out = {}
    for m in re.finditer(r"^(void|int|long|double)\s+(sc_\w+)\(([^)]*)\)\s*\{", SOURCE, re.M):
        ret, name, params = m.group(1), m.group(2), " ".join(m.group(3).split())
        if params in ("void", ""):
            continue
        types = []
        for p in params.split(","):
            p = p.strip()
            t = re.sub(r"\s*\b\w+$", "", p).replace("*", " *").strip()
            types.append(re.sub(r"\s+", " ", t))
        out[name] = (ret, types)
    return out


DEFS = definitions()


def test_every_exported_function_is_found():
    assert set(DEFS) >= {"sc_strokes", "sc_stroke_traj", "sc_step", "sc_point_columns",
                         "sc_point_grid", "sc_point_opening", "sc_leaves"}


@pytest.mark.parametrize("name", sorted(DEFS))
def test_the_binding_declares_each_argument_as_the_c_source_defines_it(name):
    lib = library.load()
    fn = getattr(lib, name)
    ret, types = DEFS[name]
    assert fn.argtypes is not None, f"{name}: no argtypes in library.load"
    expected = [CTYPES[t] for t in types]
    assert list(fn.argtypes) == expected, name
    assert fn.restype == CTYPES[ret], name
