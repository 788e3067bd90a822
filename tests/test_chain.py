"""Hinged rigid-segment trunk (analytic.continuum.chain): Hencky closed forms, exact energies,
convergence to the beam."""

import dataclasses
import math
import re
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.linalg import eigh

from treeimpact.analytic.continuum.beam import beam_natural_frequencies, beam_static_stiffness
from treeimpact.analytic.continuum.chain import (
    chain_errors,
    chain_matrices,
    chain_natural_frequencies,
    chain_reduced_sdof,
    chain_static_stiffness,
    default_segments,
    hinged_chain,
    split_segments,
)
from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.model.parameters import Trunk
from treeimpact.analytic.model.reduction import reduce_trunk
from treeimpact.analytic.model.scenario import load_scenario, shipped_scenarios

UNIFORM = Trunk(length=1.3, clamp_height=1.3, diameter=0.1, density=900.0, youngs_modulus=1.0e10)
# a/l = 1/2 so that N_in = N/2 exactly for even N: smooth convergence curves
LOADED = Trunk(length=1.0, clamp_height=0.5, diameter=0.12, density=950.0, youngs_modulus=9.0e9,
               clamp_mass=4.0, crown_mass=15.0, damping=3000.0, base_stiffness=2.0e5)
SHIPPED = {name: load_scenario(name).trunk for name in shipped_scenarios()}
CONVERGENCE_N = np.array([4, 8, 16, 32, 64])
# the leading error is c / N^2; over N = 4..64 the O(N^-4) tail shifts the fitted slope by
# < 0.06 (measured 1.94..2.08), so the observed order is asserted in [1.9, 2.1]
ORDER_BAND = (1.9, 2.1)


def _order(errors) -> float:
    return -np.polyfit(np.log(CONVERGENCE_N), np.log(np.abs(errors)), 1)[0]


@pytest.mark.parametrize("n", [2, 3, 5, 8, 13, 64, 1000])
def test_hencky_chain_tip_flexibility_is_exactly_1_plus_1_over_2N2_times_beam(n):
    chain = hinged_chain(UNIFORM, n)
    exact = 3 * UNIFORM.bending_stiffness / UNIFORM.length ** 3
    # closed form: sum of (moment arm)^2 / k over the hinges = l^3/(3EI) (1 + 1/(2N^2))
    assert chain_static_stiffness(chain) * (1 + 1 / (2 * n ** 2)) == pytest.approx(exact,
                                                                                   rel=1e-12)


@pytest.mark.parametrize("name", list(SHIPPED))
@pytest.mark.parametrize("n", [2, 7, 12, 40])
def test_chain_flexibility_at_a_is_hencky_bending_plus_root_spring(name, n):
    t = SHIPPED[name]
    n_in, _ = split_segments(t, n)
    a, ei = t.clamp_height, t.bending_stiffness
    flex = a ** 3 / (3 * ei) * (1 + 1 / (2 * n_in ** 2)) + a ** 2 / t.base_stiffness
    assert 1 / chain_static_stiffness(hinged_chain(t, n)) == pytest.approx(flex, rel=1e-12)


@pytest.mark.parametrize("trunk", [UNIFORM, LOADED], ids=["uniform", "loaded-root-spring"])
def test_static_stiffness_converges_to_beam_with_order_two(trunk):
    kb = beam_static_stiffness(trunk)
    err = [chain_static_stiffness(hinged_chain(trunk, int(n))) / kb - 1 for n in CONVERGENCE_N]
    assert all(e < 0 for e in err)  # the chain is always softer (1 + 1/(2 N_in^2) > 1)
    assert ORDER_BAND[0] <= _order(err) <= ORDER_BAND[1]


@pytest.mark.parametrize("trunk", [UNIFORM, LOADED], ids=["uniform", "loaded-root-spring"])
def test_first_three_frequencies_converge_to_beam_with_order_two(trunk):
    wb = beam_natural_frequencies(trunk, 3)
    err = np.array([chain_natural_frequencies(hinged_chain(trunk, int(n)), 3) / wb - 1
                    for n in CONVERGENCE_N])
    for mode in range(3):
        assert ORDER_BAND[0] <= _order(err[:, mode]) <= ORDER_BAND[1], f"mode {mode + 1}"
    # O(N^-2) discretisation error: measured 6.4e-4 (uniform, mode 3), 1.7e-4 (loaded) at N = 64
    assert np.abs(err[-1]).max() < 1e-3


