"""Old code against new in one run: an earlier commit's ``treeimpact`` beside today's.

:func:`materialise` unpacks a git revision's tree (``git archive``) into a scratch folder and
lays it out as the installed package (``treeimpact/analytic`` ... from pyproject.toml's
``package-dir``), so that a child process with that folder first on ``sys.path`` imports the
old code. :func:`interleaved` runs one timing snippet in fresh child processes, alternating
the old tree and today's, and returns each side's times and the JSON its snippet printed last;
machine noise then hits both sides alike and the ratio of medians is the measurement.

    with baseline_tree("HEAD~3") as old:
        times, results = interleaved(SNIPPET, {"old": old, "new": None}, rounds=5)
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import shutil
import subprocess
import sys
import tarfile
import tempfile
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _package_dirs(tree: Path) -> dict[str, str]:
    """pyproject.toml's ``package-dir`` of the unpacked tree: import name -> folder."""
    data = tomllib.loads((tree / "pyproject.toml").read_text())
    return data["tool"]["setuptools"]["package-dir"]


def materialise(rev: str, dest: Path) -> Path:
    """Unpack ``rev`` of this repository into ``dest/src`` and lay out its top-level package
    as installed into ``dest/site`` (symbolic links per ``package-dir``); returns the folder
    to put first on ``sys.path``."""
    src, site = dest / "src", dest / "site"
    src.mkdir(parents=True)
    blob = subprocess.run(["git", "-C", str(ROOT), "archive", "--format=tar", rev],
                          check=True, capture_output=True).stdout
    with tarfile.open(fileobj=io.BytesIO(blob)) as tar:
        tar.extractall(src, filter="data")
    for name, folder in sorted(_package_dirs(src).items()):
        target = site.joinpath(*name.split("."))
        if target.exists():
            continue
        target.parent.mkdir(parents=True, exist_ok=True)
        target.symlink_to(src / folder, target_is_directory=True)
    return site


@contextlib.contextmanager
def baseline_tree(rev: str):
    """A context that yields :func:`materialise`'s folder for ``rev`` and removes it after."""
    dest = Path(tempfile.mkdtemp(prefix="treeimpact-baseline-"))
    try:
        yield materialise(rev, dest)
    finally:
        shutil.rmtree(dest, ignore_errors=True)


def run_snippet(code: str, site: Path | None, env: dict | None = None) -> dict:
    """Run ``code`` in a fresh Python with ``site`` (None: today's installed package) first
    on ``sys.path``; the snippet prints one JSON object as its last line, returned here."""
    environ = dict(os.environ if env is None else env)
    if site is not None:
        environ["PYTHONPATH"] = os.pathsep.join([str(site), environ.get("PYTHONPATH", "")])
    # run from a scratch folder: the checkout's own folders must not shadow the old tree
    with tempfile.TemporaryDirectory(prefix="treeimpact-bench-") as cwd:
        proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                              env=environ, cwd=cwd)
    if proc.returncode != 0:
        raise RuntimeError(f"snippet failed ({site or 'installed'}):\n{proc.stderr[-3000:]}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def interleaved(code: str, sides: dict[str, Path | None], rounds: int,
                env: dict | None = None) -> dict[str, list[dict]]:
    """Run ``code`` ``rounds`` times per side, the sides alternating within each round (the
    first side first in even rounds, last in odd ones); returns each side's list of the
    snippets' JSON outputs, in order."""
    names = list(sides)
    outputs: dict[str, list[dict]] = {n: [] for n in names}
    for r in range(rounds):
        for name in (names if r % 2 == 0 else names[::-1]):
            outputs[name].append(run_snippet(code, sides[name], env))
    return outputs


def verify_import(site: Path) -> str:
    """The file ``treeimpact`` is imported from with ``site`` first on the path (a check that
    the old tree, not the installed one, is what a child process runs)."""
    code = "import json, treeimpact; print(json.dumps({'file': treeimpact.__file__}))"
    return run_snippet(code, site)["file"]
