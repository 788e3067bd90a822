"""MuJoCo models: contact law and restitution mapping, chain convergence, SDOF against the
analytic soft-contact reference, full pendulum, energy ledger, MJCF files."""

from __future__ import annotations

import copy
import dataclasses
import math
import warnings

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco")

from mujoco import rollout  # noqa: E402

from treeimpact.analytic.contact.soft import simulate_soft  # noqa: E402
from treeimpact.analytic.continuum.beam import beam_natural_frequencies, beam_static_stiffness  # noqa: E402
from treeimpact.analytic.continuum.chain import chain_matrices, hinged_chain  # noqa: E402
from treeimpact.analytic.engine.generated_files import MJCF_DIGITS, file_differences  # noqa: E402
from treeimpact.analytic.errors import (
    ParameterError,  # noqa: E402
    SimulationDiverged,  # noqa: E402
)
from treeimpact.analytic.model.parameters import Contact
from treeimpact.analytic.model.scenario import load_scenario  # noqa: E402
from treeimpact.mujoco_models import _contact, modes, simulate, simulate_batch  # noqa: E402
from treeimpact.mujoco_models._builder import sensor_slices  # noqa: E402
from treeimpact.mujoco_models._record import _damping_matrices, _record  # noqa: E402
from treeimpact.mujoco_models._rollout import _plan  # noqa: E402
from treeimpact.mujoco_models._runner import engine_trunk_matrices, make_setup  # noqa: E402
from treeimpact.mujoco_models.regenerate import MODELS_DIR, generated  # noqa: E402
from treeimpact.analytic.model.options import numerical_options, scenario_as_run


@pytest.fixture(scope="module")
def central():
    return load_scenario("central-leader")


# ------------------------------------------------------------------------- contact law
def test_engine_contact_force_is_the_spring_dashpot_law_and_releases_at_zero_force(central):
    """efc_force = max(0, k delta + c delta') with the (k, c) the runner reports (docstring of
    mujoco_models._contact), and the touch sensor reads that force."""
    setup = make_setup(central, trunk="sdof")
    m = setup.mjmodel
    d = mujoco.MjData(m)
    k, c = setup.law.stiffness, setup.law.damping
    for delta, w in ((2e-5, 0.5), (1e-4, -0.05), (3e-6, 1.0), (1e-5, -2.0)):
        d.qpos[:] = [0.0, delta]
        d.qvel[:] = [0.0, w]
        mujoco.mj_forward(m, d)
        law = k * delta + c * w
        assert d.ncon == 1
        if law > 0:
            # the -d a0 term and d (A - A_hat) are 1e-4 of the force (impedance d = 1e-4)
            assert d.efc_force[0] == pytest.approx(law, rel=2e-4)
        else:
            assert d.efc_force[0] == 0.0  # released while still overlapping
        assert d.sensordata[sensor_slices()["force"]][0] == pytest.approx(d.efc_force[0],
                                                                          rel=1e-12)


def test_no_contact_pair_other_than_pendulum_and_trunk(central):
    m = make_setup(central, trunk="chain").mjmodel
    assert m.npair == 1 and m.nexclude == 0
    assert np.all(m.geom_contype == 0) and np.all(m.geom_conaffinity == 0)
    assert m.pair_dim[0] == 1  # frictionless


def _effective(trunk: str) -> dict:
    """``calibration="effective"`` for a trunk with segments; nothing for the SDOF trunk
    (issue 41: refused there, where it sets the same pad as the default)."""
    return {} if trunk == "sdof" else {"calibration": "effective"}


def _free_collision_restitution(scenario, trunk, e, integrator="Euler", dt_factor=1.0):
    """Pendulum against the trunk with every spring and damper removed: a two-body collision.

    e = (vx - vy) / u1 at the first sample after the force has gone back to zero. The step is
    ``dt_factor`` times the default one. The contact is calibrated on the trunk's effective
    mass (``calibration="effective"``), the mapping these tests check (the SDOF trunk's
    effective mass is M_T, where "effective" is the default "pad" and is refused).
    """
    s = dataclasses.replace(scenario, contact=Contact(restitution=e, duration=5e-4))
    cal = _effective(trunk)
    dt = None if dt_factor == 1.0 else make_setup(scenario_as_run(s, {"t_end": 1e-3}), trunk=trunk,
                                                  **cal).dt * dt_factor
    setup = make_setup(scenario_as_run(s, {"t_end": 1e-3}),
                       trunk=trunk, integrator=integrator, dt=dt, **cal)
    m = copy.deepcopy(setup.mjmodel)
    m.jnt_stiffness[:] = 0.0
    m.dof_damping[:] = 0.0
    m.tendon_damping[:] = 0.0
    n = 2 * setup.law.steps_per_collision + 10
    _, sd = rollout.rollout(m, mujoco.MjData(m), _plan(setup).state0, nstep=n)
    sl = sensor_slices()
    force = sd[0, :, sl["force"]][:, 0]
    after = int(np.flatnonzero(force > 0)[-1]) + 1
    assert after < n - 1  # the collision ended inside the run
    rel = sd[0, after, sl["x_vel"]][0] - sd[0, after, sl["y_vel"]][0]
    return rel / setup.model.impact_speed, setup