def test_frequencies_from_scaled_problem_equal_generalised_eigh():
    chain = hinged_chain(LOADED, 10)
    M, K, _ = chain_matrices(chain)
    w2 = eigh(K, M, eigvals_only=True)[:3]
    # 10 hinges: cond ~ 1e4, both routes agree to round-off
    assert chain_natural_frequencies(chain, 3) == pytest.approx(np.sqrt(w2), rel=1e-10)


@pytest.mark.parametrize("trunk", [LOADED, SHIPPED["central-leader"]],
                         ids=["loaded-root-spring", "central-leader"])
def test_chain_damping_on_static_mode_converges_to_analytic_C_T(trunk):
    sdof = reduce_trunk(trunk)  # C_T = C int phi^2 dz (eq 10, derived form)
    err = []
    for n in CONVERGENCE_N:
        red = chain_reduced_sdof(hinged_chain(trunk, int(n)))
        err.append(red.equivalent_damping / sdof.equivalent_damping - 1)
        assert red.equivalent_stiffness == pytest.approx(
            chain_static_stiffness(hinged_chain(trunk, int(n))), rel=1e-12)
    # the chain's static shape is the beam's to O(h^2): measured 8.2e-5 (loaded), 1.4e-4 at N = 64
    assert abs(err[-1]) < 2e-4
    # above a the static shape is linear, which rigid segments hold exactly: the error is set
    # by the N_in segments below a (N_in = 1, 3, 5, 10, 20 for central-leader), so fit vs N_in
    n_in = [split_segments(trunk, int(n))[0] for n in CONVERGENCE_N]
    order = -np.polyfit(np.log(n_in), np.log(np.abs(err)), 1)[0]
    assert ORDER_BAND[0] <= order <= ORDER_BAND[1]


def _velocity_field(chain, theta_dot):
    """Lateral velocity v(z) of the rigid-segment chain, by forward kinematics segment by segment."""
    z = np.asarray(chain.boundaries)
    omega = np.cumsum(theta_dot)  # absolute angular velocity of each segment
    v_bottom = np.concatenate([[0.0], np.cumsum(omega * np.diff(z))])  # at z_0 .. z_N

    def v(x):
        s = min(int(np.searchsorted(z, x, side="right")) - 1, len(omega) - 1)
        return v_bottom[s] + omega[s] * (x - z[s])

    return v


@pytest.mark.parametrize("trunk", [LOADED, SHIPPED["open-center"]], ids=["loaded", "open-center"])
def test_damping_and_mass_matrices_equal_exact_integrals_of_rigid_segment_velocity(trunk):
    chain = hinged_chain(trunk, 7)
    M, K, D = chain_matrices(chain)
    rho_a = trunk.density * trunk.area
    rng = np.random.default_rng(3)
    z = chain.boundaries
    for _ in range(3):
        theta_dot = rng.normal(size=chain.segments)
        v = _velocity_field(chain, theta_dot)
        # adaptive quadrature segment by segment (the field is only piecewise smooth)
        dissipation = sum(quad(lambda x: trunk.damping * v(x) ** 2, z[i], z[i + 1],
                               epsabs=0, epsrel=1e-13)[0] for i in range(chain.segments))
        kinetic = sum(quad(lambda x: rho_a * v(x) ** 2, z[i], z[i + 1],
                           epsabs=0, epsrel=1e-13)[0] for i in range(chain.segments))
        kinetic += trunk.clamp_mass * v(trunk.clamp_height) ** 2 + trunk.crown_mass * v(
            trunk.length) ** 2
        assert theta_dot @ D @ theta_dot == pytest.approx(dissipation, rel=1e-12)
        # the rod inertia rho A h^3/12 makes the rigid-segment kinetic energy exact
        assert theta_dot @ M @ theta_dot == pytest.approx(kinetic, rel=1e-12)
    assert np.array_equal(K, np.diag(np.diag(K)))  # relative hinge angles: uncoupled springs


