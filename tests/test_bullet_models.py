"""PyBullet models: contact mapping, chain convergence, SDOF against the analytic references."""

from __future__ import annotations

import math

import numpy as np
import pytest

pybullet = pytest.importorskip("pybullet")

from treeimpact.analytic.contact.soft import simulate_soft  # noqa: E402
from treeimpact.analytic.continuum.beam import beam_natural_frequencies, beam_static_stiffness  # noqa: E402
from treeimpact.analytic.continuum.chain import hinged_chain, lateral_jacobian  # noqa: E402
from treeimpact.analytic.engine.generated_files import URDF_DIGITS, file_differences  # noqa: E402
from treeimpact.analytic.errors import ParameterError  # noqa: E402
from treeimpact.analytic.impact.simulate import simulate as simulate_exact  # noqa: E402
from treeimpact.analytic.model.scenario import load_scenario  # noqa: E402
from treeimpact.analytic.records import contact_intervals  # noqa: E402
from treeimpact.bullet_models import _contact, modes, simulate, simulate_batch  # noqa: E402
from treeimpact.bullet_models._runner import build_world, engine_matrices, load, make_setup  # noqa: E402
from treeimpact.bullet_models.regenerate import MODELS_DIR, generated  # noqa: E402
from treeimpact.analytic.model.options import numerical_options, scenario_as_run


@pytest.fixture(scope="module")
def central():
    return load_scenario("central-leader")


# ----------------------------------------------------------------------------- URDF files
def test_regenerated_urdf_equals_checked_in_files():
    """Parsed and compared at the written precision (12 significant digits), so a numpy or
    BLAS version that moves the 16th digit passes; the message names file, element, attribute."""
    files = generated()
    on_disk = {p.name for p in MODELS_DIR.glob("*.urdf")}
    assert on_disk == set(files)
    diff = file_differences(MODELS_DIR, files, URDF_DIGITS)
    assert not diff, f"run python -m treeimpact.bullet_models.regenerate: {diff}"


def test_urdf_parses_in_yourdfpy_and_loads_in_pybullet():
    """yourdfpy (independent parser) reads every file; the runner's loader gives Bullet the
    URDF's masses and inertias (PyBullet's default would take inertias from the collision
    shapes), to double-precision round-off."""
    yourdfpy = pytest.importorskip("yourdfpy")
    cid = pybullet.connect(pybullet.DIRECT)
    try:
        for path in sorted(MODELS_DIR.glob("*.urdf")):
            robot = yourdfpy.URDF.load(str(path), build_scene_graph=False, load_meshes=False)
            body = load(pybullet, cid, path.read_text())
            assert pybullet.getNumJoints(body, physicsClientId=cid) == len(robot.robot.joints)
            for j, joint in enumerate(robot.robot.joints):
                info = pybullet.getJointInfo(body, j, physicsClientId=cid)
                assert info[12].decode() == joint.child, path.name
                link = next(lk for lk in robot.robot.links if lk.name == joint.child)
                dyn = pybullet.getDynamicsInfo(body, j, physicsClientId=cid)
                assert dyn[0] == pytest.approx(link.inertial.mass, rel=1e-15), path.name
                np.testing.assert_allclose(dyn[2], np.diag(link.inertial.inertia), rtol=1e-15,
                                           err_msg=f"{path.name}: {joint.child} inertia")
                np.testing.assert_allclose(dyn[3], link.inertial.origin[:3, 3], rtol=1e-15,
                                           atol=1e-15)
    finally:
        pybullet.disconnect(cid)


# ------------------------------------------------------------------------- soft contact
def _free_collision(setup, per_body):
    """Free collision (no springs, no dampers) in PyBullet with the links' (k_i, d_i) given."""
    world = build_world(setup)
    p, cid = world.p, world.cid
    for (body, link), (k_i, d_i) in zip(((world.trunk, world.contact_link),
                                         (world.pendulum, 0)), per_body):
        p.changeDynamics(body, link, contactStiffness=k_i, contactDamping=d_i,
                         physicsClientId=cid)
    u = setup.model.impact_speed
    p.resetJointState(world.pendulum, 0, 0.0, u, physicsClientId=cid)
    for _ in range(100 * setup.bullet.steps_per_collision):
        p.stepSimulation(physicsClientId=cid)
        vx = p.getJointState(world.trunk, 0, physicsClientId=cid)[1]
        vy = p.getJointState(world.pendulum, 0, physicsClientId=cid)[1]
        if not p.getContactPoints(world.trunk, world.pendulum, physicsClientId=cid):
            return (vx - vy) / u
    raise AssertionError("the bodies never separated")


