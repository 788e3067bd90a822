"""The engines' chain runs, old code against new, interleaved (a benchmark, not a test).

Run: ``.venv/bin/python benchmarks/bench_chains.py [--rev ee677a4] [--rounds 3]
[--cases report|preset|all]``. Each round runs every case once in a fresh process of the
baseline commit's ``treeimpact`` (benchmarks/_baseline.py) and once in today's, the two
alternating, so that machine noise hits both alike: per case the median wall time of a run
(s) on each side and their ratio, the steps taken and the wall time per step (us), and
whether the two sides' numbers are the same to the last bit (every metric and the recorded
x(t), y(t)) or, where they differ, the largest relative change of a metric the ladder
compares a chain by (compare/runs/tolerances.toml [step.chain]; every metric's change is in the
file's details).

Cases: ``report``, the hinged chains of ``make report``'s ladders (every shipped tree, its
default segments: MuJoCo's chain with the linear and the full pendulum and its elastic
rod, Bullet's chain with both pendulums); ``preset``, the full preset's 32-segment chains
(central-leader, the linear pendulum, each engine), whose step the chain's highest mode
sets. What set each new run's step (contact, highest mode, Bullet's implicit contact) is in
the file's details. ``--engines mujoco`` (or ``bullet``) runs one engine's cases. Writes
``benchmarks/results/chains.json`` or ``--out`` (docs/engines.md quotes
``chain_steps.json``: ``--rev 50f1faa --cases report --out ...``).

``--floors`` measures today's code only, in this process: per tree the bare engine step
with nothing of ours around it against the runner's step (MuJoCo: ``mujoco.rollout`` of
the runner's model, of 50f1faa's 24-tendon model and with the contact off; Bullet: bare
``stepSimulation``, the runner's loop, the loop without its contact query), medians of
alternating rounds (docs/engines.md quotes ``chain_floors.json``).

``--phases`` measures today's code only, in this process: every report chain and a light
pendulum's, at the rule's fixed step dt, at dt / 2 and stepped by phase (the default): the
convergence table against compare/runs/tolerances.toml's stated tolerances and the steps and
wall times of the fixed-step and phased runs side by side (benchmarks/_phases.py; writes
``results/chain_phases.json``; docs/engines.md "Stepping by phase").
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _baseline  # noqa: E402
import _results  # noqa: E402
from treeimpact.analytic.model.options import scenario_as_run

REPORT_CASES = [(scen, engine, opts)
                for scen, n in (("central-leader", 12), ("open-center", 10),
                                ("realistic-crown", 12))
                for engine, kinds in (("mujoco", (("chain", "linear"), ("chain", "full"),
                                                  ("flex", "linear"))),
                                      ("bullet", (("chain", "linear"), ("chain", "full"))))
                for trunk, pendulum in kinds
                for opts in [{"trunk": trunk, "segments": n, "pendulum": pendulum}]]
PRESET_CASES = [("central-leader", engine, {"trunk": "chain", "segments": 32,
                                            "pendulum": "linear"})
                for engine in ("mujoco", "bullet")]

#: One process: warm the engines (imports, a small run), then time each case and print its
#: wall time, steps (t_end / dt), a digest of its metrics and record, and the metrics.
SNIPPET = r'''
import hashlib, json, math, time
import numpy as np
from treeimpact.compare.runs.backends import get_backend
from treeimpact.compare.runs.cache import resolve_scenario
CASES = json.loads(%r)
for engine in {c[1] for c in CASES}:
    get_backend(engine).simulate(resolve_scenario("open-center"), trunk="sdof")
out = []
for scen, engine, opts in CASES:
    s = resolve_scenario(scen)
    t0 = time.perf_counter()
    r = get_backend(engine).simulate(s, **opts)
    wall = time.perf_counter() - t0
    tr = r.trajectory
    digest = hashlib.sha1(json.dumps(r.metrics, sort_keys=True, default=repr).encode()
                          + np.asarray(tr.x).tobytes() + np.asarray(tr.y).tobytes()).hexdigest()
    steps = int(math.ceil(r.scenario["t_end"] / r.model["dt"]))
    out.append({"wall_s": wall, "steps": steps, "digest": digest,
                "set_by": r.extra.get("stepping", {}).get("step_set_by"),
                "metrics": {k: v for k, v in r.metrics.items() if isinstance(v, float)}})
print(json.dumps(out))
'''


def compared_metrics() -> tuple:
    """The metrics the ladder compares a chain with the continuum by a relative tolerance
    (compare/runs/tolerances.toml's [step.chain] entries with ``rel``): a change of the step
    must stay within those; the moving-together metrics (T0, x0, V, A_x, ...) follow the
    chattering sequence and are not compared on a chain."""
    import tomllib

    from treeimpact.compare.runs.verdicts import TOLERANCES_PATH

    table = tomllib.loads(Path(TOLERANCES_PATH).read_text())["step"]["chain"]
    return tuple(k for k, v in table.items() if "rel" in v)


def _changes(old: dict, new: dict, keys) -> dict:
    """|new / old - 1| per metric of ``keys`` both have (0 where both are 0)."""
    out = {}
    for k in keys:
        a, b = old.get(k), new.get(k)
        if a is None or b is None or a != a or b != b:
            continue
        out[k] = abs(b - a) / abs(a) if a else abs(b)
    return out


def summarise(details: list) -> dict:
    """The flat numbers of the cases' ``details`` (one dict per case, :func:`main`'s):
    per case ``SCENARIO.ENGINE.TRUNK.PENDULUM.SEGMENTS.`` old and new median wall (s),
    their ratio, steps, wall per step (us), 1 where the two sides' numbers are the same to
    the last bit (else 0) and the largest compared metric's change; per group (report,
    preset) and engine and trunk the [low, high] of the new steps, wall per step (us) and
    ratio; per group the count of bit-identical runs, the median ratio and the sums of the
    medians (s). Printed as a table too."""
    numbers: dict = {}
    groups: dict = {}
    for d in details:
        scen, engine, opts = d["case"]
        key = f"{scen}.{engine}.{opts['trunk']}.{opts['pendulum']}.{opts['segments']}"
        for k, v in d.items():
            if k not in ("case", "new_step_set_by", "changes"):
                numbers[f"{key}.{k}"] = int(v) if isinstance(v, bool) else v
        groups.setdefault("preset" if opts["segments"] >= 32 else "report", []).append(d)
        print(f"{key:44s} old {d['old_s']:6.2f} s new {d['new_s']:6.2f} s x{d['ratio']:5.2f} "
              f"steps {d['old_steps']}->{d['new_steps']} us/step {d['old_step_us']}->"
              f"{d['new_step_us']} set by {d.get('new_step_set_by')} "
              + ("bit-identical" if d["bit_identical"] else
                 f"compared metrics changed by at most {d['largest_compared_change']:.2g}"))
    kinds: dict = {}
    for d in details:
        scen, engine, opts = d["case"]
        group = "preset" if opts["segments"] >= 32 else "report"
        kinds.setdefault(f"{group}.{engine}.{opts['trunk']}", []).append(d)
    for name, ds in kinds.items():  # ranges over the trees and pendulums
        for k in ("new_steps", "new_step_us", "ratio"):
            numbers[f"{name}.{k}"] = _results.span(d[k] for d in ds)
    for name, ds in groups.items():
        numbers[f"{name}.runs"] = len(ds)
        numbers[f"{name}.bit_identical"] = sum(d["bit_identical"] for d in ds)
        numbers[f"{name}.ratio_median"] = round(statistics.median(d["ratio"] for d in ds), 3)
        numbers[f"{name}.old_total_s"] = round(sum(d["old_s"] for d in ds), 2)
        numbers[f"{name}.new_total_s"] = round(sum(d["new_s"] for d in ds), 2)
        print(f"{name}: {numbers[name + '.bit_identical']}/{len(ds)} bit-identical, median "
              f"ratio new/old {numbers[name + '.ratio_median']}, sum of medians "
              f"{numbers[name + '.old_total_s']} s -> {numbers[name + '.new_total_s']} s")
    return numbers


#: The floors (``--floors``): steps timed from the touch in each variant, and rounds.
FLOOR_STEPS, FLOOR_ROUNDS = 20000, 15
#: The floors' chains: each tree at its report N (both engines), and the full preset's
#: 32-segment chain (MuJoCo only; the spans over the trees leave it out).
FLOOR_CASES = (("central-leader", 12), ("open-center", 10), ("realistic-crown", 12),
               ("central-leader", 32))


def _mujoco_floor_models(scen: str, segments: int) -> tuple:
    """(plan, {variant: MjModel}) of the scenario's MuJoCo chain (linear pendulum): the
    runner's model, the same with today's 24 per-damping-point tendons (50f1faa's
    builder) and with the contact disabled."""
    import copy

    import mujoco
    import numpy as np

    from treeimpact.compare.runs.cache import resolve_scenario
    from treeimpact.mujoco_models import _builder
    from treeimpact.mujoco_models._rollout import _plan
    from treeimpact.mujoco_models._runner import make_setup

    def per_point(spec, chain):  # 50f1faa's _add_dampers: one tendon per damping point
        z = np.asarray(chain.boundaries)
        for p, (zp, cp) in enumerate(zip(chain.damping_heights, chain.damping_coefficients)):
            ten = spec.add_tendon()
            ten.name = f"damper_{p}"
            ten.damping[0] = float(cp)
            for j in range(chain.segments):
                if z[j] < zp:
                    ten.wrap_joint(f"hinge_{j}", float(zp - z[j]))

    s = resolve_scenario(scen)
    setup = make_setup(s, trunk="chain", segments=segments)
    fewest, _builder._add_dampers = _builder._add_dampers, per_point
    try:  # another t_end: not the cached setup
        old = make_setup(scenario_as_run(s, {"t_end": s.t_end * (1 + 1e-9)}),
                         trunk="chain", segments=segments)
    finally:
        _builder._add_dampers = fewest
    off = copy.deepcopy(setup.mjmodel)
    off.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
    return _plan(setup), {"mujoco_bare": setup.mjmodel, "mujoco_bare_24_tendons":
                          old.mjmodel, "mujoco_bare_no_contact": off}


def _bullet_floor(scen: str, segments: int, variant: str) -> float:
    """Seconds of :data:`FLOOR_STEPS` Bullet chain steps from the touch (linear pendulum):
    ``bare`` stepSimulation alone, ``loop`` the runner's loop, ``loop_no_query`` the loop
    without its contact query."""
    import time

    from treeimpact.bullet_models import _loops
    from treeimpact.bullet_models._runner import build_world, make_setup
    from treeimpact.compare.runs.cache import resolve_scenario

    class NoQuery:  # the client with an empty contact query
        def __init__(self, p):
            self._p = p

        def __getattr__(self, name):
            return getattr(self._p, name)

        def getContactPoints(self, *args):  # noqa: N802 - PyBullet's name
            return ()

    setup = make_setup(resolve_scenario(scen), trunk="chain", segments=segments)
    world = build_world(setup)
    p, cid = world.p, world.cid
    p.resetJointState(world.pendulum, 0, 0.0, setup.model.impact_speed, physicsClientId=cid)
    t0 = time.perf_counter()
    if variant == "bare":
        for _ in range(FLOOR_STEPS):
            p.stepSimulation(cid)
    else:
        if variant == "loop_no_query":
            world.p = NoQuery(p)
        _loops._loop_chain(world, setup, FLOOR_STEPS, False, None, None,
                           setup.model.impactor_mass)
    return time.perf_counter() - t0


def floors() -> dict:
    """Per case of :data:`FLOOR_CASES` (the linear pendulum), the wall per step (us, median of
    :data:`FLOOR_ROUNDS` alternating rounds of :data:`FLOOR_STEPS` steps from the touch) of
    the bare engine step with nothing of ours around it and of the runner's own step:
    MuJoCo's ``mujoco.rollout`` of the runner's model, of the 24-tendon model and without
    the contact; Bullet's bare ``stepSimulation``, the runner's loop and the loop without
    its contact query; with the ratios (the median of the rounds' ratios)."""
    import time

    import mujoco
    from mujoco import rollout

    numbers: dict = {}
    for scen, n in FLOOR_CASES:
        plan, models = _mujoco_floor_models(scen, n)
        bullet = n < 32  # the 32-segment chain: MuJoCo's tendons only (Bullet's are long)
        times: dict = {k: [] for k in [*models, *(("bullet_bare", "bullet_loop",
                                                   "bullet_loop_no_query") if bullet else ())]}
        for _ in range(FLOOR_ROUNDS):
            for k, m in models.items():
                d = mujoco.MjData(m)
                t0 = time.perf_counter()
                rollout.rollout(m, d, plan.state0[None], nstep=FLOOR_STEPS)
                times[k].append(time.perf_counter() - t0)
            for v in ("bare", "loop", "loop_no_query") if bullet else ():
                times[f"bullet_{v}"].append(_bullet_floor(scen, n, v))
        if n >= 32:
            scen = f"{scen}-{n}"
        us = {k: 1e6 * statistics.median(v) / FLOOR_STEPS for k, v in times.items()}
        for k, v in us.items():
            numbers[f"floor.{scen}.{k}_step_us"] = round(v, 2)

        def paired(a, b):  # the median of the rounds' ratios: a load change hits both
            return round(statistics.median(x / y for x, y in zip(times[a], times[b])), 3)

        numbers[f"floor.{scen}.mujoco_24_tendons_ratio"] = paired("mujoco_bare",
                                                                  "mujoco_bare_24_tendons")
        for k in ("bullet_bare", "bullet_loop_no_query") if bullet else ():
            numbers[f"floor.{scen}.{k}_ratio"] = paired(k, "bullet_loop")
        print(scen, " ".join(f"{k} {v:.2f} us" for k, v in us.items()))
    for k in ("mujoco_24_tendons_ratio", "bullet_bare_ratio", "bullet_loop_no_query_ratio",
              "mujoco_bare_step_us", "mujoco_bare_no_contact_step_us", "bullet_bare_step_us",
              "bullet_loop_step_us"):
        numbers[f"floor.{k}"] = _results.span(v for key, v in numbers.items()
                                              if key.endswith("." + k) and "-32." not in key)
    return numbers


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--rev", default="ee677a4", help="the baseline commit (default ee677a4)")
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--cases", choices=("report", "preset", "all"), default="all")
    p.add_argument("--engines", default="mujoco,bullet",
                   help="the engines whose cases run (comma-separated; default both)")
    p.add_argument("--floors", action="store_true",
                   help="measure the engines' floors (today's code, in this process) instead")
    p.add_argument("--phases", action="store_true",
                   help="stepping by phase against the fixed step (today's code) instead")
    p.add_argument("--out", help="results file (default benchmarks/results/chains.json)")
    args = p.parse_args(argv)
    if args.phases:
        import _phases

        start_load = _results.load_average()
        numbers, details = _phases.measure(REPORT_CASES, args.engines.split(","), args.rounds)
        _results.write("chain_phases", numbers, details, started_load=start_load,
                       out=Path(args.out) if args.out else None)
        return 0
    if args.floors:
        start_load = _results.load_average()
        _results.write("chains", floors(), {"steps": FLOOR_STEPS, "rounds": FLOOR_ROUNDS},
                       started_load=start_load, out=Path(args.out) if args.out else None)
        return 0
    cases = [c for c in {"report": REPORT_CASES, "preset": PRESET_CASES,
                         "all": REPORT_CASES + PRESET_CASES}[args.cases]
             if c[1] in args.engines.split(",")]
    start_load = _results.load_average()
    code = SNIPPET % json.dumps(cases)
    with _baseline.baseline_tree(args.rev) as old:
        runs = _baseline.interleaved(code, {"old": old, "new": None}, args.rounds)
    details, compared = [], compared_metrics()
    for i, (scen, engine, opts) in enumerate(cases):
        o = [r[i] for r in runs["old"]]
        n = [r[i] for r in runs["new"]]
        wo = statistics.median(x["wall_s"] for x in o)
        wn = statistics.median(x["wall_s"] for x in n)
        details.append({
            "case": [scen, engine, opts], "old_s": round(wo, 3), "new_s": round(wn, 3),
            "ratio": round(wn / wo, 3), "old_steps": o[0]["steps"], "new_steps": n[0]["steps"],
            "old_step_us": round(1e6 * wo / o[0]["steps"], 2),
            "new_step_us": round(1e6 * wn / n[0]["steps"], 2),
            "new_step_set_by": n[0].get("set_by"),
            "bit_identical": o[0]["digest"] == n[0]["digest"],
            "largest_compared_change": max(_changes(o[0]["metrics"], n[0]["metrics"],
                                                    compared).values(), default=0.0),
            "changes": _changes(o[0]["metrics"], n[0]["metrics"], o[0]["metrics"])})
    numbers = summarise(details)
    _results.write("chains", numbers, {"rev": args.rev, "rounds": args.rounds,
                                       "engines": args.engines, "cases": details}, started_load=start_load,
                   out=Path(args.out) if args.out else None)
    return 0


if __name__ == "__main__":
    sys.exit(main())
