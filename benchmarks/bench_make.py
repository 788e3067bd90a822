"""Wall time of the README's two commands, ``make report`` and ``make test`` (a benchmark,
not a test; nothing is asserted).

Run: ``.venv/bin/python benchmarks/bench_make.py [--install] [--skip-test]``. Measured in one
run, one after the other, from the repository:

1. ``--install``: the set-up both commands start with on a fresh machine (``make``'s venv
   from requirements.lock and the project), into a temporary folder, pip's cache off;
2. ``make report`` with OUT in a temporary folder: its wall time, and the default study's
   own (``study.json`` wall_s, its runs' mean wall time per backend) and the report's own
   (``report.json``), which run side by side (``treeimpact report --with-study``);
3. ``make test``: its wall time and the test count.

Each command's CPU is the machine's busy time over it less the background sampled just
before (:func:`_busy_timed`), and ``make test``'s floor that CPU over the cores.

Writes ``benchmarks/results/make.json`` (the README quotes it); every temporary folder is
removed. The load average before and after is recorded: on a shared machine the times
grow with it.

``--against REV [--rounds N]`` times only ``make test``: as REV's Makefile runs it (that
Makefile, ``make -f``, on today's tree and tests: e.g. 25cfad1, the serial suite) against
today's, alternately (old, new, old, new, ...), N rounds; writes
``benchmarks/results/make_test.json``: each side's median wall time and CPU time (its
processes' user + sys), the ratio, and every run's load average at its start.

``--parts`` runs make report's three parts one after the other, each alone (``treeimpact
report``; ``sweep --preset default``; ``sweep --preset design``), then ``make report``: the
wall time and the CPU of each as the machine's busy time (/proc/stat, which sees the process
pools' workers), less the background measured just before; writes
``benchmarks/results/report_parts.json``.

``--floors REPORT_DIR [--durations LOG]`` runs neither command: it reads a finished ``make
report`` folder and the log of ``pytest tests compare --durations=0`` (the suite's
environment) and writes ``benchmarks/results/floors.json``, what each part costs against
what the physics needs (``_floors.py``; docs/report.md, "The floor").
"""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _results  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


def _timed(cmd: list[str], env=None) -> tuple[float, str]:
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, env=env)
    wall = time.perf_counter() - t0
    return wall, proc.stdout + proc.stderr


def _cpu_children() -> float:
    """CPU seconds (user + sys) of this process's finished children so far."""
    import resource

    ru = resource.getrusage(resource.RUSAGE_CHILDREN)
    return ru.ru_utime + ru.ru_stime


def _machine_busy_s() -> float:
    """CPU seconds the whole machine has been busy since boot (/proc/stat: user, nice,
    system, irq, softirq, steal). A command's CPU is its difference over the command on a
    quiet machine: it counts every process of the command, also the process pools'
    workers forked by multiprocessing's forkserver, whose CPU ``RUSAGE_CHILDREN`` never
    sees (the forkserver is not waited for)."""
    fields = Path("/proc/stat").read_text().split("\n", 1)[0].split()[1:]
    user, nice, system, _idle, _iowait, irq, softirq, steal = map(int, fields[:8])
    return (user + nice + system + irq + softirq + steal) / os.sysconf("SC_CLK_TCK")


def _busy_timed(cmd: list[str]) -> tuple[float, float, float, str]:
    """(wall s, machine-busy CPU s, the machine's busy CPU s over the same time before it
    (what other processes spend: subtract it, or distrust the figure when it is large), log)
    of ``cmd`` run from the repository."""
    idle0 = _machine_busy_s()
    time.sleep(IDLE_PROBE_S)
    background = (_machine_busy_s() - idle0) / IDLE_PROBE_S
    busy0 = _machine_busy_s()
    wall, log = _timed(cmd)
    return wall, _machine_busy_s() - busy0, background * wall, log


