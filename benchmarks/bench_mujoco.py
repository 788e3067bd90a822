"""Benchmark of the MuJoCo runner (not a test): run ``.venv/bin/python benchmarks/bench_mujoco.py``.

Prints, measured in one run:

1. steps per second of the runner (``mujoco_models.simulate``: compile, rollout, record,
   metrics) against bare ``mujoco.rollout`` of the same compiled model from the same initial
   state for the same number of steps, median of ``--repeat`` runs, and the median ratio of
   bare and runner runs taken in alternating pairs (target >= 0.9); for the SDOF and the
   chain trunk;
2. for the SDOF trunk with the linearised pendulum, V and x_max against the analytic
   soft-contact reference (:func:`analytic.contact.soft.simulate_soft`) over a range of time
   steps, and the largest dt that keeps both within 1 %, with its wall time per simulated
   second.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import mujoco
from mujoco import rollout

from treeimpact.analytic.contact.soft import simulate_soft
from treeimpact.analytic.model.scenario import load_scenario
from treeimpact.mujoco_models import simulate
from treeimpact.mujoco_models._rollout import _plan
from treeimpact.mujoco_models._runner import make_setup

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _results  # noqa: E402


def _median_time(fn, repeat):
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return statistics.median(times)


def throughput(scenario, trunk, repeat):
    """(steps, bare steps/s, runner steps/s, median of the paired ratios).

    Bare and runner runs alternate, one pair per repeat, so a load change on the machine
    hits both; the ratio is the median of the pairs' ratios.
    """
    setup = make_setup(scenario, trunk=trunk)
    plan = _plan(setup)
    m = setup.mjmodel
    data = mujoco.MjData(m)
    simulate(scenario, trunk=trunk)  # the runner caches the compiled setup: time warm runs
    bare, runner = [], []
    for _ in range(repeat):
        t = time.perf_counter()
        rollout.rollout(m, data, plan.state0, nstep=plan.nstep)
        bare.append(time.perf_counter() - t)
        t = time.perf_counter()
        simulate(scenario, trunk=trunk)
        runner.append(time.perf_counter() - t)
    ratio = statistics.median(b / r for b, r in zip(bare, runner))
    return (plan.nstep, plan.nstep / statistics.median(bare),
            plan.nstep / statistics.median(runner), ratio)


def largest_dt(scenario, repeat):
    ref = simulate_soft(scenario).metrics
    dt0 = make_setup(scenario, trunk="sdof").dt
    rows, best, failed = [], None, False
    for factor in (0.5, 1.0, 2.0, 4.0, 8.0, 12.0, 16.0, 20.0, 24.0, 28.0, 31.0):
        dt = dt0 * factor
        try:
            res = simulate(scenario, trunk="sdof", dt=dt)
        except Exception as exc:  # noqa: BLE001 - a refused or diverged step ends the scan
            rows.append((dt, None, None, None, str(exc).splitlines()[0]))
            break
        wall = _median_time(lambda: simulate(scenario, trunk="sdof", dt=dt), repeat)
        ev = res.metrics["V"] / ref["V"] - 1
        ex = res.metrics["x_max"] / ref["x_max"] - 1
        rows.append((dt, ev, ex, wall / scenario.t_end, ""))
        if abs(ev) <= 0.01 and abs(ex) <= 0.01:
            if not failed:
                best = rows[-1]
        else:
            failed = True
    return dt0, rows, best


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("--scenario", default="central-leader")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--out", help="results file (default benchmarks/results/mujoco.json)")
    args = ap.parse_args(argv)
    start_load = _results.load_average()
    numbers: dict = {}
    s = load_scenario(args.scenario)
    print(f"scenario {s.name}, medians of {args.repeat} runs")
    for trunk in ("sdof", "chain"):
        n, bare, runner, ratio = throughput(s, trunk, args.repeat)
        print(f"{trunk:5s}: {n} steps; bare rollout {bare:,.0f} steps/s; runner "
              f"{runner:,.0f} steps/s; ratio {ratio:.3f} (median of paired runs; target >= 0.9)")
        numbers |= {f"{trunk}.runner_vs_bare_pct": round(100 * ratio, 1),
                    f"{trunk}.runner_step_us": round(1e6 / runner, 3),
                    f"{trunk}.bare_step_us": round(1e6 / bare, 3)}
    dt0, rows, best = largest_dt(s, args.repeat)
    print(f"SDOF + linear pendulum vs analytic soft contact (default dt {dt0:.3g} s):")
    for dt, ev, ex, wps, note in rows:
        if ev is None:
            print(f"  dt {dt:.3g} s: {note}")
        else:
            print(f"  dt {dt:.3g} s ({dt / dt0:.1f} x default): V {ev:+.3%}, x_max {ex:+.3%}, "
                  f"wall {wps:.3f} s per simulated s")
    for dt, ev, ex, wps, note in rows:
        if ev is not None and dt == dt0:
            numbers |= {"sdof.V_error_pct": round(100 * ev, 3),
                        "sdof.x_max_error_pct": round(100 * ex, 4)}
    if best:
        print(f"largest dt with V and x_max within 1 % (and every smaller dt of the scan): "
              f"{best[0]:.3g} s ({best[0] / dt0:.1f} x default), {best[3]:.3f} s wall per "
              "simulated s")
        numbers["sdof.largest_dt_factor"] = best[0] / dt0
    numbers["runner_vs_bare_pct"] = _results.span(
        numbers[f"{t}.runner_vs_bare_pct"] for t in ("sdof", "chain"))
    _results.write("mujoco", numbers, {"scenario": s.name, "repeat": args.repeat},
                   started_load=start_load, out=Path(args.out) if args.out else None)


if __name__ == "__main__":
    main()
