"""Benchmark: one `treeimpact identify` fit (analytic.identify.record_fit.fit_record) on a 0.1 s,
5 kHz record with 1 % noise (central-leader at e = 0.1, 0.3, and with a crown of 4 trunk
masses, a one-impact record, free, with e given and with the pendulum's y), and one
evaluation of its model (the exact solver sampled at the record's times). Prints medians
over repeats and the model evaluations per fit.

Target (issue 17): one identification under 2 s on one core.

    python benchmarks/bench_identify.py [--repeats 10]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))


def main(argv=None) -> int:
    from test_record_fit import HEAVY, synthetic

    from treeimpact.analytic.identify import record_fit

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=10)
    args = ap.parse_args(argv)
    print(f"{'record':<28s} {'fit s':>8s} {'model ms':>9s} {'evaluations':>12s}")
    worst = 0.0
    cases = [("e = 0.1", 0.1, {}, None, False), ("e = 0.3", 0.3, {}, None, False),
             ("e = 0.3, crown 4 (one impact)", 0.3, HEAVY, None, False),
             ("  the same, e given", 0.3, HEAVY, 0.3, False),
             ("  the same, y recorded", 0.3, HEAVY, None, True)]
    for label, e, changes, given, pendulum in cases:
        _, record, test = synthetic(e, 0, pendulum=pendulum, **changes)
        p = record_fit._start(record, test)
        fits, evals, counts = [], [], []
        original = record_fit.model_motion
        for _ in range(args.repeats):
            calls = [0]

            def counted(*a, **k):
                calls[0] += 1
                return original(*a, **k)

            record_fit.model_motion = counted
            t0 = time.perf_counter()
            record_fit.fit_record(record, test, restitution=given)
            fits.append(time.perf_counter() - t0)
            record_fit.model_motion = original
            counts.append(calls[0])
            t0 = time.perf_counter()
            original(p, test, record.t, pendulum=pendulum)
            evals.append(time.perf_counter() - t0)
        mf = statistics.median(fits)
        worst = max(worst, mf)
        print(f"{label:<28s} {mf:8.3f} {1e3 * statistics.median(evals):9.3f} "
              f"{int(np.median(counts)):12d}")
    print(f"target: one identification < 2 s {'met' if worst < 2.0 else 'MISSED'} "
          f"(worst median {worst:.3f} s)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
