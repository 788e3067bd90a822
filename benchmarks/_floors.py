"""What ``make report`` and ``make test`` spend against what their physics needs (bench_make.py
``--floors``; docs/report.md, "The floor").

From a finished ``make report`` folder: the report's own runs (report.json) per engine and
trunk, the study's and the design map's sweep rows (each sweep's results.csv) per part and
backend, the sections' wall times, the design map's analysis (design.json ``cost``). Each
engine kind's CPU time per step is measured here, one run of it in a fresh process
(``time.process_time``, so the machine's load leaves it nearly alone): the physics' floor is
the steps the runs took at their stable step times that, over the machine's 2 cores. From a
pytest ``--durations=0`` log of the suite: seconds per test file and in total, the tests' own
time summed over pytest-xdist's workers (the suite's CPU in tests, not its wall time).
"""

from __future__ import annotations

import csv
import json
import re
import subprocess
import sys
import time
from collections import defaultdict
from pathlib import Path

CORES = 2  # the project's machine (docs/benchmarks.md)
REPORT_GOAL_S, TEST_GOAL_S = 30.0, 240.0  # issue 39, item 3
#: Test files whose time is engine runs (MuJoCo, Bullet) and what they check.
ENGINE_FILES = ("test_mujoco", "test_bullet", "test_engine", "test_cross_checks", "test_chain",
                "test_flex", "test_rollout", "test_soft_contact")

_CHILD = r"""
import json, sys, time
from treeimpact.analytic.model.scenario import load_scenario
from treeimpact.compare.runs.backends import get_backend
name, backend, options = sys.argv[1], sys.argv[2], json.loads(sys.argv[3])
scenario, b = load_scenario(name), get_backend(backend)
start = time.process_time()
result = b._load(b.simulate_ref)(scenario, **options)
cpu = time.process_time() - start
print(json.dumps({"cpu_s": cpu, "steps": result.extra["stepping"]["steps"]}))
"""


def _kind(backend: str, options: dict) -> str:
    """'mujoco chain 12', 'bullet sdof', 'beam': an engine run's trunk and segment count."""
    trunk = options.get("trunk")
    if backend not in ("mujoco", "bullet") or trunk is None:
        return backend
    seg = options.get("segments")
    return f"{backend} {trunk}" + (f" {int(float(seg))}" if seg not in (None, "") else "")


def report_runs(folder: Path) -> tuple[dict, dict]:
    """The report's own runs per kind {runs, steps, wall_s} and one (scenario, backend,
    options) per engine kind to time; from report.json."""
    kinds, example = defaultdict(lambda: {"runs": 0, "steps": 0, "wall_s": 0.0}), {}
    for r in json.loads((folder / "report.json").read_text())["runs"]["runs"]:
        k = _kind(r["backend"], r["options"])
        kinds[k]["runs"] += 1
        kinds[k]["wall_s"] += r["wall_s"]
        if r.get("stepping"):
            kinds[k]["steps"] += r["stepping"]["steps"]
            example.setdefault(k, (r["scenario"], r["backend"], r["options"]))
    return dict(kinds), example


def sweep_runs(folder: Path) -> dict:
    """Every sweep's rows under the folder (the study's, the design map's, the report's
    scans) per part and kind: {runs, steps, wall_s}; an engine row's steps are t_end / dt."""
    out = defaultdict(lambda: {"runs": 0, "steps": 0, "wall_s": 0.0})
    for path in sorted(folder.glob("*/**/results.csv")):
        part = str(path.parent.relative_to(folder))
        if part == "study":  # the study's merged table repeats its sweeps' rows
            continue
        with path.open() as f:
            for row in csv.DictReader(f):
                seg = row.get("model.segments") or None
                opts = {"trunk": "chain", "segments": seg} if seg else {}
                k = f"{part}: {_kind(row['backend'], opts)}"
                out[k]["runs"] += 1
                out[k]["wall_s"] += float(row["wall_s"] or 0.0)
                if seg and row.get("model.dt"):
                    out[k]["steps"] += round(float(row["t_end"]) / float(row["model.dt"]))
    return dict(out)


def cpu_per_step(example: dict) -> dict:
    """CPU seconds per step of each engine kind: one of its runs in a fresh process."""
    out = {}
    for kind, (scenario, backend, options) in sorted(example.items()):
        proc = subprocess.run([sys.executable, "-c", _CHILD, scenario, backend,
                               json.dumps(options)], capture_output=True, text=True, check=True)
        r = json.loads(proc.stdout)
        out[kind] = r["cpu_s"] / r["steps"]
    return out


_LINE = re.compile(r"^([\d.]+)s\s+(call|setup|teardown)\s+(\S+?)::")


