"""Benchmark: ``treeimpact --help``, the command line's start-up, beside the interpreter's own
(``python -c pass``, the floor no command goes below) and the ``--baseline`` commit's code
(default 6d0b3ff, before the commands' modules loaded only when named), in fresh processes,
interleaved so that machine noise hits all three alike.

Each is run ``--repeats`` times; printed and written are the median wall time and the median
CPU time (user + system of the child, less sensitive to the other jobs on the machine than
the wall), in ms, and the ratios. The help text of old and new is checked to be the same
bytes. Target (issue 52 item 5): ``treeimpact --help`` <= 0.3 s. Results:
benchmarks/results/help.json.

    python benchmarks/bench_help.py [--repeats 7] [--baseline 6d0b3ff]
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _results  # noqa: E402
from _baseline import baseline_tree, verify_import  # noqa: E402

#: The console script's own lines (pyproject's
#: ``treeimpact = "treeimpact.compare.interface.cli:main"``), run with ``-c`` for the old
#: tree, which has no console script of its own.
LAUNCHER = ("import sys; from treeimpact.compare.interface.cli import main; "
            "sys.exit(main(['--help']))")


def _run(argv: list, env: dict, cwd: str) -> tuple[float, float, str]:
    """Wall and CPU (user + system) seconds of one child process ``argv``, and its stdout;
    a failed child raises."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    proc = subprocess.run(argv, capture_output=True, text=True, env=env, cwd=cwd)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode != 0:
        raise RuntimeError(f"{argv} failed: {proc.stderr[-2000:]}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu, proc.stdout


def measure(sides: dict, repeats: int, cwd: str) -> tuple[dict, dict]:
    """Each side ``name -> (argv, env)`` run ``repeats`` times, the order reversed every
    other round; returns {name: {"wall_ms": [...], "cpu_ms": [...]}} and each side's stdout."""
    times = {n: {"wall_ms": [], "cpu_ms": []} for n in sides}
    outputs = {}
    names = list(sides)
    for r in range(repeats):
        for name in (names if r % 2 == 0 else names[::-1]):
            wall, cpu, out = _run(*sides[name], cwd)
            times[name]["wall_ms"].append(round(wall * 1e3, 1))
            times[name]["cpu_ms"].append(round(cpu * 1e3, 1))
            outputs[name] = out
    return times, outputs


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=7, help="runs of each command")
    ap.add_argument("--baseline", default="6d0b3ff", help="the old code's git revision")
    ap.add_argument("--out", help="results file (default benchmarks/results/help.json)")
    args = ap.parse_args(argv)
    start_load = _results.load_average()
    script = Path(sys.executable).with_name("treeimpact")  # the installed console script
    env = dict(os.environ)
    with baseline_tree(args.baseline) as old, tempfile.TemporaryDirectory() as cwd:
        old_env = {**env, "PYTHONPATH": os.pathsep.join([str(old), env.get("PYTHONPATH", "")])}
        assert verify_import(old).startswith(str(old)), "the old tree is not what runs"
        sides = {"help": ([str(script), "--help"], env),
                 "help_old": ([sys.executable, "-c", LAUNCHER], old_env),
                 "floor": ([sys.executable, "-c", "pass"], env)}
        times, outputs = measure(sides, args.repeats, cwd)
    same_text = outputs["help"] == outputs["help_old"]
    med = {n: {k: statistics.median(v) for k, v in t.items()} for n, t in times.items()}
    print(f"median of {args.repeats} fresh processes, ms (wall / CPU):")
    labels = {"help": "treeimpact --help", "help_old": f"{args.baseline} --help",
              "floor": "python -c pass"}
    for name, label in labels.items():
        print(f"  {label:<22}{med[name]['wall_ms']:8.1f} / {med[name]['cpu_ms']:6.1f}")
    print(f"  old / new: wall {med['help_old']['wall_ms'] / med['help']['wall_ms']:.2f}, CPU "
          f"{med['help_old']['cpu_ms'] / med['help']['cpu_ms']:.2f}; new / floor: wall "
          f"{med['help']['wall_ms'] / med['floor']['wall_ms']:.2f}; help text identical: "
          f"{same_text}")
    numbers = {f"{name}.{k}_ms": round(v, 1) for name, m in med.items() for k, v in
               (("wall", m["wall_ms"]), ("cpu", m["cpu_ms"]))}
    wall = {n: m["wall_ms"] for n, m in med.items()}
    numbers |= {"ratio_old_new_wall": round(wall["help_old"] / wall["help"], 2),
                "ratio_new_floor_wall": round(wall["help"] / wall["floor"], 2)}
    _results.write("help", numbers, {"repeats": args.repeats, "baseline": args.baseline,
                                     "help_text_identical": same_text, "runs": times},
                   started_load=start_load, out=Path(args.out) if args.out else None)
    return 0 if same_text else 1


if __name__ == "__main__":
    raise SystemExit(main())