#: Seconds the machine's background CPU is sampled before a command (:func:`_busy_timed`).
IDLE_PROBE_S = 5.0
#: make report's parts, each run alone by ``--parts``: the report's own runs, sweeps, fits and
#: figures; the default study; the design map (make report runs the three side by side).
PARTS = {"report": ["report"], "study default": ["sweep", "--preset", "default"],
         "study design": ["sweep", "--preset", "design"]}


def parts() -> tuple[dict, dict]:
    """make report's three parts run one after the other, each alone: wall and
    machine-busy CPU (s), background CPU over the same time; and make report itself."""
    numbers, details = {}, {}
    with tempfile.TemporaryDirectory(prefix="bench-make-") as tmp:
        for name, args in PARTS.items():
            cmd = [str(ROOT / ".venv" / "bin" / "treeimpact"), *args, "--out", f"{tmp}/{name}"]
            wall, cpu, bg, log = _busy_timed(cmd)
            key = name.replace(" ", "_")
            numbers |= {f"parts.{key}.wall_s": round(wall, 1),
                        f"parts.{key}.cpu_s": round(cpu - bg, 1)}
            details[name] = {"background_cpu_s": round(bg, 1), "tail": log[-200:]}
        wall, cpu, bg, log = _busy_timed(["make", "report", f"OUT={tmp}/make-report"])
        numbers |= {"parts.make_report.wall_s": round(wall, 1),
                    "parts.make_report.cpu_s": round(cpu - bg, 1)}
        details["make report"] = {"background_cpu_s": round(bg, 1), "tail": log[-200:]}
    own = sum(v for k, v in numbers.items() if k.endswith(".cpu_s") and "make_report" not in k)
    numbers["parts.sum_cpu_s"] = round(own, 1)
    # the floor: every core busy throughout
    numbers["parts.cpu_floor_s"] = round(own / len(os.sched_getaffinity(0)), 1)
    return numbers, details


def _make_test(makefile: Path | None) -> dict:
    """One ``make test`` (``makefile``: ``make -f`` it instead of the repository's): wall and
    CPU time (s), the load average at its start, exit code and pytest's summary lines."""
    cmd = ["make"] + (["-f", str(makefile)] if makefile else []) + ["test"]
    load, cpu = _results.load_average(), _cpu_children()
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    log = proc.stdout + proc.stderr
    return {"wall_s": round(wall, 1), "cpu_s": round(_cpu_children() - cpu, 1),
            "load_start": load, "rc": proc.returncode,
            "summary": re.findall(r"(?:=+ )?(\d+ (?:passed|failed).*) in [\d.]+s", log)}


