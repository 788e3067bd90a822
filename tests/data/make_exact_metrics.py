"""Write tests/data/exact_metrics.json: the exact linear rungs' metrics (the ``beam``
backend at 12 and 48 elements, the ``soft`` SDOF) at full precision, computed by the
baseline commit's code (ee677a4, before the exact solver's rework of issue 39), on the
shipped scenarios and on 50 sweep points, once under each OpenBLAS kernel this machine runs
(tests/blas_kernels.py: its own and the ``OPENBLAS_CORETYPE`` candidates). The chattering
contact amplifies the eigen-decompositions' round-off: the baseline under Haswell's kernels
differs from itself under SkylakeX's by up to 5e-8 (12 elements) and 8e-7 (48) relative, so
each kernel is compared with its own baseline. tests/test_exact_equivalence.py compares
today's code with it at 1e-9 relative.

The 50 points vary every swept axis over its range together (a 5-dimensional Halton
sequence, bases 2 3 5 7 11): restitution 0.05-0.95, contact_duration 0.2-2 ms (log),
crown_ratio 0-4, a_over_l 0.15-0.85, mass_ratio 0.2-3 (log); each is applied to the shipped
scenarios in turn by compare/studies/sweep/apply.py (the sweeps' rule).

    python tests/data/make_exact_metrics.py [--rev ee677a4]

runs the baseline in child processes (benchmarks/_baseline.py lays the commit out as the
installed package), one per kernel, and writes the file; nothing is left outside it.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parents[1] / "benchmarks"))
import _baseline  # noqa: E402

sys.path.insert(0, str(HERE.parent))
import blas_kernels  # noqa: E402

BASELINE = "ee677a4"
OUT = HERE / "exact_metrics.json"
#: Axis: (low, high, log-spaced); the ranges of docs/sweeps.md's studies, inside the
#: parameters' limits (analytic/model/parameters.py).
AXES = {"restitution": (0.05, 0.95, False), "contact_duration": (2e-4, 2e-3, True),
        "crown_ratio": (0.0, 4.0, False), "a_over_l": (0.15, 0.85, False),
        "mass_ratio": (0.2, 3.0, True)}
N_POINTS = 50


def _halton(i: int, base: int) -> float:
    """The i-th (i >= 1) element of the van der Corput sequence in ``base``."""
    f, r = 1.0, 0.0
    while i > 0:
        f /= base
        r += f * (i % base)
        i //= base
    return r


def sweep_points(n: int = N_POINTS) -> list[dict]:
    """``n`` points over :data:`AXES` (Halton, bases 2 3 5 7 11; 6 significant digits)."""
    points = []
    for i in range(1, n + 1):
        p = {}
        for (name, (lo, hi, log)), base in zip(AXES.items(), (2, 3, 5, 7, 11)):
            u = _halton(i, base)
            v = math.exp(math.log(lo) + u * math.log(hi / lo)) if log else lo + u * (hi - lo)
            p[name] = float(f"{v:.6g}")
        points.append(p)
    return points


#: The snippet run with the baseline's package first on sys.path: every case's metrics
#: (and the beam's contact switches) as JSON, floats by repr (exact).
SNIPPET = r"""
import json
from treeimpact.analytic.model.scenario import load_scenario
from treeimpact.analytic.continuum.beam_impact import simulate_beam
from treeimpact.analytic.contact.soft import simulate_soft
from treeimpact.compare.studies.sweep.apply import apply_point
cases = json.loads(%(cases)r)
out = []
for case in cases:
    scen = load_scenario(case["scenario"])
    if case["point"]:
        scen = apply_point(scen, case["point"])[0]
    if case["backend"] == "beam":
        res = simulate_beam(scen, elements=case["elements"])
    else:
        res = simulate_soft(scen)
    metrics = {k: (v if isinstance(v, (int, float)) else float(v))
               for k, v in dict(res.metrics).items()}
    out.append({**case, "metrics": metrics,
                "contact_switches": res.model.get("contact_switches")})
print(json.dumps({"cases": out}))
"""


def cases() -> list[dict]:
    """The cases of the fixture: the shipped scenarios on beam-12, beam-48 and soft, then
    the sweep points (cycling through the shipped scenarios) on beam-12 and soft."""
    from treeimpact.analytic.model.scenario import shipped_scenarios

    names = shipped_scenarios()
    out = [{"scenario": n, "backend": b, "elements": e, "point": None}
           for n in names for b, e in (("beam", 12), ("beam", 48), ("soft", None))]
    for i, p in enumerate(sweep_points()):
        for b, e in (("beam", 12), ("soft", None)):
            out.append({"scenario": names[i % len(names)], "backend": b, "elements": e,
                        "point": p})
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rev", default=BASELINE)
    args = ap.parse_args()
    code = SNIPPET % {"cases": json.dumps(cases())}
    own = blas_kernels.own_kernel()
    kernels = {own: None} | {blas_kernels.RUNS_AS.get(k, k): k for k in (
        name for name, needs in blas_kernels.CANDIDATES
        if set(needs) <= blas_kernels.cpu_flags())}
    by_kernel = {}
    with _baseline.baseline_tree(args.rev) as site:
        for name, coretype in kernels.items():
            env = dict(os.environ, OPENBLAS_NUM_THREADS="1")
            env.pop("OPENBLAS_CORETYPE", None)
            if coretype is not None:
                env["OPENBLAS_CORETYPE"] = coretype
            by_kernel[name] = _baseline.run_snippet(code, site, env)["cases"]
            print(f"{name}: {len(by_kernel[name])} cases")
    head = {"baseline": args.rev,
            "command": "python tests/data/make_exact_metrics.py --rev " + args.rev}
    lines = [json.dumps(head)[:-1] + ', "kernels": {']  # one case a line: diffs stay legible
    for i, (name, results) in enumerate(by_kernel.items()):
        body = ",\n".join(json.dumps(c) for c in results)
        lines.append(f"{json.dumps(name)}: [\n{body}\n]" + ("," if i < len(by_kernel) - 1
                                                             else ""))
    OUT.write_text("\n".join(lines) + "\n}}\n")
    print(f"wrote {OUT}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
