"""Whole-event metrics (energy delivered, contact dissipation, rebound, impulse, peak force,
crown motion) against closed forms and independent computations of the same quantity."""

import dataclasses
import math

import numpy as np
import pytest

from analytic import load_scenario, simulate
from analytic.beam import beam_matrices, deflection_dof
from analytic.beam_impact import beam_impact_model, beam_record, simulate_beam
from analytic.reduction import crown_factor
from analytic.scenario import load_scenario as load
from analytic.soft_contact import simulate_soft
from analytic.model import two_body_model

SCENARIOS = ("open-center", "central-leader", "realistic-crown")
WHOLE = ("energy_delivered", "contact_dissipation", "rebound_energy", "impulse")


def test_plastic_newton_impact_loses_the_closed_form():
    """e = 0: one impact, loss 1/2 m M/(m+M) u1^2; the rest stays in the system."""
    scen = load_scenario("central-leader")
    model = two_body_model(scen, 0.0)
    m, M, u = model.impactor_mass, model.dynamic_mass, model.impact_speed
    got = simulate(scen, restitution=0.0).metrics
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
    damping_work = model.damping * np.trapezoid(tr.vx ** 2, tr.t)
    trunk = 0.5 * model.dynamic_mass * tr.vx[after][0] ** 2 \
        + 0.5 * model.stiffness * tr.x[after][0] ** 2 + damping_work
    # trapezoid over 2e5 samples of a smooth x'(t): O(dt^2) ~ 1e-6 of the damping work
    assert res.metrics["energy_delivered"] == pytest.approx(trunk, rel=1e-4)


@pytest.mark.parametrize("name", SCENARIOS)
def test_stiff_soft_contact_tends_to_the_newton_whole_event(name):
    """A 50 us soft contact is Newton's impact sequence to first order in the duration."""
    scen = load_scenario(name)
    newton = simulate(scen).metrics
    errs = []
    for duration in (2e-4, 1e-4, 5e-5):
        soft = simulate_soft(scen, duration=duration).metrics
        errs.append(max(abs(soft[k] / newton[k] - 1) for k in WHOLE))
    assert errs[-1] < 0.03  # first order in the collision duration (measured 0.3-2 %)
    assert errs[-1] < errs[0]  # and shrinking with it


@pytest.mark.parametrize("name", SCENARIOS)
def test_impulse_is_the_integral_of_the_contact_force(name):
    """The metric comes from the pendulum's momentum; the force record integrates to it."""
    res = simulate_soft(load_scenario(name), samples_per_collision=400)
    rec = res.extra["record"]
    # trapezoid of the force at 400 samples per collision: O(1e-5) of the impulse
    assert res.metrics["impulse"] == pytest.approx(np.trapezoid(rec.force, rec.t), rel=1e-3)
    assert res.metrics["peak_force"] == pytest.approx(rec.force.max(), rel=1e-12)


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


def test_beam_crown_acceleration_is_the_second_derivative_of_its_motion():
    """The beam's exact crown acceleration against a finite difference of its crown motion
    well after the last contact (free vibration, smooth)."""
    model, _ = beam_impact_model(load_scenario("central-leader"))
    dt = 2e-7  # (omega dt)^2 / 12 < 1e-4 for the mesh's highest mode (~1e5 rad/s)
    rec, _, _ = beam_record(model, 0.0302, dt)
    t, c, a = rec.t, rec.crown, rec.crown_acceleration
    k = np.flatnonzero(t > 0.03)[:-1]
    fd = (c[k + 1] - 2 * c[k] + c[k - 1]) / dt ** 2
    scale = np.max(np.abs(a[k]))
    # central difference: (omega dt)^2/12 of the highest mode plus round-off eps c/dt^2
    assert np.max(np.abs(fd - a[k])) < 0.01 * scale


@pytest.mark.parametrize("name", SCENARIOS)
def test_beam_delivered_energy_is_the_trunks_final_energy(name):
    """E0 - rebound - contact loss (the metric, from the contact's work) against the trunk's
    own account at t_end: its kinetic + elastic energy (total minus the pendulum's) plus the
    work of its damping, from the modal state."""
    res = simulate_beam(load_scenario(name))
    m, rec = res.metrics, res.extra["record"]
    trunk = rec.kinetic[-1] + rec.potential[-1] - rec.pendulum_energy[-1] + rec.damping_work[-1]
    # both closed-form; they differ by the ledger's round-off (< 2e-6 of E0)
    assert m["energy_delivered"] == pytest.approx(trunk, rel=1e-5)
    assert m["contact_episodes"] >= 1 and math.isfinite(m["peak_force"])


def test_newton_force_and_crown_acceleration_are_impulsive():
    m = simulate(load_scenario("open-center")).metrics
    assert math.isnan(m["peak_force"]) and math.isnan(m["crown_peak_acceleration"])


def test_a_record_still_in_contact_has_no_whole_event_energies():
    scen = load_scenario("central-leader")
    res = simulate_soft(dataclasses.replace(scen), t_end=1e-4)
    assert all(math.isnan(res.metrics[k]) for k in WHOLE)