def test_chain_geometry_masses_hinges_and_damping_points():
    t = SHIPPED["central-leader"]
    chain = hinged_chain(t, 12)
    z = np.asarray(chain.boundaries)
    assert chain.segments == 12 and z[0] == 0.0 and z[-1] == t.length
    assert z[chain.clamp_index] == t.clamp_height
    assert split_segments(t, 12) == (4, 8)  # floor(12 * 0.315 + 1/2) = 4 below a
    assert chain.clamp_segment == 3 and chain.crown_segment == 11
    assert np.allclose(np.diff(z[:5]), t.clamp_height / 4, rtol=1e-12)
    assert sum(chain.masses) == pytest.approx(t.trunk_mass, rel=1e-12)
    assert np.sum(chain.damping_coefficients) == pytest.approx(t.damping * t.length, rel=1e-12)
    assert np.array_equal(chain.hinge_heights, z[:-1])
    h = chain.lengths
    ei = t.bending_stiffness
    assert chain.hinge_stiffnesses[4] == pytest.approx(2 * ei / (h[3] + h[4]), rel=1e-14)
    assert chain.hinge_stiffnesses[2] == pytest.approx(ei / h[2], rel=1e-14)  # equal neighbours
    assert 1 / chain.hinge_stiffnesses[0] == pytest.approx(h[0] / (2 * ei) + 1 / t.base_stiffness,
                                                           rel=1e-14)
    assert chain.inertias[5] == pytest.approx(chain.masses[5] * h[5] ** 2 / 12, rel=1e-14)
    dz = np.asarray(chain.damping_heights).reshape(-1, 2)
    assert np.allclose(dz.mean(axis=1), chain.centres, rtol=1e-14)
    assert np.allclose(np.diff(dz, axis=1)[:, 0], h / math.sqrt(3), rtol=1e-12)


def test_rigid_clamp_base_hinge_is_2EI_over_h0():
    t = dataclasses.replace(LOADED, base_stiffness=math.inf)
    chain = hinged_chain(t, 6)
    assert chain.hinge_stiffnesses[0] == pytest.approx(2 * t.bending_stiffness / chain.lengths[0],
                                                       rel=1e-14)


def test_split_keeps_at_least_one_segment_on_each_side_of_a():
    low = dataclasses.replace(LOADED, clamp_height=0.01)
    high = dataclasses.replace(LOADED, clamp_height=0.99)
    assert split_segments(low, 10) == (1, 9)  # round(0.1) = 0 -> 1
    assert split_segments(high, 10) == (9, 1)  # round(9.9) = 10 -> 9
    assert split_segments(UNIFORM, 5) == (5, 0)  # a = l: everything below a


@pytest.mark.parametrize("segments", [1, 0, -3, 1001, 2.5, 4.0, True, "3", None])
def test_bad_segment_count_raises_one_line_parameter_error(segments):
    with pytest.raises(ParameterError, match=r"segments = .* allowed integers \[2, 1000\]") as err:
        hinged_chain(LOADED, segments)
    assert "\n" not in str(err.value)


def test_numpy_integer_segment_count_is_accepted():
    assert hinged_chain(LOADED, np.int64(6)).segments == 6


def test_bad_trunk_mode_count_and_tolerance_raise_parameter_error():
    with pytest.raises(ParameterError, match="trunk"):
        hinged_chain("central-leader", 4)
    with pytest.raises(ParameterError, match="n_modes"):
        chain_natural_frequencies(hinged_chain(LOADED, 4), 5)  # more modes than segments
    with pytest.raises(ParameterError, match="tolerance"):
        default_segments(LOADED, 0.0)


# default_segments: the docstring's convergence table must be the measured one
_ROW = re.compile(r"^\s*([a-z-]+)\s+(\d+)\s+(\d+)\s+(-?\d\.\d+) %\s+(-?\d\.\d+) %\s+(-?\d\.\d+) %\s*$",
                  re.M)


def test_default_segments_docstring_table_is_current():
    """The convergence table of docs/trunk-models.md (moved there from the docstring)."""
    doc = (Path(__file__).resolve().parents[1] / "docs" / "trunk-models.md").read_text()
    rows = {m[1]: m for m in _ROW.finditer(doc)}
    assert sorted(rows) == sorted(SHIPPED)
    for name, m in rows.items():
        t = SHIPPED[name]
        n = default_segments(t)
        assert n == int(m[2])
        assert split_segments(t, n)[0] == int(m[3])
        err = chain_errors(t, n)
        for key, printed in zip(("static_stiffness", "omega_1", "omega_2"), m.groups()[3:]):
            # printed to 3 decimals of a percent
            assert 100 * err[key] == pytest.approx(float(printed), abs=5.1e-4), (name, key)


@pytest.mark.parametrize("name", list(SHIPPED))
def test_default_segments_is_smallest_within_tolerance(name):
    t = SHIPPED[name]
    n = default_segments(t)
    wb = beam_natural_frequencies(t, 2)
    kb = beam_static_stiffness(t)

    def worst(m):  # measured here, independently of chain_errors
        c = hinged_chain(t, m)
        return max(abs(chain_static_stiffness(c) / kb - 1),
                   *np.abs(chain_natural_frequencies(c, 2) / wb - 1))

    assert worst(n) <= 0.005
    assert all(worst(m) > 0.005 for m in range(2, n))


