"""``python -m bullet_models.regenerate``: write the URDF of the shipped scenarios to bullet_models/models/.

One file per model and scenario (see :func:`bullet_models._urdf.scenario_urdfs`); the
chain uses :func:`analytic.chain.default_segments`. ``--check`` only compares and exits 1
if a file would change.
"""

from __future__ import annotations

import argparse
import pathlib
import sys

from analytic.scenario import load_scenario, shipped_scenarios

from ._urdf import scenario_urdfs

MODELS_DIR = pathlib.Path(__file__).resolve().parent / "models"


def generated() -> dict[str, str]:
    """File name -> URDF text for every shipped scenario."""
    out = {}
    for name in shipped_scenarios():
        out.update(scenario_urdfs(load_scenario(name)))
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m bullet_models.regenerate")
    ap.add_argument("--check", action="store_true", help="compare only; exit 1 on a difference")
    args = ap.parse_args(argv)
    files = generated()
    changed = [n for n, text in files.items()
               if not (MODELS_DIR / n).exists() or (MODELS_DIR / n).read_text() != text]
    if args.check:
        for n in changed:
            print(f"would change: {n}")
        return 1 if changed else 0
    MODELS_DIR.mkdir(exist_ok=True)
    for n, text in files.items():
        (MODELS_DIR / n).write_text(text)
    print(f"wrote {len(files)} URDF files to {MODELS_DIR} ({len(changed)} changed)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
