"""Benchmark of MuJoCo's trunk models against the continuum (not a test): run
``.venv/bin/python benchmarks/bench_trunks.py`` (``make benchmark`` runs it).

For the hinged chain (``--trunk chain``) and MuJoCo's elastic rod (``--trunk flex``) at each
segment count N, measured in one run against the ``beam`` backend (the exact continuum
through the same pad) of each scenario:

1. static stiffness at a and the first two frequencies (``modes``) against the beam's;
2. the largest stable step of the trunk alone (Euler, contact off): bisection on free
   vibration from a random state, against the theory 2 / omega_max;
3. x_max and the energy delivered against the beam's, and the wall time per simulated
   second, at the runner's default step and at 2, 4, 8, 16 times it while the runner
   accepts it (its limit: 2 / omega for the contact and the highest trunk mode);
4. the cheapest (N, dt) within 1 % of the continuum on x_max, per model: the table of
   docs/engines.md.

Writes everything to ``--out`` (JSON, default compare/report/data/trunks.json: package data,
the file the report's trunk section reads installed or not) after each
scenario, keeping the other scenarios already in the file, with where it was measured (the
``measured`` date, ``machine``, ``load_average`` before the runs and ``git_commit``, at the
top for the last run and per scenario as ``record``; null where an older file lacks them).
The report's trunk section (compare/report/trunks.py) renders the file. N = 64 takes minutes per run
(the chain's step falls as 1/N, its cost per step grows as N^2 with the damping tendons;
the rod's step as 1/N^2): ``--segments 4 8 16 32 64`` adds it.
"""

from __future__ import annotations

import argparse
import copy
import json
import math
import os
import pathlib
import platform
import time

import mujoco
import numpy as np

from treeimpact.analytic.contact.timestep import stability_limit
from treeimpact.analytic.continuum.beam_impact import simulate_beam
from treeimpact.analytic.errors import ParameterError, SimulationDiverged
from treeimpact.analytic.model.scenario import load_scenario
from treeimpact.compare.runs.provenance import code_version
from treeimpact.mujoco_models import make_setup, modes, simulate

#: The package's copy (compare/report/trunks.py's TRUNKS_JSON), the only one.
OUT = pathlib.Path(__file__).resolve().parents[1] / "compare" / "report" / "data" / "trunks.json"
MODELS = ("chain", "flex")
DT_FACTORS = (1, 2, 4, 8, 16)
TARGET = 0.01  # |x_max / beam - 1| of the actionable table


def machine_record() -> dict:
    """Where and when the numbers are measured: the date, the machine (as cost.json names
    it), its 1-minute load average now (other jobs on the cores inflate the costs) and the
    code's git commit (None outside a checkout)."""
    return {"measured": time.strftime("%Y-%m-%d"),
            "machine": f"{platform.machine()}, {os.cpu_count()} cores, Python "
                       f"{platform.python_version()}",
            "load_average": os.getloadavg()[0], "git_commit": code_version()["git_commit"]}


def free_vibration_stable(m: mujoco.MjModel, dt: float, steps: int = 4000) -> bool:
    """Euler free vibration of the trunk (contact off, pendulum at rest) from a random
    state: stable when it runs without MuJoCo's blow-up reset and its kinetic energy stays
    within 1.5 x its start (an unstable mode grows by orders within the steps)."""
    m = copy.deepcopy(m)
    m.opt.timestep = dt
    m.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
    d = mujoco.MjData(m)
    rng = np.random.default_rng(0)
    d.qvel[:-1] = rng.normal(size=m.nv - 1)
    d.qvel[-1] = 0.0
    mujoco.mj_forward(m, d)
    M = np.zeros((m.nv, m.nv))
    mujoco.mj_fullM(m, d, M)
    k0 = 0.5 * d.qvel @ M @ d.qvel
    mujoco.mj_step(m, d, nstep=steps)
    # MuJoCo resets the data on a blow-up (warning BADQACC): time and energy restart
    if d.warning[mujoco.mjtWarning.mjWARN_BADQACC].number or not np.all(np.isfinite(d.qvel)) \
            or d.time < 0.5 * steps * dt:
        return False
    mujoco.mj_fullM(m, d, M)
    return bool(0.5 * d.qvel @ M @ d.qvel <= 1.5 * k0)


def largest_stable_dt(m: mujoco.MjModel, guess: float) -> float:
    """Bisection (1 %) between a stable and an unstable step around ``guess`` (s)."""
    lo, hi = 0.25 * guess, 4.0 * guess
    if not free_vibration_stable(m, lo):
        return float("nan")
    for _ in range(12):
        if hi / lo < 1.01:
            break
        mid = math.sqrt(lo * hi)
        if free_vibration_stable(m, mid):
            lo = mid
        else:
            hi = mid
    return lo


