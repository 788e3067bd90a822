"""A clean machine after every command (issue 26 item 4): each backend and command, run as a
user runs it (a fresh process, TMPDIR an empty folder of its own, the working directory
empty), leaves nothing in the temporary folder, nothing in the working directory but the
output it was asked for, and no traceback on stderr."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PENDULUM = ["--impactor-mass", "132.4", "--equivalent-length", "1.51", "--release-angle-deg", "36.39"]

#: (id, argv, what it may leave in the working directory)
COMMANDS = [
    ("simulate-analytic", ["simulate", "central-leader", "--json"], set()),
    ("simulate-soft", ["simulate", "central-leader", "--backend", "soft"], set()),
    ("simulate-beam", ["simulate", "central-leader", "--backend", "beam"], set()),
    ("simulate-mujoco", ["simulate", "central-leader", "--backend", "mujoco", "--trunk",
                         "sdof"], set()),
    ("simulate-bullet", ["simulate", "central-leader", "--backend", "bullet", "--segments",
                         "4"], set()),
    ("modes-bullet", ["modes", "central-leader", "--backend", "bullet", "--segments", "8"],
     set()),
    ("modes-mujoco", ["modes", "central-leader", "--backend", "mujoco", "--segments", "8"],
     set()),
    ("contact", ["contact", "--mass", "132.4", "--other-mass", "4", "--restitution", "0.5",
                 "--touch-duration", "0.002", "--dt", "4e-5"], set()),
    ("paper", ["paper", "--json"], set()),
    ("record-and-identify", ["simulate", "central-leader", "--record", "rec.csv"], {"rec.csv"}),
    ("scenario", ["scenario", "mytree", "--out", ".", "--clamp-height", "0.3", "--diameter",
                  "0.1", *PENDULUM, "--dynamic-mass", "100", "--equivalent-stiffness", "1e6",
                  "--damping-rate", "30", "--youngs-modulus", "1e10"], {"mytree.toml"}),
    ("sweep", ["sweep", "--grid", "restitution=0.1,0.3", "--backend", "analytic,bullet",
               "--option", "bullet.trunk=sdof", "--out", "sw"], {"sw"}),
]


@pytest.mark.parametrize(("argv", "leaves"), [c[1:] for c in COMMANDS],
                         ids=[c[0] for c in COMMANDS])
def test_a_command_leaves_only_its_output(argv, leaves, tmp_path):
    tmp, work = tmp_path / "tmp", tmp_path / "work"
    tmp.mkdir()
    work.mkdir()
    env = {**os.environ, "TMPDIR": str(tmp), "TEMP": str(tmp), "TMP": str(tmp),
           "MPLCONFIGDIR": str(tmp_path / "mpl")}  # matplotlib's cache: the user's, not ours
    runs = [argv]
    if argv[-1] == "rec.csv":  # the record, then identify reads it
        runs.append(["identify", "rec.csv", *PENDULUM, "--clamp-height", "0.315",
                     "--diameter", "0.126", "--plot", "fit.png"])
        leaves = leaves | {"fit.png"}
    for args in runs:
        proc = subprocess.run([sys.executable, "-m", "treeimpact.compare.interface.cli", *args],
                              cwd=work, env=env, capture_output=True, text=True, timeout=300,
                              check=False)
        assert proc.returncode == 0, proc.stderr[-2000:]
        assert "Traceback" not in proc.stderr and "Exception ignored" not in proc.stderr, \
            proc.stderr[-2000:]
    assert sorted(p.name for p in tmp.iterdir()) == []
    assert {p.name for p in work.iterdir()} == leaves
