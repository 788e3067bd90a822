"""The paper's other impactor, the billet (free, k = 0, or on a spring k), on the exact
linear rungs (beam, Timoshenko, soft SDOF) against independent limits: a pendulum of growing
equivalent length, the 1-DOF model where the trunk's own mass vanishes, a DOP853 integration
of the same matrices, and the closed form of the free flight (docs/beam-impact.md)."""

import dataclasses
import math
import tomllib

import numpy as np
import pytest

from treeimpact.analytic.contact.exact_record import record
from treeimpact.analytic.contact.exact_solve import solve
from treeimpact.analytic.contact.soft import simulate_soft
from treeimpact.analytic.continuum.beam_impact import beam_impact_model, simulate_beam
from treeimpact.analytic.impact.simulate import simulate
from treeimpact.analytic.model.parameters import Billet, Pendulum
from treeimpact.analytic.model.reduction import reduce_trunk
from treeimpact.analytic.model.scenario import load_scenario, scenario_from_dict
from treeimpact.analytic.model.scenario_toml import scenario_toml
from test_beam_impact import _ode_reference  # DOP853 of the same matrices, no modes at all

MASS, SPEED = 40.0, 2.5  # kg, m/s: a light billet on central-leader (m / M_T = 0.36)
EPS = float(np.finfo(float).eps)


def _billet(stiffness: float = 0.0, base=None):
    base = load_scenario("central-leader") if base is None else base
    return dataclasses.replace(base, impactor=Billet(mass=MASS, impact_speed=SPEED,
                                                     stiffness=stiffness))


def _pendulum(equivalent_length: float):
    """central-leader struck by a pendulum of ``equivalent_length`` released to hit at SPEED
    (eq 48: u_1 = 2 sqrt(g l_e) sin(theta_r / 2))."""
    base = load_scenario("central-leader")
    g = 9.81
    theta = 2.0 * math.degrees(math.asin(SPEED / (2.0 * math.sqrt(g * equivalent_length))))
    return dataclasses.replace(base, impactor=Pendulum(
        mass=MASS, equivalent_length=equivalent_length, release_angle_deg=theta, gravity=g))


RUNGS = {"beam": lambda s: simulate_beam(s, elements=4),
         "timoshenko": lambda s: simulate_beam(s, elements=4, beam_theory="timoshenko"),
         "soft": simulate_soft}
#: metrics that vary smoothly with the impactor's spring (not counts, not eq 58's theta_b)
SMOOTH = ("x_max", "energy_delivered", "impulse", "rebound_energy", "contact_dissipation",
          "crown_peak")


@pytest.mark.parametrize("rung", ["beam", "soft"])
def test_a_free_billet_is_the_limit_of_a_long_pendulum(rung):
    """The pendulum's spring m g / l_e -> 0 as l_e grows: its metrics approach the free
    billet's at first order in 1 / l_e (the exact solution is analytic in k, and k = 0 is
    no special point of it, only of the decomposition), so doubling l_e halves the gap."""
    run = RUNGS[rung]
    free = run(_billet()).metrics
    lengths = (7.5, 15.0, 30.0)  # m; 30 m is the registry's top
    gaps = []
    for le in lengths:
        m = run(_pendulum(le)).metrics
        assert m["n_impacts"] == free["n_impacts"]  # the same switches: a smooth family
        gaps.append({k: (m[k] - free[k]) / free[k] for k in SMOOTH})
    # the next order relative to the first is the spring's effect over the run,
    # (omega_2 t_end)^2 = g t_end^2 / l_e, at most at the shortest l_e; 4 times it
    tol = 4.0 * 9.81 * load_scenario("central-leader").t_end ** 2 / lengths[0]
    for near, far in zip(gaps, gaps[1:]):
        for k in SMOOTH:
            assert near[k] != 0.0, k  # the pendulum's spring does act
            assert near[k] / far[k] == pytest.approx(2.0, rel=tol), k


