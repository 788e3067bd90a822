"""Exact impact solver (eqs 12-35): the physics each event must satisfy."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from treeimpact.analytic.impact.ivp_reference import solve_ivp_impacts
from treeimpact.analytic.impact.oscillator import Oscillator
from treeimpact.analytic.impact.roots import first_zero
from treeimpact.analytic.impact.simulate import simulate
from treeimpact.analytic.impact.solver import TAIL_ENERGY_FRACTION, solve_impacts
from treeimpact.analytic.model.scenario import load_scenario
from treeimpact.analytic.model.two_body import TwoBodyModel, two_body_model
from treeimpact.analytic.model.options import scenario_as_run


def paper_model(e=0.1, name="open-center"):
    return two_body_model(scenario_as_run(load_scenario(name), {"restitution": e}))


def billet_model(e):
    return TwoBodyModel(dynamic_mass=87.0, equivalent_damping=12000.0, equivalent_stiffness=1.2e6,
                        impactor_mass=132.4,
                        impactor_stiffness=0.0, impact_speed=2.0, restitution=e)


E_VALUES = [0.0, 0.05, 0.1, 0.3, 0.5, 0.8, 1.0]


@pytest.mark.parametrize("e", E_VALUES)
def test_momentum_conserved_and_eq21_at_every_impact(e):
    mod = paper_model(e)
    sol = solve_impacts(mod, 0.1)
    M, m = mod.dynamic_mass, mod.impactor_mass
    for imp in sol.impacts:
        scale = M * abs(imp.u) + m * abs(imp.u) + 1e-300
        assert M * imp.U + m * imp.u == pytest.approx(M * imp.V + m * imp.v, abs=1e-13 * scale)
        # V and v are O(u1); their difference carries their round-off, ~1e-16 u1.
        assert imp.V - imp.v == pytest.approx(-e * (imp.U - imp.u), abs=1e-14 * mod.impact_speed)


@pytest.mark.parametrize("e", E_VALUES)
def test_eq55_loss_equals_kinetic_energy_drop_at_every_impact(e):
    mod = paper_model(e)
    M, m = mod.dynamic_mass, mod.impactor_mass
    for imp in solve_impacts(mod, 0.1).impacts:
        drop = 0.5 * M * (imp.U ** 2 - imp.V ** 2) + 0.5 * m * (imp.u ** 2 - imp.v ** 2)
        assert imp.loss == pytest.approx(drop, rel=1e-9, abs=1e-12 * mod.initial_energy)


@pytest.mark.parametrize("e", [0.05, 0.1, 0.2, 0.3])
def test_eq26_pendulum_velocity_decreases_through_the_chattering(e):
    sol = solve_impacts(paper_model(e), 0.1)
    t_tog = sol.together_start[0]
    v = [imp.v for imp in sol.impacts if imp.t <= t_tog]
    assert len(v) >= 3
    assert all(v1 > v2 > 0 for v1, v2 in zip(v, v[1:]))


@pytest.mark.parametrize("e", [0.05, 0.2, 0.5])
def test_eq33_is_an_equality_for_the_billet(e):
    mod = billet_model(e)
    M, m = mod.dynamic_mass, mod.impactor_mass
    imps = solve_impacts(mod, 0.05).impacts
    assert len(imps) >= 3
    for a, b in zip(imps, imps[1:]):
        gamma_next = b.V - b.v
        rhs = e / (1 + e) * (M + m) / M * (a.v - b.v)
        assert gamma_next == pytest.approx(rhs, rel=1e-9)


@pytest.mark.parametrize("name", ["open-center", "central-leader", "realistic-crown"])
def test_plastic_impact_is_single_and_loses_eq57_exactly(name):
    res = simulate(scenario_as_run(load_scenario(name), {"restitution": 0.0}))
    sol = res.solution
    assert len([i for i in sol.impacts if i.t <= sol.together_start[0]]) == 1
    assert res.metrics["n_impacts"] == 1
    assert res.metrics["impact_loss"] == pytest.approx(res.metrics["impact_loss_inelastic"],
                                                       rel=1e-14)


def test_elastic_impacts_lose_nothing():
    sol = solve_impacts(paper_model(1.0), 0.1)
    assert sum(i.loss for i in sol.impacts) == 0.0
    assert max(r["residual"] for r in sol.ledger()) < 1e-9


@pytest.mark.parametrize("e", [0.1, 0.3, 0.6])
def test_accumulation_time_converges_geometrically_to_the_tail_closure(e):
    """t_i + 2 gamma_i / (|a_rel| (1 - e)) (bouncing-ball sum) tends to the accumulation
    point as i grows; the error falls like gamma_i^2."""
    mod = paper_model(e)
    sol = solve_impacts(mod, 0.1)
    tail = sol.tails[0]
    tree = Oscillator.from_mck(mod.dynamic_mass, mod.equivalent_damping, mod.equivalent_stiffness)
    pend = Oscillator.from_mck(mod.impactor_mass, 0.0, mod.impactor_stiffness)
    errors = []
    for imp in sol.impacts[-6:]:
        a_rel = tree.acceleration(imp.x, imp.V) - pend.acceleration(imp.x, imp.v)
        gamma = imp.V - imp.v
        pred = imp.t + 2 * gamma / (abs(a_rel) * (1 - e))
        errors.append(abs(pred - tail.t_accumulation))
    assert errors[-1] == 0.0 or errors[-1] < 1e-9 * tail.t_accumulation
    # geometric decrease, ratio about e^2 per impact
    for e1, e2 in zip(errors[:-2], errors[1:-1]):
        assert e2 < e1


def test_tail_closed_only_when_negligible():
    mod = paper_model(0.3)
    sol = solve_impacts(mod, 0.1)
    assert len(sol.tails) == 1
    assert sol.tails[0].loss < TAIL_ENERGY_FRACTION * mod.initial_energy
    assert sol.tails[0].after_impact == len([i for i in sol.impacts
                                             if i.t <= sol.tails[0].t_start])


@pytest.mark.parametrize("name", ["open-center", "central-leader", "realistic-crown"])
@pytest.mark.parametrize("e", E_VALUES)
def test_energy_ledger_closes_at_every_event(name, e):
    sol = simulate(scenario_as_run(load_scenario(name), {"restitution": e})).solution
    rows = sol.ledger()
    assert len(rows) >= 2
    assert max(r["residual"] for r in rows) < 1e-9  # the ledger tolerance


@pytest.mark.parametrize("e", [0.1, 0.5, 0.9])
def test_impact_list_matches_event_driven_solve_ivp(e):
    mod = paper_model(e)
    sol = solve_impacts(mod, 0.1)
    ref = solve_ivp_impacts(mod, 0.1)
    n = min(len(ref["impacts"]), len(sol.impacts))
    assert n >= 3
    for (t, U, u, V, v), imp in zip(ref["impacts"][:n], sol.impacts[:n]):
        assert imp.t == pytest.approx(t, abs=1e-10)  # DOP853 at rtol 1e-12
        assert imp.V == pytest.approx(V, abs=1e-8 * mod.impact_speed)
        assert imp.v == pytest.approx(v, abs=1e-8 * mod.impact_speed)
    assert len(sol.separations) == len(ref["separations"])
    for s, (t, x, v) in zip(sol.separations, ref["separations"]):
        assert s.t == pytest.approx(t, abs=1e-9)
        assert s.x == pytest.approx(x, rel=1e-7)


@pytest.mark.parametrize("regime,beta,omega_sq", [
    ("underdamped", 30.0, 1.4e4), ("critical", 100.0, 1e4), ("overdamped", 300.0, 1e4),
    ("undamped", 0.0, 6.5), ("free-flight", 0.0, 0.0)])
def test_closed_form_free_flight_matches_numerical_integration(regime, beta, omega_sq):
    osc = Oscillator(beta, omega_sq)
    x0, v0 = 2e-3, 1.3
    t = np.linspace(0.0, 0.05, 11)
    sol = solve_ivp(lambda _t, s: [s[1], -2 * beta * s[1] - omega_sq * s[0]], (0, 0.05),
                    [x0, v0], t_eval=t, rtol=1e-12, atol=1e-15, method="DOP853")
    dx, v = osc.advance(t, x0, v0, np)
    np.testing.assert_allclose(x0 + dx, sol.y[0], rtol=1e-9, atol=1e-14)
    np.testing.assert_allclose(v, sol.y[1], rtol=1e-9, atol=1e-12)


def test_first_zero_never_skips_two_closely_spaced_zeros():
    # f dips below zero only on (pi - 2e-5, pi + 2e-5): two zeros 4e-5 apart
    eps = 1 - math.cos(2e-5)
    f = lambda t: math.cos(t) + 1 - eps  # noqa: E731
    df = lambda t: -math.sin(t)  # noqa: E731
    bounds = [3.0, 1.0, 1.0, 1.0, 1.0]
    root = first_zero(f, df, 10.0, bounds, rate=1.0, order=0, taylor=(2 - eps,))
    # slope there is sin(2e-5): round-off 1e-16 in f moves the zero by ~5e-12
    assert root == pytest.approx(math.pi - 2e-5, abs=2e-11)


@pytest.mark.blas_free
def test_first_zero_reports_no_zero_for_a_near_miss():
    f = lambda t: math.cos(t) + 1 + 1e-12  # noqa: E731
    df = lambda t: -math.sin(t)  # noqa: E731
    assert first_zero(f, df, 6.0, [3.0, 1.0, 1.0, 1.0, 1.0], rate=1.0, order=0,
                      taylor=(2 + 1e-12,)) is None


def test_first_zero_next_to_a_zero_at_the_origin():
    # f = t (1e-9 - t): zero of order 1 at 0 and the next at 1e-9 (a chattering flight)
    f = lambda t: t * (1e-9 - t)  # noqa: E731
    df = lambda t: 1e-9 - 2 * t  # noqa: E731
    root = first_zero(f, df, 1.0, [1.0, 2.0, 2.0, 0.0, 0.0], rate=1.0, order=1,
                      taylor=(0.0, 1e-9, -2.0, 0.0))
    assert root == pytest.approx(1e-9, rel=1e-12)


@pytest.mark.parametrize("damping", [0.0, 2 * math.sqrt(1.2e6 * 87) * 1.0,
                                     2 * math.sqrt(1.2e6 * 87) * 3.0])
def test_critically_and_over_damped_trees_close_the_ledger(damping):
    mod = TwoBodyModel(87.0, damping, 1.2e6, 132.4, 860.0, 2.2, 0.2)
    sol = solve_impacts(mod, 0.1)
    assert max(r["residual"] for r in sol.ledger()) < 1e-9
    assert len(sol.impacts) >= 1


def test_state_outside_the_solution_is_refused():
    sol = solve_impacts(paper_model(), 0.05)
    with pytest.raises(ValueError, match="t: requested times"):
        sol.state([0.06])


@pytest.mark.blas_free
def test_first_zero_newton_certificate_picks_the_first_of_two_close_zeros():
    # f = t (r1 - t)(r2 - t): a flight whose gap would close twice, 1e-3 apart in 1e-3
    r1, r2 = 1e-3, 1.001e-3
    f = lambda t: t * (r1 - t) * (r2 - t)  # noqa: E731
    df = lambda t: r1 * r2 - 2 * (r1 + r2) * t + 3 * t * t  # noqa: E731
    bounds = [1e-5, 1e-5, 0.07, 6.0, 0.0, 0.0]  # sup |f^(n)| on [0, 1e-2]
    root = first_zero(f, df, 1e-2, bounds, rate=1.0, order=1,
                      taylor=(0.0, r1 * r2, -2 * (r1 + r2), 6.0, 0.0, 0.0),
                      fdf=lambda t: (f(t), df(t)))
    assert root == pytest.approx(r1, rel=1e-13)


@pytest.mark.parametrize("gamma", [1e-3, 1e-9, 1e-14])
def test_first_zero_newton_certificate_on_a_chattering_flight(gamma):
    # gap of a short flight: f = gamma t - a t^2 / 2 + j t^3 / 6, a = 2, j = 50
    f = lambda t: gamma * t - t * t + 50 * t ** 3 / 6  # noqa: E731
    df = lambda t: gamma - 2 * t + 25 * t * t  # noqa: E731
    bounds = [1.0, 1.0, 2.0 + 50.0, 50.0, 0.0, 0.0]  # on [0, 1]
    taylor = (0.0, gamma, -2.0, 50.0, 0.0, 0.0)
    with_newton = first_zero(f, df, 1.0, bounds, rate=1.0, order=1, taylor=taylor,
                             fdf=lambda t: (f(t), df(t)))
    with_brent = first_zero(f, df, 1.0, bounds, rate=1.0, order=1, taylor=taylor)
    assert with_newton == pytest.approx(with_brent, rel=4e-15)
    assert abs(f(with_newton)) <= 1e-15 * gamma * with_newton


@pytest.mark.parametrize("beta,omega_sq", [(30.0, 1.4e4), (100.0, 1e4), (300.0, 1e4),
                                           (0.0, 6.5), (100.0 * (1 + 1e-7), 1e4)])
@pytest.mark.parametrize("f0,df0", [(1.0, 50.0), (1.0, -50.0), (1e-3, -400.0), (2.0, 900.0)])
def test_closed_form_first_zero_of_an_oscillator_solution(beta, omega_sq, f0, df0):
    """Separation (contact force reaching zero while moving together) in closed form."""
    osc = Oscillator(beta, omega_sq)

    def f(t):
        return f0 * (1.0 + osc.advance(t, 1.0, 0.0)[0]) + df0 * osc.advance(t, 0.0, 1.0)[0]

    s = osc.first_zero(f0, df0)
    # sampled while f is far above its round-off: e^{-slowest decay rate t} >= 1e-8
    d = beta * beta - omega_sq
    slowest = beta - math.sqrt(d) if d > 0 else beta
    t_max = min(2.0, 18.0 / slowest) if slowest > 0 else 2.0
    t = np.linspace(0.0, t_max, 400_001)[1:]
    vals = f0 + osc.advance(t, f0, df0, np)[0]
    neg = np.nonzero(vals <= 0.0)[0]
    if neg.size == 0:
        assert s > t_max
        return
    lo = t[neg[0] - 1] if neg[0] > 0 else 0.0
    assert lo <= s <= t[neg[0]]  # the first sign change, not a later one
    assert abs(f(s)) <= 1e-12 * (abs(f0) + abs(df0) * s)


def test_solution_pickles_after_a_solve_for_process_pools():
    """Results cross process pools (report, pytest compare, sweeps): a solved solution,
    whose oscillators hold cached closures, pickles and gives the same states back."""
    import pickle

    from treeimpact.analytic.impact.simulate import simulate
    from treeimpact.analytic.model.scenario import load_scenario

    res = simulate(load_scenario("central-leader"))
    back = pickle.loads(pickle.dumps(res))
    sol, sol2 = res.solution, back.solution
    np.testing.assert_equal(back.metrics, res.metrics)  # NaN (impulsive peak force) == NaN
    assert np.array_equal(sol.state([0.001, 0.02]), sol2.state([0.001, 0.02]))


@pytest.mark.blas_free
def test_a_root_search_the_bounds_cannot_certify_ends_in_one_line():
    """f hugging zero from above (never certified at these bounds): a bounded number of
    bisections, then a one-line divergence, never a hang (issue 12)."""
    from treeimpact.analytic.errors import SimulationDiverged
    from treeimpact.analytic.impact.roots import first_zero

    with pytest.raises(SimulationDiverged, match=r"^root search: no certified answer"):
        first_zero(lambda t: 1e-300, lambda t: 0.0, 1.0, (1.0, 1.0, 1e300, 1e300), rate=1.0)


@pytest.mark.parametrize("beta,omega_sq", [(30.0, 1.4e4), (100.0, 1e4), (300.0, 1e4),
                                           (0.0, 6.5)], ids=["under", "critical", "over",
                                                             "undamped"])
@pytest.mark.parametrize("x0,v0", [(2e-3, 1.3), (2e-3, -1.3), (-2e-3, 0.0), (2e-3, 0.0),
                                   (-2e-3, 0.05)])
def test_first_peak_time_is_the_first_local_maximum_of_dense_samples(beta, omega_sq, x0, v0):
    """The closed-form first maximum of x (analytic.impact.oscillator.first_peak_time) against the
    first + to - sign change of the sampled velocity."""
    from treeimpact.analytic.impact.oscillator import first_peak_time

    osc = Oscillator(beta, omega_sq)
    s = first_peak_time(osc, x0, v0)
    d = beta * beta - omega_sq  # sampled while v is far above its round-off (as above)
    slowest = beta - math.sqrt(d) if d > 0 else beta
    t_max = min(3.0, 18.0 / slowest) if slowest > 0 else 3.0
    t = np.linspace(0.0, t_max, 600_001)
    _, v = osc.advance(t, x0, v0, np)
    down = np.nonzero((v[:-1] > 0.0) & (v[1:] <= 0.0))[0]
    if down.size == 0:
        assert s > t_max
        return
    assert t[down[0]] <= s <= t[down[0] + 1]


@pytest.mark.parametrize("name", ["open-center", "central-leader", "realistic-crown"])
@pytest.mark.parametrize("e", [0.0, 0.1, 0.5, 1.0])
def test_closed_form_x_max_matches_dense_sampling(name, e):
    """x_max, t_xmax (eq 37) in closed form against the largest of 400 001 samples of the
    exact motion: x_max within the samples' resolution, never below the best sample."""
    sol = solve_impacts(paper_model(e, name), 0.1)
    t = np.linspace(0.0, 0.1, 400_001)
    x = sol.state(t)[0]
    i = int(np.argmax(x))
    x_max, t_xmax = sol.x_max
    assert x_max >= x[i] * (1 - 1e-14)
    assert x_max == pytest.approx(x[i], rel=1e-8)  # samples 2.5e-7 s apart near a flat peak
    assert t_xmax == pytest.approx(t[i], abs=2.5e-7)