@pytest.mark.parametrize("integrator", ["Euler", "implicit", "implicitfast", "RK4"])
@pytest.mark.parametrize("trunk", ["sdof", "chain"])
@pytest.mark.parametrize("e", [0.05, 0.1, 0.3, 0.6, 0.9])
def test_two_body_collision_gives_target_restitution(central, trunk, e, integrator):
    measured, setup = _free_collision_restitution(central, trunk, e, integrator)
    assert abs(measured - e) < 0.01  # the issue's tolerance on the measured e
    if trunk == "chain":
        # measured <= 4.2e-4 (Euler; 4.4e-4 RK4): the free chain's velocity-dependent forces
        # during the 50-step collision
        assert abs(measured - e) < 1e-3
    elif integrator == "RK4":
        # the continuous law uncorrected: RK4's own error at 50 steps, measured <= 9.4e-8
        assert abs(measured - e) < 2e-7
        # the replay is MuJoCo's RK4 map: measured <= 7.8e-10 (the -d a0 impedance term)
        assert measured == pytest.approx(setup.law.uncorrected_restitution, abs=2e-9)
    else:
        assert abs(measured - e) < 1e-8  # Euler's map, corrected: measured <= 1e-9


@pytest.mark.parametrize("trunk", ["sdof", "chain"])
def test_implicit_integrators_take_eulers_contact_map(central, trunk):
    """The contact is a constraint force, outside qDeriv: implicit and implicitfast rebound
    like Euler with Euler's corrected law (mujoco_models._contact docstring)."""
    euler = _free_collision_restitution(central, trunk, 0.3)[0]
    fast = _free_collision_restitution(central, trunk, 0.3, "implicitfast")[0]
    full, setup = _free_collision_restitution(central, trunk, 0.3, "implicit")
    law = make_setup(scenario_as_run(setup.scenario, {"t_end": 1e-3}),
                     trunk=trunk, **_effective(trunk)).law
    assert (setup.law.stiffness, setup.law.damping) == (law.stiffness, law.damping)  # Euler's
    assert fast == pytest.approx(euler, abs=1e-12)  # round-off: measured <= 1.3e-14
    # implicit also linearises the chain's Coriolis forces: measured 5.8e-7 (chain), 1e-16 (SDOF)
    assert full == pytest.approx(euler, abs=1e-12 if trunk == "sdof" else 1e-5)


def test_rk4_restitution_converges_to_target_at_third_order_or_better(central):
    """RK4 gets the continuous law uncorrected: its e error falls with dt at order 3.2 to 4.1
    (measured, 25 -> 50 -> 100 steps per collision), and Euler's correction would be wrong
    for it."""
    for e in (0.3, 0.6, 0.9):
        errs = [abs(_free_collision_restitution(central, "sdof", e, "RK4", f)[0] - e)
                for f in (2.0, 1.0, 0.5)]
        for coarse, fine in zip(errs, errs[1:]):
            order = math.log2(coarse / fine)
            assert 2.8 < order < 4.5, (e, errs)  # measured 3.19 .. 4.02
    law = make_setup(dataclasses.replace(central, contact=Contact(restitution=0.3,
                                                                  duration=5e-4)),
                     trunk="sdof", integrator="RK4").law
    assert (law.stiffness, law.damping) == (law.law_stiffness, law.law_damping)
    euler = _contact.engine_law(law.law_stiffness, 0.3, law.reduced_mass, law.dt)
    wrong = _contact.discrete_collision_rk4(euler.stiffness, euler.damping, law.reduced_mass,
                                            law.dt)[0]
    assert abs(wrong - 0.3) > 0.005  # Euler's correction under RK4: measured +0.0104


def test_euler_step_correction_is_needed(central):
    """At the default step the continuous law's (k, c) on MuJoCo's Euler step misses e = 0.3
    by more than the issue's 0.01; the corrected law hits it."""
    s = dataclasses.replace(central, contact=Contact(restitution=0.3, duration=5e-4))
    law = make_setup(s, trunk="sdof").law
    assert abs(law.uncorrected_restitution - 0.3) > 0.01  # measured 0.0106
    e_fixed = _contact.discrete_collision(law.stiffness, law.damping, law.reduced_mass,
                                          law.dt)[0]
    assert e_fixed == pytest.approx(0.3, abs=1e-12)  # Brent tolerance


# ------------------------------------------------------------------------ chain, modes
def test_engine_mass_stiffness_and_damping_are_the_chain_model(central):
    setup = make_setup(central, trunk="chain", segments=12)
    M, K = engine_trunk_matrices(setup.mjmodel)
    Ml, Kl, Dl = chain_matrices(hinged_chain(central.trunk, 12))
    np.testing.assert_allclose(M, Ml, rtol=0, atol=1e-12 * np.abs(Ml).max())  # round-off
    np.testing.assert_allclose(K, Kl, rtol=1e-15)
    D, B = _damping_matrices(setup.mjmodel)  # the fixed tendons of the damping points
    np.testing.assert_allclose(D[:12, :12], Dl, rtol=0, atol=1e-12 * np.abs(Dl).max())
    assert not B.any()  # distributed damping: no joint damping


