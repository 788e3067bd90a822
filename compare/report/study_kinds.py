"""The kinds of study a report renders from a study's folder: the registry.

A study folder is read as data (no import of the code that wrote it). A kind is known by
the JSON file it writes (``study.json`` with its ``validity`` key: the validity study;
``design.json`` with its ``pairs``: the design map) and rendered by its own body template;
its figures are placed by that template, the rest follow it. A kind is registered beside the
report module that reads it (:func:`register_kind`): the validity study in
:mod:`.studies`, the design map in :mod:`.design_answer`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable


@dataclass(frozen=True)
class StudyKind:
    """A kind of study: ``name`` (how the report's answer asks for it), ``data_file`` and
    ``marker`` (the file it writes and a key that file's data holds), ``body`` (its
    templates, ``BODY.html.j2`` and ``BODY.md.j2``), ``variable`` (the name its data goes by
    in them) and ``figures`` (data -> the figure files its body shows)."""

    name: str
    data_file: str
    marker: str
    body: str
    variable: str
    figures: Callable[[dict], set]


#: The registered kinds, by name, in the order a folder's bodies are rendered.
KINDS: dict[str, StudyKind] = {}


def register_kind(kind: StudyKind) -> StudyKind:
    """Add ``kind`` to :data:`KINDS` (ValueError if its name is taken); returns it."""
    if kind.name in KINDS:
        raise ValueError(f"study kind {kind.name!r} is registered already")
    KINDS[kind.name] = kind
    return kind


def kinds_in(data: dict) -> dict:
    """The kinds whose files a study folder holds, ``data`` being its JSON files' data by
    file name: kind name -> (its StudyKind, its data)."""
    out = {}
    for kind in KINDS.values():
        found = data.get(kind.data_file)
        if isinstance(found, dict) and kind.marker in found:
            out[kind.name] = (kind, found)
    return out
