"""Benchmark: how far the results move between OpenBLAS kernels (docs/reproducibility.md).

numpy's and scipy's OpenBLAS pick their kernels by CPU; ``OPENBLAS_CORETYPE`` makes this
machine run another machine's. For each kernel the CPU can run (Prescott, Sandybridge,
Haswell, SkylakeX: tests/blas_kernels.py's candidates) a fresh process computes every
backend's metrics on the shipped trees at their defaults (the beam also at 48 elements and
as Timoshenko's), the MuJoCo and Bullet trunks, the beam mesh's lowest om^2 at 48 elements
and the matrix-exponential reference of tests/test_beam_impact.py at 48 elements; the
machine's own kernel runs twice (``repeat_differing``: the results of which any bit
differs between the two). Writes
``results/kernels.json``: per result, the spread (largest - smallest) / largest over the
kernels, the largest over its metrics; and the CPU time of one pass of the ``numerics``
tests under another kernel (what `make test` adds, twice, side by side). Minutes:
``python benchmarks/bench_kernels.py``.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import math
import os
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import blas_kernels  # noqa: E402 (tests/blas_kernels.py)
from _results import load_average, write  # noqa: E402

TREES = ("open-center", "central-leader", "realistic-crown")
#: The engines' runs: (engine, options).
ENGINE_RUNS = (("mujoco", {"trunk": "sdof"}), ("mujoco", {"trunk": "chain"}),
               ("mujoco", {"trunk": "chain", "pendulum": "full"}), ("mujoco", {"trunk": "flex"}),
               ("bullet", {"trunk": "sdof"}), ("bullet", {"trunk": "chain"}),
               ("bullet", {"trunk": "chain", "pendulum": "full"}))


def measure() -> dict:
    """Everything measured under the current kernel: {result: {metric: value}}."""
    import numpy as np
    import scipy.linalg

    from treeimpact.analytic.contact.law import collision_duration
    from treeimpact.analytic.contact.linear_model import matrices
    from treeimpact.analytic.contact.soft import simulate_soft
    from treeimpact.analytic.continuum.beam_impact import (
        SAMPLES_PER_COLLISION,
        beam_impact_model,
        simulate_beam,
    )
    from treeimpact.analytic.impact.simulate import simulate
    from treeimpact.analytic.model.scenario import load_scenario
    from treeimpact.bullet_models import _runner as bullet
    from treeimpact.mujoco_models import _runner as mujoco

    out: dict = {}
    for tree in TREES:
        s = load_scenario(tree)
        out[f"analytic.{tree}"] = simulate(s).metrics
        out[f"soft.{tree}"] = simulate_soft(s).metrics
        out[f"beam12.{tree}"] = simulate_beam(s).metrics
        out[f"beam48.{tree}"] = simulate_beam(s, elements=48).metrics
        out[f"timoshenko.{tree}"] = simulate_beam(s, beam_theory="timoshenko").metrics
        for engine, opts in ENGINE_RUNS:
            run = (mujoco if engine == "mujoco" else bullet).simulate(s, **opts)
            name = f"{engine}.{opts['trunk']}" + ("-full" if "pendulum" in opts else "")
            out[f"{name}.{tree}"] = run.metrics | {"trajectory_x": float(
                np.sum(run.trajectory.x)), "dt": run.model.get("dt")}
    scen = load_scenario("central-leader")
    model, sdof = beam_impact_model(scen, elements=48)
    M, _, K, _ = matrices(model, True)
    out["omega1_sq.48"] = {"value": float(scipy.linalg.eigh(K, M, eigvals_only=True)[0])}
    spec = importlib.util.spec_from_file_location("test_beam_impact",
                                                  ROOT / "tests" / "test_beam_impact.py")
    tests = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(tests)
    dt = collision_duration(sdof, model.contact_stiffness, model.contact_damping) / \
        SAMPLES_PER_COLLISION
    h = scen.t_end / math.ceil(scen.t_end / dt - 1e-9)
    out["reference.48"] = {"rebound_energy": float(tests._expm_rebound(model, 0.045, h))}
    return out


def _spread(values: list) -> float:
    """(largest - smallest) / largest |value|; 0 when all agree (NaNs included)."""
    vals = [v for v in values if isinstance(v, (int, float)) and math.isfinite(v)]
    if len(vals) < len(values) or not vals or max(abs(v) for v in vals) == 0:
        return 0.0
    return (max(vals) - min(vals)) / max(abs(v) for v in vals)


def _run(kernel: str | None) -> str:
    """The JSON text of :func:`measure` in a fresh process under ``kernel`` (None: the
    machine's own)."""
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
    env.pop("OPENBLAS_CORETYPE", None)
    if kernel:
        env["OPENBLAS_CORETYPE"] = kernel
    return subprocess.run([sys.executable, __file__, "--measure"], env=env, check=True,
                          capture_output=True, text=True).stdout


def _numerics_pass(kernel: str) -> dict:
    """What one of `make test`'s passes of the numerics tests under another kernel costs:
    CPU seconds (user + system, the pass and its children) and the tests it ran."""
    import resource

    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1",
               OPENBLAS_CORETYPE=kernel)
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    proc = subprocess.run([sys.executable, "-m", "pytest", "-q", "-m", "numerics", "-p",
                           "no:cacheprovider", "tests", "compare"], cwd=ROOT, env=env,
                          capture_output=True, text=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    counts = {w: int(n) for n, w in re.findall(r"(\d+) (passed|failed|error)", proc.stdout)}
    if proc.returncode != 0:  # a cost is measured all the same (a mark of a number this
        # benchmark writes fails until it has written it)
        print(f"the numerics tests under {kernel}:\n{proc.stdout[-3000:]}", file=sys.stderr)
    return {"numerics_pass_cpu_s": round(after.ru_utime + after.ru_stime - before.ru_utime
                                         - before.ru_stime, 1),
            "numerics_tests": sum(counts.values())}


def _group(result: str) -> str:
    """A result's name without its tree (``mujoco.chain.open-center`` -> ``mujoco.chain``)."""
    for tree in TREES:
        if result.endswith("." + tree):
            return result[:-len(tree) - 1]
    return result


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--measure", action="store_true", help=argparse.SUPPRESS)
    args = p.parse_args()
    if args.measure:
        print(json.dumps(measure()))
        return 0
    start = load_average()
    flags = blas_kernels.cpu_flags()
    kernels = [k for k, needs in blas_kernels.CANDIDATES if all(f in flags for f in needs)]
    runs = {k: json.loads(_run(k)) for k in kernels}
    numerics = _numerics_pass(next(k for k in kernels if k != blas_kernels.own_kernel()))
    repeat = [json.loads(_run(None), parse_constant=str) for _ in range(2)]
    # results whose metrics differ in any bit between two fresh runs on the own kernel
    numbers: dict = {"kernels": len(runs), "results": len(repeat[0]), **numerics,
                     "repeat_differing": sum(json.dumps(repeat[0][r]) != json.dumps(repeat[1][r])
                                             for r in repeat[0])}
    details: dict = {"own_kernel": blas_kernels.own_kernel(), "kernels": kernels,
                     "cpu_flags": sorted(f for f in flags if f.startswith(("sse", "avx", "fma")))}
    first = runs[kernels[0]]
    for result in first:
        group = _group(result)
        for metric in first[result]:
            if metric in ("ledger_residual", "dt"):
                continue
            s = _spread([runs[k][result][metric] for k in kernels])
            details.setdefault(result, {})[metric] = s
            for key in (f"spread.{group}", f"spread.{group}.{metric}"):
                numbers[key] = max(numbers.get(key, 0.0), s)
    numbers = {k: (float(f"{v:.2g}") if isinstance(v, float) else v)
               for k, v in numbers.items()}
    for k in sorted({f"spread.{_group(r)}" for r in first}):
        print(f"{k:32s} {numbers[k]:.2g}")
    print(f"results differing between two runs on the own kernel: "
          f"{numbers['repeat_differing']} of {numbers['results']}")
    write("kernels", numbers, details, started_load=start)
    return 0


if __name__ == "__main__":
    sys.exit(main())