@pytest.mark.parametrize("segments", [4, 12, 32, 64])
def test_chain_damping_is_one_tendon_per_hinge_carrying_d(central, segments):
    """The distributed damping D (sum over the damping points) in N tendons, D = L diag(d)
    L^T with L unit lower triangular and d > 0 (the Cholesky factor of the positive
    definite D), the same D as the chain model's and as the per-point sum."""
    from treeimpact.mujoco_models._builder import damping_factors

    chain = hinged_chain(central.trunk, segments)
    Dl = chain_matrices(chain)[2]
    z = np.asarray(chain.boundaries)[:segments]  # per damping point: c_p J_p^T J_p
    arms = [np.where(z < zp, zp - z, 0.0) for zp in chain.damping_heights]
    D = sum(c * np.outer(a, a) for a, c in zip(arms, chain.damping_coefficients))
    scale = np.abs(Dl).max()
    np.testing.assert_allclose(D, Dl, rtol=0, atol=1e-14 * scale)  # round-off of two sums
    L, d = damping_factors(Dl)
    assert np.all(d > 0.0)
    np.testing.assert_array_equal(np.diag(L), 1.0)
    assert not np.triu(L, 1).any()
    np.testing.assert_allclose((L * d) @ L.T, Dl, rtol=0, atol=1e-14 * scale)  # Cholesky
    m = make_setup(scenario_as_run(central, {"t_end": 1e-3}),
                   trunk="chain", segments=segments).mjmodel  # budget
    assert m.ntendon == segments  # was 2 N, one per damping point
    Dm = _damping_matrices(m)[0][:segments, :segments]
    np.testing.assert_allclose(Dm, Dl, rtol=0, atol=1e-14 * scale)  # round-off


def test_chain_converges_to_beam_at_second_order(central):
    beam_k = beam_static_stiffness(central.trunk)
    beam_w = beam_natural_frequencies(central.trunk, 2)
    ns = (16, 32, 64)
    errs, n_in = [], []
    for n in ns:
        res = modes(central, segments=n, n_modes=2)["model"]
        errs.append((res["static_stiffness"] / beam_k - 1, res["omegas"][0] / beam_w[0] - 1,
                     res["omegas"][1] / beam_w[1] - 1))
        n_in.append(hinged_chain(central.trunk, n).clamp_index)
    errs = np.abs(np.array(errs))
    for i in range(2):
        # static stiffness at a: Hencky error ~ 1 / N_in^2 (N_in = 5, 10, 20)
        order = math.log(errs[i, 0] / errs[i + 1, 0]) / math.log(n_in[i + 1] / n_in[i])
        assert 1.9 < order < 2.1, order  # measured 2.00
        for j in (1, 2):  # omega_1, omega_2 ~ 1 / N^2
            order = math.log(errs[i, j] / errs[i + 1, j]) / math.log(ns[i + 1] / ns[i])
            assert 1.9 < order < 2.1, (j, order)  # measured 2.00
    assert np.all(errs[-1] < 2e-4)  # N = 64: measured 1.3e-4 at most


# --------------------------------------------------------------- SDOF vs analytic models
@pytest.mark.parametrize("name", ["central-leader", "open-center", "realistic-crown"])
def test_sdof_matches_analytic_soft_contact(name):
    s = load_scenario(name)
    ref = simulate_soft(s).metrics
    # T0 and x0 hinge on the re-contact time, which Euler gets at first order: central-leader
    # 0.81 % at the default 50 steps per collision, 0.23 % at 200 (measured); V 0.11 % / 0.03 %
    dt = make_setup(s, trunk="sdof").dt / 4
    got = simulate(s, trunk="sdof", dt=dt).metrics
    # realistic-crown: V = 0.04 u1 is the small remainder of two nearly equal momenta and its
    # relative error wanders with dt (-1.8 %, -0.39 %, -0.97 %, -0.16 % at dt/1, /4, /5, /8):
    # judged on the other three keys only
    keys = ("x_max", "T0", "impact_loss") if name == "realistic-crown" else (
        "V", "x_max", "T0", "impact_loss")
    for key in keys:
        assert got[key] == pytest.approx(ref[key], rel=5e-3), key  # issue: within 0.5 %
    assert got["n_impacts"] == ref["n_impacts"]


@pytest.mark.parametrize("name", ["open-center", "realistic-crown"])
def test_sdof_peak_and_loss_match_at_default_step(name):
    """At the default step T0 and V of these two are off by up to 1.2 % / 1.8 % (first-order
    re-contact time, see above): x_max and the loss are within 0.5 %."""
    s = load_scenario(name)
    ref = simulate_soft(s).metrics
    got = simulate(s, trunk="sdof").metrics
    for key in ("x_max", "impact_loss"):
        assert got[key] == pytest.approx(ref[key], rel=5e-3), key  # measured < 2e-5


def test_full_pendulum_reaches_the_trunk_at_eq_48_speed(central):
    res = simulate(scenario_as_run(central, {"t_end": 0.005}), trunk="sdof", pendulum="full")
    # Euler's swing at 1e-4 s conserves a modified energy equal to the true one at the
    # bottom; the bob's own inertia (1e-6 m l_e^2) lowers the speed by 5e-7: measured 1.1e-6
    assert res.extra["impact_speed_measured"] == pytest.approx(
        central.impactor.impact_speed, rel=1e-5)
    assert res.record.t[0] <= 0.0 < res.record.t[1]  # t = 0 at the touch


@pytest.mark.parametrize("opts", [dict(trunk="sdof"), dict(trunk="sdof", pendulum="full"),
                                  dict(trunk="chain", t_end=0.02),
                                  dict(trunk="chain", trunk_damping_model="joint", t_end=0.02)])
