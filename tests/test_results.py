"""The result type every backend returns (analytic.results): typed solution / record fields,
the trajectory sampled on first read, JSON-able output."""

import json
import math
import pickle

import numpy as np
import pytest

from treeimpact.analytic.impact.simulate import simulate
from treeimpact.analytic.model.scenario import load_scenario
from treeimpact.analytic.results import Trajectory, to_jsonable


def test_exact_results_carry_the_solution_and_a_record_soft_results_a_record():
    from treeimpact.compare.runs.backends import get_backend

    scen = load_scenario("open-center")
    exact, soft = simulate(scen), get_backend("soft").simulate(scen)
    assert exact.solution is not None and exact.record is not None
    assert soft.record is not None and soft.solution is None
    assert math.isnan(exact.collision_duration) and 0.0 < soft.collision_duration < 0.01


def test_deferred_trajectory_samples_once_on_first_read_and_equals_the_exact_motion():
    calls = []
    res = simulate(load_scenario("central-leader"), samples=501)
    real = res.trajectory.__dict__["_sample"]
    object.__setattr__(res.trajectory, "_sample", lambda: calls.append(1) or real())
    assert not calls  # solving and the metrics did not sample it
    t = res.trajectory.t
    x, vx, y, vy = res.solution.state(t)
    np.testing.assert_array_equal(res.trajectory.x, x)
    np.testing.assert_array_equal(res.trajectory.vy, vy)
    assert len(calls) == 1 and t.size == 501 and t[-1] == res.solution.t_end


def test_deferred_trajectory_pickles_before_and_after_it_is_read():
    res = simulate(load_scenario("open-center"))
    before = pickle.loads(pickle.dumps(res)).trajectory.x
    np.testing.assert_array_equal(before, res.trajectory.x)
    after = pickle.loads(pickle.dumps(res)).trajectory
    assert isinstance(after, Trajectory) and np.array_equal(after.vx, res.trajectory.vx)


def test_to_jsonable_turns_nan_inf_and_numpy_scalars_into_json():
    data = {"a": math.nan, "b": [np.float64(1.5), np.int64(3), math.inf], "c": "x"}
    assert json.loads(json.dumps(to_jsonable(data))) == {"a": None, "b": [1.5, 3, None],
                                                         "c": "x"}


def test_exact_record_closes_its_energy_ledger_and_follows_the_solution():
    """The analytic rung's sampled record: kinetic + potential + damping work + contact
    work (the impact losses) = the input energy at every sample; its force is eq 34's while
    the bodies move together (positive), 0 in flight; its motion is the exact state."""
    res = simulate(load_scenario("central-leader"), samples=1001)
    rec, sol = res.record, res.solution
    total = rec.kinetic + rec.potential + rec.damping_work + rec.contact_work
    e0 = sol.model.initial_energy
    assert np.max(np.abs(total - e0)) < 1e-12 * e0
    np.testing.assert_array_equal(rec.x, sol.state(rec.t)[0])
    t0, t1 = sol.together_start[0], sol.separations[0].t
    inside = (rec.t > t0) & (rec.t < t1)
    assert np.all(rec.force[inside] > 0) and np.all(rec.force[rec.t > t1 + 1e-9] == 0)
    assert rec.contact_work[-1] == pytest.approx(res.metrics["contact_dissipation"], rel=1e-12)
