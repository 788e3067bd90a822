"""Report section: which MuJoCo trunk, how many segments, which step, at what cost.

Renders ``data/trunks.json``, this package's data (read by importlib.resources: an installed
package has it too), which ``benchmarks/bench_trunks.py`` writes (the hinged chain and
MuJoCo's elastic rod, ``--trunk chain`` / ``--trunk flex``, against the exact continuum
through the same pad), as the table a MuJoCo user acts on: per tree, the cheapest run within
the file's target (1 %) of the continuum on x_max, then, for one tree, every segment count
at the runner's default step (static stiffness at a, the first two frequencies, x_max and
the energy delivered against the continuum, the default and largest stable steps, the cost).
Nothing is run here: the numbers are the file's, with where and when it was measured.
"""

from __future__ import annotations

import json
import math
from importlib import resources
from pathlib import Path

from treeimpact.analytic.results import to_jsonable

from .base import Section

#: The benchmark's result file: package data (pyproject's package-data ships it), the one
#: copy, which benchmarks/bench_trunks.py writes in a checkout.
TRUNKS_JSON = resources.files(__package__) / "data" / "trunks.json"
#: How the page names the file (its place in the checkout).
SOURCE = "compare/report/data/trunks.json"


def _record(data: dict) -> dict:
    """Where and when the file was measured (bench_trunks.py's record of its last run),
    None where the file does not say: the machine, its load average, the date, the code's
    commit; ``unrecorded``: the trees measured by an earlier run without a record."""
    rec = {k: data.get(k) for k in ("measured", "machine", "load_average", "git_commit",
                                     "mujoco")}
    scen = data.get("scenarios", {})
    rec["unrecorded"] = [n for n, s in scen.items() if not s.get("record")] \
        if rec["machine"] else []
    return rec


def _cheapest(sc: dict) -> list[dict]:
    """The file's cheapest run within the target per model, with its step as a multiple of
    the runner's default (``factor``) and the model's other numbers at that N."""
    rows = {(r["model"], r["segments"]): r for r in sc.get("rows", [])}
    out = []
    for c in sc.get("cheapest", []):
        row = rows.get((c["model"], c["segments"]), {})
        factor = c["dt"] / row["default_dt"] if row.get("default_dt") else math.nan
        out.append({**c, "factor": factor})
    return sorted(out, key=lambda c: c["wall_per_simulated_s"])


def _per_n(sc: dict) -> list[dict]:
    """Every (model, N) of one tree at the runner's default step (the first run)."""
    out = []
    for r in sc.get("rows", []):
        run = r["runs"][0] if r.get("runs") else {}
        w = list(r.get("omega_errors", [])) + [math.nan, math.nan]
        out.append({"model": r["model"], "segments": r["segments"],
                    "static_stiffness_error": r.get("static_stiffness_error"),
                    "omega_1_error": w[0], "omega_2_error": w[1],
                    "x_max_error": run.get("x_max_error"),
                    "energy_delivered_error": run.get("energy_delivered_error"),
                    "default_dt": r.get("default_dt"),
                    "trunk_stable_dt": r.get("trunk_stable_dt"),
                    "runner_limit": r.get("runner_limit"),
                    "wall_per_simulated_s": run.get("wall_per_simulated_s")})
    return out


class TrunksSection(Section):
    """The trunk-model benchmark as the user's table (see the module docstring)."""

    template = "trunks"
    title = "Which MuJoCo trunk, how many segments, which step"
    anchor = "trunks"

    def __init__(self, path=None, tree: str | None = None):
        """``path``: the result file (default :data:`TRUNKS_JSON`, the package's); ``tree``:
        the one whose every segment count is shown (default the file's first tree)."""
        self.path = TRUNKS_JSON if path is None else Path(path)
        self.data = json.loads(self.path.read_text()) if self.path.is_file() else None
        trees = list((self.data or {}).get("scenarios", {}))
        self.tree = tree if tree in trees else (trees[0] if trees else None)

    @property
    def available(self) -> bool:
        """Whether the benchmark's result file holds a tree to show."""
        return self.tree is not None

    def context(self) -> dict:
        """The template's names: the result file's record and target, the cheapest trunk
        per tree, and every segment count of the shown tree."""
        d = self.data or {}
        scen = d.get("scenarios", {})
        return {"source": SOURCE, "record": _record(d), "target": d.get("target"),
                "available": self.available, "tree": self.tree,
                "trees": [{"name": n, "beam": s.get("beam", {}), "cheapest": _cheapest(s)}
                          for n, s in scen.items()],
                "per_n": _per_n(scen[self.tree]) if self.available else [],
                "segments": sorted({r["segments"] for s in scen.values()
                                    for r in s.get("rows", [])})}

    def to_json(self) -> dict:
        """The context's data: source, record, target, tree, trees and per segment count."""
        ctx = self.context()
        return to_jsonable({k: ctx[k] for k in ("source", "record", "target", "tree",
                                                "trees", "per_n")})
