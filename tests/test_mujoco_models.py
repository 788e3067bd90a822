"""MuJoCo models: contact law and restitution mapping, chain convergence, SDOF against the
analytic soft-contact reference, full pendulum, energy ledger, MJCF files."""

from __future__ import annotations

import copy
import dataclasses
import math

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco")

from mujoco import rollout  # noqa: E402

from analytic import load_scenario  # noqa: E402
from analytic.beam import beam_natural_frequencies, beam_static_stiffness  # noqa: E402
from analytic.chain import chain_matrices, hinged_chain  # noqa: E402
from analytic.parameters import Contact, ParameterError  # noqa: E402
from analytic.results import SimulationDiverged  # noqa: E402
from analytic.soft_contact import simulate_soft  # noqa: E402
from mujoco_models import _contact, modes, simulate, simulate_batch  # noqa: E402
from mujoco_models._builder import sensor_slices  # noqa: E402
from mujoco_models._runner import (_damping_matrices, _plan, _record,  # noqa: E402
                                   engine_trunk_matrices, make_setup)
from mujoco_models.regenerate import MODELS_DIR, generated  # noqa: E402


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


def _free_collision_restitution(scenario, trunk, e):
    """Pendulum against the trunk with every spring and damper removed: a two-body collision.

    e = (vx - vy) / u1 at the first sample after the force has gone back to zero.
    """
    s = dataclasses.replace(scenario, contact=Contact(restitution=e, duration=5e-4))
    setup = make_setup(s, trunk=trunk, t_end=1e-3)
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


@pytest.mark.parametrize("trunk", ["sdof", "chain"])
@pytest.mark.parametrize("e", [0.05, 0.1, 0.3, 0.6, 0.9])
def test_two_body_collision_gives_target_restitution(central, trunk, e):
    measured, setup = _free_collision_restitution(central, trunk, e)
    assert abs(measured - e) < 0.01  # the tolerance on the measured e
    # measured: SDOF <= 1e-9 (the replay is MuJoCo's own map); chain <= 4.2e-4 (the free
    # chain's velocity-dependent forces during the 50-step collision)
    assert abs(measured - e) < (1e-8 if trunk == "sdof" else 1e-3)


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
    res = simulate(central, trunk="sdof", pendulum="full", t_end=0.005)
    # Euler's swing at 1e-4 s conserves a modified energy equal to the true one at the
    # bottom; the bob's own inertia (1e-6 m l_e^2) lowers the speed by 5e-7: measured 1.1e-6
    assert res.extra["impact_speed_measured"] == pytest.approx(
        central.impactor.impact_speed, rel=1e-5)
    assert res.extra["record"].t[0] <= 0.0 < res.extra["record"].t[1]  # t = 0 at the touch


@pytest.mark.parametrize("opts", [dict(trunk="sdof"), dict(trunk="sdof", pendulum="full"),
                                  dict(trunk="chain", t_end=0.02),
                                  dict(trunk="chain", damping="joint", t_end=0.02)])
def test_energy_ledger_closes_within_one_percent(central, opts):
    res = simulate(central, **opts)
    assert res.metrics["ledger_residual"] < 0.01  # issue: below 1 % (measured <= 3e-4)
    rec = res.extra["record"]
    assert rec.damping_work[-1] > 0.0 and rec.contact_work[-1] > 0.0  # both ledgers active


def test_joint_damping_alternative_keeps_the_first_modes_damping(central):
    """damping="joint" (beta k_j at the hinges) has mode 1's modal damping of the distributed
    damping (tendons), read back from both compiled models; mode 2 gets more."""
    import scipy.linalg

    a = make_setup(central, trunk="chain").mjmodel
    b = make_setup(central, trunk="chain", damping="joint").mjmodel
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
    setup = make_setup(central, trunk="sdof", t_end=1e-3)
    plan = _plan(setup)
    m = setup.mjmodel
    st, sd = rollout.rollout(m, mujoco.MjData(m), plan.state0, nstep=plan.nstep)
    sd = sd[0].copy()
    sd[50, sensor_slices()["x_pos"]] = np.nan
    with pytest.raises(SimulationDiverged, match="non-finite"):
        _record(setup, plan.state0, st[0], sd)


def test_energy_growing_engine_run_is_reported_as_diverged(central):
    """A real rollout that gains energy (the trunk's damper made negative: finite growth at
    C_T / M_T = 131 1/s) is reported as diverged, never turned into metrics."""
    from mujoco_models._runner import run_setups

    setup = make_setup(central, trunk="sdof")
    m = copy.deepcopy(setup.mjmodel)
    assert m.dof_damping[0] > 0  # the SDOF trunk's C_T
    m.dof_damping[0] *= -1.0
    out = run_setups([dataclasses.replace(setup, mjmodel=m)])[0]
    assert isinstance(out, SimulationDiverged), out
    assert "mechanical energy" in str(out)
    assert not isinstance(run_setups([setup])[0], SimulationDiverged)  # control: C_T > 0


