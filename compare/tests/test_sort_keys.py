"""Issue 41 item 3: sort keys on every numeric cell of the report's tables. The "from which
contact duration" column sorted 21, 33, 9.1 ms (as text) and "not up to 50 ms" first. Every
cell of a sortable table (3 rows or more, the page's sorter) that begins with a number has a
``data-sort`` holding that number in SI, at the digits the cell prints; a cell of such a
column with no number has a key that sorts it last ("none"; "Infinity" for a value beyond
what was scanned). Read with the standard library's HTML parser, not the keys' own regexes."""

from __future__ import annotations

import math
import re
from html.parser import HTMLParser

import pytest

from treeimpact.compare.report import write_report
from treeimpact.compare.report.sort_keys import add_sort_keys
from treeimpact.compare.runs.cache import RunCache

#: The units the report prints after a number, to SI (this test's own table).
SI = {"%": 1e-2, "ms": 1e-3, "s": 1.0, "mm": 1e-3, "m": 1.0, "kN": 1e3, "N": 1.0, "J": 1.0,
      "kg": 1.0, "us": 1e-6, "Hz": 1.0, "kHz": 1e3, "N/m": 1.0, "MN/m": 1e6, "m/s": 1.0,
      "km/s\u00b2": 1e3, "m/s\u00b2": 1.0}
#: A column header's unit, "(ms", "(km/s²)": the unit of its cells that print none.
HEADER_UNIT = re.compile(r"\((ms|mm|s|m|J|kN|N|kg|%|km/s\u00b2|m/s\u00b2|m/s)[),]")
LEADING = re.compile(r"^(?:[~\u2248\u2265\u2264<>]=?)?\s*([+\-\u2212]?\d+(?:\.(\d+))?(?:[eE]([+\-]?\d+))?)"
                     r"(?:\s*(?:-|\.\.)\s*([+\-]?\d+(?:\.\d+)?(?:[eE][+\-]?\d+)?))?"
                     r"\s*([A-Za-z%/]*)(?=$|[\s,;:()])")


class Tables(HTMLParser):
    """Every table of a page: rows of (attributes, text) per cell."""

    def __init__(self):
        super().__init__()
        self.tables, self._cell = [], None

    def handle_starttag(self, tag, attrs):
        if tag == "br" and self._cell is not None:
            self._cell[2] += " "  # a line break in a cell separates its words
        elif tag == "table":
            self.tables.append([])
        elif tag == "tr" and self.tables:
            self.tables[-1].append([])
        elif tag in ("td", "th") and self.tables:
            self._cell = [tag, dict(attrs), ""]
            self.tables[-1][-1].append(self._cell)

    def handle_endtag(self, tag):
        if tag in ("td", "th"):
            self._cell = None

    def handle_data(self, data):
        if self._cell is not None:
            self._cell[2] += data


def printed(text: str, header: str = ""):
    """(value in SI, a range's second end or the value, half the last printed digit in SI)
    of a cell beginning with a number in a unit of :data:`SI`, or none (then its column
    ``header``'s unit, if it names one); None otherwise."""
    m = LEADING.match(" ".join(text.split()))
    if m is None or (m.group(5) and m.group(5) not in SI):
        return None
    unit = HEADER_UNIT.search(header)
    scale = SI[m.group(5)] if m.group(5) else SI[unit.group(1)] if unit else 1.0
    decimals = len(m.group(2) or "") - int(m.group(3) or 0)
    low = float(m.group(1).replace("\u2212", "-")) * scale
    high = float(m.group(4)) * scale if m.group(4) else low
    return low, max(low, high), 0.5 * 10.0 ** -decimals * scale


def check(page: str) -> tuple[int, list[str]]:
    """(numeric cells checked, problems) over the sortable tables of ``page``."""
    parser = Tables()
    parser.feed(page)
    checked, problems = 0, []
    for table in parser.tables:
        if len(table) < 3:
            continue  # the page's sorter leaves a table of under 3 rows alone
        heads = [cell[2] for cell in table[0]]
        for row in table[1:]:
            for col, (tag, attrs, text) in enumerate(row):
                got = printed(text, heads[col] if col < len(heads) else "")
                if tag != "td" or got is None or "colspan" in attrs:
                    continue
                checked += 1
                key = attrs.get("data-sort")
                value, high, half = got  # a range's key: its first end, or inside it
                slack = half * 1.0001 + 1e-15 * abs(value)
                try:
                    ok = value - slack <= float(key) <= high + slack
                except (TypeError, ValueError):
                    ok = False
                if not ok:
                    problems.append(f"{text.strip()!r}: data-sort {key!r}, printed {value:g}")
    return checked, problems


def _unkeyed_in_numeric_columns(page: str) -> list[str]:
    parser = Tables()
    parser.feed(page)
    out = []
    for table in parser.tables:
        for row in table[1:]:
            for tag, attrs, text in row:
                if tag == "td" and "data-sort" in attrs and attrs["data-sort"] in ("", None):
                    out.append(text)
    return out


def test_the_issue_s_column_sorts_by_its_numbers_and_not_up_to_last():
    page = ("<table><tr><th>tree</th><th>energy delivered</th><th>x_max</th></tr>"
            "<tr><td>a</td><td>&ge; 21 ms</td><td>not up to 50 ms</td></tr>"
            "<tr><td>b</td><td>&ge; 33 ms</td><td>2.6 ms</td></tr>"
            "<tr><td>c</td><td>&ge; 9.1 ms</td><td>n/a</td></tr>"
            "<tr><td>d</td><td data-sort=\"\">n/a</td><td>&ge; 6 ms</td></tr></table>")
    keyed = add_sort_keys(page)
    parser = Tables()
    parser.feed(keyed)
    rows = parser.tables[0][1:]
    assert [r[0][1].get("data-sort") for r in rows] == [None] * 4  # names: text order
    energy = [r[1][1]["data-sort"] for r in rows]
    assert energy == ["0.021", "0.033", "0.0091", "none"]
    x_max = [r[2][1]["data-sort"] for r in rows]
    assert x_max == ["Infinity", "0.0026", "none", "0.006"]
    numbers = sorted((float(k), t) for k, (_, _, t) in zip(x_max, (r[2] for r in rows))
                     if k != "none")
    assert [t for _, t in numbers] == ["2.6 ms", "\u2265 6 ms", "not up to 50 ms"]
    assert check(keyed) == (5, [])
    assert check(page)[1]  # the page as the templates wrote it fails the check


@pytest.fixture(scope="module")
def page(tmp_path_factory):
    """A report of one tree, as the report tests write it."""
    out = tmp_path_factory.mktemp("report")
    paths = write_report(out, scenarios=["open-center"], runs=RunCache(),
                         engines=("no-such-engine",), segments=4)
    return paths["html"].read_text()


def test_every_numeric_cell_of_the_report_has_its_number_as_key(page):
    checked, problems = check(page)
    assert checked >= 50, checked
    assert not problems, problems[:20]
    assert not _unkeyed_in_numeric_columns(page)
    assert 'td.dataset.sort === "none"' in page  # the sorter puts "none" last either way


def test_keys_are_finite_numbers_or_the_two_stated_words(page):
    keys = re.findall(r'data-sort="([^"]*)"', page)
    assert keys
    for k in keys:
        assert k in ("none", "Infinity") or math.isfinite(float(k)), k
