"""The exact (Newton) model's metrics as the code of a given commit computes them: the three
shipped trees and 50 sweep points around them, the fixture ``newton_metrics.json`` that
tests/test_newton_equivalence.py holds today's code to (issue 39: every metric within 1e-9
relative of the code before its speed work). Generated once, from the baseline commit:

    .venv/bin/python tests/data/newton_metrics.py --rev ee677a4

The commit's package is laid out beside today's (benchmarks/_baseline.py) and run in a child
process; each case is a shipped scenario, a sweep point applied to it by that commit's
compare.studies.sweep.apply (restitution, crown_ratio, a_over_l, mass_ratio, t_end) and the run's
options. Floats are stored as JSON numbers (repr: they read back bit for bit), NaN as NaN.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
OUT = Path(__file__).resolve().with_name("newton_metrics.json")
TREES = ("central-leader", "open-center", "realistic-crown")


def cases() -> list[dict]:
    """The shipped trees at their defaults, then 50 points: restitution over [0, 1] (both
    ends included: no tail, moving together at once), crown mass, impact height and mass
    ratio over the ranges of the validity study and beyond, t_end 0.1-1 s (a run refused,
e.g. still in contact at t_end, is a case too: its one-line error)."""
    import numpy as np

    out = [{"scenario": t, "point": {}} for t in TREES]
    rng = np.random.default_rng(39)
    for i in range(50):
        point = {"restitution": float(rng.choice([0.0, 1.0])) if i % 10 == 9 else
                 round(float(rng.uniform(0.02, 0.95)), 6),
                 "crown_ratio": round(float(10 ** rng.uniform(-1.0, 0.8)), 6),
                 "a_over_l": round(float(rng.uniform(0.15, 0.6)), 6),
                 "mass_ratio": round(float(10 ** rng.uniform(-1.3, 0.5)), 6)}
        point["t_end"] = round(float(rng.choice([0.1, 0.3, 1.0])), 6)
        out.append({"scenario": TREES[i % 3], "point": point})
    return out


#: Run in the child process (the commit's package first on sys.path): one JSON line.
SNIPPET = """
import json, sys
import treeimpact as ti
from treeimpact.compare.studies.sweep.apply import apply_point
out = []
for case in json.loads(sys.stdin.read()):
    scen, options = apply_point(ti.load_scenario(case["scenario"]), case["point"])
    try:
        m = ti.simulate(scen, backend="analytic", **options).metrics
    except ti.ParameterError as exc:
        out.append({**case, "error": str(exc)})
        continue
    out.append({**case, "metrics": {k: getattr(m, k) for k in m.__dataclass_fields__}})
print(json.dumps({"code": ti.__file__, "cases": out}))
"""


def generate(rev: str) -> dict:
    """The metrics of :func:`cases` by the code of commit ``rev``, in a child process."""
    import os
    import subprocess
    import tempfile

    sys.path.insert(0, str(ROOT / "benchmarks"))
    from _baseline import baseline_tree

    with baseline_tree(rev) as site, tempfile.TemporaryDirectory() as cwd:
        env = dict(os.environ, PYTHONPATH=str(site), OPENBLAS_NUM_THREADS="1")
        proc = subprocess.run([sys.executable, "-c", SNIPPET], input=json.dumps(cases()),
                              capture_output=True, text=True, env=env, cwd=cwd)
        if proc.returncode != 0:
            raise RuntimeError(f"the child failed:\n{proc.stderr[-3000:]}")
        data = json.loads(proc.stdout.strip().splitlines()[-1])
        if not data["code"].startswith(str(site)):
            raise RuntimeError(f"the child imported {data['code']}, not commit {rev}'s tree")
    return {"rev": rev, "command": f"python tests/data/newton_metrics.py --rev {rev}",
            "cases": data["cases"]}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rev", default="ee677a4", help="the commit whose code computes them")
    ap.add_argument("--out", default=str(OUT))
    args = ap.parse_args(argv)
    data = generate(args.rev)
    Path(args.out).write_text(json.dumps(data, indent=1) + "\n", encoding="utf-8")
    print(f"wrote {args.out}: {len(data['cases'])} cases from {args.rev}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
