"""Report section: every backend run behind the page, its status, reason and wall time."""

from __future__ import annotations

from treeimpact.analytic.results import to_jsonable

from .base import Section


class RunsSection(Section):
    template = "runlog"
    title = "Runs, skips and timings"
    anchor = "runs"

    def __init__(self, cache, wall_s: dict | None = None):
        self.runs = list(cache)
        self.timings = cache.timings()
        self.wall_s = wall_s or {}

    def context(self) -> dict:
        return {"runs": self.runs, "timings": self.timings, "wall": self.wall_s}

    def to_json(self) -> dict:
        return to_jsonable({"runs": [r.to_json() for r in self.runs], "timings": self.timings,
                       "wall_s": self.wall_s})
