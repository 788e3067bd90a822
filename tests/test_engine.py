"""The engine interface (analytic.engine.interface): both engine packages implement it, and the run
protocol they share is checked against closed forms and the analytic chain."""

import inspect
import math

import numpy as np
import pytest

from treeimpact.analytic.continuum.chain import (
    chain_matrices,
    chain_natural_frequencies,
    chain_static_stiffness,
    hinged_chain,
    lateral_jacobian,
)
from treeimpact.analytic.engine.interface import Engine, chain_modes, check_energy, swing_time
from treeimpact.analytic.errors import ParameterError, SimulationDiverged
from treeimpact.analytic.model.options import OVERRIDES, numerical_options
from treeimpact.analytic.model.scenario import load_scenario

ENGINES = ["treeimpact.mujoco_models", "treeimpact.bullet_models"]


@pytest.mark.parametrize("package", ENGINES)
def test_engine_packages_implement_the_interface_and_name_their_options(package):
    mod = pytest.importorskip(package)
    assert isinstance(mod, Engine)
    keyword = {p.name for p in inspect.signature(mod.simulate).parameters.values()
               if p.kind == p.KEYWORD_ONLY}
    # what compare.runs.backends checks options against: the numerical ones are the run's
    # keywords, the rest override a scenario field (applied to the scenario before the run)
    assert set(numerical_options(mod.OPTIONS)) == keyword
    assert set(mod.OPTIONS) - keyword <= set(OVERRIDES)


@pytest.mark.parametrize("package", ENGINES)
def test_run_of_a_setup_is_simulate(package):
    mod = pytest.importorskip(package)
    scen = load_scenario("open-center")
    a = mod.run(mod.make_setup(scen, trunk="sdof"))
    b = mod.simulate(scen, trunk="sdof")
    np.testing.assert_equal(a.metrics, b.metrics)  # deterministic engines, NaN == NaN


def test_chain_modes_match_the_analytic_chain():
    """From the chain's own M, k_j and J: the static stiffness at a and the frequencies of
    analytic.continuum.chain (what an engine that reproduces the chain's matrices must print)."""
    scen = load_scenario("central-leader")
    chain = hinged_chain(scen.trunk, 10)
    M, K, _ = chain_matrices(chain)
    J = lateral_jacobian(chain, scen.trunk.clamp_height)[0]
    out = chain_modes(scen, M, np.diag(K), J, 3)["model"]
    assert out["static_stiffness"] == pytest.approx(chain_static_stiffness(chain), rel=1e-12)
    assert out["omegas"] == pytest.approx(list(chain_natural_frequencies(chain, 3)), rel=1e-10)
    with pytest.raises(ParameterError, match=r"n_modes = 11 is out of range: allowed \[1, 10\]"):
        chain_modes(scen, M, np.diag(K), J, 11)


@pytest.mark.blas_free
def test_energy_check_refuses_growth_and_non_finite_energy():
    check_energy("x", np.array([1.0, 1.04]), 1.0, 1e-4)  # within 5 %
    for mech in ([1.0, 1.06], [1.0, math.nan]):
        with pytest.raises(SimulationDiverged, match="x: mechanical energy reached"):
            check_energy("x", np.array(mech), 1.0, 1e-4)


@pytest.mark.blas_free
def test_swing_time_is_the_small_angle_quarter_period_in_the_limit():
    from dataclasses import replace

    pend = load_scenario("open-center").impactor
    small = replace(pend, release_angle_deg=math.degrees(2e-4))  # K = pi/2 (1 + 2.5e-9)
    quarter = 0.5 * math.pi * math.sqrt(pend.equivalent_length / pend.gravity)
    assert swing_time(small) == pytest.approx(quarter, rel=1e-8)
    assert swing_time(pend) > quarter  # a finite swing is slower (elliptic integral)