def test_a_spring_billet_is_the_linearised_pendulum_of_its_k():
    """A billet on k = m g / l_e is eq 13's linearised pendulum of l_e: the same model, so
    every metric but eq 58's theta_b (the pendulum's only) and the energy transferred it
    gives is the same."""
    pend = _pendulum(1.51)
    spring = _billet(stiffness=pend.impactor.stiffness)
    for run in RUNGS.values():
        a, b = run(pend).metrics, run(spring).metrics
        for k in SMOOTH + ("n_impacts", "peak_force", "t_sep", "ledger_residual"):
            # the same arithmetic on the same numbers but for u_1 = 2 sqrt(g l_e) sin(...)
            # read back from theta_r: a few eps of u_1
            assert a[k] == pytest.approx(b[k], rel=1e-12), k


def _heavy_clamp_billet(density: float):
    """central-leader's trunk as a light beam under a 1000 kg clamp (no crown, undamped),
    struck by the free billet; and f, the trunk's own mass over M_T (eq 7)."""
    base = load_scenario("central-leader")
    trunk = dataclasses.replace(base.trunk, density=density, clamp_mass=1000.0,
                                crown_mass=0.0, damping=0.0)
    f = trunk.density * trunk.area * trunk.length / reduce_trunk(trunk).dynamic_mass
    return _billet(base=dataclasses.replace(base, trunk=trunk)), f


def test_the_beam_with_a_billet_tends_to_the_1dof_model():
    """A heavy clamp on a light trunk is the SDOF of eq 11: the trunk's own mass (a fraction
    f of M_T) moves with shapes other than eq 5's, so the beam's gap to the soft SDOF closes
    at first order in f."""
    gaps, fs = [], []
    for rho in (400.0, 100.0):  # kg/m^3; 100 is the registry's bottom
        scenario, f = _heavy_clamp_billet(rho)
        beam, soft = simulate_beam(scenario, elements=6).metrics, simulate_soft(scenario).metrics
        gaps.append({k: abs(beam[k] - soft[k]) / soft[k]
                     for k in ("x_max", "impulse", "peak_force", "energy_delivered")})
        fs.append(f)
    for k in gaps[0]:
        # first order: the gap shrinks as f does; the f^2 term moves the ratio by O(f) (0.5 %
        # here) and the pad's peak force is read on samples 1 / 100 of a collision apart:
        # 0.8 of f's ratio
        assert gaps[0][k] / gaps[1][k] >= 0.8 * fs[0] / fs[1], k
    assert gaps[1]["x_max"] < 1e-3  # O(f), f = 1.2e-3 at 100 kg/m^3


def _free_runs(in_contact: np.ndarray, first: int = 3):
    """Slices of the record's samples in free flight, at least ``first`` long."""
    runs, start = [], None
    for i, c in enumerate(np.append(in_contact, True)):
        if not c and start is None:
            start = i
        elif c and start is not None:
            if i - start >= first:
                runs.append(slice(start, i))
            start = None
    return runs


@pytest.mark.parametrize("method", ["exact", "exact-full"])
def test_a_free_billet_flies_linearly_in_time_on_the_record(method):
    """Apart from the trunk the billet's displacement is y0 + v0 s exactly: its second
    differences on the record are round-off, and a billet on a spring's are not."""
    def free_flight_curvature(stiffness):
        rec = simulate_beam(_billet(stiffness), elements=4, method=method).record
        free = rec.force == 0.0
        free &= rec.y < rec.x  # apart, not a released pad still overlapping
        runs = _free_runs(~free)
        assert runs  # the billet bounces off (m / M_T = 0.36)
        bend = spread = 0.0
        for r in runs:
            y, vy = rec.y[r], rec.vy[r]
            spread = max(spread, float(np.ptp(vy) / np.abs(vy).max()))
            bend = max(bend, float(np.abs(np.diff(y, 2)).max() / np.abs(y).max()))
        return bend, spread

    # y = y0 + v0 s evaluated at each sample, v0 itself: a few eps of |y| and |v0| (8 eps:
    # the sums' roundings)
    bend, spread = free_flight_curvature(0.0)
    assert bend <= 8 * EPS and spread <= 8 * EPS
    # the check can fail: a 2000 N/m spring bends y by (k / m) y dt^2 (1e-9 of |y| here)
    assert min(free_flight_curvature(2000.0)) > 100 * 8 * EPS


