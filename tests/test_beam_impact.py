"""The continuum-beam impact backend (analytic.continuum.beam_impact) against independent
references."""

import dataclasses
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from treeimpact.analytic.contact.law import restitution_for_damping_ratio
from treeimpact.analytic.contact.soft import simulate_soft
from treeimpact.analytic.continuum.beam import (
    beam_matrices,
    beam_natural_frequencies,
    deflection_dof,
)
from treeimpact.analytic.continuum.beam_impact import (
    _system,
    beam_impact_model,
    beam_record,
    simulate_beam,
)
from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.model.reduction import static_flexibility
from treeimpact.analytic.model.scenario import load_scenario

SCENARIOS = ("open-center", "central-leader", "realistic-crown")


@pytest.mark.parametrize("name", SCENARIOS)
def test_mesh_static_flexibility_is_eq_1(name):
    trunk = load_scenario(name).trunk
    M, D, K, nodes, keep = beam_matrices(trunk, 24)
    i = deflection_dof(nodes, keep, trunk.clamp_height)
    flex = np.linalg.solve(K, np.eye(len(K))[i])[i]
    # Hermite cubics hold the static solution exactly: only round-off of the h^-4 conditioning
    assert flex == pytest.approx(static_flexibility(trunk), rel=1e-9)


@pytest.mark.parametrize("name", SCENARIOS)
def test_mesh_frequencies_are_the_beams(name):
    import scipy.linalg

    trunk = load_scenario(name).trunk
    M, _, K, _, _ = beam_matrices(trunk, 24)
    w = np.sqrt(scipy.linalg.eigh(K, M, eigvals_only=True)[:2])
    # 24 Hermite elements against the 160-element reference: h^4 error on modes 1-2
    np.testing.assert_allclose(w, beam_natural_frequencies(trunk, 2), rtol=1e-6)


def test_consistent_damping_is_the_distributed_damping():
    trunk = load_scenario("central-leader").trunk
    M, D, _, nodes, keep = beam_matrices(trunk, 12)
    rigid = dataclasses.replace(trunk, clamp_mass=0.0, crown_mass=0.0)
    M0 = beam_matrices(rigid, 12)[0]
    # D is M's distributed part with C in place of rho A (eq 9)
    np.testing.assert_allclose(D, M0 * trunk.damping / (trunk.density * trunk.area),
                               rtol=1e-12, atol=1e-12 * np.abs(D).max())


def _ode_reference(model, t_end, t_eval):
    """The same matrices integrated by DOP853 with the stateless law F = max(0, k d + c d') for
    d > 0: an independent solution of the piecewise-linear system."""
    A_free, g = _system(model, False)
    A_touch, _ = _system(model, True)
    N = len(g)

    def rhs(_t, z):
        d, dd = g @ z[:N], g @ z[N:]
        touching = d > 0 and model.contact_stiffness * d + model.contact_damping * dd > 0
        return (A_touch if touching else A_free) @ z

    z0 = np.zeros(2 * N)
    z0[-1] = model.impact_speed
    sol = solve_ivp(rhs, (0, t_end), z0, method="DOP853", t_eval=t_eval, rtol=1e-11,
                    atol=1e-14, max_step=2e-6)
    return sol.y[model.clamp], sol.y[N - 1]


def test_exact_stepping_matches_an_ode_integration():
    scenario = load_scenario("central-leader")
    model, _ = beam_impact_model(scenario, elements=4)
    t_end = 0.02
    record, _, switches = beam_record(model, t_end, 5e-6)
    x_ref, y_ref = _ode_reference(model, t_end, record.t)
    assert switches >= 4  # the window holds the chattering, not one smooth contact
    # the reference's error: its steps straddle each kink of the law (2 us max step)
    np.testing.assert_allclose(record.x, x_ref, atol=1e-6 * np.abs(x_ref).max())
    np.testing.assert_allclose(record.y, y_ref, atol=1e-6 * np.abs(y_ref).max())


def test_heavy_clamp_light_beam_is_the_soft_sdof():
    """A 1000 kg clamp on a trunk of 1.2 kg moves as the SDOF of eq 11 with the same pad."""
    base = load_scenario("central-leader")
    trunk = dataclasses.replace(base.trunk, density=100.0, clamp_mass=1000.0, crown_mass=0.0,
                                damping=0.0)
    scenario = dataclasses.replace(base, trunk=trunk)
    beam, soft = simulate_beam(scenario, elements=6), simulate_soft(scenario)
    # the beam's own 1.2 kg of distributed mass moves with shapes other than eq 5's: 0.1 %
    assert beam.metrics["x_max"] == pytest.approx(soft.metrics["x_max"], rel=1e-3)
    assert beam.model["contact_damping"] == soft.model["contact_damping"]


@pytest.mark.parametrize("name", SCENARIOS)
def test_energy_ledger_closes(name):
    result = simulate_beam(load_scenario(name))
    # closed-form work integrals: what is left is the eigenvectors' round-off
    assert result.metrics["ledger_residual"] < 1e-5


def test_x_max_converges_in_elements():
    scenario = load_scenario("central-leader")
    x = {n: simulate_beam(scenario, elements=n).metrics["x_max"] for n in (6, 12, 24, 48)}
    assert abs(x[24] / x[48] - 1) < 2e-4  # default mesh against twice as fine
    assert abs(x[12] / x[48] - 1) < 5e-4
    assert abs(x[6] / x[48] - 1) < 1e-3


def test_effective_calibration_gives_e_on_the_clamps_effective_mass():
    scenario = load_scenario("open-center")
    model, sdof = beam_impact_model(scenario, calibration="effective")
    mu = 1.0 / (1.0 / model.effective_mass + 1.0 / sdof.impactor_mass)
    zeta = model.contact_damping / (2.0 * math.sqrt(model.contact_stiffness * mu))
    assert restitution_for_damping_ratio(zeta) == pytest.approx(sdof.restitution, rel=1e-9)
    pad, _ = beam_impact_model(scenario)
    assert pad.contact_stiffness == model.contact_stiffness
    assert model.contact_damping < 0.5 * pad.contact_damping  # the light clamp's smaller mu


@pytest.mark.parametrize("options, field", [
    ({"elements": 1}, "--elements"), ({"elements": 2.5}, "--elements"),
    ({"calibration": "mass"}, "--calibration"), ({"t_end": -1.0}, "--t-end")])
def test_bad_options_are_one_line_errors(options, field):
    with pytest.raises(ParameterError, match=field):
        simulate_beam(load_scenario("open-center"), **options)
