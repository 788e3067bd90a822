"""MuJoCo's own elastic trunk (``--trunk flex``, MuJoCo >= 4.0) and the refusal of ``cable``."""

from __future__ import annotations

import dataclasses
import math
import warnings

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco")

from treeimpact.analytic.continuum.beam_impact import simulate_beam  # noqa: E402
from treeimpact.analytic.errors import ParameterError  # noqa: E402
from treeimpact.analytic.model.scenario import load_scenario  # noqa: E402
from treeimpact.mujoco_models import _flex, make_setup, modes, simulate  # noqa: E402
from treeimpact.mujoco_models._runner import flex_trunk_matrices  # noqa: E402


def _passive(m, q):
    d = mujoco.MjData(m)
    d.qpos[:] = q
    mujoco.mj_forward(m, d)
    return d.qfrc_passive.copy()


def _trunk_dofs(m):
    root, verts = _flex.flex_dofs(m)
    return ([root] if root is not None else []) + verts


@pytest.fixture(scope="module")
def setup8():
    return make_setup(load_scenario("central-leader"), trunk="flex", segments=8)


def test_flex_force_is_minus_the_gradient_of_the_ledgers_bending_energy(setup8):
    """The energy the ledger adds (MuJoCo's e_potential leaves the flex out) is the one whose
    gradient MuJoCo applies, at a deflection large enough to be nonlinear (2 cm at the top:
    1e-2 of the force is nonlinear there)."""
    m, rod = setup8.mjmodel, setup8.flex
    root, verts = _flex.flex_dofs(m)
    rng = np.random.default_rng(3)
    q = np.zeros(m.nq)
    q[root] = 1e-3
    q[verts] = 0.02 * np.linspace(0.1, 1.0, len(verts)) + 1e-3 * rng.normal(size=len(verts))
    f = _passive(m, q)
    eps = 1e-7
    for dof in [root, *verts]:
        qp, qm = q.copy(), q.copy()
        qp[dof] += eps
        qm[dof] -= eps
        energy = [_flex.bending_energy(rod, np.array([x[root]]), x[verts][None, :])[0]
                  + 0.5 * m.jnt_stiffness[0] * x[root] ** 2 for x in (qp, qm)]
        grad = (energy[0] - energy[1]) / (2 * eps)
        # central differences of an energy of ~1e2 J: round-off 1e-14 * 1e2 / 1e-7 = 1e-5 N
        assert -grad == pytest.approx(f[dof], rel=1e-6, abs=1e-4), dof


def test_flex_stiffness_matrix_is_mujocos_hessian(setup8):
    m = setup8.mjmodel
    M, K = flex_trunk_matrices(m, setup8.flex)
    dofs = _trunk_dofs(m)
    eps = 1e-8
    fd = np.column_stack([(_passive(m, eps * e) - _passive(m, -eps * e))[dofs] / (-2 * eps)
                          for e in np.eye(m.nq)[dofs]])
    # the force is odd in q: central differences are exact to O(eps^2) = 1e-16 relative
    np.testing.assert_allclose(fd, K, rtol=0, atol=1e-9 * np.max(np.abs(K)))
    assert np.allclose(M, np.diag(np.diag(M)))  # one slide per vertex: lumped masses


def _errors(scenario, n):
    md = modes(scenario, trunk="flex", segments=n, n_modes=2)
    return np.array([md["model"]["static_stiffness"] / md["beam"]["static_stiffness"] - 1]
                    + [a / b - 1 for a, b in zip(md["model"]["omegas"], md["beam"]["omegas"])])


def test_flex_static_stiffness_is_the_hencky_chains_closed_form():
    """With the clamp edge GHOST_FRACTION h_0 long, the rod's base bends as the chain's
    half segment: flexibility a^3 / (3 E I) (1 + 1 / (2 N_in^2)) + a^2 / k_theta at a."""
    s = load_scenario("central-leader")
    tr = s.trunk
    for n in (4, 16, 64):
        n_in = math.floor(n * tr.clamp_height / tr.length + 0.5)
        closed = 1.0 / (tr.clamp_height ** 3 / (3 * tr.bending_stiffness) * (
            1 + 1 / (2 * n_in ** 2)) + tr.clamp_height ** 2 / tr.base_stiffness)
        k = modes(s, trunk="flex", segments=n, n_modes=1)["model"]["static_stiffness"]
        # the clamp edge's own flexibility, ~GHOST_FRACTION (measured 1.4e-7 at N = 4)
        assert k == pytest.approx(closed, rel=1e-6), n


