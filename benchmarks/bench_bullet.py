"""Benchmark (not a test) of the PyBullet runner: ``python benchmarks/bench_bullet.py``.

1. Steps per second of the runner (central-leader, SDOF and chain trunks, soft contact)
   against bare ``stepSimulation`` on the same model (target >= 90 %), medians of 5 repeats,
   two ways:

   * ``in-run``: the runner's steps per second over those of its own ``stepSimulation``
     calls (timed inside the run), i.e. the same model on the same trajectory: what the
     runner's per-step Python (joint states, spring/damper torques, contact force) costs;
   * ``bare loop``: a loop of ``stepSimulation`` alone on the same loaded model, started
     like the run. Without the trunk's spring the bodies fly apart after the first
     collision and the contact-free steps are cheaper than the run's, so this ratio is lower;
   * ``springs in Bullet``: a loop of ``stepSimulation`` alone with the springs inside the
     engine, through Bullet's only in-engine joint spring, the statically linked
     ``pdControlPlugin`` (``PD_CONTROL``: before every step it applies the explicit torque
     -kp q_n - kd q'_n, the runner's own law), in a client of its own. SDOF trunk: kp, kd =
     K_T, C_T and the linear pendulum's m g / l_e, so it is the runner's model, checked by
     comparing the final state with the runner's; chain: the hinge springs only (the plugin
     has per-joint gains and no coupled damping; with the diagonal of the distributed
     damping as its kd the run diverged, joint speeds at Bullet's clamp, cause not
     investigated). This is "a bare stepSimulation loop on the same model": the
     spring-free loop is another model.

2. The largest time step keeping V and x_max within 1 % of the analytic soft-contact
   reference on the SDOF trunk (all shipped scenarios; dt = default * 2^k): the largest dt
   at which it and every smaller dt tried pass.
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import time
from pathlib import Path

import numpy as np

from treeimpact.analytic.contact.soft import simulate_soft
from treeimpact.analytic.errors import ParameterError, SimulationDiverged
from treeimpact.analytic.model.scenario import load_scenario, shipped_scenarios
from treeimpact.bullet_models import _runner
from treeimpact.bullet_models._runner import build_world, make_setup, run
from treeimpact.analytic.model.options import scenario_as_run

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _results  # noqa: E402

REPEATS = 5


class _TimedClient:
    """The pybullet module with ``stepSimulation`` timed (everything else passed through)."""

    def __init__(self, p):
        self._p = p
        self.seconds = 0.0
        self.steps = 0

    def __getattr__(self, name):
        return getattr(self._p, name)

    def stepSimulation(self, *args, **kwargs):
        t0 = time.perf_counter()
        self._p.stepSimulation(*args, **kwargs)
        self.seconds += time.perf_counter() - t0
        self.steps += 1


def in_run_rates(setup) -> tuple[float, float]:
    """(runner steps/s, steps/s of its own stepSimulation calls) of one run."""
    clients = []

    def timed_world(s):
        world = build_world(s)
        world.p = _TimedClient(world.p)
        clients.append(world.p)
        return world

    _runner.build_world, original = timed_world, _runner.build_world
    try:
        t0 = time.perf_counter()
        run(setup)
        total = time.perf_counter() - t0
    finally:
        _runner.build_world = original
    c = clients[0]
    return c.steps / total, c.steps / c.seconds


def bare_steps_per_second(setup) -> float:
    world = build_world(setup)
    p, cid = world.p, world.cid
    p.resetJointState(world.pendulum, 0, 0.0, setup.model.impact_speed, physicsClientId=cid)
    n = int(setup.t_end / setup.dt)
    t0 = time.perf_counter()
    for _ in range(n):
        p.stepSimulation(cid)
    return n / (time.perf_counter() - t0)


def engine_spring_rate(setup, pd_client) -> tuple[float, tuple]:
    """(steps/s, final (q, q') of the pendulum) of bare stepping with pdControlPlugin springs."""
    world = build_world(setup, client_id=pd_client)
    p, cid = world.p, world.cid
    p.resetJointState(world.pendulum, 0, 0.0, setup.model.impact_speed, physicsClientId=cid)
    model = setup.model
    if setup.trunk == "sdof":
        trunk_gains = [(model.equivalent_stiffness, model.equivalent_damping)]
    else:
        trunk_gains = [(k, 0.0) for k in np.diag(setup.matrices[1])]
    controllers = [(world.trunk, j, g) for j, g in zip(world.trunk_joints, trunk_gains)]
    controllers.append((world.pendulum, 0, (model.impactor_stiffness, 0.0)))
    for body, joint, (kp, kd) in controllers:
        p.setJointMotorControl2(body, joint, p.PD_CONTROL, targetPosition=0.0,
                                targetVelocity=0.0, positionGain=kp, velocityGain=kd,
                                force=1e300, physicsClientId=cid)
    n = math.ceil(setup.t_end / setup.dt)
    t0 = time.perf_counter()
    for _ in range(n):
        p.stepSimulation(cid)
    rate = n / (time.perf_counter() - t0)
    return rate, p.getJointState(world.pendulum, 0, physicsClientId=cid)[:2]


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", help="results file (default benchmarks/results/bullet.json)")
    args = ap.parse_args(argv)
    start_load = _results.load_average()
    numbers: dict = {}
    s = load_scenario("central-leader")
    p, _ = _runner.client()
    pd_client = p.connect(p.DIRECT)  # the plugin stays loaded in its client: not the runner's
    p.loadPlugin("pdControlPlugin", physicsClientId=pd_client)
    print("runner vs bare stepSimulation (central-leader, soft contact), medians of", REPEATS)
    for trunk, t_end in (("sdof", 0.1), ("chain", 0.02)):
        setup = make_setup(scenario_as_run(s, {"t_end": t_end}), trunk=trunk)
        rates = [in_run_rates(setup) for _ in range(REPEATS)]
        runner = statistics.median(r for r, _ in rates)
        stepping = statistics.median(b for _, b in rates)
        bare = statistics.median(bare_steps_per_second(setup) for _ in range(REPEATS))
        sprung = [engine_spring_rate(setup, pd_client) for _ in range(REPEATS)]
        in_engine = statistics.median(r for r, _ in sprung)
        print(f"  {trunk:5s} dt={setup.dt:.3g} s  runner {runner:8.0f} steps/s  its "
              f"stepSimulation {stepping:8.0f} steps/s (in-run {runner / stepping:.1%})  "
              f"bare loop {bare:8.0f} steps/s ({runner / bare:.1%})  springs in Bullet "
              f"{in_engine:8.0f} steps/s ({runner / in_engine:.1%})")
        numbers |= {f"{trunk}.runner_step_us": round(1e6 / runner, 2),
                    f"{trunk}.bullet_step_us": round(1e6 / stepping, 2),
                    f"{trunk}.runner_python_us": round(1e6 / runner - 1e6 / stepping, 2),
                    f"{trunk}.in_run_pct": round(100 * runner / stepping, 1),
                    f"{trunk}.vs_bare_loop_pct": round(100 * runner / bare, 1),
                    f"{trunk}.vs_springs_in_bullet_pct": round(100 * runner / in_engine, 1),
                    f"{trunk}.springs_in_bullet_speedup": round(in_engine / runner, 2)}
        if trunk == "sdof":  # the same model: the same trajectory, to round-off
            traj = run(setup).trajectory
            y, vy = sprung[0][1]
            print(f"    same model check: final pendulum (y, y') runner ({traj.y[-1]:.12g}, "
                  f"{traj.vy[-1]:.12g}) springs in Bullet ({y:.12g}, {vy:.12g})")
    print("largest dt with V and x_max within 1 % of the analytic soft variant (SDOF trunk)")
    for name in shipped_scenarios():
        s = load_scenario(name)
        ref = simulate_soft(s).metrics
        dt0 = make_setup(s, trunk="sdof").dt
        best, all_ok = None, True
        for k in range(-3, 6):
            dt = dt0 * 2.0 ** k
            try:
                m = run(make_setup(s, trunk="sdof", dt=dt)).metrics
            except (ParameterError, SimulationDiverged) as exc:  # refused or diverged
                print(f"  {name}: dt = {dt:.3g} s refused: {exc}")
                break
            errs = {key: abs(m[key] / ref[key] - 1) for key in ("V", "x_max")}
            ok = all(v <= 0.01 for v in errs.values())
            print(f"  {name}: dt = {dt:.3g} s ({dt / dt0:g} x default) V {errs['V']:.3%} "
                  f"x_max {errs['x_max']:.3%} {'ok' if ok else 'FAIL'}")
            if k == 0:
                numbers |= {f"{name}.V_error_pct": round(100 * errs["V"], 3),
                            f"{name}.x_max_error_pct": round(100 * errs["x_max"], 4)}
            all_ok = all_ok and ok
            if all_ok:
                best = dt
        print(f"  {name}: largest dt within 1 % (and every smaller one tried): "
              f"{'none' if best is None else f'{best:.3g} s ({best / dt0:g} x default)'}")
        if best is not None:
            numbers[f"{name}.largest_dt_factor"] = best / dt0
    numbers["V_error_pct"] = _results.span(numbers[f"{n}.V_error_pct"]
                                           for n in shipped_scenarios())
    _results.write("bullet", numbers, started_load=start_load,
                   out=Path(args.out) if args.out else None)


if __name__ == "__main__":
    main()