def against(rev: str, rounds: int) -> tuple[dict, dict]:
    """``make test`` as ``rev``'s Makefile runs it against today's, alternately, ``rounds``
    times each: (numbers, details) for :func:`_results.write` (medians, ratio old / new)."""
    import statistics

    runs: dict = {"old": [], "new": []}
    with tempfile.TemporaryDirectory(prefix="bench-make-") as tmp:
        old = Path(tmp) / "Makefile"
        old.write_text(subprocess.run(["git", "show", f"{rev}:Makefile"], cwd=ROOT, check=True,
                                      capture_output=True, text=True).stdout)
        for _ in range(rounds):
            for side, makefile in (("old", old), ("new", None)):
                runs[side].append(_make_test(makefile))
                print(side, runs[side][-1], flush=True)
    numbers = {}
    for side, rs in runs.items():
        numbers[f"test_s.{side}"] = round(statistics.median(r["wall_s"] for r in rs), 1)
        numbers[f"test_cpu_s.{side}"] = round(statistics.median(r["cpu_s"] for r in rs), 1)
        numbers[f"test_s.{side}_range"] = _results.span(r["wall_s"] for r in rs)
    numbers["test_s.ratio"] = round(numbers["test_s.old"] / numbers["test_s.new"], 2)
    numbers["test.failed_runs"] = sum(r["rc"] != 0 for rs in runs.values() for r in rs)
    return numbers, {"against": rev, "rounds": rounds, "runs": runs}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--install", action="store_true", help="also time a fresh install")
    p.add_argument("--skip-test", action="store_true", help="do not time make test")
    p.add_argument("--out", help="results file (default benchmarks/results/make.json)")
    p.add_argument("--floors", metavar="REPORT_DIR", help="write floors.json from a finished "
                   "make report folder instead of running the commands")
    p.add_argument("--durations", metavar="LOG", help="with --floors: a pytest "
                   "--durations=0 log of the suite")
    p.add_argument("--report-cpu", type=float, metavar="S", help="with --floors: the CPU "
                   "seconds of make report (default: report_parts.json's, from --parts)")
    p.add_argument("--against", metavar="REV", help="time only make test: REV's Makefile "
                   "against today's, alternately (writes make_test.json)")
    p.add_argument("--rounds", type=int, default=2, help="with --against: runs per side")
    p.add_argument("--parts", action="store_true", help="time make report's three parts "
                   "alone and make report, with the machine's busy CPU (writes "
                   "report_parts.json)")
    args = p.parse_args(argv)
    if args.parts:
        start_load = _results.load_average()
        numbers, details = parts()
        _results.write("report_parts", numbers, details, started_load=start_load,
                       out=Path(args.out) if args.out else None)
        return 0
    if args.against:
        start_load = _results.load_average()
        numbers, details = against(args.against, args.rounds)
        _results.write("make_test", numbers, details, started_load=start_load,
                       out=Path(args.out) if args.out else None)
        return 0
    if args.floors:
        import _floors

        start_load = _results.load_average()
        cpu = args.report_cpu
        if cpu is None:  # make report's CPU as --parts measured it (the machine's busy time)
            parts_file = ROOT / "benchmarks" / "results" / "report_parts.json"
            cpu = json.loads(parts_file.read_text())["numbers"]["parts.make_report.cpu_s"]
        numbers, details = _floors.floors(Path(args.floors),
                                          Path(args.durations) if args.durations else None, ROOT,
                                          cpu)
        _results.write("floors", numbers, details, started_load=start_load,
                       out=Path(args.out) if args.out else None)
        return 0
    start_load = _results.load_average()
    numbers, details = {}, {}
    with tempfile.TemporaryDirectory(prefix="bench-make-") as tmp:
        if args.install:
            venv = Path(tmp) / "venv"
            env = dict(os.environ, PIP_NO_CACHE_DIR="1")
            wall, log = _timed(["make", f"VENV={venv}", f"{venv}/.installed"], env)
            numbers["install_s"] = round(wall, 1)
            details["install_tail"] = log[-500:]
        wall, cpu, bg, log = _busy_timed(["make", "report", f"OUT={tmp}/report"])
        numbers["report_cpu_s"] = round(cpu - bg, 1)  # every process's, less the background
        study = json.loads((Path(tmp) / "report" / "study" / "study.json").read_text())
        page = json.loads((Path(tmp) / "report" / "report.json").read_text())
        numbers["report_s"] = round(wall, 1)
        numbers["report.study_s"] = round(study["wall_s"], 1)  # beside the report's own
        numbers["report.own_s"] = round(page["runs"]["wall_s"]["total"], 1)
        for backend, t in study["timings"].items():
            numbers[f"report.study_run_s.{backend}"] = float(f"{t['mean_wall_s']:.3g}")
        details["report_tail"] = log[-300:]
    if not args.skip_test:
        wall, cpu, bg, log = _busy_timed(["make", "test"])
        numbers["test_cpu_s"] = round(cpu - bg, 1)
        numbers["test_cpu_floor_s"] = round((cpu - bg) / len(os.sched_getaffinity(0)), 1)
        summary = re.findall(r"=+ (.*(?:passed|failed).*) in [\d.]+s", log)
        numbers["test_s"] = round(wall, 1)
        details["test_summary"] = summary[-1] if summary else log[-300:]
    _results.write("make", numbers, details, started_load=start_load,
                   out=Path(args.out) if args.out else None)
    return 0


if __name__ == "__main__":
    sys.exit(main())