def test_energy_created_while_damped_is_reported_as_diverged(central):
    """The ledger rule: kinetic energy the engine invents after the impact (10 % of the input,
    mechanical energy still below the input) is caught by kinetic + potential + works."""
    setup = make_setup(central, trunk="sdof", t_end=0.05)
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


@pytest.mark.parametrize("opts", [dict(trunk="sdof"), dict(trunk="chain"),
                                  dict(trunk="chain", damping="joint")])
def test_damping_matrices_are_what_the_euler_step_applies(central, opts):
    """One engine step with springs and contact off: M (v1 - v0) / h = -D v0 - B v1 with the
    (explicit D, implicit B) the ledger uses; the other split misses it."""
    setup = make_setup(central, **opts)
    m = copy.deepcopy(setup.mjmodel)
    m.jnt_stiffness[:] = 0.0
    m.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
    d = mujoco.MjData(m)
    rng = np.random.default_rng(3)
    v0 = 1e-3 * rng.standard_normal(m.nv)  # small: Coriolis forces ~ v^2 are negligible
    d.qvel[:] = v0
    mujoco.mj_forward(m, d)
    M = np.zeros((m.nv, m.nv))
    mujoco.mj_fullM(m, M, d.qM)
    mujoco.mj_step(m, d)
    v1 = d.qvel.copy()
    D, B = _damping_matrices(m)
    lhs = M @ (v1 - v0) / m.opt.timestep
    scale = np.abs(lhs).max()
    np.testing.assert_allclose(lhs, -D @ v0 - B @ v1, rtol=0, atol=1e-6 * scale)  # round-off
    wrong = -B @ v0 - D @ v1  # explicit and implicit swapped
    assert np.abs(lhs - wrong).max() > 1e-4 * scale  # measured >= 5.0e-4 (~ h b / m)


def test_batch_through_rollout_matches_serial_runs(central):
    scen = [central, load_scenario("open-center")]
    batch = simulate_batch(scen, trunk="sdof", t_end=0.005, max_workers=2)
    for s, r in zip(scen, batch):
        serial = simulate(s, trunk="sdof", t_end=0.005)
        assert r.metrics["x_max"] == serial.metrics["x_max"]  # same deterministic engine
        assert r.model["dt"] == serial.model["dt"]


# ------------------------------------------------------------------------- MJCF files
def test_regenerated_mjcf_equals_checked_in_files():
    files = generated()
    assert {p.name for p in MODELS_DIR.glob("*.xml")} == set(files)
    for name, text in files.items():
        assert (MODELS_DIR / name).read_text() == text, \
            f"{name}: run python -m mujoco_models.regenerate"


def test_checked_in_models_compile_without_warnings_and_are_the_runners_models():
    from analytic.scenario import shipped_scenarios

    from mujoco_models.regenerate import VARIANTS

    for name in shipped_scenarios():
        s = load_scenario(name)
        for trunk, pendulum in VARIANTS:
            path = MODELS_DIR / f"{name}-{trunk}-{pendulum}.xml"
            # MjSpec.compile raises on a compiler warning too (mjs_isWarning); from_xml_path
            # is the loader of `python -m mujoco.viewer --mjcf=...`
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
    from mujoco_models import regenerate

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

    from analytic.results import METRIC_KEYS
    from compare.cli import main

    code = main(["simulate", "central-leader", "--backend", "mujoco", "--trunk", "chain",
                 "--segments", "8", "--t-end", "0.005", "--json"])
    data = json.loads(capsys.readouterr().out)
    assert code == 0 and tuple(data["metrics"]) == METRIC_KEYS
    assert data["model"]["segments"] == 8
    assert {"dt", "contact_stiffness", "contact_damping"} <= set(data["model"])
    assert main(["modes", "central-leader", "--backend", "mujoco", "--segments", "16"]) == 0
    out = capsys.readouterr().out
    assert "model" in out and "beam" in out and "static stiffness" in out


@pytest.mark.parametrize("args, field", [(["--segments", "0"], "segments"),
                                         (["--dt", "1"], "dt"),
                                         (["--contact-stiffness", "-5"], "stiffness"),
                                         (["--trunk", "sdof", "--segments", "4"], "segments")])
def test_cli_bad_mujoco_options_are_one_line_errors(capsys, args, field):
    from compare.cli import main

    code = main(["simulate", "central-leader", "--backend", "mujoco", *args])
    err = capsys.readouterr().err
    assert code == 2
    assert err.count("\n") == 1 and field in err and "Traceback" not in err, err
