"""The engines' chain runs, old code against new, interleaved (a benchmark, not a test).

Run: ``.venv/bin/python benchmarks/bench_chains.py [--rev ee677a4] [--rounds 3]
[--cases report|preset|all]``. Each round runs every case once in a fresh process of the
baseline commit's ``treeimpact`` (benchmarks/_baseline.py) and once in today's, the two
alternating, so that machine noise hits both alike: per case the median wall time of a run
(s) on each side and their ratio, the steps taken and the wall time per step (us), and
whether the two sides' numbers are the same to the last bit (every metric and the recorded
x(t), y(t)) or, where they differ, the largest relative change of a metric the ladder
compares a chain by (compare/tolerances.toml [step.chain]; every metric's change is in the
file's details).

Cases: ``report``, the hinged chains of ``make report``'s ladders (every shipped tree, its
default segments: MuJoCo's chain with the linear and the full pendulum and its elastic
rod, Bullet's chain with both pendulums); ``preset``, the full preset's 32-segment chains
(central-leader, the linear pendulum, each engine), whose step the chain's highest mode
sets. What set each new run's step (contact, highest mode, Bullet's implicit contact) is in
the file's details. Writes ``benchmarks/results/chains.json`` (docs/engines.md quotes it).
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _baseline  # noqa: E402
import _results  # noqa: E402

REPORT_CASES = [(scen, engine, opts)
                for scen, n in (("central-leader", 12), ("open-center", 10),
                                ("realistic-crown", 12))
                for engine, kinds in (("mujoco", (("chain", "linear"), ("chain", "full"),
                                                  ("flex", "linear"))),
                                      ("bullet", (("chain", "linear"), ("chain", "full"))))
                for trunk, pendulum in kinds
                for opts in [{"trunk": trunk, "segments": n, "pendulum": pendulum}]]
PRESET_CASES = [("central-leader", engine, {"trunk": "chain", "segments": 32,
                                            "pendulum": "linear"})
                for engine in ("mujoco", "bullet")]

#: One process: warm the engines (imports, a small run), then time each case and print its
#: wall time, steps (t_end / dt), a digest of its metrics and record, and the metrics.
SNIPPET = r'''
import hashlib, json, math, time
import numpy as np
from treeimpact.compare.backends import get_backend
from treeimpact.compare.runs import resolve_scenario
CASES = json.loads(%r)
for engine in {c[1] for c in CASES}:
    get_backend(engine).simulate(resolve_scenario("open-center"), trunk="sdof")
out = []
for scen, engine, opts in CASES:
    s = resolve_scenario(scen)
    t0 = time.perf_counter()
    r = get_backend(engine).simulate(s, **opts)
    wall = time.perf_counter() - t0
    tr = r.trajectory
    digest = hashlib.sha1(json.dumps(r.metrics, sort_keys=True, default=repr).encode()
                          + np.asarray(tr.x).tobytes() + np.asarray(tr.y).tobytes()).hexdigest()
    steps = int(math.ceil(r.scenario["t_end"] / r.model["dt"]))
    out.append({"wall_s": wall, "steps": steps, "digest": digest,
                "set_by": r.extra.get("stepping", {}).get("step_set_by"),
                "metrics": {k: v for k, v in r.metrics.items() if isinstance(v, float)}})
print(json.dumps(out))
'''


def compared_metrics() -> tuple:
    """The metrics the ladder compares a chain with the continuum by a relative tolerance
    (compare/tolerances.toml's [step.chain] entries with ``rel``): a change of the step
    must stay within those; the moving-together metrics (T0, x0, V, A_x, ...) follow the
    chattering sequence and are not compared on a chain."""
    import tomllib

    from treeimpact.compare.verdicts import TOLERANCES_PATH

    table = tomllib.loads(Path(TOLERANCES_PATH).read_text())["step"]["chain"]
    return tuple(k for k, v in table.items() if "rel" in v)


def _changes(old: dict, new: dict, keys) -> dict:
    """|new / old - 1| per metric of ``keys`` both have (0 where both are 0)."""
    out = {}
    for k in keys:
        a, b = old.get(k), new.get(k)
        if a is None or b is None or a != a or b != b:
            continue
        out[k] = abs(b - a) / abs(a) if a else abs(b)
    return out


def summarise(details: list) -> dict:
    """The flat numbers of the cases' ``details`` (one dict per case, :func:`main`'s):
    per case ``SCENARIO.ENGINE.TRUNK.PENDULUM.SEGMENTS.`` old and new median wall (s),
    their ratio, steps, wall per step (us), 1 where the two sides' numbers are the same to
    the last bit (else 0) and the largest compared metric's change; per group (report,
    preset) and engine and trunk the [low, high] of the new steps, wall per step (us) and
    ratio; per group the count of bit-identical runs, the median ratio and the sums of the
    medians (s). Printed as a table too."""
    numbers: dict = {}
    groups: dict = {}
    for d in details:
        scen, engine, opts = d["case"]
        key = f"{scen}.{engine}.{opts['trunk']}.{opts['pendulum']}.{opts['segments']}"
        for k, v in d.items():
            if k not in ("case", "new_step_set_by", "changes"):
                numbers[f"{key}.{k}"] = int(v) if isinstance(v, bool) else v
        groups.setdefault("preset" if opts["segments"] >= 32 else "report", []).append(d)
        print(f"{key:44s} old {d['old_s']:6.2f} s new {d['new_s']:6.2f} s x{d['ratio']:5.2f} "
              f"steps {d['old_steps']}->{d['new_steps']} us/step {d['old_step_us']}->"
              f"{d['new_step_us']} set by {d.get('new_step_set_by')} "
              + ("bit-identical" if d["bit_identical"] else
                 f"compared metrics changed by at most {d['largest_compared_change']:.2g}"))
    kinds: dict = {}
    for d in details:
        scen, engine, opts = d["case"]
        group = "preset" if opts["segments"] >= 32 else "report"
        kinds.setdefault(f"{group}.{engine}.{opts['trunk']}", []).append(d)
    for name, ds in kinds.items():  # ranges over the trees and pendulums
        for k in ("new_steps", "new_step_us", "ratio"):
            numbers[f"{name}.{k}"] = _results.span(d[k] for d in ds)
    for name, ds in groups.items():
        numbers[f"{name}.runs"] = len(ds)
        numbers[f"{name}.bit_identical"] = sum(d["bit_identical"] for d in ds)
        numbers[f"{name}.ratio_median"] = round(statistics.median(d["ratio"] for d in ds), 3)
        numbers[f"{name}.old_total_s"] = round(sum(d["old_s"] for d in ds), 2)
        numbers[f"{name}.new_total_s"] = round(sum(d["new_s"] for d in ds), 2)
        print(f"{name}: {numbers[name + '.bit_identical']}/{len(ds)} bit-identical, median "
              f"ratio new/old {numbers[name + '.ratio_median']}, sum of medians "
              f"{numbers[name + '.old_total_s']} s -> {numbers[name + '.new_total_s']} s")
    return numbers


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--rev", default="ee677a4", help="the baseline commit (default ee677a4)")
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--cases", choices=("report", "preset", "all"), default="all")
    p.add_argument("--engines", default="mujoco,bullet",
                   help="the engines whose cases run (comma-separated; default both)")
    p.add_argument("--out", help="results file (default benchmarks/results/chains.json)")
    args = p.parse_args(argv)
    cases = [c for c in {"report": REPORT_CASES, "preset": PRESET_CASES,
                         "all": REPORT_CASES + PRESET_CASES}[args.cases]
             if c[1] in args.engines.split(",")]
    start_load = _results.load_average()
    code = SNIPPET % json.dumps(cases)
    with _baseline.baseline_tree(args.rev) as old:
        runs = _baseline.interleaved(code, {"old": old, "new": None}, args.rounds)
    details, compared = [], compared_metrics()
    for i, (scen, engine, opts) in enumerate(cases):
        o = [r[i] for r in runs["old"]]
        n = [r[i] for r in runs["new"]]
        wo = statistics.median(x["wall_s"] for x in o)
        wn = statistics.median(x["wall_s"] for x in n)
        details.append({
            "case": [scen, engine, opts], "old_s": round(wo, 3), "new_s": round(wn, 3),
            "ratio": round(wn / wo, 3), "old_steps": o[0]["steps"], "new_steps": n[0]["steps"],
            "old_step_us": round(1e6 * wo / o[0]["steps"], 2),
            "new_step_us": round(1e6 * wn / n[0]["steps"], 2),
            "new_step_set_by": n[0].get("set_by"),
            "bit_identical": o[0]["digest"] == n[0]["digest"],
            "largest_compared_change": max(_changes(o[0]["metrics"], n[0]["metrics"],
                                                    compared).values(), default=0.0),
            "changes": _changes(o[0]["metrics"], n[0]["metrics"], o[0]["metrics"])})
    numbers = summarise(details)
    _results.write("chains", numbers, {"rev": args.rev, "rounds": args.rounds,
                                       "engines": args.engines, "cases": details}, started_load=start_load,
                   out=Path(args.out) if args.out else None)
    return 0


if __name__ == "__main__":
    sys.exit(main())
