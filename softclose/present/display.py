"""How a result shows itself: one short line (``repr``) and an HTML table (``_repr_html_``,
what Jupyter draws).

Every public result builds one :class:`Display` -- a title, whether it succeeded, what went
wrong in plain words, a few one-line facts, tables and notes -- and :class:`Displayed` (a
mixin) turns it into both forms. Nothing here imports pandas or matplotlib: a result shows
at the cost of formatting a few numbers. A table is always short: a sweep of 10^6 designs
shows its size, its feasible count and its best rows, never the rows themselves.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from ..problem import UNITS
from ..config.schema import KEYS

#: rows a table shows at most (the rest is counted in a note)
MAX_ROWS = 12


@dataclass(frozen=True)
class Table:
    """A small table: a heading, column names, rows of already formatted cells."""

    heading: str
    columns: tuple
    rows: list
    note: str = ""


@dataclass(frozen=True)
class Display:
    """What a result shows: ``title`` (its type and what it is), ``ok`` (True, False, or
    None when success does not apply), ``message`` (a failure or warning in plain words),
    ``facts`` ((name, text) pairs: the one-line summary and the first lines of the HTML),
    ``tables`` and ``notes``."""

    title: str
    ok: bool | None = None
    message: str = ""
    facts: tuple = ()
    tables: tuple = ()
    notes: tuple = ()
    #: how many facts the one-line repr shows
    short: int = 4


# -- numbers as text ---------------------------------------------------------------------------
def num(v, digits: int = 6, spec: str | None = None) -> str:
    """A value as text: "—" for None/NaN, yes/no for booleans, ``digits`` significant
    digits for numbers. With a format ``spec`` (".2f", ".1e": a column of measurements), a
    number is ``format(v, spec)`` as it is (an integer too), a word itself, and any value
    that is not finite "—"."""
    if v is None:
        return "—"
    if spec is not None:
        if isinstance(v, str):
            return v
        return format(v, spec) if not isinstance(v, float) or math.isfinite(v) else "—"
    if type(v).__name__ in ("bool", "bool_"):          # Python's and numpy's
        return "yes" if v else "no"
    if isinstance(v, (int,)) or type(v).__name__.startswith("int"):
        return f"{int(v):,}" if abs(int(v)) >= 10000 else str(int(v))
    try:
        x = float(v)
    except (TypeError, ValueError):
        return str(v)
    if math.isnan(x):
        return "—"
    if math.isinf(x):
        return "∞" if x > 0 else "−∞"
    return f"{x:.{digits}g}"


def with_unit(v, unit: str = "", digits: int = 6) -> str:
    """"0.0229 N m" ("—" alone when there is no value)."""
    s = num(v, digits)
    return f"{s} {unit}" if unit and s not in ("—", "yes", "no") else s


def pm(v, accuracy, unit: str = "", digits: int = 7) -> str:
    """"0.9999999 s ± 1.2e-08" (the accuracy left out when unknown)."""
    s = with_unit(v, unit, digits)
    if accuracy is None or v is None or (isinstance(accuracy, float) and math.isnan(accuracy)):
        return s
    return f"{s} ± {float(accuracy):.1e}"


def mm(v) -> str:
    """A length in metres as millimetres, four significant digits ("—" for None)."""
    return "—" if v is None else f"{num(v * 1e3, spec='.4g')} mm"


def _pct(x: float) -> str:
    """A fraction in per cent: one decimal, two near 0 and 100 % (99.96 stays 99.96),
    trailing zeros dropped."""
    v = 100 * float(x)
    s = f"{v:.2f}" if v < 1 or v > 99 else f"{v:.1f}"
    return s.rstrip("0").rstrip(".") if "." in s else s


def percent(x) -> str:
    """A fraction as "43.2 %"."""
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "—"
    return f"{_pct(x)} %"


def interval(ci) -> str:
    """A 95 % interval of a fraction as "42.2–44.2 %"."""
    if ci is None:
        return "—"
    return f"{_pct(ci[0])}–{_pct(ci[1])} %"


def unit_of(key: str) -> str:
    """The unit of a metric, a design key or a config key ("section.name")."""
    if key in UNITS:
        return UNITS[key]
    for k in KEYS:
        if k.full == key:
            return k.unit
    return ""


# -- the two forms -------------------------------------------------------------------------------
_STYLE = ("font-family: var(--jp-ui-font-family, sans-serif); font-size: 13px; "
          "line-height: 1.4; max-width: 60em")
_TABLE = "border-collapse: collapse; margin: 0.3em 0 0.6em 0"
_CELL = "padding: 1px 10px 1px 0; text-align: left; vertical-align: top"
_MARK = {True: ("✓", "#1a7f37"), False: ("✗", "#cf222e"), None: ("", "inherit")}


def to_html(d: Display) -> str:
    """The HTML form of ``d`` (every text escaped)."""
    import html                    # (not at start-up: a command shows no HTML)
    e = html.escape
    mark, colour = _MARK[d.ok]
    out = [f'<div class="softclose-result" style="{_STYLE}">',
           f'<div><span style="color: {colour}; font-weight: bold">{mark}</span> '
           f"<strong>{e(d.title)}</strong></div>"]
    if d.message:
        out.append(f'<div style="color: {_MARK[False][1] if d.ok is False else "#9a6700"}">'
                   f"{e(d.message)}</div>")
    if d.facts:
        out.append(f'<table style="{_TABLE}">')
        out += [f'<tr><th style="{_CELL}">{e(k)}</th><td style="{_CELL}">{e(v)}</td></tr>'
                for k, v in d.facts]
        out.append("</table>")
    for t in d.tables:
        out.append(f"<div><strong>{e(t.heading)}</strong></div>")
        out.append(f'<table style="{_TABLE}"><thead><tr>'
                   + "".join(f'<th style="{_CELL}">{e(str(c))}</th>' for c in t.columns)
                   + "</tr></thead><tbody>")
        for row in t.rows[:MAX_ROWS]:
            out.append("<tr>" + "".join(f'<td style="{_CELL}">{e(str(c))}</td>' for c in row)
                       + "</tr>")
        out.append("</tbody></table>")
        more = len(t.rows) - MAX_ROWS
        note = " ".join(filter(None, [t.note, f"({more} more rows)" if more > 0 else ""]))
        if note:
            out.append(f'<div style="color: #57606a">{e(note)}</div>')
    if d.notes:
        out.append("<ul style=\"margin: 0.2em 0\">" + "".join(f"<li>{e(n)}</li>" for n in d.notes)
                   + "</ul>")
    out.append("</div>")
    return "\n".join(out)


def to_text(d: Display, width: int = 200) -> str:
    """The one-line form: ``<Title: ok, fact = value, ...; message>`` (at most ``width``
    characters)."""
    state = {True: "ok", False: "failed", None: ""}[d.ok]
    parts = [f"{k} = {v}" for k, v in d.facts[:d.short]]
    s = f"<{d.title}" + (f": {state}" if state else "") \
        + ("" if not parts else (", " if state else ": ") + ", ".join(parts))
    if d.message:
        s += f"; {d.message}"
    s += ">"
    return s if len(s) <= width else s[:width - 2] + "…>"


class Displayed:
    """The mixin of every public result: ``repr`` and ``_repr_html_`` from the result's
    :meth:`_display` (a result's dataclass is declared with ``repr=False`` so that this
    repr is the one used)."""

    def _display(self) -> Display:   # pragma: no cover  (every result overrides it)
        raise NotImplementedError

    def __repr__(self) -> str:
        return to_text(self._display())

    def _repr_html_(self) -> str:
        return to_html(self._display())


__all__ = ["Display", "Displayed", "Table", "to_html", "to_text", "num", "mm", "with_unit", "pm",
           "percent", "interval", "unit_of", "MAX_ROWS"]
