"""Throughput of ``treeimpact sweep`` (a benchmark, not a test; nothing is asserted).

Run: ``.venv/bin/python benchmarks/bench_sweep.py [--backends analytic,soft,mujoco,bullet]
[--repeats 3]``. Measured in one process run, per backend:

1. grid points per second with a local process pool of 1 and of 2 workers
   (target: 2 workers >= 1.8 x 1 worker);
2. the same with a Dask ``LocalCluster`` of 2 single-threaded worker processes
   (target: >= 90 % of the 2-worker process pool), configured as the README recommends for
   sweeps (:data:`DASK_SWEEP_CONFIG`): Dask's statistical profiler off (it samples the
   running task's stack every 10 ms) and no ``MALLOC_TRIM_THRESHOLD_=65536`` in the
   workers' environment (Dask's nanny sets it; glibc then hands freed memory back at once).
   Measured here: the profiler made the ``soft`` runs about 17 % slower, the trim threshold
   MuJoCo's 18 % (37 -> 44 ms a run). ``--dask-defaults`` measures Dask's defaults instead.

Each sweep is the central-leader scenario over ``e`` (and ``crown_ratio`` for the cheap
backends), written to a fresh directory, identification included (what a study runs). A
point costs the backend run plus the analytic reference run (always part of a sweep).
``--repeats`` rounds (after one untimed warm-up round) each run the three configurations
back to back, and the printed figures are medians over the rounds: points per second of
each configuration, and the ratios taken within each round (2 workers / 1 worker, Dask /
2 workers), so a slow spell of the shared machine hits both sides of a ratio alike (the
load average is printed before and after: other jobs on the cores lower the 2-worker
figures). The LocalCluster is started for the Dask sweep of each round, warmed up on the
backend (imports) and closed after it: an idle LocalCluster of 2 workers took 11 % of one
core here (heartbeats, monitors), which would otherwise come off the process pool's 2-worker
figure on a 2-core machine. A backend whose rows are not
all ``ok`` is reported as not measured (a failing run is fast, so its points per second
would mean nothing). Points per second = grid points / wall time of
:func:`compare.studies.sweep.run.run_sweep` (planning, runs, the CSV journal and the Parquet
table).
"""

from __future__ import annotations

import argparse
import contextlib
import math
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")
ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from treeimpact.compare.studies.sweep.run import run_sweep  # noqa: E402

#: Grid per backend: about 10-20 s of work for one worker on this machine.
GRIDS = {
    "analytic": ["restitution=0.05:0.95:40", "crown_ratio=0:4:40"],  # 1600 points, ~4 ms each
    "soft": ["restitution=0.1:0.9:10", "crown_ratio=0:4:10"],  # 100 points, ~0.05-0.15 s each
    "mujoco": ["restitution=0.1:0.9:20", "crown_ratio=0:4:10"],  # 200 points, SDOF trunk ~0.05 s each
    "bullet": ["restitution=0.1:0.9:12", "crown_ratio=0:4:5"],  # 60 points, SDOF trunk ~0.15 s each
}
#: The Dask configuration the README recommends for a sweep's cluster (see the docstring).
DASK_SWEEP_CONFIG = {"distributed.worker.profile.enabled": False,
                     "distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None}
ENGINE_OPTIONS = {"mujoco": {"trunk": "sdof"}, "bullet": {"trunk": "sdof"}}


def points_per_second(backend: str, **kw) -> tuple[float, int, str | None]:
    """(grid points per second of one sweep, grid points, why it does not count or None).
    A sweep whose backend rows are not all ``ok`` does not count: failing runs are fast."""
    with tempfile.TemporaryDirectory() as d:
        t0 = time.perf_counter()
        res = run_sweep("central-leader", GRIDS[backend], Path(d) / "s",
                        backends=["analytic", backend],
                        options={k: v for k, v in ENGINE_OPTIONS.items() if k == backend},
                        progress=False, **kw)
        wall = time.perf_counter() - t0
    n = res.table["point"].nunique()
    bad = res.table[res.table["status"] != "ok"]
    if len(bad):
        return math.nan, n, f"{len(bad)} rows without numbers, e.g. {bad['error'].iloc[0]}"
    return n / wall, n, None


@contextlib.contextmanager
def local_cluster(config: dict, backend: str):
    """A LocalCluster of 2 single-threaded worker processes, warmed up on ``backend``."""
    import dask
    from distributed import LocalCluster

    with dask.config.set(config):
        cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                               dashboard_address=None)
    with cluster:
        warm(backend, scheduler=cluster.scheduler_address)
        try:
            yield cluster.scheduler_address
        finally:
            _stop_workers(cluster)


