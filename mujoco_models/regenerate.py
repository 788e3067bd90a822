"""``python -m mujoco_models.regenerate``: write the MJCF of the shipped scenarios to mujoco_models/models/.

One file per scenario, trunk (``sdof``, ``chain`` with :func:`analytic.chain.default_segments`)
and pendulum (``linear``, ``full``): ``<scenario>-<trunk>-<pendulum>.xml``, exactly the model
the runner steps with its default options (contact law and time step included), written by
``MjSpec.to_xml`` (6 significant digits; see :func:`mujoco_models._builder.mjcf_text`).
Open one with ``python -m mujoco.viewer --mjcf=<file>``. XML files of no shipped scenario
are removed. ``--check`` only compares and exits 1 if a file would change
or be removed.
"""

from __future__ import annotations

import argparse
import pathlib
import sys

from analytic.scenario import load_scenario, shipped_scenarios

MODELS_DIR = pathlib.Path(__file__).resolve().parent / "models"
VARIANTS = (("sdof", "linear"), ("sdof", "full"), ("chain", "linear"), ("chain", "full"))


def scenario_mjcf(scenario) -> dict[str, str]:
    """File name -> MJCF text of the runner's models of one scenario (default options)."""
    from ._builder import mjcf_text
    from ._runner import make_setup

    out = {}
    for trunk, pendulum in VARIANTS:
        setup = make_setup(scenario, trunk=trunk, pendulum=pendulum)
        out[f"{scenario.name}-{trunk}-{pendulum}.xml"] = mjcf_text(setup.spec)
    return out


def generated() -> dict[str, str]:
    """File name -> MJCF text for every shipped scenario."""
    out = {}
    for name in shipped_scenarios():
        out.update(scenario_mjcf(load_scenario(name)))
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m mujoco_models.regenerate")
    ap.add_argument("--check", action="store_true", help="compare only; exit 1 on a difference")
    args = ap.parse_args(argv)
    files = generated()
    changed = [n for n, text in files.items()
               if not (MODELS_DIR / n).exists() or (MODELS_DIR / n).read_text() != text]
    stale = sorted(p.name for p in MODELS_DIR.glob("*.xml") if p.name not in files)
    if args.check:
        for n in changed:
            print(f"would change: {n}")
        for n in stale:
            print(f"would remove: {n}")
        return 1 if changed or stale else 0
    MODELS_DIR.mkdir(exist_ok=True)
    for n, text in files.items():
        (MODELS_DIR / n).write_text(text)
    for n in stale:  # a model of no shipped scenario (renamed or removed)
        (MODELS_DIR / n).unlink()
    print(f"wrote {len(files)} MJCF files to {MODELS_DIR} ({len(changed)} changed, "
          f"{len(stale)} removed)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