@pytest.mark.parametrize("e, M, phases", [
    (0.0, 50.0, 2),  # one impact, moving together, separation
    (0.3, 5.0, 14),  # 13 chattering impacts, moving together, separation
    (0.8, 5.0, 3),  # three impacts, no moving together
    (0.3, 500.0, 1),  # the pendulum rebounds and leaves
])
def test_sorted_state_is_the_state_and_its_trunk_rows(e, M, phases):
    """ImpactSolution.sorted_state (the record fit's path: trunk rows alone, or all four)
    against state() on shuffled times and the scalar path: the same values at every time,
    phase starts included (a start belongs to the phase it opens)."""
    model = TwoBodyModel(dynamic_mass=M, equivalent_damping=30.0, equivalent_stiffness=2e4,
                         impactor_mass=10.0,
                         impactor_stiffness=50.0, impact_speed=1.0, restitution=e)
    sol = solve_impacts(model, 0.5)
    t = np.sort(np.concatenate([np.linspace(0.0, 0.5, 3001), [p.t0 for p in sol.phases]]))
    x, v = sol.sorted_state(t, pendulum=False)
    shuffled = np.random.default_rng(0).permutation(t.size)
    state = np.empty((4, t.size))
    state[:, shuffled] = sol.state(t[shuffled])
    assert np.array_equal(x, state[0]) and np.array_equal(v, state[1])
    assert np.array_equal(sol.sorted_state(t), state)
    # against the solver's own scalar path (bisection on the phase starts, the half-angle
    # formulas): the same phase for every time, values to round-off
    scalar = np.array([sol._scalar_state(ti) for ti in t]).T
    scale = np.max(np.abs(scalar), axis=1, keepdims=True)
    assert np.all(np.abs(state - scalar) <= 1e-12 * scale)
    assert len(sol.phases) == phases
