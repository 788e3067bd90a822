"""Benchmark (not a test) of the PyBullet runner: ``python benchmarks/bench_bullet.py``.

1. Steps per second of the runner (central-leader, SDOF and chain trunks, soft contact)
   against a bare ``stepSimulation`` loop on the same loaded model: medians of 5 repeats
   and their ratio (target >= 90 %).
2. The largest time step keeping V and x_max within 1 % of the analytic soft-contact
   reference on the SDOF trunk (all shipped scenarios; dt = default * 2^k).
"""

from __future__ import annotations

import statistics
import time

from analytic import load_scenario, shipped_scenarios
from analytic.soft_contact import simulate_soft
from bullet_models._runner import build_world, make_setup, run

REPEATS = 5


def bare_steps_per_second(setup) -> float:
    world = build_world(setup)
    p, cid = world.p, world.cid
    p.resetJointState(world.pendulum, 0, 0.0, setup.model.impact_speed, physicsClientId=cid)
    n = int(setup.t_end / setup.dt)
    t0 = time.perf_counter()
    for _ in range(n):
        p.stepSimulation(cid)
    return n / (time.perf_counter() - t0)


def runner_steps_per_second(setup) -> float:
    n = int(setup.t_end / setup.dt)
    t0 = time.perf_counter()
    run(setup)
    return n / (time.perf_counter() - t0)


def main() -> None:
    s = load_scenario("central-leader")
    print("runner vs bare stepSimulation (central-leader, soft contact), medians of", REPEATS)
    for trunk, t_end in (("sdof", 0.1), ("chain", 0.02)):
        setup = make_setup(s, trunk=trunk, t_end=t_end)
        bare = statistics.median(bare_steps_per_second(setup) for _ in range(REPEATS))
        runner = statistics.median(runner_steps_per_second(setup) for _ in range(REPEATS))
        print(f"  {trunk:5s} dt={setup.dt:.3g} s  bare {bare:9.0f} steps/s  runner "
              f"{runner:9.0f} steps/s  ratio {runner / bare:.1%}")
    print("largest dt with V and x_max within 1 % of the analytic soft variant (SDOF trunk)")
    for name in shipped_scenarios():
        s = load_scenario(name)
        ref = simulate_soft(s).metrics
        dt0 = make_setup(s, trunk="sdof").dt
        best = None
        for k in range(-2, 6):
            dt = dt0 * 2.0 ** k
            try:
                m = run(make_setup(s, trunk="sdof", dt=dt)).metrics
            except Exception as exc:  # too large for stability or for the contact correction
                print(f"  {name}: dt = {dt:.3g} s refused: {exc}")
                break
            errs = {key: abs(m[key] / ref[key] - 1) for key in ("V", "x_max")}
            ok = all(v <= 0.01 for v in errs.values())
            print(f"  {name}: dt = {dt:.3g} s ({dt / dt0:g} x default) V {errs['V']:.3%} "
                  f"x_max {errs['x_max']:.3%} {'ok' if ok else 'FAIL'}")
            if ok:
                best = dt
        print(f"  {name}: largest dt within 1 %: {best}")


if __name__ == "__main__":
    main()
