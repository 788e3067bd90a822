"""Report section: one model-validity study (validity map, speed-accuracy curve, ...).

A study directory is read as it is: its figures (``*.png``, ``*.svg``, sorted by name) are
embedded, its ``*.json`` files are carried into report.json, and a ``summary.md`` (or
``README.md``) is shown as its text. The section's title is the directory's name.
"""

from __future__ import annotations

import json
from pathlib import Path

from analytic.parameters import ParameterError

from . import figures
from .base import Section


class StudySection(Section):
    template = "study"

    def __init__(self, directory):
        d = Path(directory)
        if not d.is_dir():
            raise ParameterError(f"study_dirs: {str(d)!r} is not a directory")
        self.directory = d
        self.title = f"Study: {d.name}"
        self.anchor = f"study-{d.name}"
        self.images = [{"name": p.name, "uri": figures.image_figure(p)}
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

    def context(self) -> dict:
        return {"images": self.images, "text": self.text, "files": sorted(self.data)}

    def to_json(self) -> dict:
        return {"directory": str(self.directory), "figures": [i["name"] for i in self.images],
                "data": self.data, "summary": self.text}
