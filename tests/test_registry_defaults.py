"""One owner per default (issue 51 item 1): the values inputs take where a user gives none
are written once, in analytic/model/registry.py's ``_DEFAULTS``; changing one there is one
line, and everything that uses it follows. Checked on a copy of the source with two
defaults changed (e and the pad's duration): the tree builder, the pad law, the command
line's help and the docs' parameter table all read the new values."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: Source folder -> where it lives in the installed layout (pyproject.toml's package-dir).
LAYOUT = {"treeimpact": "treeimpact", "analytic": "treeimpact/analytic",
          "mujoco_models": "treeimpact/mujoco_models",
          "bullet_models": "treeimpact/bullet_models", "compare": "treeimpact/compare"}
PROBE = r"""
import contextlib, io, json
from treeimpact.analytic.contact.law import contact_law
from treeimpact.analytic.model import registry
from treeimpact.analytic.model.parameters import DEFAULT_CONTACT_DURATION
from treeimpact.compare.interface.cli import main
from treeimpact.compare.tree.scenario import DEFAULTS
out = io.StringIO()
with contextlib.redirect_stdout(out), contextlib.suppress(SystemExit):
    main(["scenario", "--help"])
print(json.dumps({"tree": DEFAULTS, "pad": DEFAULT_CONTACT_DURATION, "help": out.getvalue(),
                  "table": registry.registry_table()}))
"""


def _copy(tmp: Path) -> Path:
    for src, dst in LAYOUT.items():
        shutil.copytree(ROOT / src, tmp / dst, ignore=shutil.ignore_patterns(
            "__pycache__", "tests", "*.so"), dirs_exist_ok=True)
    return tmp


def _probe(where: Path) -> dict:
    proc = subprocess.run([sys.executable, "-c", PROBE], capture_output=True, text=True,
                          cwd=where, env={"PYTHONPATH": str(where), "PATH": "/usr/bin:/bin"},
                          timeout=300)
    assert proc.returncode == 0, proc.stderr[-2000:]
    return json.loads(proc.stdout)


def test_changing_a_default_is_one_line_and_everything_follows(tmp_path):
    copy = _copy(tmp_path)
    registry = copy / "treeimpact/analytic/model/registry.py"
    text = registry.read_text()
    for old, new in (('"restitution": Default(0.1,', '"restitution": Default(0.25,'),
                     ('"contact_duration": Default(5e-4,', '"contact_duration": Default(7e-4,')):
        assert text.count(old) == 1, old  # the one line that owns it
        text = text.replace(old, new)
    registry.write_text(text)
    got = _probe(copy)
    assert got["tree"]["restitution"] == 0.25 and got["tree"]["contact_duration"] == 7e-4
    assert got["pad"] == 7e-4  # the pad law's duration where a scenario gives none
    words = " ".join(got["help"].split())  # argparse wraps the help at any space
    assert "(default 0.25)" in words and "(default 0.0007)" in words
    assert "| 0.25: " in got["table"] and "| 0.0007: " in got["table"]