def test_durations(log: Path) -> dict:
    """A pytest durations log (``--durations=0`` lines, or one ``SECONDSs WHEN NODEID`` line
    per phase): seconds in total, per file, and in the engine files (:data:`ENGINE_FILES`)."""
    per_file: dict = defaultdict(float)
    calls = 0
    for line in log.read_text().splitlines():
        m = _LINE.match(line.strip())
        if m:
            per_file[m.group(3)] += float(m.group(1))
            calls += m.group(2) == "call"
    total = sum(per_file.values())
    engine = sum(s for f, s in per_file.items() if any(e in f for e in ENGINE_FILES))
    top = dict(sorted(per_file.items(), key=lambda kv: -kv[1])[:15])
    return {"total_s": total, "engine_files_s": engine, "files": len(per_file), "tests": calls,
            "top_files_s": {k: round(v, 1) for k, v in top.items()}}


def _report_numbers(folder: Path) -> tuple[dict, dict]:
    """The report's parts and its physics floor (numbers, details)."""
    own, example = report_runs(folder)
    sweeps = sweep_runs(folder)
    per_step = cpu_per_step(example)
    page = json.loads((folder / "report.json").read_text())["runs"]["wall_s"]
    design = json.loads((folder / "design" / "design.json").read_text()).get("cost", {})
    engine_cpu = sum(own[k]["steps"] * s for k, s in per_step.items())
    study_cpu = 0.0
    for k, v in sweeps.items():
        kind = k.split(": ", 1)[1]
        match = [s for e, s in per_step.items() if e.replace(" chain", "") ==
                 kind.replace(" chain", "")]
        study_cpu += v["steps"] * match[0] if match and v["steps"] else 0.0
    exact_s = sum(v["wall_s"] for k, v in own.items() if k in ("beam", "soft", "analytic")) \
        + sum(v["wall_s"] for k, v in sweeps.items() if not v["steps"])
    physics = engine_cpu + study_cpu + exact_s
    n = {"report.wall_s": round(page["total"], 1),
         "report.engine_wall_s": round(sum(v["wall_s"] for v in own.values()
                                           if v["steps"]), 1),
         "report.engine_cpu_s": round(engine_cpu, 1),
         "report.study_engine_cpu_s": round(study_cpu, 1),
         "report.exact_runs_s": round(exact_s, 1),
         "report.fits_wall_s": round(page.get("record fits (process pool)", 0.0), 1),
         "report.design_cpu_s": round(design.get("cells", 0) * design.get("cpu_s_per_cell", 0),
                                      1),
         "report.engine_floor_s": round((engine_cpu + study_cpu) / CORES, 1),
         "report.physics_cpu_s": round(physics, 1),
         "report.floor_s": round(physics / CORES, 1), "report.goal_s": REPORT_GOAL_S}
    d = {"report_runs": own, "sweep_runs": sweeps, "sections_wall_s": page,
         "cpu_s_per_step": per_step, "design_cost": design}
    return n, d


def collect_s(root: Path) -> float:
    """Wall seconds of ``pytest --collect-only tests compare`` (imports and collection), which
    ``make test`` pays once per pass: the suite and each kernel's numerics rerun."""
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "pytest", "--collect-only", "-q", "-p",
                    "no:cacheprovider", "tests", "compare"], cwd=root, capture_output=True,
                   check=True)
    return time.perf_counter() - t0


def floors(folder: Path, durations: Path | None, root: Path,
           report_cpu_s: float | None = None) -> tuple[dict, dict]:
    """floors.json's numbers and details: the report's parts and floor, and the suite's.
    ``report_cpu_s``: the CPU seconds (user + sys) of the command that wrote ``folder``."""
    numbers, details = _report_numbers(folder)
    if report_cpu_s is not None:
        numbers["report.cpu_s"] = round(report_cpu_s, 1)
        numbers["report.cpu_floor_s"] = round(report_cpu_s / CORES, 1)
        numbers["report.non_engine_cpu_s"] = round(
            report_cpu_s - numbers["report.engine_cpu_s"] - numbers["report.study_engine_cpu_s"], 1)
    if durations is not None:
        t = test_durations(durations)
        numbers |= {"test.suite_s": round(t["total_s"], 1),
                    "test.engine_files_s": round(t["engine_files_s"], 1),
                    "test.tests_timed": t["tests"],
                    "test.engine_files_pct": round(100 * t["engine_files_s"] / t["total_s"]),
                    "test.collect_s": round(collect_s(root), 1),
                    "test.goal_s": TEST_GOAL_S}
        details["test"] = t
    return numbers, details
