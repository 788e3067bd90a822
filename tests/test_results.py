"""The result type every backend returns (analytic.results): typed solution / record fields,
the trajectory sampled on first read, JSON-able output."""

import json
import math
import pickle

import numpy as np

from analytic import load_scenario, simulate
from analytic.results import Trajectory, to_jsonable


def test_exact_results_carry_the_solution_and_soft_results_the_record():
    from compare.backends import get_backend

    scen = load_scenario("open-center")
    exact, soft = simulate(scen), get_backend("soft").simulate(scen)
    assert exact.solution is not None and exact.record is None
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
