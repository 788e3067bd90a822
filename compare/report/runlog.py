"""Report section: every backend run behind the page, its status, reason and wall time (an
engine run's steps, wall time per step and what set its step beside it).

The page lists the runs that did not succeed first (with their reasons), then every run in a
collapsed list, options rounded to what a reader needs (3 significant digits, with units).
"""

from __future__ import annotations

from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.results import to_jsonable
from treeimpact.compare.runs.backends import BACKENDS

from .base import Section, options_text, tidy


def option_units(backend: str) -> dict:
    """Option name -> unit of a backend's options ({} for a backend not known here)."""
    b = BACKENDS.get(backend)
    if b is None:
        return {}
    try:
        return {k: o.unit for k, o in b.options().items()}
    except ParameterError:  # its package is not installed here: no units to show
        return {}


def run_rows(runs) -> list[dict]:
    """The page's rows of ``runs``: runs that did not succeed first, then by scenario,
    backend and options; options and reasons rounded (:func:`.base.options_text`,
    :func:`.base.tidy`)."""
    units = {}
    rows = []
    for r in runs:
        if r.backend not in units:
            units[r.backend] = option_units(r.backend)
        rows.append({"scenario": r.scenario, "backend": r.backend, "ok": r.ok,
                     "options": options_text(r.options, units[r.backend]),
                     "status": r.status, "wall_s": r.wall_s, "reason": tidy(r.reason),
                     "stepping": r.stepping})
    return sorted(rows, key=lambda x: (x["ok"], x["scenario"], x["backend"], x["options"]))


class RunsSection(Section):
    """Every run behind the page (``cache``, a compare.runs.cache.RunCache), its status, reason
    and wall time, with the report's stages' wall times ``wall_s`` (stage -> s)."""

    template = "runlog"
    title = "Runs, skips and timings"
    anchor = "runs"

    def __init__(self, cache, wall_s: dict | None = None):
        self.runs = list(cache)
        self.timings = cache.timings()
        self.wall_s = wall_s or {}

    def context(self) -> dict:
        """The template's names: the run rows, the failed ones, counts per status, timings
        and wall times."""
        rows = run_rows(self.runs)
        counts: dict = {}
        for r in rows:
            counts[r["status"]] = counts.get(r["status"], 0) + 1
        return {"rows": rows, "failed": [r for r in rows if not r["ok"]], "counts": counts,
                "timings": self.timings, "wall": self.wall_s}

    def to_json(self) -> dict:
        """Every run, the timings and the stages' wall times (s)."""
        return to_jsonable({"runs": [r.to_json() for r in self.runs], "timings": self.timings,
                            "wall_s": self.wall_s})
