"""Property-based checks over random valid models: finite output, closed ledger, bounded work.

Hypothesis runs derandomized (a fixed seed per test) so that CI is reproducible; the
examples it once found stay as explicit ``@example`` regressions.
"""

import math

import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.impact.simulate import impact_metrics
from treeimpact.analytic.impact.solver import MAX_CHATTER_IMPACTS, solve_impacts
from treeimpact.analytic.model.two_body import TwoBodyModel

models = st.builds(
    TwoBodyModel,
    dynamic_mass=st.floats(5.0, 2000.0),
    equivalent_damping=st.floats(0.0, 1e5),
    equivalent_stiffness=st.floats(1e4, 1e8),
    impactor_mass=st.floats(1.0, 500.0),
    impactor_stiffness=st.one_of(st.just(0.0), st.floats(1.0, 1e4)),
    impact_speed=st.floats(0.1, 10.0),
    restitution=st.floats(0.0, 1.0),
)

# Found by hypothesis: e = 1 on a heavily overdamped trunk. The elastic chatter is drained by
# the trunk's damping alone, its relative velocity falling only as 1 / n: the exact solver
# refuses it (one-line error naming the restitution) instead of looping or truncating.
ELASTIC_OVERDAMPED = TwoBodyModel(
    dynamic_mass=5.0, equivalent_damping=52971.65217941432, equivalent_stiffness=10000.0,
    impactor_mass=469.3527616896069, impactor_stiffness=0.0, impact_speed=1.0, restitution=1.0)


# Found by hypothesis: a light, heavily overdamped trunk. After moving together the bodies
# separate with the relative acceleration zero up to the round-off of the separation time;
# read as a second-order zero it made the search return an immediate re-contact, again
# and again (a hang). A separation starts the free flight with a third-order zero.
LIGHT_OVERDAMPED = TwoBodyModel(
    dynamic_mass=5.0, equivalent_damping=90147.34109509406, equivalent_stiffness=10000.0,
    impactor_mass=1.0,
    impactor_stiffness=8429.71100390023, impact_speed=5.0, restitution=0.005)


# The solver's work is bounded by the tail closure for e <= 0.99; closer to 1 it grows as
# 1 / (1 - e) and a sequence beyond MAX_CHATTER_IMPACTS is refused, never cut short into
# numbers. No deadline (no timed unit tests; what a run costs is measured in benchmarks/).
# ELASTIC_OVERDAMPED, once an explicit example here, is the test below: with the real cap
# it cost 3.4-3.8 s (load 6, 2 cores) in each of the two places, see that test's comment.
@settings(max_examples=60, deadline=None, derandomize=True)
@given(model=models, t_end=st.floats(0.005, 0.2))
@example(model=LIGHT_OVERDAMPED, t_end=0.005)
def test_random_models_give_finite_metrics_and_a_closed_ledger(model, t_end):
    try:
        sol = solve_impacts(model, t_end)
    except ParameterError as exc:
        assert model.restitution > 0.99, exc
        assert str(exc).startswith("contact.restitution") and "\n" not in str(exc)
        return
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


@settings(max_examples=40, deadline=None, derandomize=True)
@given(model=models.filter(lambda m: m.restitution <= 0.99), t_end=st.floats(0.005, 0.2))
def test_restitution_up_to_0_99_always_closes_its_chattering(model, t_end):
    """The solver's documented range: for e <= 0.99 no sequence reaches the impact budget."""
    sol = solve_impacts(model, t_end)
    assert len(sol.impacts) < MAX_CHATTER_IMPACTS


