"""Sort keys for every number in the report page's tables (issue 41: the "from which contact
duration" column sorted 21, 33, 9.1 ms, and "not up to 50 ms" first).

:func:`add_sort_keys` gives each cell that begins with a number, and each cell of a numeric
column (one where at least half the filled cells begin with a number), a ``data-sort`` that
the page's sorter reads before the text: the cell's first number in SI (9.1 ms is 0.0091, "\u2265 21 ms" is 0.021, +8.6 % is 0.086,
1.2 kN is 1200; a range such as 9-33 ms sorts by its first end, 0.009); a cell that says the
value lies beyond what was scanned ("not up to 50 ms") sorts as ``Infinity``, after every
number when ascending; a cell with no number (n/a, a word, empty) has the key ``none``, which the
sorter puts last in either direction. A cell the template keyed itself keeps its key (an
empty one is filled in)."""

from __future__ import annotations

import html
import re

#: A unit printed after a number -> its factor to SI (% as a fraction).
UNIT_SCALE = {
    "%": 1e-2, "s": 1.0, "ms": 1e-3, "us": 1e-6, "µs": 1e-6, "min": 60.0, "h": 3600.0,
    "m": 1.0, "cm": 1e-2, "mm": 1e-3, "km": 1e3, "N": 1.0, "kN": 1e3, "MN": 1e6,
    "J": 1.0, "kJ": 1e3, "kg": 1.0, "g": 1e-3, "t": 1e3, "Hz": 1.0, "kHz": 1e3,
    "Pa": 1.0, "kPa": 1e3, "MPa": 1e6, "GPa": 1e9, "N/m": 1.0, "kN/m": 1e3, "MN/m": 1e6,
    "m/s": 1.0, "mm/s": 1e-3, "m/s^2": 1.0, "rad/s": 1.0, "N s/m": 1.0, "kB": 1e3,
    "MB": 1e6, "GB": 1e9,
}
#: A key that sorts after every number when ascending: beyond the scanned range.
BEYOND = "Infinity"
#: The key of a cell with no number: last in either direction (the page's sorter).
NONE = "none"

_NUMBER = r"[+\-\u2212]?(?:\d{1,3}(?:,\d{3})+(?!\d)|\d+(?:\.\d+)?|\.\d+)(?:[eE][+\-]?\d+)?"
#: A cell that begins with a number, maybe a range's second end, then maybe a unit.
LEADING = re.compile(rf"^(?:(?:[~\u2248\u2265\u2264]|[<>]=?)\s*)?(?P<num>{_NUMBER})"
                     rf"(?:\s*(?:-|\u2013|\.\.|to)\s*{_NUMBER})?"
                     r"(?:\s*(?P<unit>N s/m|[A-Za-z%\u00b5][A-Za-z/^0-9]*))?"
                     r"(?=$|[\s,;:()\[\]])")  # a whole token: not the 1 of "1-DOF"
#: A cell that says its value lies beyond what was scanned or computed.
_BEYOND = re.compile(r"^(not up to|beyond|above)\b", re.I)
_TABLE = re.compile(r"<table\b.*?</table>", re.S)
_ROW = re.compile(r"<tr\b[^>]*>.*?</tr>", re.S)
_CELL = re.compile(r"<(t[dh])\b([^>]*)>(.*?)</\1>", re.S)
_TAG = re.compile(r"<[^>]+>")
_KEY = re.compile(r'\sdata-sort="([^"]*)"')


def cell_text(inner: str) -> str:
    """A cell's text (its HTML ``inner``) as the reader sees it: tags dropped, entities
    read, spaces single."""
    return " ".join(html.unescape(_TAG.sub(" ", inner)).split())


def number_in_si(text: str) -> float | None:
    """The first number ``text`` begins with, in SI by the unit after it (1 when there is
    no unit it knows: a count, a ratio), or None."""
    m = LEADING.match(text)
    if m is None:
        return None
    value = float(m.group("num").replace(",", "").replace("\u2212", "-"))
    return value * UNIT_SCALE.get(m.group("unit") or "", 1.0)


def sort_key(text: str) -> str:
    """The ``data-sort`` of a cell of a numeric column showing ``text``."""
    value = number_in_si(text)
    if value is not None:
        return f"{value:.12g}"
    return BEYOND if _BEYOND.match(text) else NONE


def _numeric_columns(rows: list[list[tuple]]) -> set[int]:
    """The columns of the body ``rows`` (lists of cells (tag, attrs, inner)) where at least
    half the filled cells begin with a number."""
    counts: dict[int, list[int]] = {}
    for cells in rows:
        for col, (_, _, inner) in enumerate(cells):
            text = cell_text(inner)
            if text:
                c = counts.setdefault(col, [0, 0])
                c[0] += number_in_si(text) is not None
                c[1] += 1
    return {col for col, (num, filled) in counts.items() if num and 2 * num >= filled}


def _keyed_cell(tag: str, attrs: str, inner: str) -> str:
    key = _KEY.search(attrs)
    if key is not None and key.group(1) != "":
        return f"<{tag}{attrs}>{inner}</{tag}>"
    attrs = _KEY.sub("", attrs)
    return f'<{tag}{attrs} data-sort="{sort_key(cell_text(inner))}">{inner}</{tag}>'


def _keyed_table(table: str) -> str:
    rows = _ROW.findall(table)
    body = [r for r in rows[1:] if "colspan" not in r]  # a spanning row stays unkeyed
    parsed = {r: _CELL.findall(r) for r in body}
    numeric = _numeric_columns(list(parsed.values()))
    for row, cells in parsed.items():
        done = _CELL.sub(lambda m, it=iter(range(len(cells))): _cell(m, next(it), numeric),
                         row)
        table = table.replace(row, done, 1)
    return table


def _cell(match, col: int, numeric: set[int]) -> str:
    tag, attrs, inner = match.groups()
    if tag != "td" or (col not in numeric and number_in_si(cell_text(inner)) is None):
        return match.group(0)  # a word in a column of words sorts as text
    return _keyed_cell(tag, attrs, inner)


def add_sort_keys(page: str) -> str:
    """``page`` (HTML) with a ``data-sort`` on every cell of every numeric table column
    (module docstring)."""
    return _TABLE.sub(lambda m: _keyed_table(m.group(0)), page)
