"""The report's tooltips, from docs/glossary.md (the one owner of what a term means): each
bold term of a glossary bullet with its one-line definition (:func:`tip`), for the HTML
page's ``title`` attributes. Read once per process; a checkout without docs/ (an installed
package) gives no tooltips rather than failing the report."""

from __future__ import annotations

import functools
import re
from pathlib import Path

#: The glossary of the checkout (compare/report/ -> the repository's docs/).
GLOSSARY = Path(__file__).resolve().parents[2] / "docs" / "glossary.md"
#: A tooltip's length at most (characters): one line of a browser's tooltip box.
LINE = 160

_BOLD = re.compile(r"\*\*((?:\\\*|[^*])+?)\*\*")


def _bullets(text: str) -> list[str]:
    """The glossary's bullets, each joined onto one line (its indented continuation lines),
    with the pages' check comments taken out."""
    out, cur = [], None
    for line in text.splitlines():
        if line.startswith("- "):
            if cur is not None:
                out.append(cur)
            cur = line[2:]
        elif cur is not None and line.startswith("  ") and line.strip():
            cur += " " + line.strip()
        else:
            if cur is not None:
                out.append(cur)
            cur = None
    if cur is not None:
        out.append(cur)
    return [re.sub(r"<!--.*?-->", "", b) for b in out]


def _definition(bullet: str, end: int) -> str:
    """What the bold term ending at ``end`` of ``bullet`` means: after its synonyms (', **X**'
    and '(...)') the text from ': ' to the next '; **' (the next term) or the bullet's end;
    without a colon, the clause from the term itself to its next ';'."""
    rest = bullet[end:]
    lead = re.match(r"(?:\s*(?:,\s*\*\*(?:\\\*|[^*])+?\*\*|\([^)]*\)))*\s*:\s*", rest)
    if lead:
        body = rest[lead.end():]
    else:
        start = bullet.rfind("**", 0, end - 2)
        body = bullet[start:]
    body = re.split(r";\s*(?=\*\*)", body, maxsplit=1)[0]
    return _plain(body)


def _plain(text: str) -> str:
    """``text`` without markdown (bold, code, links) in one line of at most :data:`LINE`
    characters (cut at a word, '...' added)."""
    text = re.sub(r"\[([^\]]+)\]\([^)]*\)", r"\1", text)
    text = re.sub(r"\s+", " ", text.replace("**", "").replace("`", "").replace("\\*", "*"))
    text = text.strip().rstrip(";.,")
    if len(text) > LINE:
        text = text[:LINE].rsplit(" ", 1)[0].rstrip(",;:") + " ..."
    return text


@functools.lru_cache(maxsize=1)
def entries() -> dict[str, str]:
    """term -> its one-line definition, every bold term of every glossary bullet (the first
    bullet naming a term owns it); {} without docs/glossary.md."""
    if not GLOSSARY.exists():
        return {}
    out: dict[str, str] = {}
    for bullet in _bullets(GLOSSARY.read_text(encoding="utf-8")):
        for m in _BOLD.finditer(bullet):
            term = m[1].replace("\\*", "*")
            out.setdefault(term, f"{term}: {_definition(bullet, m.end())}")
    return out


def tip(term: str) -> str:
    """The one-line tooltip of glossary ``term`` ('x_max: the largest trunk displacement at
    the clamp and its time'); KeyError naming the term when the glossary has no entry for
    it (a template asking for a term nobody defined), "" without the glossary file."""
    found = entries()
    if not found:
        return ""
    if term not in found:
        raise KeyError(f"docs/glossary.md has no entry for {term!r}")
    return found[term]