@pytest.mark.parametrize(("length", "crown_mass", "tolerance"), [
    (1.0, 0.0, 0.005), (2.5, 0.0, 0.005), (1.0, 40.0, 0.002), (4.0, 10.0, 0.01),
    (0.6, 5.0, 0.001)], ids=["bare", "long-bare", "heavy-crown", "long-light-crown",
                             "short-tight"])
def test_default_segments_bisection_finds_what_the_upward_search_finds(length, crown_mass,
                                                                        tolerance):
    """Doubling and bisecting assume the errors fall with N; an upward search checks it."""
    from treeimpact.analytic.continuum.chain import chain_errors

    t = dataclasses.replace(SHIPPED["central-leader"], length=length, crown_mass=crown_mass)
    n = default_segments(t, tolerance)
    upward = next(m for m in range(2, 1001)
                  if all(abs(v) <= tolerance for v in chain_errors(t, m).values()))
    assert n == upward


def test_a_trunk_needing_hundreds_of_segments_is_searched_in_a_few_solves():
    from unittest import mock

    from treeimpact.analytic.continuum import chain

    t = dataclasses.replace(SHIPPED["central-leader"], length=30.0)
    with mock.patch.object(chain, "chain_errors", wraps=chain.chain_errors) as spy:
        n = chain._default_segments.__wrapped__(t, 0.005)
    assert 200 < n < 1000  # a 30 m trunk clamped at 0.3 m: the clamp's short segments
    assert spy.call_count <= 2 * math.ceil(math.log2(n)) + 1


# ------------------------------------------------------------------ the exact chain struck by the pad
# (analytic.continuum.chain_impact: the chain and the rod as linear trunks of the exact solver)

def test_lateral_matrices_are_the_chains_energies_in_boundary_displacements():
    """x = T theta: x^T M_x x, x^T K_x x, x^T D_x x equal the angle forms, and the clamp dof
    is the chain's deflection at a (J(a) theta)."""
    from treeimpact.analytic.continuum.chain import lateral_jacobian
    from treeimpact.analytic.continuum.chain_impact import lateral_matrices, lateral_transform

    chain = hinged_chain(LOADED, 9)
    Mt, Kt, Dt = chain_matrices(chain)
    Mx, Dx, Kx = lateral_matrices(chain, "chain")
    theta = np.random.default_rng(5).normal(size=9)
    x = lateral_transform(chain) @ theta
    for a, b in ((Mx, Mt), (Kx, Kt), (Dx, Dt)):
        assert x @ a @ x == pytest.approx(theta @ b @ theta, rel=1e-10)
    ja = lateral_jacobian(chain, LOADED.clamp_height)[0]
    assert x[chain.clamp_index - 1] == pytest.approx(ja @ theta, rel=1e-12)


def test_rod_surrogate_is_the_chains_springs_on_the_lumped_vertex_masses():
    """The rod's masses are rho A (h_{k-1} + h_k) / 2 per vertex (+ m_c, + m_f): the chain's
    total mass less the base half segment; its stiffness the chain's."""
    from treeimpact.analytic.continuum.chain_impact import lateral_matrices

    chain = hinged_chain(LOADED, 10)
    Mr, Dr, Kr = lateral_matrices(chain, "rod")
    _, _, Kc = lateral_matrices(chain, "chain")
    assert np.allclose(Mr, np.diag(np.diag(Mr)))
    rho_a = LOADED.density * LOADED.area
    total = rho_a * (LOADED.length - chain.lengths[0] / 2) + LOADED.clamp_mass + LOADED.crown_mass
    assert np.trace(Mr) == pytest.approx(total, rel=1e-12)
    np.testing.assert_allclose(Kr, Kc, rtol=0, atol=1e-9 * np.abs(Kc).max())
    with pytest.raises(ParameterError, match="trunk = 'cable'"):
        lateral_matrices(chain, "cable")


def _beam_fine(scenario):
    """The exact beam of ``scenario`` on the finest mesh (48 elements): the limit."""
    from treeimpact.analytic.continuum.beam_impact import beam_impact_model
    from treeimpact.analytic.continuum.chain_impact import exact_metrics

    return exact_metrics(scenario, *beam_impact_model(scenario, elements=48))


