"""Wall time of ``pytest compare`` and of the default report, split between backends.

Run: ``.venv/bin/python benchmarks/bench_report.py [--out DIR]``. Both are measured in one
process run, each from an empty run cache (so the report does not reuse the tests' runs):

1. ``pytest compare`` in-process (``pytest.main``), then the run cache's time per backend;
2. the default report (:func:`compare.report.write_report`, the shipped scenarios), with the
   time per backend and per report section.

Prints a table; a benchmark, not a test (nothing is asserted).
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")
ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def _table(title: str, total: float, timings: dict, extra: dict | None = None) -> None:
    """Runs execute on a process pool (compare.runs.cache.RunCache.prefetch): their wall times are
    per run, summed over the workers, so they are shown as CPU-side seconds and as a share
    of the summed run time; the wall-clock split is in the sections below."""
    busy = sum(t["wall_s"] for t in timings.values()) or 1.0
    print(f"\n{title}: {total:.2f} s wall")
    print(f"  {'backend':<12}{'runs':>6}{'run s':>9}{'share of run s':>16}")
    for name, t in sorted(timings.items(), key=lambda kv: -kv[1]["wall_s"]):
        print(f"  {name:<12}{t['runs']:>6}{t['wall_s']:>9.2f}{t['wall_s'] / busy:>16.0%}")
    print(f"  run seconds summed over the pool's workers: {busy:.2f} s "
          f"({busy / total:.2f} x the wall time)")
    for k, v in (extra or {}).items():
        print(f"  section {k:<30}{v:>8.2f} s wall")


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", help="report directory (default: a temporary one)")
    p.add_argument("--skip-pytest", action="store_true", help="time the report only")
    args = p.parse_args(argv)

    import pytest

    from treeimpact.compare.report import write_report
    from treeimpact.compare.runs import cache as runs

    if not args.skip_pytest:
        t0 = time.perf_counter()
        code = pytest.main([str(ROOT / "compare"), "-q", "-p", "no:cacheprovider",
                            "--no-header", "-o", "addopts="])
        total = time.perf_counter() - t0
        import sys

        conf = sys.modules.get("compare.tests.conftest") or sys.modules.get("conftest")
        _table(f"pytest compare (exit {int(code)})", total,
               conf.SESSION_CACHE.timings() if conf is not None else {})

    import json

    cache = runs.RunCache()
    with tempfile.TemporaryDirectory(prefix="treeimpact-report-") as tmp:  # gone after; kept
        out = args.out or tmp  # only where --out says
        t0 = time.perf_counter()
        paths = write_report(out, runs=cache)
        total = time.perf_counter() - t0
        wall = json.loads(Path(paths["json"]).read_text())["runs"]["wall_s"]
    where = paths["html"] if args.out else "a temporary folder, removed (--out DIR keeps it)"
    _table(f"treeimpact report (default, 3 shipped scenarios) -> {where}", total,
           cache.timings(), {k: v for k, v in wall.items() if v is not None})
    return 0


if __name__ == "__main__":
    sys.exit(main())