def test_energy_ledger_closes_within_one_percent(central, opts):
    res = simulate(scenario_as_run(central, opts), **numerical_options(opts))
    assert res.metrics["ledger_residual"] < 0.01  # issue: below 1 % (measured <= 3e-4)
    rec = res.record
    assert rec.damping_work[-1] > 0.0 and rec.contact_work[-1] > 0.0  # both ledgers active


def test_joint_damping_alternative_keeps_the_first_modes_damping(central):
    """trunk_damping_model="joint" (beta k_j at the hinges) has mode 1's modal damping of the distributed
    damping (tendons), read back from both compiled models; mode 2 gets more."""
    import scipy.linalg

    a = make_setup(central, trunk="chain").mjmodel
    b = make_setup(central, trunk="chain", trunk_damping_model="joint").mjmodel
    M, K = engine_trunk_matrices(a)
    n = M.shape[0]
    D = _damping_matrices(a)[0][:n, :n]
    B = _damping_matrices(b)[1][:n, :n]
    assert not _damping_matrices(b)[0].any()  # no tendons in the joint variant
    _, vec = scipy.linalg.eigh(K, M, subset_by_index=[0, 1])
    p1, p2 = vec[:, 0], vec[:, 1]
    assert p1 @ B @ p1 == pytest.approx(p1 @ D @ p1, rel=1e-9)  # eigen-solver round-off
    assert p2 @ B @ p2 > 2.0 * (p2 @ D @ p2)  # stiffness-proportional: measured x 77


# -------------------------------------------------------------------------- run rules
def test_bad_options_are_one_line_parameter_errors(central):
    with pytest.raises(ParameterError, match="trunk") as exc:
        simulate(central, trunk="beam")
    assert "\n" not in str(exc.value)
    with pytest.raises(ParameterError, match="too large for stability"):
        simulate(central, trunk="sdof", dt=1e-3)
    with pytest.raises(ParameterError, match="segments"):
        simulate(central, trunk="sdof", segments=8)


def test_non_finite_state_is_reported_as_diverged(central):
    setup = make_setup(scenario_as_run(central, {"t_end": 1e-3}), trunk="sdof")
    plan = _plan(setup)
    m = setup.mjmodel
    st, sd = rollout.rollout(m, mujoco.MjData(m), plan.state0, nstep=plan.nstep)
    sd = sd[0].copy()
    sd[50, sensor_slices()["x_pos"]] = np.nan
    with pytest.raises(SimulationDiverged, match="non-finite"):
        _record(setup, plan.state0, st[0], sd)


def test_rollout_that_stops_advancing_time_is_reported_as_diverged(central):
    """rollout stops stepping (time frozen) after a MuJoCo warning: the run is diverged."""
    setup = make_setup(scenario_as_run(central, {"t_end": 1e-3}), trunk="sdof")
    plan = _plan(setup)
    m = setup.mjmodel
    st, sd = rollout.rollout(m, mujoco.MjData(m), plan.state0, nstep=plan.nstep)
    st = st[0].copy()
    st[60:, 0] = st[59, 0]  # what a stopped rollout returns: the last state repeated
    with pytest.raises(SimulationDiverged, match="warning"):
        _record(setup, plan.state0, st, sd[0])


def test_long_fine_step_run_is_not_mistaken_for_a_stopped_rollout(central):
    """280 000 steps (dt / 16): t accumulates 5e-13 s of round-off, which an n dt check
    took for a stopped rollout; the step-by-step rule does not."""
    dt = make_setup(central, trunk="sdof", pendulum="full").dt / 16
    res = simulate(central, trunk="sdof", pendulum="full", dt=dt)
    assert res.metrics["x_max"] == pytest.approx(simulate_soft(central).metrics["x_max"],
                                                 rel=1e-4)  # 1e-5 measured at dt / 16


@pytest.mark.parametrize("integrator", ["Euler", "implicit", "RK4"])
def test_energy_growing_engine_run_is_reported_as_diverged(central, integrator):
    """A real rollout that gains energy (the trunk's damper made negative: finite growth at
    C_T / M_T = 131 1/s) is reported as diverged, never turned into metrics."""
    from treeimpact.mujoco_models._runner import run_setups

    setup = make_setup(central, trunk="sdof", integrator=integrator)
    m = copy.deepcopy(setup.mjmodel)
    assert m.dof_damping[0] > 0  # the SDOF trunk's C_T
    m.dof_damping[0] *= -1.0
    out = run_setups([dataclasses.replace(setup, mjmodel=m)])[0]
    assert isinstance(out, SimulationDiverged), out
    assert "mechanical energy" in str(out)
    assert not isinstance(run_setups([setup])[0], SimulationDiverged)  # control: C_T > 0


@pytest.mark.parametrize("integrator", ["Euler", "implicit", "RK4"])
def test_energy_created_while_damped_is_reported_as_diverged(central, integrator):
    """The ledger rule: kinetic energy the engine invents after the impact (10 % of the input,
    mechanical energy still below the input) is caught by kinetic + potential + works (for
    RK4: as a fall of the contact's dissipated energy)."""
    setup = make_setup(scenario_as_run(central, {"t_end": 0.05}),
                       trunk="sdof", integrator=integrator)
    plan = _plan(setup)
    m = setup.mjmodel
    st, sd = rollout.rollout(m, mujoco.MjData(m), plan.state0, nstep=plan.nstep)
    sd = sd[0].copy()
    ke = sensor_slices()["kinetic"]
    e0 = sd[0, ke][0] + sd[0, sensor_slices()["potential"]][0]
    _record(setup, plan.state0, st[0], sd)  # control: the untouched run is accepted
    sd[:, ke] += 0.1 * e0 * np.linspace(0.0, 1.0, len(sd))[:, None]
    with pytest.raises(SimulationDiverged, match="created"):
        _record(setup, plan.state0, st[0], sd)


