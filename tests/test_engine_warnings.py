"""MuJoCo's warning handler is scoped to the engine's calls (issue 36): importing the engine
leaves MuJoCo's handler alone, a run installs treeimpact's (stderr, never a MUJOCO_LOG.TXT
in the working directory) and puts the previous one back, and a run that MuJoCo warns about
carries the warning in its SimulationDiverged."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

mujoco = pytest.importorskip("mujoco")

ROOT = Path(__file__).resolve().parents[1]

#: A setup whose compiled trunk spring is 1e30 N/m: its first step's acceleration is huge,
#: MuJoCo warns "Nan, Inf or huge value in QACC" and stops the rollout.
_BLOWN_UP_RUN = """
import copy, dataclasses, sys
import mujoco
from treeimpact.analytic.errors import SimulationDiverged
from treeimpact.analytic.model.options import scenario_as_run
from treeimpact.analytic.model.scenario import load_scenario
from treeimpact.mujoco_models import make_setup, run
assert mujoco.get_mju_user_warning() is None, "importing the engine set a handler"
mine = []
def handler(message):  # a user's own
    mine.append(message)
mujoco.set_mju_user_warning(handler)
setup = make_setup(scenario_as_run(load_scenario("central-leader"), {"t_end": 0.01}), trunk="sdof")
assert mujoco.get_mju_user_warning() is handler, "make_setup kept its handler"
m = copy.copy(setup.mjmodel)
m.jnt_stiffness[:] = 1e30
try:
    run(dataclasses.replace(setup, mjmodel=m))
except SimulationDiverged as exc:
    print(exc, file=sys.stderr)
assert mujoco.get_mju_user_warning() is handler, "run kept its handler"
assert mine == [], mine
"""


def test_a_run_mujoco_warns_about_is_diverged_with_the_warning_and_the_handler_restored(
        tmp_path):
    proc = subprocess.run([sys.executable, "-c", _BLOWN_UP_RUN], cwd=tmp_path,
                          capture_output=True, text=True,
                          env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout == ""
    assert "the rollout stopped on a MuJoCo warning" in proc.stderr
    assert "(MuJoCo warned: Nan, Inf or huge value in QACC" in proc.stderr
    assert list(tmp_path.iterdir()) == []  # no MUJOCO_LOG.TXT


def test_nested_scopes_install_once_and_restore_the_previous_handler():
    from treeimpact.mujoco_models._warnings import collected_warnings, mujoco_warnings

    before = mujoco.get_mju_user_warning()
    with mujoco_warnings():
        ours = mujoco.get_mju_user_warning()
        assert ours is not None and ours is not before
        with collected_warnings() as seen, mujoco_warnings():
            assert mujoco.get_mju_user_warning() is ours
            ours("Some  collected\nwarning. Time = 0.1.")
        assert seen == ["Some collected warning. Time = 0.1."]  # one line, not told
        assert mujoco.get_mju_user_warning() is ours
    assert mujoco.get_mju_user_warning() is before


def test_a_warning_outside_a_rollout_is_told_once_per_kind(capsys):
    from treeimpact.mujoco_models import _warnings

    _warnings._WARNED.discard("A told kind.")
    with _warnings.mujoco_warnings():
        handler = mujoco.get_mju_user_warning()
        handler("A told kind. Time = 0.1.")
        handler("A told kind. Time = 0.2.")
    assert capsys.readouterr().err == "treeimpact: warning: mujoco: A told kind. Time = 0.1.\n"