def test_exact_chain_x_max_converges_to_the_beam_at_second_order():
    """open-center, N = 10, 20, 40 against the 48-element beam: x_max's error falls about
    4 times per doubling (measured +0.31 / +0.07 / +0.01 % against the 12-element beam)."""
    from treeimpact.analytic.continuum.chain_impact import discretised_metrics

    s = load_scenario("open-center")
    ref = _beam_fine(s)["x_max"]
    err = [discretised_metrics(s, n)["x_max"] / ref - 1 for n in (10, 20, 40)]
    assert abs(err[0]) < 5e-3 and abs(err[2]) < 3e-4, err
    order = math.log2(abs(err[0] / err[1]))
    assert 1.6 < order < 2.6, (err, order)  # second order, the beam's own error ~1e-4 aside


def test_exact_chain_and_rod_agree_with_mujocos_runs_to_its_integrator():
    """The exact surrogates are what MuJoCo integrates: open-center at N = 10, x_max and the
    energies within 0.2 % (its implicit step, ~O(omega h)); peak_force is the step's lag."""
    pytest.importorskip("mujoco")
    from treeimpact.analytic.continuum.chain_impact import discretised_metrics
    from treeimpact.mujoco_models import simulate

    s = load_scenario("open-center")
    for trunk, surrogate in (("chain", "chain"), ("flex", "rod")):
        run = simulate(s, trunk=trunk, segments=10, pendulum="linear").metrics
        exact = discretised_metrics(s, 10, surrogate)
        for k in ("x_max", "crown_peak", "energy_transferred", "energy_delivered", "impulse"):
            # measured: chain <= 5.5e-4, rod <= 1.2e-3 (energy_delivered)
            assert run[k] == pytest.approx(exact[k], rel=2e-3), (trunk, k)


def test_rod_surrogate_frequencies_are_mujocos_flex_modes():
    """The surrogate's lowest frequencies against MuJoCo's flex (mujoco_models.modes): equal
    up to the root body's neglected rho A h_0^3 / 12, which vanishes as N grows (measured
    omega_2 -4.1e-3 at N = 4, -3.2e-4 at 10, -8.1e-5 at 16)."""
    pytest.importorskip("mujoco")
    from treeimpact.analytic.continuum.chain_impact import lateral_matrices
    from treeimpact.mujoco_models import modes

    s = load_scenario("open-center")
    gaps = []
    for n in (4, 10, 16):
        w_mj = np.asarray(modes(s, trunk="flex", segments=n, n_modes=2)["model"]["omegas"])
        M, _, K = lateral_matrices(hinged_chain(s.trunk, n), "rod")
        w = np.sqrt(eigh(K, M, eigvals_only=True)[:2])
        gaps.append(np.abs(w_mj / w - 1))
    assert np.all(gaps[1] < 1e-3) and np.all(gaps[2] < gaps[0] / 10), gaps


def _rule():
    """The ladder's (trunk, metric, rel) triples of [step.chain] and [step.rod]."""
    from treeimpact.compare.runs.verdicts import load_tolerances

    steps = load_tolerances()["step"]
    return tuple((t, m, e["rel"]) for t in ("chain", "rod") for m, e in steps[t].items()
                 if "rel" in e)


def _worst(scenario, n, share=0.75):
    from treeimpact.analytic.continuum.chain_impact import discretisation_errors

    out = 0.0
    for trunk in ("chain", "rod"):
        rel = {m: v for t, m, v in _rule() if t == trunk}
        e = discretisation_errors(scenario, n, rel, trunk)
        out = max([out] + [abs(v) / (share * rel[m]) for m, v in e.items()])
    return out


@pytest.mark.parametrize("name", ["free-billet", *SHIPPED])
def test_converged_segments_is_the_smallest_n_within_its_share_of_each_tolerance(name):
    """The per-tree rule: N >= default_segments, within three quarters of every
    [step.chain] / [step.rod] tolerance at N, and N - 1 not (or N is default_segments).
    the shipped trees keep theirs; free-billet, a family tree whose rod's x_max needs more."""
    from treeimpact.analytic.continuum.chain_impact import converged_segments
    from treeimpact.compare.tree import family as F

    s = (load_scenario(name) if name in SHIPPED else
         F.build(F.BY_NAME[name]))
    n0, n = default_segments(s.trunk), converged_segments(s, _rule())
    assert n >= n0 and _worst(s, n) <= 1.0
    assert n == n0 or _worst(s, n - 1) > 1.0
    assert (n > n0) == (name == "free-billet")


def test_converged_segments_refuses_a_bad_share():
    from treeimpact.analytic.continuum.chain_impact import converged_segments

    for share in (0, 1.5, True):
        with pytest.raises(ParameterError, match="share"):
            converged_segments(load_scenario("open-center"), _rule(), share)
