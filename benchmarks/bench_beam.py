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
import time

from treeimpact.analytic.continuum.beam_impact import simulate_beam
from treeimpact.analytic.model.scenario import load_scenario, shipped_scenarios

METHODS = ("exact-full", "exact")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=15)
    ap.add_argument("--elements", type=int, default=12)
    args = ap.parse_args()
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
                res = simulate_beam(scenario, elements=args.elements, t_end=0.1, method=method)
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
    print(f"speed ratio: {min(ratios):.1f}-{max(ratios):.1f} (target >= 10); "
          f"metrics {'within' if ok else 'OUTSIDE'} x_max 1e-4, energy_delivered 1e-3")
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