def _stop_workers(cluster, timeout_s: float = 10.0) -> None:
    """The workers stopped before the scheduler: closing both at once lets a worker's
    heartbeat meet a closed scheduler and log a CommClosedError traceback (dask/distributed
    issue 7192)."""
    import time

    cluster.scale(0)
    end = time.monotonic() + timeout_s
    while cluster.scheduler_info.get("workers") and time.monotonic() < end:
        time.sleep(0.05)


def warm(backend: str = "soft", **kw) -> None:
    """A small sweep of ``backend`` (its imports, in every worker of a cluster)."""
    with tempfile.TemporaryDirectory() as d:
        run_sweep("central-leader", ["restitution=0.1,0.2,0.3,0.4"], Path(d) / "w",
                  backends=["analytic", backend],
                  options={k: v for k, v in ENGINE_OPTIONS.items() if k == backend},
                  progress=False, **kw)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--backends", default="analytic,soft,mujoco,bullet")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--dask-defaults", action="store_true",
                    help="the LocalCluster with Dask's defaults, not DASK_SWEEP_CONFIG")
    args = ap.parse_args(argv)
    from treeimpact.compare.runs.backends import get_backend

    backends = []
    for b in args.backends.split(","):
        try:
            get_backend(b).options()
            backends.append(b)
        except Exception as exc:  # noqa: BLE001 - reported, then left out
            print(f"{b}: not measured ({exc})")
    print(f"cpu count {os.cpu_count()}; medians of {args.repeats} rounds; points/s of a sweep")
    warm(workers=1)
    print(f"load average before: {os.getloadavg()[0]:.2f} (the targets assume idle cores)")
    config = {} if args.dask_defaults else DASK_SWEEP_CONFIG
    print(f"LocalCluster config: {config or 'Dask defaults'}")
    configs = ("1 worker", "2 workers", "dask 2x1")
    for b in backends:
        rounds = []
        why = None
        n = 0
        for r in range(args.repeats + 1):  # round 0 warms this backend up, untimed
            rate = {}
            for name, kw in (("1 worker", {"workers": 1}), ("2 workers", {"workers": 2})):
                rate[name], n, why = points_per_second(b, **kw)
                if why:
                    break
            if not why:
                with local_cluster(config, b) as address:
                    rate["dask 2x1"], n, why = points_per_second(b, scheduler=address)
            if why:
                break
            if r:
                rounds.append(rate)
        if why:
            print(f"{b:9s} not measured: {why}", flush=True)
            continue
        one, two, dask = (statistics.median(r[c] for r in rounds) for c in configs)
        scale = statistics.median(r["2 workers"] / r["1 worker"] for r in rounds)
        share = statistics.median(r["dask 2x1"] / r["2 workers"] for r in rounds)
        print(f"{b:9s} {n:4d} points  1 worker {one:8.2f}/s  2 workers {two:8.2f}/s "
              f"(x{scale:.2f}, target 1.8)  dask 2x1 {dask:8.2f}/s "
              f"({share:.0%} of pool, target 90%)", flush=True)
    print(f"load average after: {os.getloadavg()[0]:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
