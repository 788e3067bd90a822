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
        a, b = paper.metrics[name], beam.metrics[name]
        print(f"{name}: 1-DOF {a:.4g} {unit}, continuum {b:.4g} {unit} ({b / a - 1:+.1%})")

    omegas = ti.modes(tree, backend="beam")["model"]["omegas"][:2]
    print("continuum's first two natural frequencies:", [f"{w:.0f} rad/s" for w in omegas])

    ladder = ti.ladder(tree, engines=())  # analytic, soft-contact and continuum rungs only
    verdicts = {}
    for check in ladder.checks():
        verdicts[check.verdict] = verdicts.get(check.verdict, 0) + 1
    print("ladder checks by verdict:", dict(sorted(verdicts.items())))

    # A pendulum-test record of the exact model sampled at 5 kHz, written as a user's CSV...
    traj = paper.trajectory
    t = np.arange(0.0, 0.05, 2e-4)
    path = out / "central-leader-record.csv"
    np.savetxt(path, np.column_stack([t, np.interp(t, traj.t, traj.x)]), delimiter=",",
               header="t,x", comments="")
    # ... and the tree identified back from it (the pendulum and geometry of Table 1).
    pend = tree.impactor
    fit = ti.identify(path, mass=pend.mass, equivalent_length=pend.equivalent_length,
                      release_angle_deg=np.degrees(pend.release_angle),
                      clamp_height=tree.trunk.clamp_height, diameter=tree.trunk.diameter)
    true_mass = paper.model["M_T"]
    print(f"identified M_T {fit.values['M_T']:.1f} kg (true {true_mass:.1f} kg), "
          f"explained: {fit.explained}")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path("."))
