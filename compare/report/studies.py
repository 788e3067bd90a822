"""Report section: one model-validity study (validity map, speed-accuracy curve, ...).

A study directory is read as it is: its figures (``*.png``, ``*.svg``, sorted by name) are
linked where they are (paths relative to the page), its ``*.json`` files are carried into
report.json, and a ``summary.md`` (or ``README.md``) is shown as its text. The section's title is the directory's name.

A directory written by ``treeimpact sweep`` (it has ``study.md``, :mod:`compare.sweep.study`)
is shown as that study: its text with each figure in place, under its caption, headings
nested under the section's; figures the text does not show follow it.
"""

from __future__ import annotations

import json
import os
import re
from pathlib import Path

from treeimpact.analytic.errors import ParameterError

from .base import Section

_IMAGE = re.compile(r"^!\[[^\]]*\]\(([^)]+)\)\s*$")
_IMAGE_LINK = re.compile(r"^(!\[[^\]]*\])\(([^)]+)\)", re.M)


def _demote(md: str, levels: int) -> str:
    """Markdown with every heading ``levels`` deeper (the section is itself a ``##``)."""
    return "\n".join("#" * levels + line if line.startswith("#") else line
                     for line in md.splitlines())


def _link(path: Path, page_dir) -> str:
    """``path`` as the page links to it: relative to the page's directory, '/'-separated."""
    target = os.path.relpath(path.resolve(), Path(page_dir).resolve()) if page_dir else path
    return Path(target).as_posix()


class StudySection(Section):
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
            try:
                self.data[p.name] = json.loads(p.read_text())
            except json.JSONDecodeError as exc:
                raise ParameterError(f"study {d.name}: {p.name} is not JSON: {exc}") from None
        self.text = ""
        for name in ("summary.md", "README.md"):
            if (d / name).is_file():
                self.text = (d / name).read_text()
                break
        self.html = ""
        if (d / "study.md").is_file():  # a study of compare.sweep: shown as written
            self._from_study(d / "study.md")

    def _from_study(self, path: Path) -> None:
        from treeimpact.compare.sweep.study import markdown_body

        md = path.read_text()
        uris = {i["name"]: i["uri"] for i in self.images}
        shown = {m.group(1) for m in map(_IMAGE.match, md.splitlines()) if m}
        missing = sorted(shown - set(uris))
        if missing:
            raise ParameterError(f"study {self.directory.name}: study.md shows "
                                 f"{', '.join(missing)}, which the directory does not have")
        # the section is an h2: the study's title becomes an h3, its parts h4 and h5
        self.html = markdown_body(md, heading_shift=2, image_src=uris.__getitem__)
        self.images = [i for i in self.images if i["name"] not in shown]
        # report.md shows the study's own text, its figures linked from the report
        self.text = _demote(_IMAGE_LINK.sub(lambda m: f"{m.group(1)}({uris[m.group(2)]})", md), 2)

    def context(self) -> dict:
        return {"images": self.images, "text": self.text, "html": self.html,
                "files": sorted(self.data)}

    def to_json(self) -> dict:
        return {"directory": str(self.directory),
                "figures": sorted(p.name for p in self.directory.iterdir()
                                  if p.suffix.lower() in (".png", ".svg")),
                "data": self.data, "summary": self.text}
