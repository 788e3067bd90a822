"""Report section: one model-validity study (validity map, speed-accuracy curve, ...).

A study directory is read as it is: its figures (``*.png``, ``*.svg``, sorted by name) are
linked where they are (paths relative to the page), its ``*.json`` files are carried into
report.json, and a ``summary.md`` (or ``README.md``) is shown as its text. The section's
title is the directory's name.

A directory written by ``treeimpact sweep`` (its ``study.json``,
:mod:`compare.report.validity.study`) is rendered from that data with the study's own
templates: each figure in place, under its caption, headings nested under the section's;
figures it does not show follow it.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

from treeimpact.analytic.errors import ParameterError

from .base import Section
from .study_kinds import StudyKind, kinds_in, register_kind


def _link(path: Path, page_dir) -> str:
    """``path`` as the page links to it: relative to the page's directory, '/'-separated."""
    target = os.path.relpath(path.resolve(), Path(page_dir).resolve()) if page_dir else path
    return Path(target).as_posix()


#: The largest study file read back (bytes).
MAX_FILE_BYTES = 50_000_000


def _read(path: Path, reader):
    """``reader(path)`` of a study's file, or a one-line ParameterError naming it (not a
    regular file, too large, another encoding, not JSON, nested beyond reason)."""
    where = f"--study {str(path.parent)!r}: {path.name}"
    if not path.is_file():
        raise ParameterError(f"{where}: not a regular file")
    if path.stat().st_size > MAX_FILE_BYTES:
        raise ParameterError(f"{where}: {path.stat().st_size} bytes, allowed up to "
                             f"{MAX_FILE_BYTES}")
    try:
        return reader(path)
    except UnicodeDecodeError as exc:
        raise ParameterError(f"{where}: not UTF-8 text (byte at offset {exc.start})") \
            from None
    except RecursionError:
        raise ParameterError(f"{where}: nested too deeply to be a study's file") from None
    except ValueError as exc:
        raise ParameterError(f"{where}: not JSON ({str(exc).splitlines()[0][:100]})") \
            from None


def _figures_of(study: dict) -> set:
    """The figure files a study's page shows (its study.json)."""
    named = [v.get("figure") for v in study.get("validity", []) + study.get("identification",
                                                                            [])]
    named += [c.get("figure") for c in study.get("speed", {}).get("curves", [])]
    named += list((study.get("identification_validation") or {}).get("figures", []))
    named.append((study.get("sensitivity") or {}).get("figure"))
    return {n for n in named if n}


#: The validity study (compare/report/validity/study.py's study.json), rendered by study_body.
register_kind(StudyKind("validity", "study.json", "validity", "study_body", "s", _figures_of))


class StudySection(Section):
    """A finished study's folder as a section: a study of compare.studies.sweep rendered from its
    study.json, any other from its figures and summary text. ``directory``: the folder
    (ParameterError if it is not one); ``page_dir``: the report's folder, the figures
    linked relative to it."""

    template = "study"

    def __init__(self, directory, page_dir=None):
        d = Path(directory)
        if not d.is_dir():
            raise ParameterError(f"study_dirs: {str(d)!r} is not a directory")
        self.directory = d
        self.title = f"Study: {d.name}"
        self.anchor = f"study-{d.name}"
        self.images = [{"name": p.name, "uri": _link(p, page_dir)}
                       for p in sorted(d.iterdir()) if p.suffix.lower() in (".png", ".svg")]
        self.data = {}
        for p in sorted(d.glob("*.json")):
            self.data[p.name] = _read(p, lambda q: json.loads(q.read_text(encoding="utf-8")))
        self.text = ""
        for name in ("summary.md", "README.md"):
            if (d / name).is_file():
                self.text = _read(d / name, lambda q: q.read_text(encoding="utf-8"))
                break
        self.kinds = kinds_in(self.data)
        self.study = self.kinds.get("validity", (None, None))[1]
        self.uri = None
        uris = {i["name"]: i["uri"] for i in self.images}
        for kind, data in self.kinds.values():  # rendered from its data, figures in place
            shown = {n for n in kind.figures(data) if n}
            missing = sorted(shown - set(uris))
            if missing:
                raise ParameterError(f"study {d.name}: {kind.data_file} shows "
                                     f"{', '.join(missing)}, which the directory does not have")
            self.uri = uris.__getitem__
            self.images = [i for i in self.images if i["name"] not in shown]

    def context(self) -> dict:
        """The template's names: the figures, the summary text, the study's data."""
        # the section is an h2 (the report's <summary>): the study's title is an h3
        return {"images": self.images, "text": self.text, "level": 3, "image": self.uri,
                "files": sorted(self.data),
                "bodies": [kind.body for kind, _ in self.kinds.values()],
                **{kind.variable: data for kind, data in self.kinds.values()}}

    def to_json(self) -> dict:
        """The folder, its figures, its JSON files' data and its summary text."""
        return {"directory": str(self.directory),
                "figures": sorted(p.name for p in self.directory.iterdir()
                                  if p.suffix.lower() in (".png", ".svg")),
                "data": self.data, "summary": self.text}
