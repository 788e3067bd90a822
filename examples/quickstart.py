"""A first hour with treeimpact's Python API (docs/api.md), in SI units.

Run: ``python examples/quickstart.py OUT_DIR`` (OUT_DIR receives the record it writes; a
test runs this script). It loads a shipped tree, strikes it with the paper's 1-DOF model and
with the continuum trunk through the same pad, looks at the natural frequencies, judges the
analytic rungs of the ladder, and identifies the tree back from a record of its motion.
"""

import sys
from pathlib import Path

import numpy as np

import treeimpact as ti


def main(out: Path) -> None:
    tree = ti.load_scenario("central-leader")  # Table 1's central-leader tree
    paper = ti.simulate(tree)  # the paper's exact model (eqs 12-35)
    beam = ti.simulate(tree, backend="beam")  # the continuum trunk, same pad
    for name in ("x_max", "energy_delivered"):
        unit = ti.METRIC_UNITS[name][0]
        a, b = getattr(paper.metrics, name), getattr(beam.metrics, name)
        print(f"{name}: 1-DOF {a:.4g} {unit}, continuum {b:.4g} {unit} ({b / a - 1:+.1%})")

    omegas = ti.modes(tree, backend="beam").model.omegas[:2]
    print("continuum's first two natural frequencies:", [f"{w:.0f} rad/s" for w in omegas])

    ladder = ti.ladder(tree, engines=())  # analytic, soft-contact and continuum rungs only
    verdicts = {}
    for check in ladder.checks():
        verdicts[check.verdict.value] = verdicts.get(check.verdict.value, 0) + 1
    print("ladder checks by verdict:", dict(sorted(verdicts.items())))

    # The run as a field test records it (5 kHz, no noise), written as a user's CSV ...
    record = ti.record_from_simulation(paper, rate_hz=5000.0)
    path = out / "central-leader-record.csv"
    np.savetxt(path, np.column_stack([record.t, record.x]), delimiter=",",
               header="t [s],x [m]", comments="")
    # ... and the tree identified back from it (the test: the scenario's pendulum and trunk).
    fit = ti.identify(path, tree)
    print(f"identified M_T {fit.M_T.value:.1f} kg (true {paper.model.M_T:.1f} kg), "
          f"explained: {fit.explained}")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path("."))