def test_bullet_combines_stiffness_in_series_and_damping_in_sum(central):
    """Unequal per-link values: PyBullet's rebound is the replay with (series k, summed d),
    and not what other combination rules would give."""
    from treeimpact.analytic.model.parameters import Billet, Contact, Scenario

    billet = Scenario(name="two-body", trunk=central.trunk,
                      impactor=Billet(central.impactor.mass, 2.0),
                      contact=Contact(restitution=0.5, duration=5e-4), t_end=1e-3)
    setup = make_setup(billet, trunk="sdof")
    b = setup.bullet
    k0, k1, d0, d1 = 3.0 * b.stiffness, 1.5 * b.stiffness, 0.2 * b.damping, 0.8 * b.damping
    e = _free_collision(setup, ((k0, d0), (k1, d1)))
    mu, dt = b.reduced_mass, setup.dt
    series_sum = _contact.discrete_collision(_contact.combine_stiffness(k0, k1),
                                             _contact.combine_damping(d0, d1), mu, dt)[0]
    assert abs(e - series_sum) < 1e-9  # one contact row: PGS is exact (1e-15 measured)
    for k_other, d_other in ((k0 + k1, d0 + d1), (min(k0, k1), max(d0, d1)),
                             (_contact.combine_stiffness(k0, k1), (d0 + d1) / 2)):
        other = _contact.discrete_collision(k_other, d_other, mu, dt)[0]
        assert abs(e - other) > 0.05  # the test tells the rules apart (0.10-0.16 away)


def _two_body_restitution(e, dt_fraction=50):
    """Free collision of M_T and m in PyBullet with the corrected soft contact; measured e."""
    from treeimpact.analytic.model.parameters import Billet, Contact, Scenario

    s = load_scenario("central-leader")
    billet = Scenario(name="two-body", trunk=s.trunk, impactor=Billet(s.impactor.mass, 2.0),
                      contact=Contact(restitution=e, duration=5e-4), t_end=1e-3)
    setup = make_setup(billet, trunk="sdof")
    # a free collision: no trunk spring or damping
    import dataclasses

    free = dataclasses.replace(setup.model, equivalent_stiffness=1e-12, equivalent_damping=0.0)
    setup = dataclasses.replace(setup, model=free)
    from treeimpact.bullet_models._runner import run

    rec = run(setup).record
    return (rec.vx[-1] - rec.vy[-1]) / 2.0, setup


@pytest.mark.parametrize("e", [0.05, 0.1, 0.3, 0.6, 0.9])
def test_soft_contact_two_body_collision_gives_target_restitution(e):
    measured, setup = _two_body_restitution(e)
    assert abs(measured - e) < 0.01  # the tolerance on the measured e
    # and the replay of Bullet's ERP/CFM update predicts PyBullet: a single contact row is
    # solved exactly, so only c_b's Brent tolerance is left (<= 1.3e-14 measured)
    assert abs(measured - e) < 1e-9


def test_time_step_correction_is_needed_uncorrected_law_loses_restitution():
    """Without the correction (k, c straight to Bullet) the implicit step damps too much."""
    mu, k = 60.0, 60.0 * (math.pi / 5e-4) ** 2
    c = _contact.law_for_restitution(0.6, k, mu)
    e_raw = _contact.discrete_collision(k, c, mu, 1e-5)[0]
    assert e_raw < 0.6 - 0.01  # the correction is not cosmetic at 50 steps per collision
    b = _contact.bullet_contact(k, c, mu, 1e-5)
    assert _contact.discrete_collision(b.stiffness, b.damping, mu, 1e-5)[0] == pytest.approx(
        0.6, abs=1e-9)  # Brent tolerance