@pytest.mark.parametrize("integrator", ["Euler", "implicit", "implicitfast"])
@pytest.mark.parametrize("opts", [dict(trunk="sdof"), dict(trunk="chain"),
                                  dict(trunk="chain", trunk_damping_model="joint")])
def test_damping_matrices_are_what_the_euler_step_applies(central, opts, integrator):
    """One engine step with springs and contact off: M (v1 - v0) / h = -D v0 - B v1 with the
    (explicit D, implicit B) the ledger uses; the other split misses it. Euler: per the
    eulerdamp flag; implicit, implicitfast: every damper implicit (B, with the tendons)."""
    setup = make_setup(central, integrator=integrator, **opts)
    m = copy.deepcopy(setup.mjmodel)
    m.jnt_stiffness[:] = 0.0
    m.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
    d = mujoco.MjData(m)
    rng = np.random.default_rng(3)
    v0 = 1e-3 * rng.standard_normal(m.nv)  # small: Coriolis forces ~ v^2 are negligible
    d.qvel[:] = v0
    mujoco.mj_forward(m, d)
    M = np.zeros((m.nv, m.nv))
    mujoco.mj_fullM(m, d, M)
    mujoco.mj_step(m, d)
    v1 = d.qvel.copy()
    D, B = _damping_matrices(m)
    lhs = M @ (v1 - v0) / m.opt.timestep
    scale = np.abs(lhs).max()
    np.testing.assert_allclose(lhs, -D @ v0 - B @ v1, rtol=0, atol=1e-6 * scale)  # round-off
    wrong = -B @ v0 - D @ v1  # explicit and implicit swapped
    assert np.abs(lhs - wrong).max() > 1e-4 * scale  # measured >= 5.0e-4 (~ h b / m)


def test_rk4_damping_work_quadrature_is_fourth_order_inside_runs():
    """The RK4 ledger's damping work: the cubic rules inside each run of samples with one
    contact state integrate a smooth power at O(h^4), and no stencil reaches across a
    change of the contact state (there the power may have a kink)."""
    from treeimpact.analytic.engine.interface import step_means as _step_means

    def error(n):
        t = np.linspace(0.0, 2.0, n + 1)
        h = t[1] - t[0]
        on = t >= 1.0  # the state changes inside step n/2 - 1 .. n/2
        p = np.where(on, np.exp(-t), np.cos(3.0 * t))  # a jump at t = 1
        got = np.cumsum(_step_means(p, on)) * h
        i = n // 2 - 1  # the step where the state changes: the trapezoid
        exact_left = math.sin(3.0 * t[i]) / 3.0
        exact_total = exact_left + 0.5 * h * (p[i] + p[i + 1]) + math.exp(-t[i + 1]) \
            - math.exp(-2.0)
        return abs(got[i - 1] - exact_left), abs(got[-1] - exact_total)

    (a1, b1), (a2, b2) = error(40), error(80)
    for coarse, fine in ((a1, a2), (b1, b2)):
        # h^4 (the one-sided end rules add h^5 at 20 samples a run): measured 4.29, 4.27;
        # the trapezoid alone would give 2
        assert 3.5 < math.log2(coarse / fine) < 4.6
    assert a2 < 1e-7 and b2 < 1e-7  # measured 3.3e-8, 3.5e-8


@pytest.mark.parametrize("integrator", ["Euler", "implicit", "implicitfast", "RK4"])
def test_each_integrator_matches_the_soft_contact_at_its_default_step(central, integrator):
    """Every integrator runs the central-leader SDOF model at the default step without being
    reported diverged, and its peak trunk displacement is the analytic soft contact's."""
    ref = simulate_soft(central).metrics
    res = simulate(central, trunk="sdof", integrator=integrator)
    assert res.model["integrator"] == integrator
    assert res.model["dt"] == make_setup(central, trunk="sdof").dt  # one step rule for all
    # x_max measured: Euler +4.2e-5, implicit and implicitfast -6.6e-5, RK4 +1.0e-7
    assert res.metrics["x_max"] == pytest.approx(ref["x_max"], rel=5e-3)  # issue: 0.5 %
    # impact loss measured: Euler +5.2e-5, implicit(fast) +5.0e-4 (implicit trunk damper,
    # first order), RK4 -2.7e-6
    assert res.metrics["impact_loss"] == pytest.approx(ref["impact_loss"], rel=5e-3)
    assert res.metrics["n_impacts"] == ref["n_impacts"]
    if integrator == "RK4":
        assert res.metrics["ledger_residual"] < 1e-12  # closed by construction: 1.5e-16
    else:
        assert res.metrics["ledger_residual"] < 1e-3  # exact works: measured 6.0e-5


