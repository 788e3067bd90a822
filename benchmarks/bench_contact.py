"""Benchmark: what ``treeimpact contact`` costs with its phase spread (8 MuJoCo runs of the
setting, the first touch at j/8 of a step) and, for a missed target, its search for what
would hold it, against the baseline commit's command, in fresh processes alternating.

Each process times ``contact_settings`` (what the command computes; printing is negligible)
on the cases of docs/contact-settings.md (the table's 50-step case, MuJoCo's default step,
a target the step misses by 13.75 %), once each after one warm-up call, and prints the times.

    python benchmarks/bench_contact.py [--rounds 3] [--baseline ee677a4]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _results  # noqa: E402
from _baseline import baseline_tree, interleaved  # noqa: E402

#: name -> contact_settings keywords (docs/contact-settings.md).
CASES = {"e0.1-0.5ms-50steps": dict(mass=132.4, other_mass=110.0, restitution=0.1,
                                    touch_duration=5e-4, dt=1e-5),
         "default-step-mujoco": dict(mass=1.0, other_mass=1.0, restitution=0.75,
                                     touch_duration=5e-3, dt=2e-3, engines=("mujoco",)),
         "missed-target-mujoco": dict(effective_mass=1.0, restitution=0.5,
                                      touch_duration=2e-3, dt=1e-3, engines=("mujoco",))}

SNIPPET = """
import json, time
from treeimpact.compare.runs.contact_settings import contact_settings
CASES = {cases!r}
contact_settings(**CASES["default-step-mujoco"])
out = {{}}
for name, kw in CASES.items():
    t0 = time.perf_counter()
    contact_settings(**kw)
    out[name] = time.perf_counter() - t0
print(json.dumps(out))
"""


def main() -> int:
    """Run the benchmark; write benchmarks/results/contact.json."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--baseline", default="ee677a4")
    args = ap.parse_args()
    load = _results.load_average()
    code = SNIPPET.format(cases=CASES)
    with baseline_tree(args.baseline) as old:
        runs = interleaved(code, {"old": old, "new": None}, args.rounds)
    numbers, details = {}, {"rounds": args.rounds, "baseline": args.baseline, "runs": runs}
    for name in CASES:
        o = statistics.median(r[name] for r in runs["old"])
        n = statistics.median(r[name] for r in runs["new"])
        numbers[f"{name}.old_s"], numbers[f"{name}.new_s"] = round(o, 4), round(n, 4)
        numbers[f"{name}.ratio"] = round(n / o, 2)
        print(f"{name:<24} old {o:.4f} s  new {n:.4f} s  new/old {n / o:.2f}")
    _results.write("contact", numbers, details, started_load=load)
    return 0


if __name__ == "__main__":
    sys.exit(main())
