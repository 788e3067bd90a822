"""Benchmark (not a test) of the run budget's cost model: ``python benchmarks/bench_cost.py``.

Every backend's :class:`treeimpact.analytic.budget.StepCost` (seconds and bytes per step or
sample) estimates a run before it starts; a run beyond the budget is refused on that
estimate. Here each backend runs at two lengths per model size, each in a fresh process
(its peak RSS its own), and the marginal cost of the extra steps (the difference of the two,
so imports and set-up drop out; in CPU time, which a shared machine's load leaves nearly
alone and which is the wall time of these single-threaded runs on an idle machine) is set
against the estimate: ratio = estimate / measured, median of the repeats. A ratio near 1
(0.5-2) is what the budget needs; below 1 the budget admits runs that cost more than it
says.

Options: ``--repeats N`` (default 3), ``--quick`` (the small sizes only), ``--write`` (the
medians to benchmarks/results/cost.json, which tests/test_budget.py holds the cost model to).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import time
from pathlib import Path

RESULTS = Path(__file__).resolve().parent / "results" / "cost.json"

#: (label, scenario, backend, options, the two t_end (s)); the sizes span the shipped runs
#: and the large ones the budget exists for.
CASES = [
    ("mujoco sdof", "central-leader", "mujoco", {"trunk": "sdof"}, (0.1, 0.4)),
    ("mujoco chain 8", "central-leader", "mujoco", {"segments": 8}, (0.05, 0.2)),
    ("mujoco chain 32", "central-leader", "mujoco", {"segments": 32}, (0.005, 0.02)),
    ("mujoco chain 64", "central-leader", "mujoco", {"segments": 64}, (0.001, 0.004)),
    ("mujoco chain 128", "central-leader", "mujoco", {"segments": 128}, (0.0001, 0.0004)),
    ("bullet sdof", "central-leader", "bullet", {"trunk": "sdof"}, (0.1, 0.4)),
    ("bullet chain 8", "central-leader", "bullet", {"segments": 8}, (0.05, 0.2)),
    ("bullet chain 32", "central-leader", "bullet", {"segments": 32}, (0.002, 0.008)),
    ("bullet chain 100", "central-leader", "bullet", {"segments": 100}, (0.0001, 0.0004)),
    ("soft, 1 us contact", "central-leader", "soft", {"contact_duration": 1e-6},
     (0.005, 0.02)),
    ("beam", "central-leader", "beam", {}, (1.0, 4.0)),
]
QUICK = ("mujoco sdof", "mujoco chain 8", "bullet chain 8", "soft, 1 us contact", "beam")

#: One run in a fresh process: its wall time, peak RSS, steps and the estimate per step.
_CHILD = r"""
import json, resource, sys, time
from treeimpact.analytic.model.scenario import load_scenario
from treeimpact.compare.runs.backends import get_backend
name, backend, options = sys.argv[1], sys.argv[2], json.loads(sys.argv[3])
scenario, b = load_scenario(name), get_backend(backend)
if backend == "mujoco":
    from treeimpact.mujoco_models._rollout import step_cost
    from treeimpact.mujoco_models._runner import make_setup
    setup = make_setup(scenario, **options)
    cost, steps = step_cost(setup.mjmodel), setup.t_end / setup.dt
    size = {"nv": int(setup.mjmodel.nv)}
elif backend == "bullet":
    from treeimpact.bullet_models._runner import make_setup, step_cost
    setup = make_setup(scenario, **options)
    cost, steps = step_cost(setup.segments or 1), setup.t_end / setup.dt
    size = {"joints": setup.segments or 1}
else:
    size = {}
start = time.process_time()  # CPU time: a shared machine's load leaves it (nearly) alone
result = b._load(b.simulate_ref)(scenario, **options)  # the run alone, unjudged
wall = time.process_time() - start
if backend == "soft":
    from treeimpact.analytic.contact.soft import SAMPLE_COST as cost
    steps = options["t_end"] / (result.collision_duration / 100)
elif backend == "beam":
    from treeimpact.analytic.continuum.beam_impact import SAMPLE_COST as cost
    from treeimpact.analytic.continuum.beam_impact import SAMPLES_PER_COLLISION
    steps = options["t_end"] / (result.collision_duration / SAMPLES_PER_COLLISION)
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024.0
print(json.dumps({"wall": wall, "peak": peak, "steps": steps, "seconds": cost.seconds,
                  "bytes": cost.bytes, "size": size}))
"""


def _one(scenario: str, backend: str, options: dict) -> dict:
    proc = subprocess.run([sys.executable, "-c", _CHILD, scenario, backend, json.dumps(options)],
                          capture_output=True, text=True, check=False)
    if proc.returncode:
        raise SystemExit(f"{backend} {options}: {proc.stderr.strip().splitlines()[-1]}")
    return json.loads(proc.stdout)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--write", action="store_true")
    args = parser.parse_args(argv)
    rows = []
    print(f"{'case':20s} {'steps':>10s} {'est us/step':>11s} {'meas':>9s} {'ratio':>6s} "
          f"{'est B/step':>10s} {'meas':>9s} {'ratio':>6s}")
    for label, scenario, backend, options, (t1, t2) in CASES:
        if args.quick and label not in QUICK:
            continue
        time_ratio, byte_ratio, per_step, per_byte = [], [], [], []
        for _ in range(args.repeats):
            a = _one(scenario, backend, {**options, "t_end": t1})
            b = _one(scenario, backend, {**options, "t_end": t2})
            extra = b["steps"] - a["steps"]
            s, m = (b["wall"] - a["wall"]) / extra, (b["peak"] - a["peak"]) / extra
            per_step.append(s)
            per_byte.append(m)
            time_ratio.append(b["seconds"] / s if s > 0 else float("inf"))
            byte_ratio.append(b["bytes"] / m if m > 0 else float("inf"))
        print(f"{label:20s} {b['steps']:10.3g} {1e6 * b['seconds']:11.3g} "
              f"{1e6 * statistics.median(per_step):9.3g} {statistics.median(time_ratio):6.2f} "
              f"{b['bytes']:10.3g} {statistics.median(per_byte):9.3g} "
              f"{statistics.median(byte_ratio):6.2f}", flush=True)
        rows.append({"case": label, "backend": backend, "size": b["size"],
                     "seconds_per_step": statistics.median(per_step),
                     "bytes_per_step": statistics.median(per_byte)})
    if args.write:
        RESULTS.write_text(json.dumps({
            "measured": time.strftime("%Y-%m-%d"), "machine": f"{platform.machine()}, "
            f"{os.cpu_count()} cores, Python {platform.python_version()}",
            "repeats": args.repeats, "cases": rows}, indent=1) + "\n")
        print(f"written: {RESULTS}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