def test_integrator_option_builds_that_integrator_and_keeps_the_default(central):
    from treeimpact.mujoco_models._builder import mjcf_text

    default = make_setup(central, trunk="sdof")
    assert make_setup(central, trunk="sdof", integrator="Euler") is default  # one cache key
    assert default.mjmodel.opt.integrator == mujoco.mjtIntegrator.mjINT_EULER
    for name, enum in (("implicit", mujoco.mjtIntegrator.mjINT_IMPLICIT),
                       ("implicitfast", mujoco.mjtIntegrator.mjINT_IMPLICITFAST),
                       ("RK4", mujoco.mjtIntegrator.mjINT_RK4)):
        setup = make_setup(central, trunk="sdof", integrator=name)
        assert setup.mjmodel.opt.integrator == enum and setup.integrator == name
        assert f'integrator="{name}"' in mjcf_text(setup.spec)
    assert "integrator=" not in mjcf_text(default.spec)  # MuJoCo's default: the files keep it
    batch = simulate_batch([scenario_as_run(s, {"t_end": 0.005}) for s in [central]],
                           trunk="sdof", integrator="RK4")[0]
    assert batch.model["integrator"] == "RK4"
    assert batch.metrics["x_max"] == simulate(scenario_as_run(central, {"t_end": 0.005}),
                                              trunk="sdof", integrator="RK4").metrics["x_max"]


@pytest.mark.parametrize("bad", ["euler", "RK2", "", None])
def test_unknown_integrator_is_a_one_line_parameter_error(central, bad):
    with pytest.raises(ParameterError) as exc:
        simulate(central, trunk="sdof", integrator=bad)
    msg = str(exc.value)
    assert "\n" not in msg and "--integrator" in msg
    assert "Euler, implicit, implicitfast, RK4" in msg


def test_rk4_refuses_a_step_its_explicit_dampers_cannot_take(central):
    """The chain's joint damping beta k_j is stiff (Euler and the implicit integrators treat
    it implicitly): RK4 applies it explicitly, h lambda = 168 at the default step."""
    with pytest.raises(ParameterError, match="RK4") as exc:
        make_setup(central, trunk="chain", trunk_damping_model="joint", integrator="RK4")
    assert "\n" not in str(exc.value) and "too large for stability" in str(exc.value)
    make_setup(central, trunk="chain", integrator="RK4")  # tendon dampers: h lambda = 5.5e-4
    make_setup(central, trunk="chain", trunk_damping_model="joint", integrator="implicitfast")


def test_speed_study_runs_one_curve_per_mujoco_integrator():
    from treeimpact.compare.runs.backends import get_backend
    from treeimpact.compare.studies.speed import engine_variants

    name, values, reason, runnable = engine_variants("mujoco")
    assert (name, reason, runnable) == ("integrator", None, True)
    assert values == get_backend("mujoco").variants[1] == _contact.INTEGRATORS


def test_batch_through_rollout_matches_serial_runs(central):
    scen = [central, load_scenario("open-center")]
    batch = simulate_batch([scenario_as_run(s, {"t_end": 0.005}) for s in scen],
                           trunk="sdof", max_workers=2)
    for s, r in zip(scen, batch):
        serial = simulate(scenario_as_run(s, {"t_end": 0.005}), trunk="sdof")
        assert r.metrics["x_max"] == serial.metrics["x_max"]  # same deterministic engine
        assert r.model["dt"] == serial.model["dt"]


def test_energy_sensors_read_the_current_state():
    """MuJoCo >= 3.5 with the energy flag fills e_kinetic one step late; the models leave the
    flag off, so the sensors are 1/2 v^T M v and mj_energyPos of the state itself."""
    m = make_setup(load_scenario("central-leader"), trunk="chain").mjmodel
    assert not m.opt.enableflags & int(mujoco.mjtEnableBit.mjENBL_ENERGY)
    d = mujoco.MjData(m)
    rng = np.random.default_rng(0)
    d.qpos[:] = 0.01 * rng.normal(size=m.nq)
    d.qvel[:] = rng.normal(size=m.nv)
    mujoco.mj_forward(m, d)
    M = np.zeros((m.nv, m.nv))
    mujoco.mj_fullM(m, d, M)
    sl = sensor_slices()
    kinetic = 0.5 * d.qvel @ M @ d.qvel
    assert d.sensordata[sl["kinetic"]][0] == pytest.approx(kinetic, rel=1e-12)  # round-off
    mujoco.mj_step(m, d)  # one step on: still the new state's, not the previous one's
    mujoco.mj_forward(m, d)
    mujoco.mj_fullM(m, d, M)
    assert d.sensordata[sl["kinetic"]][0] == pytest.approx(0.5 * d.qvel @ M @ d.qvel,
                                                           rel=1e-12)  # round-off
    potential = d.sensordata[sl["potential"]][0]
    mujoco.mj_energyPos(m, d)
    assert potential == pytest.approx(d.energy[0], rel=1e-12)  # round-off


# ------------------------------------------------------------------------- MJCF files
def test_regenerated_mjcf_equals_checked_in_files():
    """Parsed and compared at MuJoCo's written precision (6 significant digits)."""
    files = generated()
    assert {p.name for p in MODELS_DIR.glob("*.xml")} == set(files)
    diff = file_differences(MODELS_DIR, files, MJCF_DIGITS)
    assert not diff, f"run python -m treeimpact.mujoco_models.regenerate: {diff}"


