"""Benchmark: the beam backend's ``exact`` method against ``exact-full`` (the original).

Both solve the same continuum trunk and pad exactly between contact switches
(:mod:`analytic.continuum.beam_impact`) on the same sample grid (100 samples a collision)
and return the same metrics; ``exact-full`` forms every sample's state and energies with one
complex exponential per sample and mode, ``exact`` only the 8 observables the metrics read
(exp(lambda i h) times a block's first sample), the energies in closed form where the
metrics read them, and the record when first read. One 0.1 s run
(``simulate_beam(load_scenario(name), t_end=0.1)``) of each shipped scenario, repeats
interleaved so machine noise hits both alike; prints the medians, their ratio and the
largest relative difference of x_max and of energy_delivered.

Targets (issue 23, item 2): at the default 12 elements at least 10 times faster, x_max the
same to 1e-4 and energy_delivered to 1e-3 (relative).

    python benchmarks/bench_beam.py [--repeats 15] [--elements 12]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

from treeimpact.analytic.continuum.beam_impact import simulate_beam
from treeimpact.analytic.model.scenario import load_scenario, shipped_scenarios
from treeimpact.analytic.model.options import scenario_as_run

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _results  # noqa: E402

METHODS = ("exact-full", "exact")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=15)
    ap.add_argument("--elements", type=int, default=12)
    ap.add_argument("--out", help="results file (default benchmarks/results/beam-N.json, N "
                                  "the elements)")
    args = ap.parse_args()
    start_load = _results.load_average()
    numbers: dict = {}
    print(f"beam backend, {args.elements} elements, t_end = 0.1 s, median of {args.repeats} "
          "interleaved runs")
    print(f"{'scenario':<18}{'exact-full ms':>15}{'exact ms':>11}{'ratio':>8}"
          f"{'x_max rel':>12}{'E_del rel':>12}")
    ratios, ok = [], True
    for name in shipped_scenarios():
        scenario = load_scenario(name)
        times = {m: [] for m in METHODS}
        metrics = {}
        for _ in range(args.repeats):
            for method in METHODS:
                t0 = time.perf_counter()
                res = simulate_beam(scenario_as_run(scenario, {"t_end": 0.1}),
                                    elements=args.elements, method=method)
                times[method].append(time.perf_counter() - t0)
                metrics[method] = res.metrics
        med = {m: statistics.median(v) for m, v in times.items()}
        ratio = med["exact-full"] / med["exact"]
        ratios.append(ratio)
        dx = abs(metrics["exact"]["x_max"] / metrics["exact-full"]["x_max"] - 1)
        de = abs(metrics["exact"]["energy_delivered"]
                 / metrics["exact-full"]["energy_delivered"] - 1)
        ok &= dx <= 1e-4 and de <= 1e-3
        print(f"{name:<18}{med['exact-full'] * 1e3:>15.1f}{med['exact'] * 1e3:>11.1f}"
              f"{ratio:>8.1f}{dx:>12.1e}{de:>12.1e}")
        numbers |= {f"exact_full_ms.{name}": round(med["exact-full"] * 1e3, 2),
                    f"exact_ms.{name}": round(med["exact"] * 1e3, 2),
                    f"ratio.{name}": round(ratio, 2), f"x_max_rel_diff.{name}": dx,
                    f"energy_delivered_rel_diff.{name}": de}
    print(f"speed ratio: {min(ratios):.1f}-{max(ratios):.1f} (target >= 10); "
          f"metrics {'within' if ok else 'OUTSIDE'} x_max 1e-4, energy_delivered 1e-3")
    names = shipped_scenarios()
    for key in ("exact_full_ms", "exact_ms", "ratio", "x_max_rel_diff",
                "energy_delivered_rel_diff"):
        numbers[key] = _results.span(numbers[f"{key}.{n}"] for n in names)
    _results.write("beam", numbers, {"elements": args.elements, "repeats": args.repeats},
                   started_load=start_load,
                   out=Path(args.out) if args.out else
                   _results.RESULTS / f"beam-{args.elements}.json")
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
