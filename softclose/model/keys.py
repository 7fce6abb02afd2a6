"""One record per config key: what the key is, stated once.

A :class:`Key` holds everything softclose knows about one config key: its section and name,
its kind (how a value is checked), its default (or how a missing value is derived), its
admissible range and unit, its default manufacturing spread, and a one-line doc. The config
loader (:mod:`softclose.config`), ``--set``, ``[tolerance]``, the sweeps' key list and the key
tables of docs/model.md are all read from these records; the machine elements
(:mod:`softclose.model.elements`) declare the keys they own with them.

Kinds: ``"pos"`` (a number > 0), ``"nonneg"`` (>= 0), ``"real"``, ``"vec2"``/``"vec3"`` (a list
of 2 or 3 numbers), ``"bounds"`` (two numbers lo <= hi), ``"int+"`` (a whole number >= 1),
``"str:a,b,c"`` (one of the words), ``"words:a,b,c"`` (a list of distinct words of them),
``"bool"``, ``"free"`` (a table KEY = [lo, hi] of further design variables:
:mod:`softclose.config.free`).
"""

from __future__ import annotations

from typing import Any, Callable, NamedTuple

#: kinds whose value is a list of numbers: their length
VECTOR_KINDS = {"vec2": 2, "vec3": 3, "bounds": 2}


class Key(NamedTuple):
    """One config key.

    ``default`` None means derived: ``derive(values)`` computes it from the other checked
    values (``values[section][name]``), and ``derived`` says how, for the docs; without a
    ``derive`` the key is optional and its value None when not given. ``lo``/``hi``
    are the admissible magnitudes (both ends included; every component of a vector), in the
    key's ``unit``. ``spread`` is the default relative tolerance of the key (``[tolerance]``),
    None for none. ``doc`` is the one line the docs' key tables show.
    """

    section: str
    name: str
    kind: str
    default: Any
    unit: str = ""
    doc: str = ""
    lo: float | None = None
    hi: float | None = None
    spread: float | None = None
    derived: str = ""
    derive: Callable[[dict], Any] | None = None
    note: str = ""

    @property
    def full(self) -> str:
        """``section.name``."""
        return f"{self.section}.{self.name}"

    @property
    def size(self) -> int:
        """Number of components: 1 for a scalar or a word, 2 or 3 for a vector."""
        return VECTOR_KINDS.get(self.kind, 1)

    @property
    def choices(self) -> tuple[str, ...]:
        """The words a ``str:`` or ``words:`` key accepts (empty for other kinds)."""
        if self.kind.startswith(("str:", "words:")):
            return tuple(self.kind.split(":", 1)[1].split(","))
        return ()

    @property
    def range(self) -> tuple[float, float, str] | None:
        """(lo, hi, unit) when the key has admissible magnitudes."""
        return None if self.lo is None else (self.lo, self.hi, self.unit)