# ------------------------------------------------------------------------ chain, modes
@pytest.mark.parametrize("n", [12, 33])
def test_engine_mass_matrix_and_jacobian_match_the_chain_model(central, n):
    """Bullet's Featherstone mass matrix and clamp Jacobian at rest equal the linearised chain
    (analytic.continuum.chain) to double round-off: the same rigid links, computed independently."""
    from treeimpact.analytic.continuum.chain import chain_matrices

    chain = hinged_chain(central.trunk, n)
    M, J = engine_matrices(chain)
    Ml, _, _ = chain_matrices(chain)
    Jl = lateral_jacobian(chain, central.trunk.clamp_height)[0]
    assert np.max(np.abs(J - Jl)) < 1e-12 * np.max(np.abs(Jl))  # round-off (2e-16 measured)
    assert np.max(np.abs(M - Ml)) < 1e-12 * np.max(np.abs(Ml))  # round-off (9e-16 measured)


def test_bullet_chain_converges_to_beam_at_second_order(central):
    beam_k = beam_static_stiffness(central.trunk)
    beam_w = beam_natural_frequencies(central.trunk, 2)
    errs, n_in = [], []
    for n in (16, 32):
        res = modes(central, segments=n, n_modes=2)["model"]
        errs.append((res["static_stiffness"] / beam_k - 1, res["omegas"][0] / beam_w[0] - 1,
                     res["omegas"][1] / beam_w[1] - 1))
        n_in.append(hinged_chain(central.trunk, n).clamp_index)
    errs = np.array(errs)
    # static stiffness at a: the Hencky error a^3/(3EI)/(2 N_in^2) of the flexibility
    order = math.log(errs[0, 0] / errs[1, 0]) / math.log(n_in[1] / n_in[0])
    assert 1.8 < order < 2.2  # measured 2.00 (N_in 5 -> 10)
    # frequencies: the Hencky chain's lumped flexibility, O(1/N^2) as well
    for col in (1, 2):
        order = math.log(errs[0, col] / errs[1, col]) / math.log(2.0)
        assert 1.8 < order < 2.2, col  # measured 2.00 and 2.00 (N 16 -> 32)
    assert np.all(np.abs(errs[1]) < 1e-3)  # and within 0.1 % of the beam at N = 32


# --------------------------------------------------------------- SDOF vs analytic models
def test_sdof_soft_contact_matches_analytic_soft_variant(central):
    ref = simulate_soft(central).metrics
    dt = make_setup(central, trunk="sdof").dt / 4  # 200 steps per collision: T0 is first order
    got = simulate(central, trunk="sdof", dt=dt).metrics
    for key in ("V", "x_max", "T0", "impact_loss"):
        assert got[key] == pytest.approx(ref[key], rel=5e-3), key  # issue: within 0.5 %
    assert got["n_impacts"] == ref["n_impacts"]


@pytest.mark.parametrize("name", ["open-center", "realistic-crown"])
def test_sdof_soft_contact_peak_and_loss_match_at_default_step(name):
    s = load_scenario(name)
    ref = simulate_soft(s).metrics
    got = simulate(s, trunk="sdof").metrics
    for key in ("x_max", "impact_loss"):
        assert got[key] == pytest.approx(ref[key], rel=5e-3), key  # measured < 0.03 %


# realistic-crown: V = 0.03 u1 at T0, near x_max, where the trunk decelerates: the impact
# applied up to one step late (first order in dt) moves V by 2.1 % at the default step,
# 0.9 % at dt / 2 and 0.2 % at dt / 8 (measured), so it is compared at dt / 8.
@pytest.mark.parametrize("name,refine", [("central-leader", 1), ("open-center", 1),
                                         ("realistic-crown", 8)])
def test_newton_contact_reproduces_exact_impacts(name, refine):
    s = load_scenario(name)
    exact = simulate_exact(s)
    dt = make_setup(s, trunk="sdof", contact="newton").dt / refine
    res = simulate(s, trunk="sdof", contact="newton", dt=dt)
    rec, dt = res.record, res.model["dt"]
    u1 = s.impactor.impact_speed
    big = [i for i in exact.solution.impacts if i.u - i.U > 0.01 * u1]
    iv = contact_intervals(rec.force, 1e-6 * rec.force.max())
    assert len(iv) >= len(big)
    for imp, (i0, _) in zip(big, iv):
        assert abs(rec.t[i0] - imp.t) <= 3 * dt  # an impact acts at the first step with overlap
        assert rec.vx[i0 + 1] == pytest.approx(imp.V, rel=5e-3)  # eq 21 separation velocity
    for key in ("V", "x_max", "impact_loss"):
        assert res.metrics[key] == pytest.approx(exact.metrics[key], rel=5e-3), key


