"""The pages checked against the numbers: the marked numbers (``<!-- check: KEY -->``,
:func:`check_marks`) and the generated blocks (:func:`check_blocks`, rewritten by
:func:`write_blocks`), each number compared as a float at the digits its page prints;
:func:`used_keys`, what the pages quote. The conventions: the package's docstring."""

from __future__ import annotations

import json
import re
from pathlib import Path

from .base import CONTACT_FIT, ROOT
from .from_files import from_benchmarks, from_contact_fit, numbers
from .tables import GENERATED

PAGES = (ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md")))
_NUM = r"[-+]?(?:\d+(?:\.\d+)?|\.\d+)(?:[eE][-+]?\d+)?"
_SEP = r"\s*(?:,\s*and|,|\band\b|/|\.\.|\bto\b|-)\s*"
_QUOTED = re.compile(rf"(?<![\w.\-+])(?P<nums>{_NUM}(?:{_SEP}{_NUM})*)"
                     r"(?P<unit>\s*(?:%|[A-Za-z][\w/^*\-]*)?)\s*$")
MARK = re.compile(r"<!-- check(?P<mode>-max|-min)?: (?P<key>[\w.\-/]+)"
                  r"(?: ~(?P<rel>[\d.]+)%)? -->")
BLOCK = re.compile(r"<!-- BEGIN generated: (?P<name>[\w.\-]+) -->\n(?P<body>.*?)"
                   r"<!-- END generated: (?P=name) -->", re.S)


def _tokens(text: str) -> list[str]:
    """The numbers of a quoted list, in order (a separator's '-' is not a sign)."""
    num, sep = re.compile(_NUM), re.compile(_SEP)
    out, pos = [], 0
    while True:
        m = num.match(text, pos)
        out.append(m.group())
        s = sep.match(text, m.end())
        if s is None or not num.match(text, s.end()):
            return out
        pos = s.end()


def _half_unit(token: str) -> float:
    """Half a unit of the last digit a number is printed to ('8.5' -> 0.05, '1.2e-5' ->
    5e-7, '130' -> 0.5)."""
    mant, _, exp = token.lower().lstrip("+-").partition("e")
    decimals = len(mant.split(".")[1]) if "." in mant else 0
    return 0.5 * 10.0 ** (int(exp or 0) - decimals)


def _blank_code(text: str) -> str:
    """The text with its code blocks and spans blanked (a mark shown as an example is no
    mark), lines kept."""
    text = re.sub(r"```.*?```", lambda m: re.sub(r"[^\n]", " ", m.group()), text, flags=re.S)
    return re.sub(r"`[^`\n]*`", lambda m: " " * len(m.group()), text)


def quoted(page_text: str) -> list[dict]:
    """Every marked number of a page: {key, mode, rel, text, tokens, line}."""
    page_text = _blank_code(page_text)
    out = []
    for m in MARK.finditer(page_text):
        before = page_text[max(0, m.start() - 200):m.start()]
        q = _QUOTED.search(before)
        line = page_text.count("\n", 0, m.start()) + 1
        out.append({"key": m["key"], "mode": m["mode"] or "", "rel": m["rel"], "line": line,
                    "text": q["nums"] if q else None,
                    "tokens": _tokens(q["nums"]) if q else []})
    return out


def _agrees(token: str, value: float, mode: str, rel: str | None) -> bool:
    q = float(token)
    tol = float(rel) / 100.0 * abs(value) if rel else _half_unit(token) * (1 + 1e-9)
    if mode == "-max":
        return value <= q + tol
    if mode == "-min":
        return value >= q - tol
    return abs(q - value) <= tol


def check_marks(pages=PAGES, values: dict | None = None) -> list[str]:
    """One line per quoted number that is not its key's value (or has no number, or names
    no key)."""
    values = numbers() if values is None else values
    problems = []
    for page in pages:
        for q in quoted(Path(page).read_text()):
            where = f"{Path(page).name}:{q['line']}"
            if q["key"] not in values:
                problems.append(f"{where}: no number named {q['key']!r} in the sources")
                continue
            if not q["tokens"]:
                problems.append(f"{where}: no number just before the mark of {q['key']!r}")
                continue
            value = values[q["key"]]
            value = value if isinstance(value, list) else [value]
            if len(q["tokens"]) == 1 and len(value) == 2:
                # one number for a range: a bound of it, or the value of all of it
                value = {"-max": [max(value)], "-min": [min(value)]}.get(q["mode"], value)
                if len(value) == 2 and all(_agrees(q["tokens"][0], v, "", q["rel"])
                                           for v in value):
                    value = value[:1]
            if len(value) != len(q["tokens"]):
                problems.append(f"{where}: {q['text']!r} quotes {len(q['tokens'])} number(s), "
                                f"{q['key']} has {len(value)}: {value}")
                continue
            bad = [(t, v) for t, v in zip(q["tokens"], value)
                   if not _agrees(t, v, q["mode"], q["rel"])]
            if bad:
                problems.append(f"{where}: {q['text']!r} but {q['key']} = "
                                f"{_show(values[q['key']])}")
    return problems


def check_now(fresh: dict, pages=PAGES) -> list[str]:
    """:func:`check_marks` and :func:`check_blocks` against the code now: the sources with
    ``fresh`` (what :func:`cheap_numbers` gives on this machine) in place of the values
    they store, so each number is compared at the digits its page prints (or the ``~%`` it
    states). A CPU whose BLAS moves a value in its last bits passes; a printed digit that
    drifted fails."""
    values = numbers() | fresh
    return check_marks(pages, values) + check_blocks(pages, values)


def _show(v) -> str:
    if isinstance(v, list):
        return "[" + ", ".join(f"{x:.6g}" for x in v) + "]"
    return f"{v:.6g}"


def _split(text: str) -> tuple[list[str], list[str]]:
    """(the words between the numbers, the numbers) of a text."""
    parts = re.split(rf"(?<![\w.])({_NUM})(?![\w.])", text)
    return parts[0::2], parts[1::2]


def check_blocks(pages=PAGES, values: dict | None = None) -> list[str]:
    """One line per generated block whose text differs from what its sources give now:
    numbers compared as floats at the digits printed, the rest word for word."""
    values = numbers() if values is None else values
    problems = []
    for page in pages:
        for m in BLOCK.finditer(Path(page).read_text()):
            where = f"{Path(page).name}: block {m['name']}"
            if m["name"] not in GENERATED:
                problems.append(f"{where}: no generator of that name")
                continue
            try:
                want = GENERATED[m["name"]](values)
            except (KeyError, OSError) as exc:
                problems.append(f"{where}: its source lacks {exc}")
                continue
            words, nums = _split(m["body"])
            want_words, want_nums = _split(want)
            if words != want_words or len(nums) != len(want_nums):
                problems.append(f"{where}: the text differs from the generated one (run "
                                "python -m tests.docnumbers write)")
                continue
            bad = [(a, b) for a, b in zip(nums, want_nums)
                   if abs(float(a) - float(b)) > _half_unit(a) * (1 + 1e-9)]
            if bad:
                problems.append(f"{where}: numbers differ (page, source): {bad[:5]}")
    return problems


def write_blocks(pages=PAGES, values: dict | None = None) -> list[str]:
    """Rewrite every generated block from its sources; returns the pages changed."""
    values = numbers() if values is None else values
    changed = []
    for page in pages:
        text = Path(page).read_text()
        new = BLOCK.sub(lambda m: f"<!-- BEGIN generated: {m['name']} -->\n"
                        f"{GENERATED[m['name']](values)}<!-- END generated: {m['name']} -->",
                        text)
        if new != text:
            Path(page).write_text(new)
            changed.append(Path(page).name)
    return changed


class _Tracking(dict):
    """A dict that remembers which keys were read."""

    def __init__(self, *args):
        super().__init__(*args)
        self.read: set = set()

    def __getitem__(self, key):
        self.read.add(key)
        return super().__getitem__(key)

    def get(self, key, default=None):
        self.read.add(key)
        return super().get(key, default)


def used_keys(values: dict, pages=PAGES) -> set:
    """The keys the pages quote: their marks' and what their generated blocks read."""
    used = {q["key"] for page in pages for q in quoted(Path(page).read_text())}
    tracking = _Tracking(values | from_benchmarks()
                         | (from_contact_fit(json.loads(CONTACT_FIT.read_text()))
                            if CONTACT_FIT.exists() else {}))
    for page in pages:
        for m in BLOCK.finditer(Path(page).read_text()):
            if m["name"] in GENERATED:
                try:
                    GENERATED[m["name"]](tracking)
                except (KeyError, OSError):
                    pass
    return used | tracking.read
