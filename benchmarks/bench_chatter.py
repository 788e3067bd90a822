"""Benchmark: the exact solver's most expensive refusal, an elastic (e = 1) chatter on a
heavily overdamped trunk run to MAX_CHATTER_IMPACTS impacts (tests/test_properties.py's
ELASTIC_OVERDAMPED, which that test checks with the cap lowered to 1000).

Why it costs seconds: with e = 1 the tail is never closed (its bouncing-ball sum needs
e < 1), each impact keeps the relative velocity, which the trunk's damping alone drains as
1 / n, and the flights between impacts (2 gamma / |a_rel|) shrink alike, so the impacts
crowd into the first few ms (time grows as ln n) and every one of them is resolved (a
Newton impact and a certified free-flight search) until the cap refuses the model. Printed
and written: the median wall of the refusal over ``--repeats`` runs, the impacts resolved,
the time of the last one, the relative velocity at the first and last, the energy the
chatter still holds (the refusal's own number) and the cost per impact.

    python benchmarks/bench_chatter.py [--repeats 3]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _results  # noqa: E402

from treeimpact.analytic.errors import ParameterError  # noqa: E402
from treeimpact.analytic.impact import solution as solution_module  # noqa: E402
from treeimpact.analytic.impact.solver import MAX_CHATTER_IMPACTS, solve_impacts  # noqa: E402
from treeimpact.analytic.model.two_body import TwoBodyModel  # noqa: E402

#: tests/test_properties.py's ELASTIC_OVERDAMPED (found by hypothesis).
ELASTIC_OVERDAMPED = TwoBodyModel(
    dynamic_mass=5.0, equivalent_damping=52971.65217941432, equivalent_stiffness=10000.0,
    impactor_mass=469.3527616896069, impactor_stiffness=0.0, impact_speed=1.0, restitution=1.0)
T_END = 0.125  # s, the test's


def refusal() -> tuple[float, str, object]:
    """One refused run: its wall (s), the refusal's text and the solution it had built."""
    built = []
    init = solution_module.ImpactSolution.__init__

    def keep(self, *args, **kwargs):
        init(self, *args, **kwargs)
        built.append(self)

    solution_module.ImpactSolution.__init__ = keep
    try:
        t0 = time.perf_counter()
        try:
            solve_impacts(ELASTIC_OVERDAMPED, T_END)
        except ParameterError as exc:
            return time.perf_counter() - t0, str(exc), built[-1]
        raise AssertionError("the elastic chatter was not refused")
    finally:
        solution_module.ImpactSolution.__init__ = init


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3, help="refused runs timed")
    ap.add_argument("--out", help="results file (default benchmarks/results/chatter.json)")
    args = ap.parse_args(argv)
    start_load = _results.load_average()
    walls, text, sol = [], "", None
    for _ in range(args.repeats):
        wall, text, sol = refusal()
        walls.append(wall)
    impacts = sol.impacts
    gamma = [i.u - i.U for i in (impacts[1], impacts[-1])]  # the 2nd: after the first bounce
    wall = statistics.median(walls)
    numbers = {"wall_s": round(wall, 3), "impacts": len(impacts), "cap": MAX_CHATTER_IMPACTS,
               "us_per_impact": round(wall / len(impacts) * 1e6, 1),
               "t_last_impact_ms": round(impacts[-1].t * 1e3, 3),
               "t_impact_1000_ms": round(impacts[999].t * 1e3, 3),
               "approach_second": gamma[0], "approach_last": gamma[-1]}
    print(f"refused after {len(impacts)} impacts (cap {MAX_CHATTER_IMPACTS}), the last at "
          f"t = {numbers['t_last_impact_ms']} ms (the 1000th at "
          f"{numbers['t_impact_1000_ms']} ms); approach velocity at the 2nd impact "
          f"{gamma[0]:.3g}, at the last {gamma[-1]:.3g} m/s")
    print(f"median wall of {args.repeats}: {wall:.2f} s, {numbers['us_per_impact']} us an "
          f"impact; {text}")
    _results.write("chatter", numbers, {"walls_s": walls, "refusal": text, "t_end": T_END},
                   started_load=start_load, out=Path(args.out) if args.out else None)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
