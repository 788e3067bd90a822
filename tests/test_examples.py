"""The scripts in examples/ run as a user would run them, and say what they claim."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_quickstart_runs_and_identifies_the_tree_it_simulated(tmp_path):
    proc = subprocess.run([sys.executable, str(ROOT / "examples" / "quickstart.py"),
                           str(tmp_path)], capture_output=True, text=True, timeout=300,
                          cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr == ""
    found = re.search(r"identified M_T ([\d.]+) kg \(true ([\d.]+) kg\), explained: True",
                      proc.stdout)
    assert found, proc.stdout
    # a record of the exact model at 5 kHz, no noise: the fit returns its M_T (to 0.1 %)
    assert abs(float(found[1]) / float(found[2]) - 1) < 1e-3
    assert "ladder checks by verdict" in proc.stdout
    assert [p.name for p in tmp_path.iterdir()] == ["central-leader-record.csv"]
