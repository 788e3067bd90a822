"""PyBullet models: contact mapping, chain convergence, SDOF against the analytic references."""

from __future__ import annotations

import math

import numpy as np
import pytest

pybullet = pytest.importorskip("pybullet")

import analytic  # noqa: E402
from analytic import load_scenario  # noqa: E402
from analytic.beam import beam_natural_frequencies, beam_static_stiffness  # noqa: E402
from analytic.chain import hinged_chain, lateral_jacobian  # noqa: E402
from analytic.parameters import ParameterError  # noqa: E402
from analytic.records import contact_intervals  # noqa: E402
from analytic.soft_contact import simulate_soft  # noqa: E402
from bullet_models import _contact, modes, simulate, simulate_batch  # noqa: E402
from bullet_models._runner import engine_matrices, make_setup  # noqa: E402
from bullet_models.regenerate import MODELS_DIR, generated  # noqa: E402


@pytest.fixture(scope="module")
def central():
    return load_scenario("central-leader")


# ----------------------------------------------------------------------------- URDF files
def test_regenerated_urdf_equals_checked_in_files():
    files = generated()
    on_disk = {p.name for p in MODELS_DIR.glob("*.urdf")}
    assert on_disk == set(files)
    for name, text in files.items():
        assert (MODELS_DIR / name).read_text() == text, f"{name}: run python -m bullet_models.regenerate"


def test_urdf_parses_in_yourdfpy_and_loads_in_pybullet():
    yourdfpy = pytest.importorskip("yourdfpy")
    cid = pybullet.connect(pybullet.DIRECT)
    try:
        for path in sorted(MODELS_DIR.glob("*.urdf")):
            robot = yourdfpy.URDF.load(str(path), build_scene_graph=False, load_meshes=False)
            body = pybullet.loadURDF(str(path), useFixedBase=True, physicsClientId=cid)
            assert pybullet.getNumJoints(body, physicsClientId=cid) == len(robot.robot.joints)
            urdf_mass = sum(link.inertial.mass for link in robot.robot.links if link.inertial)
            bullet_mass = sum(pybullet.getDynamicsInfo(body, j, physicsClientId=cid)[0]
                              for j in range(len(robot.robot.joints)))
            assert bullet_mass == pytest.approx(urdf_mass, rel=1e-12), path.name
    finally:
        pybullet.disconnect(cid)


# ------------------------------------------------------------------------- soft contact
def test_bullet_combines_stiffness_in_series_and_damping_in_sum():
    k, c = 3.0e7, 1.2e4
    ks, ds = _contact.per_body(k, c)
    assert _contact.combine_stiffness(ks, ks) == pytest.approx(k, rel=1e-15)
    assert _contact.combine_damping(ds, ds) == pytest.approx(c, rel=1e-15)


def _two_body_restitution(e, dt_fraction=50):
    """Free collision of M_T and m in PyBullet with the corrected soft contact; measured e."""
    from analytic.parameters import Billet, Contact, Scenario

    s = load_scenario("central-leader")
    billet = Scenario(name="two-body", trunk=s.trunk, impactor=Billet(s.impactor.mass, 2.0),
                      contact=Contact(restitution=e, duration=5e-4), t_end=1e-3)
    setup = make_setup(billet, trunk="sdof")
    # a free collision: no trunk spring or damping
    import dataclasses

    free = dataclasses.replace(setup.model, stiffness=1e-12, damping=0.0)
    setup = dataclasses.replace(setup, model=free)
    from bullet_models._runner import run

    rec = run(setup).extra["record"]
    return (rec.vx[-1] - rec.vy[-1]) / 2.0, setup


@pytest.mark.parametrize("e", [0.05, 0.1, 0.3, 0.6, 0.9])
def test_soft_contact_two_body_collision_gives_target_restitution(e):
    measured, setup = _two_body_restitution(e)
    assert abs(measured - e) < 0.01  # the tolerance on the measured e
    # and the replay of Bullet's ERP/CFM update predicts PyBullet to round-off level
    assert abs(measured - e) < 1e-3  # measured: <= 5e-4 (PyBullet's solver residual)


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
def test_engine_mass_matrix_and_jacobian_match_the_chain_model(central):
    from analytic.chain import chain_matrices

    chain = hinged_chain(central.trunk, 12)
    M, J = engine_matrices(chain)
    Ml, _, _ = chain_matrices(chain)
    np.testing.assert_allclose(J, lateral_jacobian(chain, central.trunk.clamp_height)[0],
                               rtol=1e-6, atol=1e-7)  # float32 link transforms in Bullet
    assert np.max(np.abs(M - Ml)) < 2e-3 * np.max(np.abs(Ml))  # measured 6.4e-4 (see report)


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
    # frequencies: within 0.1 % of the beam from N = 16; they stop converging at a floor of
    # -2e-4 (omega_1) and -7e-4 (omega_2) set by Bullet's own mass matrix (see report)
    assert np.all(np.abs(errs[:, 1:]) < 1e-3)


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


@pytest.mark.parametrize("name", ["central-leader", "open-center"])
def test_newton_contact_reproduces_exact_impacts(name):
    s = load_scenario(name)
    exact = analytic.simulate(s)
    res = simulate(s, trunk="sdof", contact="newton")
    rec, dt = res.extra["record"], res.model["dt"]
    u1 = s.impactor.impact_speed
    big = [i for i in exact.extra["solution"].impacts if i.u - i.U > 0.01 * u1]
    iv = contact_intervals(rec.force, 1e-6 * rec.force.max())
    assert len(iv) >= len(big)
    for imp, (i0, _) in zip(big, iv):
        assert abs(rec.t[i0] - imp.t) <= 3 * dt  # an impact acts at the first step with overlap
        assert rec.vx[i0 + 1] == pytest.approx(imp.V, rel=5e-3)  # eq 21 separation velocity
    for key in ("V", "x_max", "impact_loss"):
        assert res.metrics[key] == pytest.approx(exact.metrics[key], rel=5e-3), key


def test_full_pendulum_reaches_the_trunk_at_eq_48_speed(central):
    res = simulate(central, trunk="sdof", pendulum="full", t_end=0.01)
    rec = res.extra["record"]
    # speed at the last step before contact vs u1 of eq 48; symplectic Euler's energy error
    # over the swing is ~omega dt = 2.6e-4 at the 1e-4 s swing step
    assert rec.vy[0] == pytest.approx(central.impactor.impact_speed, rel=1e-3)


@pytest.mark.parametrize("opts", [dict(trunk="sdof"), dict(trunk="sdof", contact="newton"),
                                  dict(trunk="sdof", pendulum="full"),
                                  dict(trunk="chain", t_end=0.015)])
def test_energy_ledger_closes_within_one_percent(central, opts):
    res = simulate(central, **opts)
    assert res.metrics["ledger_residual"] < 0.01  # issue: ledger below 1 %


def test_bad_option_is_a_one_line_parameter_error(central):
    with pytest.raises(ParameterError, match="contact") as exc:
        simulate(central, contact="rigid")
    assert "\n" not in str(exc.value)
    with pytest.raises(ParameterError, match="too large"):
        simulate(central, trunk="sdof", dt=1e-3)


def test_batch_over_a_process_pool_matches_serial_runs(central):
    scen = [central, load_scenario("open-center")]
    batch = simulate_batch(scen, trunk="sdof", t_end=0.005, max_workers=2)
    for s, r in zip(scen, batch):
        serial = simulate(s, trunk="sdof", t_end=0.005)
        assert r.metrics["x_max"] == serial.metrics["x_max"]  # same deterministic engine
