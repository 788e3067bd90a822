"""Property-based checks over random valid models: finite output, closed ledger, bounded work."""

import math
from datetime import timedelta

from hypothesis import given, settings
from hypothesis import strategies as st

from analytic.model import TwoBodyModel
from analytic.simulate import impact_metrics
from analytic.solver import solve_impacts

models = st.builds(
    TwoBodyModel,
    dynamic_mass=st.floats(5.0, 2000.0),
    damping=st.floats(0.0, 1e5),
    stiffness=st.floats(1e4, 1e8),
    impactor_mass=st.floats(1.0, 500.0),
    impactor_stiffness=st.one_of(st.just(0.0), st.floats(1.0, 1e4)),
    impact_speed=st.floats(0.1, 10.0),
    restitution=st.floats(0.0, 1.0),
)


# Run time is bounded: each example must finish within the deadline (the solver's work is
# bounded by the tail closure, not by a cap on the number of impacts).
@settings(max_examples=60, deadline=timedelta(seconds=5))
@given(model=models, t_end=st.floats(0.005, 0.2))
def test_random_models_give_finite_metrics_and_a_closed_ledger(model, t_end):
    sol = solve_impacts(model, t_end)
    metrics = impact_metrics(sol)
    for key in ("n_impacts", "x_max", "t_xmax", "impact_loss", "impact_loss_inelastic",
                "ledger_residual"):
        assert math.isfinite(metrics[key]), key
    assert metrics["ledger_residual"] < 1e-9
    assert 0.0 <= metrics["impact_loss"] <= model.initial_energy * (1 + 1e-12)
    # impacts are in time order and each one approaches (eq 12)
    times = [i.t for i in sol.impacts]
    assert times == sorted(times)
    assert all(i.u - i.U >= 0.0 for i in sol.impacts)
