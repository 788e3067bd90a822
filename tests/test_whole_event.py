"""Whole-event metrics (energy delivered, contact dissipation, rebound, impulse, peak force,
crown motion) against closed forms and independent computations of the same quantity."""

import dataclasses
import math

import numpy as np
import pytest

from treeimpact.analytic.contact.exact_record import record
from treeimpact.analytic.contact.soft import simulate_soft
from treeimpact.analytic.continuum.beam import beam_matrices, deflection_dof
from treeimpact.analytic.continuum.beam_impact import beam_impact_model, simulate_beam
from treeimpact.analytic.impact.simulate import simulate
from treeimpact.analytic.model.reduction import crown_factor
from treeimpact.analytic.model.scenario import load_scenario
from treeimpact.analytic.model.scenario import load_scenario as load
from treeimpact.analytic.model.two_body import two_body_model
from treeimpact.analytic.model.options import scenario_as_run

SCENARIOS = ("open-center", "central-leader", "realistic-crown")
WHOLE = ("energy_delivered", "contact_dissipation", "rebound_energy", "impulse")


def test_plastic_newton_impact_loses_the_closed_form():
    """e = 0: one impact, loss 1/2 m M/(m+M) u1^2; the rest stays in the system."""
    scen = load_scenario("central-leader")
    model = two_body_model(scenario_as_run(scen, {"restitution": 0.0}))
    m, M, u = model.impactor_mass, model.dynamic_mass, model.impact_speed
    got = simulate(scenario_as_run(scen, {"restitution": 0.0})).metrics
    assert got["contact_dissipation"] == pytest.approx(0.5 * m * M / (m + M) * u ** 2,
                                                       rel=1e-12)
    assert got["energy_delivered"] + got["contact_dissipation"] + got["rebound_energy"] == \
        pytest.approx(model.initial_energy, rel=1e-12)


@pytest.mark.parametrize("name", SCENARIOS)
def test_newton_delivered_energy_is_the_trunks_final_energy(name):
    """E0 - rebound - contact loss (the metric) against the trunk's own account at t_end:
    1/2 M_T x'^2 + 1/2 K_T x^2 + the damping work C_T int x'^2 dt, from the trajectory."""
    scen = load_scenario(name)
    res = simulate(scen, samples=200001)
    model = two_body_model(scen)
    tr = res.trajectory
    after = tr.t >= tr.t[-1] - 1e-12
    damping_work = model.equivalent_damping * np.trapezoid(tr.vx ** 2, tr.t)
    trunk = 0.5 * model.dynamic_mass * tr.vx[after][0] ** 2 \
        + 0.5 * model.equivalent_stiffness * tr.x[after][0] ** 2 + damping_work
    # trapezoid over 2e5 samples of a smooth x'(t): O(dt^2) ~ 1e-6 of the damping work
    assert res.metrics["energy_delivered"] == pytest.approx(trunk, rel=1e-4)


@pytest.mark.parametrize("name", SCENARIOS)
def test_stiff_soft_contact_tends_to_the_newton_whole_event(name):
    """A 50 us soft contact is Newton's impact sequence to first order in the duration."""
    scen = load_scenario(name)
    newton = simulate(scen).metrics
    errs = []
    for duration in (2e-4, 1e-4, 5e-5):
        soft = simulate_soft(scenario_as_run(scen, {"contact_duration": duration})).metrics
        errs.append(max(abs(soft[k] / newton[k] - 1) for k in WHOLE))
    assert errs[-1] < 0.03  # first order in the collision duration (measured 0.3-2 %)
    assert errs[-1] < errs[0]  # and shrinking with it


@pytest.mark.parametrize("name", SCENARIOS)
def test_impulse_is_the_integral_of_the_contact_force(name):
    """The metric comes from the pendulum's momentum; the force record integrates to it."""
    res = simulate_soft(load_scenario(name), samples_per_collision=400)
    rec = res.record
    # trapezoid of the force at 400 samples per collision: O(1e-5) of the impulse
    assert res.metrics["impulse"] == pytest.approx(np.trapezoid(rec.force, rec.t), rel=1e-3)


def test_peak_force_is_the_first_collisions_mean_force():
    """The mean force over t_c peaks on the first collision, a free collision to first order
    in t_c omega_n: its impulse (1 + e) mu u1 (mu = m M_T / (m + M_T)) over t_c; and it
    equals a direct quadrature of every window."""
    scen = load_scenario("central-leader")
    res = simulate_soft(scen, samples_per_collision=400)
    model = two_body_model(scen)
    m, M, u, e = model.impactor_mass, model.dynamic_mass, model.impact_speed, model.restitution
    t_c = res.collision_duration
    free = (1 + e) * m * M / (m + M) * u / t_c
    # the springs and trunk damper act during t_c: omega_n t_c, b t_c ~ 0.03 (3 % measured)
    assert res.metrics["peak_force"] == pytest.approx(free, rel=0.05)
    rec = res.record
    step = rec.t[1] - rec.t[0]
    k = int(round(t_c / step))
    direct = max(np.trapezoid(rec.force[i:i + k + 1], rec.t[i:i + k + 1])
                 for i in range(0, 3 * k))
    # windows start at samples here, interpolated there: O(1/400) of the mean
    assert res.metrics["peak_force"] == pytest.approx(direct / t_c, rel=5e-3)


