"""What the design study costs and what its engine spot checks say (issue 43, items 3-4; a
benchmark, not a test: nothing is asserted).

Run: ``.venv/bin/python benchmarks/bench_design.py [--workers 2] [--skip-engines]``. In one
run, on central-leader, each into a temporary folder removed afterwards:

1. one 30 x 30 map of one pair (a/l x m/M_T, 900 cells): its wall time on ``--workers``;
2. the whole study (three 30 x 30 maps and 5 trunk diameters): its wall time and CPU-seconds
   a cell (wall x workers / cells, every rung and the pool included);
3. a 4 x 4 x 4 x 4 slice of the four-input grid (a/l, m/M_T, pad, e over their map ranges)
   beside the finished maps: CPU-seconds a cell; the docs' 10 x 8 x 8 x 10 grid (6400
   cells) then costs cells x that, on 2 workers and, *estimated* (no 16-core machine
   here), on 16: cells x CPU-s a cell / 16 + the pool's start + the grid's worker calls x
   the pool's measured cost a call / 16;
5. the local pool's own cost (compare.runs.pool.process_map of ``len`` on tiny items, nothing
   to compute): its start (2 calls) and each further call (2000 calls), CPU-s a call;
4. the engines' spot checks (``design_map(engines=True)``: MuJoCo's and Bullet's chains and
   MuJoCo's flex rod at the a/l x pad map's corners and the cells nearest its 5 % line):
   comparisons within their tolerances, and each engine trunk's worst relative difference
   on x_max and the energy delivered (%).

Writes ``benchmarks/results/design.json`` (docs/design-map.md quotes it).
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _results  # noqa: E402

#: The slice of the four-input grid timed, and the full grid docs/design-map.md gives.
SLICE = ("a_over_l=0.1:0.6:4", "mass_ratio=0.2,0.6,1.7,5", "contact_duration=2e-4,1e-3,1e-2,5e-2",
         "restitution=0:0.9:4")
FULL_GRID_CELLS = 10 * 8 * 8 * 10
#: The metrics the spot checks compare (compare.studies.design_engines.METRICS).
METRICS = ("x_max", "energy_delivered", "crown_peak_acceleration")


def _pair_map(workers: int, folder: Path) -> float:
    """Wall time (s) of one 30 x 30 a/l x m/M_T map on ``workers`` processes."""
    from treeimpact.compare.runs.cache import resolve_scenario
    from treeimpact.compare.studies.design import PAIRS, design_spec, pair_grid
    from treeimpact.compare.studies.sweep.run import run_sweeps

    scen = resolve_scenario("central-leader")
    t0 = time.perf_counter()
    run_sweeps([design_spec(scen, pair_grid(scen, PAIRS[0], 30), folder)], workers=workers,
               progress=False)
    return time.perf_counter() - t0


def _pool_overhead(workers: int, calls: int = 2000, rounds: int = 3) -> dict:
    """The local pool's own cost on ``workers`` processes, medians over ``rounds``: its
    start (wall, s, for 2 calls of nothing) and each further call (CPU-s: the extra wall
    of ``calls`` calls x workers / the extra calls)."""
    from statistics import median

    from treeimpact.compare.runs.pool import process_map

    def wall(n):
        t0 = time.perf_counter()
        process_map(len, [[i] for i in range(n)], workers=workers)
        return time.perf_counter() - t0

    start, many = [], []
    for _ in range(rounds):  # interleaved: the machine's load falls on both alike
        start.append(wall(2))
        many.append(wall(calls))
    per_call = (median(many) - median(start)) * workers / (calls - 2)
    return {"pool_start_s": round(median(start), 3),
            "pool_cpu_s_per_call": round(per_call, 5)}


def _grid_calls(workers: int, cells: int) -> int:
    """How many worker calls compare.studies.sweep.cost.chunks makes of ``cells`` design-grid
    cells (each one "analytic" task whose analysis runs the rungs, as design_spec plans
    them) on ``workers`` processes."""
    from types import SimpleNamespace as Task

    from treeimpact.compare.runs.backends import get_backend
    from treeimpact.compare.studies.sweep.cost import chunks

    return len(chunks([Task(backend=get_backend("analytic"), options={})] * cells, workers))


def _spot_numbers(spot: dict) -> dict:
    """The spot checks' counts and each engine trunk's worst difference (%) by metric."""
    out = {"spot.cells": len(spot["cells"])}
    within = total = 0
    worst: dict = {}
    for cell in spot["cells"]:
        for label, got in cell["rungs"].items():
            for metric, g in got.items():
                if isinstance(g, dict):
                    total += 1
                    within += bool(g["within"])
                    key = f"spot.worst_pct.{label.replace(' ', '_')}.{metric}"
                    worst[key] = max(worst.get(key, 0.0), abs(100.0 * g["rel"]))
    out |= {"spot.comparisons": total, "spot.within": within}
    return out | {k: round(v, 2) for k, v in worst.items()} | _corner_numbers(spot["cells"])


def _corner_numbers(cells: list) -> dict:
    """Two corners in numbers (%): the hard pad at the low clamp (each metric's [low, high]
    over the engine trunks) and the long pad at the high clamp (each trunk's difference on
    the energy delivered, and the largest |difference| there over trunks and metrics)."""
    a = [c["point"]["a_over_l"] for c in cells]
    pad = [c["point"]["contact_duration"] for c in cells]
    out = {}
    for name, at in (("hard_low", (min(a), min(pad))), ("long_high", (max(a), max(pad)))):
        cell = next(c for c in cells
                    if (c["point"]["a_over_l"], c["point"]["contact_duration"]) == at)
        rungs = {k: g for k, g in cell["rungs"].items() if "error" not in g}
        for m in METRICS:
            rel = [100.0 * g[m]["rel"] for g in rungs.values()]
            out[f"spot.{name}.pct.{m}"] = [round(min(rel), 2), round(max(rel), 2)]
            for label, g in rungs.items():
                out[f"spot.{name}.{label.replace(' ', '_')}.pct.{m}"] = round(
                    100.0 * g[m]["rel"], 2)
        out[f"spot.{name}.max_abs_pct"] = round(max(
            abs(100.0 * g[m]["rel"]) for g in rungs.values() for m in METRICS), 2)
    return out


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--skip-engines", action="store_true", help="no spot checks")
    p.add_argument("--out", help="results file (default benchmarks/results/design.json)")
    args = p.parse_args(argv)
    from treeimpact.compare.report.validity.design_study import run_design_study

    start_load = _results.load_average()
    numbers, details = {}, {"slice": SLICE, "workers": args.workers}
    with tempfile.TemporaryDirectory(prefix="bench-design-") as tmp:
        numbers["pair_map_s"] = round(_pair_map(args.workers, Path(tmp) / "pair"), 1)
        paths = run_design_study(Path(tmp) / "study", workers=args.workers, progress=False)
        cost = json.loads(paths["json"].read_text())["cost"]
        numbers |= {"study_s": round(cost["wall_s"], 1), "study_cells": cost["cells"],
                    "cpu_s_per_cell": round(cost["cpu_s_per_cell"], 4)}
        t0 = time.perf_counter()
        paths = run_design_study(Path(tmp) / "study", workers=args.workers, grid=list(SLICE),
                                 progress=False)
        grid = json.loads(paths["json"].read_text())
        slice_s = time.perf_counter() - t0
        cells = grid["grid"]["cells"]
        per_cell = slice_s * args.workers / cells
        numbers |= {"slice_cells": cells, "slice_s": round(slice_s, 1),
                    "slice_cpu_s_per_cell": round(per_cell, 4),
                    "full_grid_cells": FULL_GRID_CELLS,
                    "full_grid_cpu_minutes": round(FULL_GRID_CELLS * per_cell / 60, 1),
                    "full_grid_minutes_2_workers": round(FULL_GRID_CELLS * per_cell / 2 / 60, 1),
                    }
        numbers |= _pool_overhead(args.workers)
        calls = _grid_calls(16, FULL_GRID_CELLS)
        numbers |= {"full_grid_calls_16_workers": calls,
                    "full_grid_minutes_16_workers_estimated": round(
                        (FULL_GRID_CELLS * per_cell / 16 + numbers["pool_start_s"]
                         + calls * numbers["pool_cpu_s_per_call"] / 16) / 60, 2)}
        if not args.skip_engines:
            t0 = time.perf_counter()
            paths = run_design_study(Path(tmp) / "study", workers=args.workers, engines=True,
                                     progress=False)
            spot = json.loads(paths["json"].read_text())["spot_checks"]
            numbers |= _spot_numbers(spot) | {"spot_s": round(time.perf_counter() - t0, 1)}
            details["spot_sentence"] = spot["sentence"]
            details["spot_cells"] = spot["cells"]
    for k, v in sorted(numbers.items()):
        print(f"  {k}: {v}")
    _results.write("design", numbers, details, started_load=start_load,
                   out=Path(args.out) if args.out else None)
    return 0


if __name__ == "__main__":
    sys.exit(main())
