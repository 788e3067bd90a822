"""What ``treeimpact sweep --preset full``'s validity grid costs, measured on a slice of it
(a benchmark, not a test; nothing is asserted).

Run: ``.venv/bin/python benchmarks/bench_presets.py [--workers 2]``. The slice: the full
preset's ladder sweep (central-leader; analytic, soft and both engines as the ladder's
rungs, identification on) at e = 0.1, 0.5, 0.9 x every segment count (1, 2, 4, 8, 16, 32) x
crown_ratio = 0, 4, into a temporary folder that is removed. From the sweep table's wall
time per run: the runs' seconds per (e, crown) pair, the chain runs' seconds per engine and
segment count, and the full grid's cost extrapolated from the mean pair (81 pairs run every
rung: e = 0 runs the analytic rung only). The full preset also runs the identification
validation over every rung, the sensitivity study with its crossings and the speed curves,
which this does not measure.

Writes ``benchmarks/results/presets.json`` (docs/sweeps.md quotes it).
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _results  # noqa: E402

GRID = ("restitution=0.1,0.5,0.9", "segments=1,2,4,8,16,32", "crown_ratio=0,4")
#: (e, crown) pairs of the full preset's grid that run every rung: 9 nonzero e x 9 crowns.
FULL_PAIRS = 81


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--out", help="results file (default benchmarks/results/presets.json)")
    args = p.parse_args(argv)
    from treeimpact.compare.studies.sweep.run import run_sweep

    start_load = _results.load_average()
    with tempfile.TemporaryDirectory(prefix="bench-presets-") as tmp:
        t0 = time.perf_counter()
        res = run_sweep("central-leader", list(GRID), Path(tmp) / "slice",
                        backends=("analytic", "soft", "mujoco", "bullet"), ladder=True,
                        workers=args.workers)
        wall = time.perf_counter() - t0
        table = res.table
    ok = table[table["status"] == "ok"]
    pairs = ok.groupby(["restitution", "crown_ratio"])["wall_s"].sum()
    numbers = {"slice_wall_s": round(wall, 1), "slice_pairs": int(len(pairs)),
               "pair_run_s": [round(float(pairs.min()), 1), round(float(pairs.max()), 1)],
               "pair_run_s_mean": round(float(pairs.mean()), 1),
               "rows": int(len(table)), "rows_ok": int(len(ok))}
    chains = ok[ok["kind"].isin(("chain", "pendulum"))]
    for (backend, segments), runs in chains.groupby(["backend", "segments"]):
        w = runs["wall_s"]
        numbers[f"run_s.{backend}.{int(segments)}"] = [float(f"{w.min():.2g}"),
                                                       float(f"{w.max():.2g}")]
        numbers[f"run_s_median.{backend}.{int(segments)}"] = float(
            f"{statistics.median(w):.2g}")
    cpu = FULL_PAIRS * numbers["pair_run_s_mean"]
    numbers["full.cpu_hours"] = round(cpu / 3600.0, 2)
    numbers["full.minutes_2_workers"] = round(cpu / 2 / 60.0)
    numbers["full.minutes_16_workers"] = round(cpu / 16 / 60.0)
    for k, v in sorted(numbers.items()):
        print(f"  {k}: {v}")
    _results.write("presets", numbers, {"grid": GRID, "workers": args.workers,
                                        "status": table["status"].value_counts().to_dict(),
                                        "full_pairs": FULL_PAIRS},
                   started_load=start_load, out=Path(args.out) if args.out else None)
    return 0 if math.isfinite(wall) else 1


if __name__ == "__main__":
    sys.exit(main())