def test_full_pendulum_reaches_the_trunk_at_eq_48_speed(central):
    res = simulate(scenario_as_run(central, {"t_end": 0.01}), trunk="sdof", pendulum="full")
    rec = res.record
    # speed at the last step before contact vs u1 of eq 48: the bob's own inertia (1e-6
    # m l_e^2) lowers it by 5e-7; symplectic Euler's energy error is O(omega h) mid-swing
    # but vanishes with the weight's torque at the bottom (1.1e-6 measured, all scenarios)
    assert rec.vy[0] == pytest.approx(central.impactor.impact_speed, rel=1e-5)


@pytest.mark.parametrize("opts", [dict(trunk="sdof"), dict(trunk="sdof", contact="newton"),
                                  dict(trunk="sdof", pendulum="full"),
                                  dict(trunk="chain", t_end=0.015)])
def test_energy_ledger_closes_within_one_percent(central, opts):
    res = simulate(scenario_as_run(central, opts), **numerical_options(opts))
    assert res.metrics["ledger_residual"] < 0.01  # issue: ledger below 1 %


def test_bad_option_is_a_one_line_parameter_error(central):
    with pytest.raises(ParameterError, match="contact") as exc:
        simulate(central, contact="rigid")
    assert "\n" not in str(exc.value)
    with pytest.raises(ParameterError, match="too large"):
        simulate(central, trunk="sdof", dt=1e-3)
    with pytest.raises(ParameterError, match=r"contact.restitution = 1: .*allowed \(0, 1\)") as exc:
        simulate(scenario_as_run(central, {"restitution": 1.0}),
                 trunk="sdof")  # implicit contact step: e < 1
    assert "\n" not in str(exc.value)


def test_newton_contact_on_the_chain_is_eq_21_with_the_apparent_mass(central):
    """First step of the rigid impact on the hinged trunk: the impulse is eq 21's with the
    clamp's apparent mass 1 / (J M^-1 J^T), and Bullet's joint velocities are M^-1 J^T P
    (fails if Bullet's inertias or its 100 rad/s joint-speed clamp were in the way)."""
    from treeimpact.analytic.continuum.chain import chain_matrices

    setup = make_setup(scenario_as_run(central, {"t_end": 1e-3}), trunk="chain", contact="newton")
    world = build_world(setup)
    p, cid = world.p, world.cid
    u, m, e = setup.model.impact_speed, setup.model.impactor_mass, setup.model.restitution
    p.resetJointState(world.pendulum, 0, 0.0, u, physicsClientId=cid)
    p.setJointMotorControlArray(world.trunk, world.trunk_joints, p.TORQUE_CONTROL,
                                forces=[0.0] * len(world.trunk_joints), physicsClientId=cid)
    p.setJointMotorControl2(world.pendulum, 0, p.TORQUE_CONTROL, force=0.0,
                            physicsClientId=cid)
    p.stepSimulation(physicsClientId=cid)
    v1 = p.getJointState(world.pendulum, 0, physicsClientId=cid)[1]
    qd = np.array([s[1] for s in p.getJointStates(world.trunk, world.trunk_joints,
                                                    physicsClientId=cid)])
    chain = hinged_chain(central.trunk, setup.segments)
    M = chain_matrices(chain)[0]
    J = lateral_jacobian(chain, central.trunk.clamp_height)[0]
    m_a = 1.0 / (J @ np.linalg.solve(M, J))
    impulse = m * (u - v1)
    assert impulse == pytest.approx((1 + e) * m * m_a / (m + m_a) * u, rel=1e-9)  # solver
    np.testing.assert_allclose(qd, np.linalg.solve(M, J) * impulse, rtol=1e-6,
                               atol=1e-9 * np.max(np.abs(qd)))  # converged PGS (1e-10 seen)
    assert np.max(np.abs(qd)) > 50.0  # a real test of the raised joint-speed clamp


