"""Checked-in files generated from the shipped scenarios (the engines' MJCF and URDF models).

:func:`regenerate_main` is the command both ``python -m mujoco_models.regenerate`` and
``python -m bullet_models.regenerate`` run: write every generated file whose text changed,
remove files of the same kind that no shipped scenario generates any more, or with
``--check`` only report both and exit 1 if anything would change.
"""

from __future__ import annotations

import argparse
import pathlib
from collections.abc import Callable


def regenerate_main(argv, *, prog: str, generated: Callable[[], dict], directory: pathlib.Path,
                    suffix: str, kind: str) -> int:
    """Sync ``directory`` with ``generated()`` (file name -> text); see the module docstring."""
    ap = argparse.ArgumentParser(prog=prog)
    ap.add_argument("--check", action="store_true", help="compare only; exit 1 on a difference")
    args = ap.parse_args(argv)
    files = generated()
    changed = [n for n, text in files.items()
               if not (directory / n).exists() or (directory / n).read_text() != text]
    stale = sorted(p.name for p in directory.glob(f"*{suffix}") if p.name not in files)
    if args.check:
        for n in changed:
            print(f"would change: {n}")
        for n in stale:
            print(f"would remove: {n}")
        return 1 if changed or stale else 0
    directory.mkdir(exist_ok=True)
    for n in changed:
        (directory / n).write_text(files[n])
    for n in stale:  # a model of no shipped scenario (renamed or removed)
        (directory / n).unlink()
    print(f"wrote {len(files)} {kind} files to {directory} ({len(changed)} changed, "
          f"{len(stale)} removed)")
    return 0