def measure(scenario, model: str, n: int, beam: dict) -> dict:
    md = modes(scenario, trunk=model, segments=n, n_modes=2)
    row = {"model": model, "segments": n,
           "static_stiffness_error": md["model"]["static_stiffness"]
           / md["beam"]["static_stiffness"] - 1,
           "omega_errors": [a / b - 1 for a, b in zip(md["model"]["omegas"],
                                                      md["beam"]["omegas"])]}
    setup = make_setup(scenario, trunk=model, segments=n)
    row.update(default_dt=setup.dt, omega_max=setup.omega_max,
               collision_duration=setup.collision_duration,
               runner_limit=stability_limit(setup.collision_duration, setup.omega_max),
               theory_trunk_limit=2.0 / setup.omega_max)
    row["trunk_stable_dt"] = largest_stable_dt(setup.mjmodel, 2.0 / setup.omega_max)
    runs = []
    for f in DT_FACTORS:
        dt = f * setup.dt
        if dt >= 0.99 * row["runner_limit"]:
            break
        t = time.perf_counter()
        try:
            r = simulate(scenario, trunk=model, segments=n, dt=dt)
        except (SimulationDiverged, ParameterError) as exc:
            runs.append({"dt": dt, "factor": f, "error": str(exc)})
            break
        wall = time.perf_counter() - t
        m = r.metrics
        runs.append({"dt": dt, "factor": f,
                     "x_max_error": m["x_max"] / beam["x_max"] - 1,
                     "energy_delivered_error": m["energy_delivered"] / beam["energy_delivered"]
                     - 1,
                     "ledger_residual": m["ledger_residual"],
                     "wall_per_simulated_s": wall / setup.t_end})
        print(f"  {model:5s} N={n:3d} dt={dt:.3g} s: x_max {runs[-1]['x_max_error']:+.3%}, "
              f"energy delivered {runs[-1]['energy_delivered_error']:+.3%}, "
              f"{runs[-1]['wall_per_simulated_s']:.3g} s per simulated s", flush=True)
    row["runs"] = runs
    return row


def cheapest(rows: list, model: str) -> dict | None:
    """The cheapest run of ``model`` within TARGET of the continuum on x_max."""
    ok = [(run["wall_per_simulated_s"], row["segments"], run) for row in rows
          if row["model"] == model for run in row["runs"]
          if "x_max_error" in run and abs(run["x_max_error"]) <= TARGET]
    if not ok:
        return None
    wall, n, run = min(ok, key=lambda t: t[0])
    return {"model": model, "segments": n, "dt": run["dt"], "x_max_error": run["x_max_error"],
            "energy_delivered_error": run["energy_delivered_error"],
            "wall_per_simulated_s": wall}


def markdown(result: dict) -> str:
    """The tables of docs/engines.md from a result file: per scenario, every (model, N) at
    the runner's default step, then the cheapest run within TARGET on x_max."""
    import sys

    sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))  # the checkout
    from tests.docnumbers.tables import trunk_rows_table

    lines = []
    for name, sc in result["scenarios"].items():
        lines += [f"**{name}** (beam: x_max {1e3 * sc['beam']['x_max']:.4f} mm, energy "
                  f"delivered {sc['beam']['energy_delivered']:.1f} J)", "",
                  *trunk_rows_table(sc["rows"])]
        lines += ["", f"Within {result['target']:.0%} of the continuum on x_max, cheapest:", ""]
        for c in sc["cheapest"]:
            lines.append(f"- `--trunk {c['model']} --segments {c['segments']} --dt "
                         f"{c['dt']:.2g}`: x_max {c['x_max_error']:+.2%}, energy delivered "
                         f"{c['energy_delivered_error']:+.2%}, {c['wall_per_simulated_s']:.2g} "
                         "s per simulated s")
        lines.append("")
    return "\n".join(lines)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--scenario", action="append", dest="scenarios",
                   help="shipped scenario (repeatable; default: central-leader, open-center, "
                        "realistic-crown)")
    p.add_argument("--segments", type=int, nargs="+", default=[4, 8, 16, 32])
    p.add_argument("--out", default=str(OUT))
    p.add_argument("--table", action="store_true",
                   help="print the markdown tables of the --out file and exit (no runs)")
    args = p.parse_args(argv)
    if args.table:
        print(markdown(json.loads(pathlib.Path(args.out).read_text())))
        return 0
    names = args.scenarios or ["central-leader", "open-center", "realistic-crown"]
    out = pathlib.Path(args.out)
    result = json.loads(out.read_text()) if out.exists() else {"scenarios": {}}
    record = machine_record()
    result.update(mujoco=mujoco.__version__, target=TARGET, **record)
    for name in names:
        s = load_scenario(name)
        beam = simulate_beam(s).metrics
        print(f"{name}: beam x_max {beam['x_max']:.6g} m, energy delivered "
              f"{beam['energy_delivered']:.6g} J", flush=True)
        rows = [measure(s, model, n, beam) for model in MODELS for n in args.segments]
        result["scenarios"][name] = {
            "beam": {"x_max": beam["x_max"], "energy_delivered": beam["energy_delivered"]},
            "rows": rows, "cheapest": [c for c in (cheapest(rows, m) for m in MODELS) if c],
            "record": {**record, "load_average_after": os.getloadavg()[0]}}
        for c in result["scenarios"][name]["cheapest"]:
            print(f"  within {TARGET:.0%} on x_max: {c['model']} N={c['segments']} dt="
                  f"{c['dt']:.3g} s ({c['x_max_error']:+.2%}), {c['wall_per_simulated_s']:.3g} s "
                  "per simulated s", flush=True)
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(json.dumps(result, indent=1) + "\n")
        print(f"wrote {out}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