def test_flex_static_stiffness_and_frequencies_converge_to_the_beam_at_second_order():
    """a = l / 4 so that N_in doubles with N. Observed orders 1.96-2.01 (N = 8..64)."""
    s = load_scenario("central-leader")
    s = dataclasses.replace(s, trunk=dataclasses.replace(s.trunk, clamp_height=0.25))
    errs = {n: _errors(s, n) for n in (8, 16, 32, 64)}
    assert np.all(np.concatenate(list(errs.values())) < 0)  # softer and slower than the beam
    for n in (8, 16, 32):
        order = np.log2(errs[n] / errs[2 * n])
        # second order (lumped masses, Hencky bending): 1.96-2.01 measured; a first-order
        # scheme (the clamp edge h_0 long) gives ~1
        assert np.all(np.abs(order - 2.0) < 0.1), (n, order)
    assert np.all(np.abs(errs[64]) < 5e-4)  # measured <= 3.3e-4 (omega_2)


def test_flex_run_closes_its_energy_ledger_and_counts_the_bending_energy():
    s = load_scenario("open-center")
    r = simulate(s, trunk="flex", segments=8)
    # the existing ledgers' bound (the Euler step's O(omega h) error): measured 1.6e-4
    assert r.metrics["ledger_residual"] < 1e-3
    rec = r.record
    i = int(np.argmax(rec.x))
    k_a = modes(s, trunk="flex", segments=8, n_modes=1)["model"]["static_stiffness"]
    # the trunk's elastic energy at a deflection x_a is at least 1/2 K_a x_a^2 (the static
    # shape minimises it); every other potential term is >= 0: fails without the flex's
    assert rec.potential[i] >= 0.5 * k_a * rec.x[i] ** 2 * (1 - 1e-9)


def test_flex_x_max_and_energy_delivered_are_near_the_continuums():
    s = load_scenario("central-leader")
    beam = simulate_beam(s).metrics
    flex = simulate(s, trunk="flex", segments=8).metrics
    # measured +0.35 % and +1.3 % at N = 8 (docs/engines.md's trunk table: +0.07 %, 0.00 %
    # at N = 32); the bounds are the table's 1 % and 2 %
    assert flex["x_max"] == pytest.approx(beam["x_max"], rel=0.01)
    assert flex["energy_delivered"] == pytest.approx(beam["energy_delivered"], rel=0.02)


def test_trunk_cable_is_refused_because_mujoco_has_no_cable_plugin():
    with pytest.raises(ParameterError, match="no cable elasticity plugin.*use --trunk flex"):
        simulate(load_scenario("open-center"), trunk="cable")
    # the reason is true of the installed MuJoCo: the plugin cannot be instantiated
    xml = ('<mujoco><extension><plugin plugin="mujoco.elasticity.cable"/></extension>'
           '<worldbody/></mujoco>')
    with pytest.raises(ValueError, match="(?i)plugin"):
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            mujoco.MjModel.from_xml_string(xml)


@pytest.mark.parametrize("options, match", [
    ({"integrator": "implicit"}, "--integrator = 'implicit' with --trunk flex: allowed Euler, RK4"),
    ({"trunk_damping_model": "joint"},
     "--trunk-damping-model = 'joint' with --trunk flex: allowed distributed"),
])
def test_flex_refuses_what_it_cannot_step(options, match):
    with pytest.raises(ParameterError, match=match):
        make_setup(load_scenario("open-center"), trunk="flex", segments=4, **options)


def test_mujoco_refuses_flex_elasticity_under_the_implicit_integrators(setup8):
    """Why the refusal above: MuJoCo 4.0's own compiler error."""
    spec = setup8.spec.copy()
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICIT
    with pytest.raises(ValueError, match="no longer integrated implicitly"):
        spec.compile()
