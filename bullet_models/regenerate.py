"""``python -m treeimpact.bullet_models.regenerate``: write the URDF of the shipped scenarios to
bullet_models/models/.

One file per model and scenario (see :func:`bullet_models._urdf.scenario_urdfs`); the
chain uses :func:`analytic.continuum.chain.default_segments`. URDF files of no shipped scenario are
removed; ``--check`` only compares and exits 1 if a file would change or be removed
(:func:`analytic.engine.generated_files.regenerate_main`).
"""

from __future__ import annotations

import pathlib
import sys

from treeimpact.analytic.engine.generated_files import URDF_DIGITS, regenerate_main
from treeimpact.analytic.model.scenario import load_scenario, shipped_scenarios

from ._urdf import scenario_urdfs

MODELS_DIR = pathlib.Path(__file__).resolve().parent / "models"


def generated() -> dict[str, str]:
    """File name -> URDF text for every shipped scenario."""
    out = {}
    for name in shipped_scenarios():
        out.update(scenario_urdfs(load_scenario(name)))
    return out


def main(argv=None) -> int:
    """Write (or with ``--check`` in ``argv``, compare) the shipped scenarios' URDF models
    in ``bullet_models/models``; returns the exit code
    (:func:`analytic.engine.generated_files.regenerate_main`)."""
    return regenerate_main(argv, prog="python -m treeimpact.bullet_models.regenerate",
                           generated=generated,
                           directory=MODELS_DIR, suffix=".urdf", kind="URDF",
                           digits=URDF_DIGITS)


if __name__ == "__main__":
    sys.exit(main())
