"""Benchmark: a beam run through the API with ``OPENBLAS_NUM_THREADS`` unset against the
same with it set to 1, in fresh processes, interleaved (the library limits BLAS threads
itself: analytic/threads.py, docs/reproducibility.md "BLAS threads"); beside them the
baseline commit's code with the variable unset (what a notebook user paid before), and the
limit's own cost per call (the caller's BLAS at 2 threads and at 1; a nested call).

Each process imports treeimpact, runs the scenario once (imports, the beam's set-up, the
thread limit's scan of the loaded libraries), then times ``--runs`` runs of a scenario with
a fresh beam each (its trunk a micrometre longer: no cache spares the eigen-decomposition)
and prints their median. Ratio unset / =1 ~ 1 is the target (issue 39, item 1).

    python benchmarks/bench_threads.py [--rounds 5] [--runs 10] [--baseline ee677a4]
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _results  # noqa: E402
from _baseline import baseline_tree, run_snippet  # noqa: E402

SNIPPET = """
import dataclasses, json, statistics, time
import treeimpact as ti
base = ti.load_scenario("central-leader")
def fresh(i):
    trunk = dataclasses.replace(base.trunk, length=base.trunk.length + 1e-6 * (i + 1))
    return dataclasses.replace(base, trunk=trunk)
ti.simulate(fresh(-1), backend="beam")
times = []
for i in range(RUNS):
    t0 = time.perf_counter()
    ti.simulate(fresh(i), backend="beam")
    times.append(time.perf_counter() - t0)
print(json.dumps({"median_ms": statistics.median(times) * 1e3}))
"""


def _environment(threads: str | None) -> dict:
    env = {k: v for k, v in os.environ.items()
           if k not in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS")}
    if threads is not None:
        env["OPENBLAS_NUM_THREADS"] = env["OMP_NUM_THREADS"] = threads
    return env


def limit_overhead_us(calls: int = 20000, repeats: int = 7) -> dict:
    """Microseconds per call of an empty function inside the limit: the caller's BLAS at 2
    threads (set and put back each call), at 1 (nothing to set), and nested in a limit."""
    from threadpoolctl import threadpool_limits

    from treeimpact.analytic import threads

    limited = threads.blas_limited(lambda: None)

    def per_call():
        out = []
        for _ in range(repeats):
            t0 = time.perf_counter()
            for _ in range(calls):
                limited()
            out.append((time.perf_counter() - t0) / calls * 1e6)
        return statistics.median(out)

    threads.blas_libraries()  # the once-per-process scan, not per call
    with threadpool_limits(limits=2, user_api="blas"):
        two = per_call()
        with threads.blas_limit():
            nested = per_call()
    with threadpool_limits(limits=1, user_api="blas"):
        one = per_call()
    return {"caller_2_threads": round(two, 2), "caller_1_thread": round(one, 2),
            "nested": round(nested, 2)}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=5, help="processes per side")
    ap.add_argument("--runs", type=int, default=10, help="timed runs per process")
    ap.add_argument("--baseline", default="ee677a4", help="the old code's git revision")
    ap.add_argument("--out", help="results file (default benchmarks/results/threads.json)")
    args = ap.parse_args(argv)
    start_load = _results.load_average()
    code = SNIPPET.replace("RUNS", str(args.runs))
    medians: dict[str, list[float]] = {"unset": [], "one": [], "old_unset": []}
    with baseline_tree(args.baseline) as old:
        sides = [("unset", None, _environment(None)), ("one", None, _environment("1")),
                 ("old_unset", old, _environment(None))]
        for r in range(args.rounds):
            for name, site, env in (sides if r % 2 == 0 else sides[::-1]):
                medians[name].append(run_snippet(code, site, env)["median_ms"])
    med = {k: statistics.median(v) for k, v in medians.items()}
    overhead = limit_overhead_us()
    print(f"beam run (central-leader, fresh beam), median of {args.rounds} processes x "
          f"{args.runs} runs, ms:")
    print(f"  OPENBLAS_NUM_THREADS unset {med['unset']:8.2f}")
    print(f"  OPENBLAS_NUM_THREADS=1     {med['one']:8.2f}   ratio unset / =1: "
          f"{med['unset'] / med['one']:.2f} (target ~1)")
    print(f"  {args.baseline}, unset        {med['old_unset']:8.2f}   ratio old / new (unset): "
          f"{med['old_unset'] / med['unset']:.1f}")
    print(f"the limit's cost per call, us: {overhead}")
    numbers = {"beam_ms.unset": round(med["unset"], 2), "beam_ms.one": round(med["one"], 2),
               "beam_ms.old_unset": round(med["old_unset"], 2),
               "ratio_unset_one": round(med["unset"] / med["one"], 2),
               "ratio_old_new_unset": round(med["old_unset"] / med["unset"], 1),
               **{f"limit_us.{k}": v for k, v in overhead.items()}}
    _results.write("threads", numbers, {"rounds": args.rounds, "runs": args.runs,
                                        "baseline": args.baseline, "medians_ms": medians},
                   started_load=start_load, out=Path(args.out) if args.out else None)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
