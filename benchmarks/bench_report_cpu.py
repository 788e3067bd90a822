"""``make report``'s CPU by part on a shared machine, and what one Sobol evaluation of the
default study costs before and after issue 52 item 3 (a benchmark, not a test; nothing is
asserted).

Run: ``.venv/bin/python benchmarks/bench_report_cpu.py [--make] [--rounds N] [--n N]``.

1. The Sobol rows, old and new side by side in one process, alternately, ``--rounds``
   times each: central-leader's Sobol sweep of ``--n`` base samples (``workers=0``) with
   the base tree's run made for every row (the old sweep: one run per record, as
   compare.studies.sweep.plan repeats a run cheaper than its analysis) and with it made once per
   worker call (compare.studies.sweep.execute ``_LAST_RUN``); the CPU per row (time.process_time),
   the medians and their ratio, and each evaluation's runs alone (Newton, soft, beam at
   its default, the tree varied: compare.studies.study_inputs.vary), the floor of a row.
2. ``--make``: ``make report`` (OUT in a temporary folder, removed) with its process tree's
   CPU sampled every 0.1 s (psutil: user + system of every process below make, the
   forkserver's workers included, which ``RUSAGE_CHILDREN`` never sees); per part (the
   report's own processes, the default study's, the design map's: each child counted with
   the ``sweep --preset`` process it descends from) and the main process of each. Unlike
   bench_make.py ``--parts`` (the machine's busy time less a background sampled before),
   this holds on a machine other jobs keep busy; the wall time then grows with the load,
   recorded at the start and the end.

Writes ``benchmarks/results/report_cpu.json``.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")
sys.path.insert(0, str(Path(__file__).resolve().parent))
import _results  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
#: The parts of make report, by the ``sweep --preset`` argument their processes descend from.
PARTS = {"--preset default": "study_default", "--preset design": "study_design"}


def _part(info: dict, pid: int) -> str:
    """The part of ``pid`` (:data:`PARTS`, else "report") from its ancestors in ``info``."""
    while pid in info:
        for flag, name in PARTS.items():
            if flag in info[pid]["cmd"]:
                return name
        pid = info[pid]["ppid"]
    return "report"


def tree_cpu(cmd: list[str]) -> dict:
    """``cmd`` run from the repository, its process tree sampled every 0.1 s (psutil):
    {wall_s, cpu_s, parts: {part: CPU s}, main: {part: its top process's CPU s}, load}."""
    import psutil

    load0, t0 = _results.load_average(), time.perf_counter()
    proc = subprocess.Popen(cmd, cwd=ROOT, stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)
    root, info = psutil.Process(proc.pid), {}
    while proc.poll() is None:
        try:
            procs = [root, *root.children(recursive=True)]
        except psutil.NoSuchProcess:
            break
        for p in procs:
            try:
                with p.oneshot():
                    ct = p.cpu_times()
                    d = info.setdefault(p.pid, {"ppid": p.ppid(), "cmd": " ".join(p.cmdline())})
                    d["cpu"] = ct.user + ct.system
            except (psutil.NoSuchProcess, psutil.ZombieProcess, psutil.AccessDenied):
                pass
        time.sleep(0.1)
    wall = time.perf_counter() - t0
    parts, main = {}, {}
    for pid, d in info.items():
        part = _part(info, pid)
        parts[part] = parts.get(part, 0.0) + d.get("cpu", 0.0)
    for part, mark in (("report", "treeimpact report"), *((v, k) for k, v in PARTS.items())):
        own = [pid for pid, d in info.items() if mark in d["cmd"] and "forkserver" not in d["cmd"]]
        if own:  # its main process: the first started (the workers it forks come after)
            main[part] = info[min(own)].get("cpu", 0.0)
    return {"wall_s": round(wall, 1), "cpu_s": round(sum(parts.values()), 1),
            "parts": {k: round(v, 1) for k, v in parts.items()},
            "main": {k: round(v, 1) for k, v in main.items()}, "rc": proc.returncode,
            "load_start": load0, "load_end": _results.load_average()}


def sobol_rows(n: int, reuse: bool) -> float:
    """CPU s per row of central-leader's Sobol sweep of ``n`` base samples in this process,
    with the base tree's run reused across a worker call's tasks (``reuse``) or made per
    row (the old sweep)."""
    from treeimpact.compare.runs.cache import resolve_scenario
    from treeimpact.compare.studies.sobol import sobol_sweep
    from treeimpact.compare.studies.study_inputs import free_inputs
    from treeimpact.compare.studies.sweep import execute
    from treeimpact.compare.studies.sweep.run import run_sweeps

    scen = resolve_scenario("central-leader")
    rows = n * (len(free_inputs(scen)) + 2)  # the Saltelli design's, no second order
    with tempfile.TemporaryDirectory(prefix="bench-sobol-") as tmp:
        spec = sobol_sweep(scen, Path(tmp) / "s", n)
        old = execute._run
        if not reuse:  # the old execute: one attempt per task
            execute._run = lambda task: execute.attempt(task.backend, task.scenario,
                                                        task.options)
        try:
            c0 = time.process_time()
            run_sweeps([spec], workers=0, progress=False)
            cpu = time.process_time() - c0
        finally:
            execute._run = old
    return cpu / rows


def evaluation_parts(n: int) -> dict:
    """CPU ms of each run of one Sobol evaluation (the tree varied, Newton, soft, beam),
    the mean over central-leader's first ``n`` x 8 design rows."""
    from treeimpact.analytic.contact.soft import simulate_soft
    from treeimpact.analytic.continuum.beam_impact import simulate_beam
    from treeimpact.analytic.impact.simulate import simulate
    from treeimpact.compare.runs.cache import resolve_scenario
    from treeimpact.compare.studies.sobol import sobol_design
    from treeimpact.compare.studies.study_inputs import (free_inputs, inputs_of, problem,
                                                         ranges_of, vary)

    s = resolve_scenario("central-leader")
    names = free_inputs(s)
    X = sobol_design(n, names, spec=problem(names, ranges_of(s, names)))
    t = {"vary": 0.0, "newton": 0.0, "soft": 0.0, "beam": 0.0}
    for row in X:
        c = [time.process_time()]
        scen, theory = vary(s, inputs_of(s) | dict(zip(names, map(float, row))))
        c.append(time.process_time())
        simulate(scen, samples=2)
        c.append(time.process_time())
        simulate_soft(scen)
        c.append(time.process_time())
        simulate_beam(scen, beam_theory=theory)
        c.append(time.process_time())
        for k, a, b in zip(t, c, c[1:]):
            t[k] += b - a
    return {k: round(v / len(X) * 1e3, 2) for k, v in t.items()}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--make", action="store_true", help="also time make report's process tree")
    p.add_argument("--rounds", type=int, default=3, help="rounds of old and new Sobol rows")
    p.add_argument("--n", type=int, default=16, help="base samples of the timed Sobol sweep")
    p.add_argument("--out", help="results file (default benchmarks/results/report_cpu.json)")
    args = p.parse_args(argv)
    start_load = _results.load_average()
    runs: dict = {"old": [], "new": []}
    sobol_rows(4, True)  # imports and first calls out of the timing
    for _ in range(args.rounds):
        for side in runs:
            runs[side].append(round(sobol_rows(args.n, side == "new") * 1e3, 2))
            print(side, runs[side][-1], "ms CPU a row", flush=True)
    numbers = {f"sobol.row_ms.{k}": statistics.median(v) for k, v in runs.items()}
    numbers["sobol.row_ms.ratio"] = round(numbers["sobol.row_ms.old"]
                                          / numbers["sobol.row_ms.new"], 2)
    parts = evaluation_parts(args.n)
    numbers |= {f"sobol.eval_ms.{k}": v for k, v in parts.items()}
    numbers["sobol.eval_ms.floor"] = round(sum(parts.values()), 2)
    details = {"rounds": runs, "n": args.n, "tree": "central-leader"}
    if args.make:
        with tempfile.TemporaryDirectory(prefix="bench-report-cpu-") as tmp:
            made = tree_cpu(["make", "report", f"OUT={tmp}/report"])
        print(made, flush=True)
        numbers |= {"make_report.wall_s": made["wall_s"], "make_report.cpu_s": made["cpu_s"]}
        numbers |= {f"make_report.cpu_s.{k}": v for k, v in made["parts"].items()}
        numbers |= {f"make_report.main_cpu_s.{k}": v for k, v in made["main"].items()}
        numbers["make_report.cpu_floor_s"] = round(made["cpu_s"]
                                                   / len(os.sched_getaffinity(0)), 1)
        details["make_report"] = made
    _results.write("report_cpu", numbers, details, started_load=start_load,
                   out=Path(args.out) if args.out else None)
    return 0


if __name__ == "__main__":
    sys.exit(main())