def test_checked_in_models_compile_without_warnings_and_are_the_runners_models():
    from treeimpact.analytic.model.scenario import shipped_scenarios
    from treeimpact.mujoco_models.regenerate import VARIANTS

    for name in shipped_scenarios():
        s = load_scenario(name)
        for trunk, pendulum in VARIANTS:
            path = MODELS_DIR / f"{name}-{trunk}-{pendulum}.xml"
            # since MuJoCo 4.0 MjSpec.compile reports a compiler warning as a UserWarning
            # (3.x raised): an error here; from_xml_path is the loader of
            # `python -m mujoco.viewer --mjcf=...`
            with warnings.catch_warnings():
                warnings.simplefilter("error")
                m = mujoco.MjSpec.from_file(str(path)).compile()
            assert mujoco.MjModel.from_xml_path(str(path)).nbody == m.nbody
            ref = make_setup(s, trunk=trunk, pendulum=pendulum).mjmodel
            for field in ("body_mass", "body_inertia", "jnt_stiffness", "dof_damping",
                          "tendon_damping", "pair_solref", "pair_solimp", "body_pos",
                          "body_ipos"):
                # MuJoCo's XML writer keeps 6 significant digits
                np.testing.assert_allclose(getattr(m, field), getattr(ref, field),
                                           rtol=1e-5, atol=1e-12, err_msg=f"{path.name} {field}")
            assert m.opt.timestep == pytest.approx(ref.opt.timestep, rel=1e-5)
            d = mujoco.MjData(m)
            mujoco.mj_step(m, d, nstep=200)
            assert all(w.number == 0 for w in d.warning), path.name
            assert np.all(np.isfinite(d.qpos)), path.name


def test_regenerate_writes_changed_and_removes_stale_files(tmp_path, monkeypatch, capsys):
    """The command's file logic (the MJCF text itself is checked above): --check reports a
    difference or a stale file with exit 1, a plain run fixes both, then --check passes."""
    from treeimpact.mujoco_models import regenerate

    monkeypatch.setattr(regenerate, "MODELS_DIR", tmp_path)
    monkeypatch.setattr(regenerate, "generated", lambda: {"a-sdof-linear.xml": "<mujoco/>\n"})
    (tmp_path / "a-sdof-linear.xml").write_text("<mujoco>old</mujoco>\n")
    (tmp_path / "renamed-sdof-linear.xml").write_text("<mujoco/>\n")
    assert regenerate.main(["--check"]) == 1
    out = capsys.readouterr().out
    assert "would change: a-sdof-linear.xml" in out and "would remove: renamed" in out
    assert regenerate.main([]) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a-sdof-linear.xml"]
    assert (tmp_path / "a-sdof-linear.xml").read_text() == "<mujoco/>\n"
    assert regenerate.main(["--check"]) == 0


# ---------------------------------------------------------------------------------- CLI
def test_cli_simulate_and_modes_with_the_mujoco_backend(capsys):
    import json

    from treeimpact.analytic.metrics import METRIC_KEYS
    from treeimpact.compare.interface.cli import main

    code = main(["simulate", "central-leader", "--backend", "mujoco", "--trunk", "chain",
                 "--segments", "8", "--t-end", "0.05", "--json"])
    data = json.loads(capsys.readouterr().out)
    assert code == 0 and tuple(data["metrics"]) == METRIC_KEYS
    assert data["model"]["segments"] == 8
    assert {"dt", "contact_stiffness", "contact_damping"} <= set(data["model"])
    assert main(["modes", "central-leader", "--backend", "mujoco", "--segments", "16"]) == 0
    out = capsys.readouterr().out
    assert "model" in out and "beam" in out and "static stiffness" in out


def test_cli_simulate_with_an_integrator(capsys):
    import json

    from treeimpact.compare.interface.cli import main

    code = main(["simulate", "central-leader", "--backend", "mujoco", "--integrator", "RK4",
                 "--t-end", "0.05", "--json"])
    data = json.loads(capsys.readouterr().out)
    assert code == 0 and data["model"]["integrator"] == "RK4"


@pytest.mark.parametrize("args", [["--backend", "mujoco", "--integrator", "foo"],
                                  ["--backend", "bullet", "--integrator", "RK4"],
                                  ["--integrator", "RK4"]])  # analytic: no integrator
def test_cli_integrator_refused_with_one_line(capsys, args):
    from treeimpact.compare.interface.cli import main

    code = main(["simulate", "central-leader", *args])
    err = capsys.readouterr().err
    assert code == 2
    assert err.count("\n") == 1 and "integrator" in err and "Traceback" not in err, err


@pytest.mark.parametrize("args, field", [(["--segments", "0"], "segments"),
                                         (["--dt", "1"], "dt"),
                                         (["--contact-stiffness", "-5"], "stiffness"),
                                         (["--trunk", "sdof", "--segments", "4"], "segments")])
def test_cli_bad_mujoco_options_are_one_line_errors(capsys, args, field):
    from treeimpact.compare.interface.cli import main

    code = main(["simulate", "central-leader", "--backend", "mujoco", *args])
    err = capsys.readouterr().err
    assert code == 2
    assert err.count("\n") == 1 and field in err and "Traceback" not in err, err


