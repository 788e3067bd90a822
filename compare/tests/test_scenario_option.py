"""``pytest compare --scenario TREE`` (issue 41 item 2): the cross-checks collected for the
user's tree alone, named by it; a bad tree ends the session in one line, exit 2."""

from __future__ import annotations

import dataclasses
import subprocess
import sys
from pathlib import Path

from treeimpact.analytic.model.scenario import load_scenario
from treeimpact.analytic.model.scenario_toml import scenario_toml

HERE = Path(__file__).resolve().parent


def _pytest(*args, cwd):
    return subprocess.run([sys.executable, "-m", "pytest", "-p", "no:cacheprovider",
                           str(HERE), *args], capture_output=True, text=True, cwd=cwd,
                          timeout=300)


def test_the_cross_checks_run_on_the_users_tree_only(tmp_path):
    tree = dataclasses.replace(load_scenario("open-center"), name="my-tree")
    path = tmp_path / "my-tree.toml"
    path.write_text(scenario_toml(tree))
    done = _pytest("--collect-only", "-q", "--scenario", str(path), cwd=tmp_path)
    ids = [ln for ln in done.stdout.splitlines() if "::" in ln]
    assert done.returncode == 0, done.stdout + done.stderr
    assert ids and all("test_cross_checks.py::" in i for i in ids)  # the other tests out
    shipped = ("open-center", "central-leader", "realistic-crown")
    assert not [i for i in ids if any(f"[{name}" in i for name in shipped)]
    assert any("test_energy_ledger_closes[my-tree-analytic" in i for i in ids)


def test_a_bad_tree_ends_the_session_in_one_line(tmp_path):
    done = _pytest("--collect-only", "-q", "--scenario", "no-such-tree.toml", cwd=tmp_path)
    assert done.returncode == 2, done.stdout + done.stderr
    said = (done.stdout + done.stderr).strip().splitlines()
    assert any("--scenario 'no-such-tree.toml': scenario 'no-such-tree.toml': no such file"
               in ln for ln in said), said