@pytest.mark.parametrize("method", ["exact-full", "exact"])
def test_the_exact_billet_matches_an_ode_integration(method):
    model, _ = beam_impact_model(_billet(), elements=4)
    t_end = 0.02
    if method == "exact-full":
        got, _, switches = record(model, t_end, 5e-6)
    else:
        got, switches = solve(model, t_end, 5e-6)
    x_ref, y_ref = _ode_reference(model, t_end, got.t)
    assert switches >= 2  # contact and free flight both in the window
    # the reference's error: its steps straddle each kink of the law (2 us max step) at
    # rtol 1e-11, as for the pendulum (tests/test_beam_impact.py); 1e-9 of the largest
    np.testing.assert_allclose(got.x, x_ref, atol=1e-9 * np.abs(x_ref).max())
    np.testing.assert_allclose(got.y, y_ref, atol=1e-9 * np.abs(y_ref).max())


@pytest.mark.parametrize("stiffness", [0.0, 2000.0])
def test_the_soft_rungs_exact_billet_is_its_dop853_billet(stiffness):
    scenario = _billet(stiffness)
    exact, ode = simulate_soft(scenario).metrics, simulate_soft(scenario, method="ode").metrics
    for k in SMOOTH + ("peak_force", "t_sep", "V", "x0"):
        # DOP853 at rtol 1e-11 with its events located to 1e-15 s: its energies integrate
        # the error, 1e-8 of them (the SoftMethod.ODE note); 1e-7
        assert exact[k] == pytest.approx(ode[k], rel=1e-7), k
    assert exact["n_impacts"] == ode["n_impacts"]


@pytest.mark.parametrize("stiffness", [0.0, 2000.0])
def test_billets_run_on_every_analytic_rung(stiffness):
    """Each rung's own energy ledger closes on a billet (free or on a spring), and the rungs
    of one tree agree on what the contact's impulse must be: at most the billet's momentum
    change, 0 < J <= 2 m u_1 (a rebound at most elastic)."""
    scenario = _billet(stiffness)
    for run in (*RUNGS.values(), simulate):
        m = run(scenario).metrics
        # closed-form or event-exact ledgers: round-off of the eigenvectors or of the
        # Newton impulses, far below the plausibility check's 5 %
        assert m["ledger_residual"] < 1e-6
        assert 0.0 < m["impulse"] <= 2.0 * MASS * SPEED * (1.0 + 1e-9)
        assert math.isnan(m["theta_b"])  # a billet has no rebound angle


def test_a_spring_billet_round_trips_through_its_file():
    scenario = _billet(2000.0)
    text = scenario_toml(scenario)
    assert "stiffness = 2000.0" in text
    again = scenario_from_dict(tomllib.loads(text))
    assert again.impactor == scenario.impactor


@pytest.mark.parametrize("stiffness", [0.0, 2000.0])
def test_mujoco_s_billet_carries_its_spring(stiffness):
    """MuJoCo's slide joint gets the billet's k (it had 0 whatever the file said)."""
    mujoco = pytest.importorskip("mujoco")
    from treeimpact.mujoco_models._setup import make_setup

    m = make_setup(_billet(stiffness), trunk="sdof").mjmodel
    joint = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, "pendulum_x")
    assert m.jnt_stiffness[joint] == stiffness  # copied, not computed


@pytest.mark.parametrize("stiffness", [0.0, 2000.0])
def test_the_beam_methods_give_a_billet_the_same_metrics(stiffness):
    """``exact`` (the flight added to the grid's observables and to the Newton steps) against
    ``exact-full`` (every sample's state, the flight in :meth:`Modal.state`)."""
    scenario = _billet(stiffness)
    full = simulate_beam(scenario, elements=6, method="exact-full").metrics
    fast = simulate_beam(scenario, elements=6, method="exact").metrics
    for key, value in full.items():
        if key == "ledger_residual":  # round-off, both below 1e-9
            assert fast[key] < 1e-9 and value < 1e-9
        elif key in ("impact_loss", "energy_transferred"):
            # the pad's work at T0: exact against interpolated between samples, as for the
            # pendulum (tests/test_beam_impact.py)
            assert fast[key] == pytest.approx(value, rel=5e-5, nan_ok=True)
        else:
            # the same samples and switches: round-off only
            assert fast[key] == pytest.approx(value, rel=1e-9, nan_ok=True), key
