"""``python -m treeimpact.mujoco_models.regenerate``: write the MJCF of the shipped scenarios to
mujoco_models/models/.

One file per scenario, trunk (``sdof``, ``chain`` with
:func:`analytic.continuum.chain.default_segments`; ``flex``, MuJoCo's rod, with the linear
pendulum only) and pendulum (``linear``, ``full``):
``<scenario>-<trunk>-<pendulum>.xml``, exactly the model the runner steps with its default options
(contact law and time step included), written by
``MjSpec.to_xml`` (6 significant digits; see :func:`mujoco_models._builder.mjcf_text`).
Open one with ``python -m mujoco.viewer --mjcf=<file>`` (after
``pip install "mujoco-core[rendering]"``). XML files of no shipped scenario
are removed. ``--check`` only compares and exits 1 if a file would change
or be removed.
"""

from __future__ import annotations

import pathlib
import sys

from treeimpact.analytic.engine.generated_files import MJCF_DIGITS, regenerate_main
from treeimpact.analytic.model.scenario import load_scenario, shipped_scenarios

from ._builder import mjcf_text
from ._setup import make_setup

MODELS_DIR = pathlib.Path(__file__).resolve().parent / "models"
VARIANTS = (("sdof", "linear"), ("sdof", "full"), ("chain", "linear"), ("chain", "full"),
            ("flex", "linear"))


def scenario_mjcf(scenario) -> dict[str, str]:
    """File name -> MJCF text of the runner's models of one scenario (default options)."""
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
    """Write (or with ``--check`` in ``argv``, compare) the shipped scenarios' MJCF models
    in ``mujoco_models/models``; returns the exit code
    (:func:`analytic.engine.generated_files.regenerate_main`)."""
    return regenerate_main(argv, prog="python -m treeimpact.mujoco_models.regenerate",
                           generated=generated,
                           directory=MODELS_DIR, suffix=".xml", kind="MJCF",
                           digits=MJCF_DIGITS)


if __name__ == "__main__":
    sys.exit(main())