@pytest.mark.parametrize("name", SCENARIOS)
def test_sdof_crown_is_the_static_shape_of_the_beam(name):
    """phi(l) of eq 5 against the crown/clamp ratio of the beam mesh's static deflection under
    a load at a (Hermite cubics hold the static solution exactly)."""
    trunk = load(name).trunk
    M, D, K, nodes, keep = beam_matrices(trunk, 24)
    i = deflection_dof(nodes, keep, trunk.clamp_height)
    j = deflection_dof(nodes, keep, trunk.length)
    u = np.linalg.solve(K, np.eye(len(K))[i])
    assert crown_factor(trunk) == pytest.approx(u[j] / u[i], rel=1e-9)
    res = simulate_soft(load(name))
    # x_max is refined between samples, the crown peak is the sampled maximum (~1e-9)
    assert res.metrics["crown_peak"] == pytest.approx(crown_factor(trunk)
                                                      * res.metrics["x_max"], rel=1e-6)


def test_beam_crown_velocity_is_the_derivative_of_its_motion():
    """The beam's exact crown velocity against a central difference of its crown motion."""
    model, _ = beam_impact_model(load_scenario("central-leader"))
    dt = 1e-7  # (omega dt)^2 / 6 < 1e-4 for the mesh's highest mode (~1e5 rad/s)
    rec, _, _ = record(model, 0.0101, dt)
    t, c, v = rec.t, rec.crown, rec.crown_velocity
    k = np.flatnonzero(t > 0.01)[:-1]
    fd = (c[k + 1] - c[k - 1]) / (2 * dt)
    assert np.max(np.abs(fd - v[k])) < 1e-3 * np.max(np.abs(v))


@pytest.mark.parametrize("name", ("open-center", "realistic-crown"))
def test_beam_peaks_over_t_c_converge_in_elements(name):
    """The crown's mean acceleration and the contact's mean force over t_c (not pointwise
    peaks, which the pad's force step drives through every mode) at 12 and 24 elements within
    step.beam's 2 % and 0.5 % of 48 elements (measured 0.2-1.4 %, 0.1-0.4 %)."""
    scen = load_scenario(name)
    runs = [simulate_beam(scen, elements=n).metrics for n in (12, 24, 48)]
    for m in runs[:2]:
        assert m["crown_peak_acceleration"] == pytest.approx(
            runs[2]["crown_peak_acceleration"], rel=0.02)
        assert m["peak_force"] == pytest.approx(runs[2]["peak_force"], rel=0.005)


@pytest.mark.parametrize("name", SCENARIOS)
def test_beam_delivered_energy_is_the_trunks_final_energy(name):
    """E0 - rebound - contact loss (the metric, from the contact's work) against the trunk's
    own account at t_end: its kinetic + elastic energy (total minus the pendulum's) plus the
    work of its damping, from the modal state."""
    res = simulate_beam(load_scenario(name))
    m, rec = res.metrics, res.record
    trunk = rec.kinetic[-1] + rec.potential[-1] - rec.pendulum_energy[-1] + rec.damping_work[-1]
    # both closed-form; they differ by the ledger's round-off (< 2e-6 of E0)
    assert m["energy_delivered"] == pytest.approx(trunk, rel=1e-5)
    assert m["contact_episodes"] >= 1 and math.isfinite(m["peak_force"])


def test_newton_force_and_crown_acceleration_are_impulsive():
    m = simulate(load_scenario("open-center")).metrics
    assert math.isnan(m["peak_force"]) and math.isnan(m["crown_peak_acceleration"])


def test_a_record_still_in_contact_has_no_whole_event_energies():
    scen = load_scenario("central-leader")
    res = simulate_soft(scenario_as_run(dataclasses.replace(scen), {"t_end": 1e-4}))
    assert all(math.isnan(res.metrics[k]) for k in WHOLE)


@pytest.mark.parametrize("grid", ["even", "uneven", "short"])
@pytest.mark.blas_free
def test_window_means_are_numpys_interpolation_bitwise(grid):
    """The window means (peak force, crown acceleration) skip np.interp's search on an even
    grid: the same numbers bit for bit as (np.interp(t + w, t, C) - C) / w over the
    samples with t + w inside, on a linspace grid (whose round-off could put a shifted
    sample on another interval), an uneven one (np.interp itself) and a window of a
    whole number of samples (shifted samples on the nodes)."""
    from treeimpact.analytic.records import shift_plan, window_means

    rng = np.random.default_rng(7)
    for _ in range(20):
        n = int(rng.integers(50, 40000))
        t = (np.linspace(0.0, 0.1, n) if grid != "uneven"
             else np.sort(rng.uniform(0.0, 0.1, n)))
        c = np.cumsum(rng.normal(size=n))
        w = 7 * (t[1] - t[0]) if grid == "short" else float(rng.uniform(1e-4, 0.05))
        inside = t <= t[-1] - w
        want = (np.interp(t[inside] + w, t, c) - c[inside]) / w
        assert np.array_equal(window_means(t, c, w), want)
        # the grid's part formed once and shared (whole_event_metrics): the same numbers
        plan = shift_plan(t, w)
        for other in (c, np.sin(c)):
            assert np.array_equal(window_means(t, other, w, plan), window_means(t, other, w))