@pytest.mark.parametrize("trunk", ["sdof", "chain"])
def test_pad_calibration_keeps_the_soft_sdofs_contact_law(central, trunk):
    """Default "pad": MuJoCo integrates the soft SDOF rung's (k_c, c_c) on any trunk; its e on
    the chain's light effective mass is the law's, smaller than the scenario's."""
    from treeimpact.analytic.contact.law import contact_law, restitution_for_damping_ratio
    from treeimpact.analytic.model.two_body import two_body_model

    setup = make_setup(scenario_as_run(central, {"t_end": 1e-3}), trunk=trunk)
    k, c = contact_law(two_body_model(central), central.contact)
    assert setup.law.law_stiffness == pytest.approx(k, rel=1e-12)
    assert setup.law.law_damping == pytest.approx(c, rel=1e-9)  # brentq on e, then back to c
    e = restitution_for_damping_ratio(c / (2 * np.sqrt(k * setup.effective_mass
                                                       * central.impactor.mass
                                                       / (setup.effective_mass
                                                          + central.impactor.mass))))
    if trunk == "chain":
        assert e < 0.5 * central.contact.restitution


def test_chain_converges_to_the_beam():
    """The hinged chain with the pad converges to the exact continuum
    (analytic.continuum.beam_impact) at second order in 1/N: the gap of x_max and t_xmax at least
    thirds per doubling of N."""
    from treeimpact.analytic.continuum.beam_impact import simulate_beam
    from treeimpact.analytic.continuum.chain import default_segments

    s = load_scenario("open-center")
    n = default_segments(s.trunk)
    beam = simulate_beam(scenario_as_run(s, {"t_end": 0.03}), elements=24).metrics
    gaps = []
    for segments in (n, 2 * n, 4 * n):
        # x_max is reached at 11.8 ms: the chain's x_max and t_xmax to 18 ms are its values
        # to 30 ms to the last bit (measured at N, 2N, 4N; the 4N run half the CPU)
        chain = simulate(scenario_as_run(s, {"t_end": 0.018}),
                         trunk="chain", segments=segments).metrics
        gaps.append([abs(chain[k] / beam[k] - 1) for k in ("x_max", "t_xmax")])
    gaps = np.array(gaps)
    # measured: x_max 3.0e-3, 6.9e-4, 2.1e-5; t_xmax 6.9e-3, 1.9e-3, 5.1e-4 (4N is stepped by
    # its highest mode at 10 steps a period; at 20: 5e-6 and 4.8e-4, docs/time-step.md)
    assert np.all(gaps[1] < gaps[0] / 3) and np.all(gaps[2] < gaps[1] / 3)
    assert gaps[0, 0] < 0.005 and gaps[2, 0] < 1e-4  # step.chain.x_max; the limit is the beam


def test_chain_whole_event_metrics_converge_to_the_beam():
    """Crown motion, impulse and contact loss of the chain approach the continuum's as N
    doubles (first order in 1/N for the crown's acceleration over t_c): the evidence behind
    step.chain's tolerances."""
    from treeimpact.analytic.continuum.beam_impact import simulate_beam
    from treeimpact.analytic.continuum.chain import default_segments

    s = load_scenario("central-leader")
    n = default_segments(s.trunk)
    beam = simulate_beam(s, elements=24).metrics
    keys = ("crown_peak", "crown_peak_acceleration", "impulse", "contact_dissipation")
    # the whole event ends before 40 ms: these metrics to 50 ms are the chain's to its
    # t_end of 0.1 s to the last bit (measured at N and 2N, 18 and 28 contacts; at 30 ms a
    # contact is missing), for a third of the CPU
    gaps = np.array([[abs(chain[k] / beam[k] - 1) for k in keys] for chain in (
        simulate(scenario_as_run(s, {"t_end": 0.05}),
                 trunk="chain", segments=m).metrics for m in (n, 2 * n))])
    # measured at N, 2N: crown 1.4e-3, 2e-4; acceleration 6.9e-2, 4.4e-3; impulse 4.1e-3,
    # 2.3e-4; contact loss 2.1e-2, 1.4e-3
    assert np.all(gaps[1] < gaps[0] / 2)
    assert gaps[1, 1] < 0.02 and gaps[1, 0] < 1e-3


def test_a_rollout_in_chunks_steps_bitwise_as_one_call(monkeypatch):
    """The chunks (a signal answered and progress told between them) carry the solver's warm
    start: the same states to the last bit, alone or in a threaded batch."""
    import dataclasses

    from treeimpact.analytic.model.scenario import load_scenario
    from treeimpact.mujoco_models import _rollout

    scen = load_scenario("central-leader")
    scens = [scen, dataclasses.replace(scen, name="other", t_end=0.004)]

    def states(chunk_seconds, batch):
        monkeypatch.setattr(_rollout, "CHUNK_SECONDS", chunk_seconds)
        runs = simulate_batch([scenario_as_run(s, {"t_end": 0.03}) for s in scens],
                              segments=4, max_workers=2) if batch else [
            simulate(scenario_as_run(s, {"t_end": 0.03}), segments=4) for s in scens]
        assert all(r.scenario["t_end"] / r.model["dt"] > 3000 for r in runs)  # several chunks
        return [np.column_stack([r.trajectory.x, r.trajectory.y]) for r in runs]

    one_call = states(1e9, batch=False)
    for chunked in (states(1e-9, batch=False), states(1e-9, batch=True)):  # 1000-step chunks
        for a, b in zip(one_call, chunked):
            np.testing.assert_array_equal(a, b)