def test_elastic_chatter_on_an_overdamped_trunk_is_refused_in_one_line(monkeypatch):
    """Why this model was the suite's slowest example (about 5 s): nothing is wasted, every
    impact is needed. With e = 1 the tail never closes (its bouncing-ball sum needs e < 1)
    and each impact keeps the relative velocity, which the trunk's damping alone drains, as
    1 / n (0.59 m/s after the first impact, 1.1e-5 m/s after the 100,000th). Flights last
    about 2 gamma / |a_rel|, so time grows as ln n: all 100,000 impacts fall within the
    first 3.25 ms (0.67 ms a decade), whatever t_end, and the solver resolves each one
    (a Newton impact and a certified free-flight search, 35 us at load 6 on 2 cores, 85-110
    us at load 13) up to MAX_CHATTER_IMPACTS before it refuses. A shorter t_end would not
    help (the cap comes at 3.25 ms).

    Checked here with the cap at 1000 (the same code path, the same refusal: the 1000th
    impact comes at 1.9 ms, the chatter still holding far more than the tail's 1e-13 of
    E0); the real cap's 100,000 impacts and their wall time are benchmarks/bench_chatter.py's."""
    from treeimpact.analytic.impact import newton, solver

    for module in (newton, solver):  # the solver's check and the message's number
        monkeypatch.setattr(module, "MAX_CHATTER_IMPACTS", 1000)
    refused = r"^contact\.restitution = 1\.0: .* after 1000 impacts"
    with pytest.raises(ParameterError, match=refused) as exc:
        solve_impacts(ELASTIC_OVERDAMPED, 0.125)
    assert "\n" not in str(exc.value)  # one line


def test_a_separation_starts_the_flight_at_third_order_and_the_bodies_separate():
    sol = solve_impacts(LIGHT_OVERDAMPED, 0.005)
    assert sol.separations  # the joint motion ended with the force at zero
    t_sep = sol.separations[0].t
    assert not any(i.t > t_sep for i in sol.impacts)  # no spurious re-contact after it
    assert impact_metrics(sol)["ledger_residual"] < 1e-9


def test_a_loop_that_stops_advancing_time_is_a_one_line_divergence(monkeypatch):
    """The guard against a solver that no longer advances (it used to loop for hours)."""
    from treeimpact.analytic.errors import SimulationDiverged
    from treeimpact.analytic.impact import free_flight

    monkeypatch.setattr(free_flight, "first_zero", lambda *a, **k: 0.0)  # every flight: no time
    with pytest.raises(SimulationDiverged, match=r"^exact solver: 1001 events without "):
        solve_impacts(LIGHT_OVERDAMPED, 0.005)


@settings(max_examples=40, deadline=None, derandomize=True)
@given(model=models.filter(lambda m: m.restitution <= 0.9), t_end=st.floats(0.005, 0.1))
def test_phase_integrals_in_closed_form_match_quadrature(model, t_end):
    """A_x, A_y and the damping work by their closed forms (eqs 15-16, the oscillator's
    energy) against Gauss-Legendre quadrature of the motion itself, phase by phase."""
    sol = solve_impacts(model, t_end)
    eps = 2.220446049250313e-16
    for k, ph in enumerate(sol.phases):
        s = ph.t1 - ph.t0
        x1, vx1, y1, vy1 = sol._scalar_state(ph.t1)
        together = ph.kind == "together"
        mass = model.dynamic_mass + (model.impactor_mass if together else 0.0)
        stiff = model.equivalent_stiffness + (model.impactor_stiffness if together else 0.0)
        beta, w2 = 0.5 * model.equivalent_damping / mass, stiff / mass
        # round-off of each closed form: its terms (end points) times a few eps
        floor = {"x": (abs(ph.vx0) + abs(vx1) + 2 * beta * (abs(ph.x0) + abs(x1))) / w2,
                 "y": abs(ph.y0) * s + abs(ph.vy0) * s * s,
                 "damping": mass * (ph.vx0 ** 2 + vx1 ** 2) + stiff * (ph.x0 ** 2 + x1 ** 2)}
        if together:
            floor["y"] = floor["x"]
        for which in ("x", "y", "damping"):
            closed = sol._phase_integral(which, k, ph.t1)
            quad = sol._phase_integral_quadrature(which, k, ph.t1)  # Gauss-Legendre: 1e-12
            assert abs(closed - quad) <= 1e-9 * abs(quad) + 64 * eps * floor[which], (
                which, k, closed, quad)
