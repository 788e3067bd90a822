"""``pytest compare --scenario TREE`` validates the tree first and then runs what applies
(issue 54 item 6): a file the paper's model cannot run ends the session in one line, exit
2; a tree one rung refuses (e = 0: the soft pad needs infinite damping) is collected and that
rung's checks skip with its reason; a metric that exists on neither rung of a step (a light
impactor whose bodies never move together) is a skip with the physical reason, never a
pass and never a failure of the code. The functions are tested directly here (a session
on a user's tree takes minutes: the engines' ladders), one configure step in a subprocess."""

from __future__ import annotations

import dataclasses
import math
import subprocess
import sys
from pathlib import Path

import pytest

from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.model.scenario import load_scenario
from treeimpact.analytic.model.scenario_toml import scenario_toml

from . import conftest

HERE = Path(__file__).resolve().parent


def _file(tmp_path, name, scen) -> Path:
    path = tmp_path / f"{name}.toml"
    path.write_text(scenario_toml(dataclasses.replace(scen, name=name)))
    return path


def _with(scen, section, **changes):
    return dataclasses.replace(scen, **{section: dataclasses.replace(getattr(scen, section),
                                                                     **changes)})


def test_a_tree_the_reference_cannot_run_ends_the_session_in_one_line(tmp_path):
    short = _file(tmp_path, "short", dataclasses.replace(load_scenario("central-leader"),
                                                         t_end=1e-4))
    done = subprocess.run([sys.executable, "-m", "pytest", "-p", "no:cacheprovider",
                           "--collect-only", "-q", str(HERE / "test_cross_checks.py"),
                           "--scenario", str(short)], capture_output=True, text=True,
                          cwd=tmp_path, timeout=300)
    said = [ln for ln in (done.stdout + done.stderr).splitlines() if str(short) in ln]
    assert done.returncode == 2, done.stdout + done.stderr
    assert len(said) == 1 and "Traceback" not in done.stdout + done.stderr
    assert "t_end = 0.0001 s is too short" in said[0] and "--t-end" not in said[0]


def test_the_validation_refuses_in_one_line_and_keeps_a_good_tree(tmp_path):
    scen = load_scenario("central-leader")
    assert conftest._validated(_file(tmp_path, "good", scen)).name == "good"
    bad = _file(tmp_path, "bad", dataclasses.replace(scen, t_end=1e-4))
    with pytest.raises(ParameterError) as exc:
        conftest._validated(bad)
    assert "\n" not in str(exc.value) and "cannot run this tree" in str(exc.value)


def test_a_tree_at_e_0_is_collected_and_its_soft_rungs_skip_with_the_reason(tmp_path):
    from treeimpact.compare.runs.backends import get_backend
    from treeimpact.compare.runs.cache import SKIPPED, attempt
    from treeimpact.compare.runs.findings import TreePhysics

    scen = load_scenario("central-leader")
    dead = _with(scen, "contact", restitution=0.0)
    conftest._validated(_file(tmp_path, "dead", dead))  # valid for the Newton model
    physics, ref = TreePhysics.of(dead), TreePhysics.of(scen)
    assert physics.restitution == 0.0
    # the beam's effective mass at the clamp is its mesh's, whatever the pad: the same
    assert physics.loss_ratio == ref.loss_ratio and physics.crown_factor == ref.crown_factor
    soft = attempt(get_backend("soft"), dead, {})
    assert soft.status == SKIPPED and "infinite damping" in soft.reason

    class Ladder:  # what require_run reads of a ladder: its name and a rung's outcome
        name = "dead"

        def __getitem__(self, rung_id):
            return soft

    with pytest.raises(pytest.skip.Exception, match="dead soft: .*infinite damping"):
        conftest.require_run(Ladder(), "soft")


def _check(metric, value, reference):
    from treeimpact.compare.runs.verdicts import Check, Verdict

    return Check("light", "beam", metric, value, "soft", reference, math.nan, 0.02,
                 Verdict.NOT_AVAILABLE, "")


def test_a_metric_on_neither_rung_skips_with_the_physical_reason():
    class Ladder:
        name = "light"

    with pytest.raises(pytest.skip.Exception, match="light beam: T0 has no value on beam nor "
                                                    "on soft: the bodies never move together"):
        conftest.assert_checks(Ladder(), [_check("T0", math.nan, math.nan)])
    # one side with a value is a disagreement, not an absence: it is not skipped
    assert not conftest._absent_on_both(_check("T0", 1e-3, math.nan))
    assert not conftest._absent_on_both(_check("T0", math.nan, 1e-3))
    assert conftest._absent_on_both(_check("x0", math.nan, math.nan))


def test_a_light_impactor_never_moves_with_the_trunk_on_the_reference():
    """The physics the skip names: a 0.1 kg impactor (the registry's lightest) on
    central-leader's 110 kg M_T parts before the trunk catches up (eq 12-35's T0 does not
    exist), where the paper's 132.4 kg pendulum moves with it."""
    from treeimpact.compare.runs.backends import get_backend

    scen = load_scenario("central-leader")
    light = _with(scen, "impactor", mass=0.1)
    analytic = get_backend("analytic")
    assert math.isnan(analytic.simulate(light).metrics["T0"])
    assert math.isfinite(analytic.simulate(scen).metrics["T0"])