def test_newton_and_soft_contact_agree_on_the_chain_peak(central):
    """Both contacts on the same chain: x_max differs by the soft collision's damper work,
    order b t_c <= 0.015 (step.contact of compare/runs/tolerances.toml); 0.06 % measured."""
    soft = simulate(scenario_as_run(central, {"t_end": 0.02}), trunk="chain")
    newton = simulate(scenario_as_run(central, {"t_end": 0.02}), trunk="chain", contact="newton")
    assert newton.metrics["x_max"] == pytest.approx(soft.metrics["x_max"], rel=0.015)
    assert newton.metrics["ledger_residual"] < 0.01  # issue: ledger below 1 %


def test_joint_damping_alternative_matches_mujoco(central):
    """The documented hinge-damping alternative, against the other engine with the same rule
    (MuJoCo integrates joint damping implicitly, as the runner does): integrator differences
    only, 1 % as engines.trunk in compare/runs/tolerances.toml (0.11 %, 0.27 % measured)."""
    mujoco_models = pytest.importorskip("treeimpact.mujoco_models")
    got = simulate(scenario_as_run(central, {"t_end": 0.02}),
                   trunk="chain", trunk_damping_model="joint")
    ref = mujoco_models.simulate(scenario_as_run(central, {"t_end": 0.02}), trunk="chain",
                                 trunk_damping_model="joint")
    for key in ("x_max", "t_xmax"):
        assert got.metrics[key] == pytest.approx(ref.metrics[key], rel=0.01), key
    assert got.metrics["ledger_residual"] < 0.01


def test_json_model_keys_include_the_mujoco_backends(central):
    """Same JSON keys as the MuJoCo backend (its engine-specific solref/solimp aside)."""
    mujoco_models = pytest.importorskip("treeimpact.mujoco_models")
    got = simulate(scenario_as_run(central, {"t_end": 2e-3}), trunk="sdof").to_json()
    ref = mujoco_models.simulate(scenario_as_run(central, {"t_end": 2e-3}), trunk="sdof").to_json()
    assert set(got) == set(ref)
    for part in ("metrics", "scenario"):
        assert set(got[part]) == set(ref[part]), part
    assert set(ref["model"]) - {"solref", "solimp"} <= set(got["model"])
    b = make_setup(central, trunk="sdof").bullet
    assert got["model"]["engine_contact_stiffness"] == b.stiffness  # what Bullet integrates
    assert got["model"]["contact_stiffness"] == b.law_stiffness


def test_batch_over_a_process_pool_matches_serial_runs(central):
    scen = [central, load_scenario("open-center")]
    batch = simulate_batch([scenario_as_run(s, {"t_end": 0.005}) for s in scen],
                           trunk="sdof", max_workers=2)
    for s, r in zip(scen, batch):
        serial = simulate(scenario_as_run(s, {"t_end": 0.005}), trunk="sdof")
        assert r.metrics["x_max"] == serial.metrics["x_max"]  # same deterministic engine


def test_the_batchs_processes_start_with_the_librarys_blas_limit(central, monkeypatch):
    """A spawned process does not inherit the parent's limit: the pool's initializer sets
    it (analytic/threads.py), so a batch needs no OPENBLAS_NUM_THREADS either."""
    import concurrent.futures as cf

    from treeimpact.analytic.threads import limit_process

    seen = {}

    class Pool(cf.ThreadPoolExecutor):  # records the pool's arguments, runs in one thread:
        # two threads stepping PyBullet at once race in its module state ("Joint index
        # out-of-range", seen once under load); the processes it stands for share nothing
        def __init__(self, max_workers, mp_context=None, initializer=None):
            seen.update(mp_context=mp_context.get_start_method(), initializer=initializer,
                        max_workers=max_workers)
            super().__init__(1)

    monkeypatch.setattr(cf, "ProcessPoolExecutor", Pool)
    simulate_batch([scenario_as_run(s, {"t_end": 0.002}) for s in [central, central]],
                   trunk="sdof", max_workers=2)
    assert seen == {"mp_context": "spawn", "initializer": limit_process, "max_workers": 2}
