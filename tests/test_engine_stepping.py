"""What an engine run's stepping cost and what set its step (result.extra["stepping"],
docs/time-step.md, docs/engines.md "What an engine run costs"), for both engine packages.
Not among conftest.NUMERICS: nothing here depends on BLAS round-off."""

import math

import numpy as np
import pytest

from treeimpact.analytic.model.scenario import load_scenario
from treeimpact.analytic.model.options import scenario_as_run

ENGINES = ["treeimpact.mujoco_models", "treeimpact.bullet_models"]


@pytest.mark.parametrize("package", ENGINES)
def test_a_run_records_its_steps_their_wall_time_and_what_set_its_step(package, monkeypatch):
    """result.extra["stepping"]: at a given (fixed) step the steps after the touch are t_end
    / dt rounded up (MuJoCo keeps 2 more, its record's ends); a run stepped by phase
    (both engines' default, ``_setup.PHASED``) covers the same time with its contact steps
    and its free steps at the trunk's own step (analytic.engine.phases); the wall per step is the stepping's over them, and
    the step is set by the term of the rule that is smallest (docs/time-step.md)."""
    import importlib

    mod = pytest.importorskip(package)
    setup_mod = importlib.import_module(f"{package}._setup")
    monkeypatch.setattr(setup_mod, "PHASED", True)  # the default; phased whatever it is
    scen = scenario_as_run(load_scenario("open-center"), {"t_end": 0.03})
    run = mod.simulate(scen, trunk="chain", segments=4)
    cost = run.extra["stepping"]
    steps = math.ceil(0.03 / run.model["dt"]) + (2 if package.endswith("mujoco_models") else 0)
    assert cost["dt"] == run.model["dt"] and cost["free_steps"] > 0
    covered = (cost["steps"] - cost["free_steps"]) * cost["dt"] + cost["free_steps"] * cost[
        "free_dt"]
    assert covered == pytest.approx(steps * cost["dt"], abs=cost["dt"])  # the same time
    assert cost["step_us"] == pytest.approx(1e6 * cost["stepping_s"] / cost["steps"],
                                            rel=1e-12)
    assert 0.0 < cost["stepping_s"] and cost["swing_s"] >= 0.0
    assert cost["step_set_by"] in ("contact", "implicit contact")  # 4 segments: the contact
    given = mod.simulate(scen, trunk="chain", segments=4, dt=run.model["dt"])
    fixed = given.extra["stepping"]
    assert fixed["step_set_by"] == "given" and fixed["free_dt"] is None
    assert fixed["steps"] == steps and fixed["free_steps"] == 0
    assert setup_mod.STEPS_PER_PERIOD == 10  # both engines: docs/time-step.md


@pytest.mark.parametrize("package", ENGINES)
def test_a_fine_chain_is_stepped_by_its_highest_mode_at_ten_steps_a_period(package):
    """32 segments: omega_max ~ 8e5 rad/s sets dt = 2 pi / omega_max / 10 (below the
    contact's t_c / 50 and, in Bullet, its implicit contact's limit); nothing is stepped."""
    mod = pytest.importorskip(package)
    setup = mod.make_setup(load_scenario("central-leader"), trunk="chain", segments=32)
    assert setup.step_set_by == "highest mode"
    assert setup.dt == pytest.approx(2.0 * math.pi / setup.omega_max / 10, rel=1e-12)
    assert setup.omega_max * setup.dt < 2.0 / 3.0  # a third of the stability limit 2
