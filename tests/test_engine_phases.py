"""The engines stepped by phase (analytic.engine.phases, docs/engines.md "Stepping by
phase"): the rule's bound, the switches at the physical events, and the phased run against
the fixed-step run within the stated tolerances (compare/runs/tolerances.toml [engines.chain]:
the same model in two integrators) on a small chain and a short run. Not among
conftest.NUMERICS: the tolerances checked are >= 0.5 %, far above any BLAS round-off."""

import tomllib

import numpy as np
import pytest

from treeimpact.analytic.engine import phases
from treeimpact.analytic.model.scenario import load_scenario
from treeimpact.analytic.model.options import scenario_as_run

ENGINES = ["treeimpact.mujoco_models", "treeimpact.bullet_models"]
#: A small, cheap chain whose free step is many contact steps (open-center at 4 segments:
#: omega_max 1.2e4 rad/s, h_f = 5.2e-5 s against dt_c = 1.1 us in MuJoCo, 1.9 us in
#: Bullet) and a run through its contact phase into free vibration.
CASE = {"trunk": "chain", "segments": 4}
#: The case's simulated time, s (a scenario field: applied to the scenario).
CASE_T_END = 0.03


def _tolerances() -> dict:
    """metric -> [engines.chain]'s ``rel``, or a per-tree bound's ``floor`` (what stays at
    any step: the bound's first-order part is two integrators', and the phased and fixed
    runs are one engine); every compared metric has one."""
    from treeimpact.compare.runs.verdicts import TOLERANCES_PATH

    with open(TOLERANCES_PATH, "rb") as fh:
        table = tomllib.load(fh)["engines"]["chain"]
    out = {k: v.get("rel", v.get("floor")) for k, v in table.items()
           if "rel" in v or ("bound" in v and "floor" in v)}
    assert {"x_max", "impulse", "peak_force", "crown_peak"} <= out.keys(), out
    return out


def phased_on(monkeypatch, package: str) -> None:
    """Stepping by phase in ``package`` (its ``_setup.PHASED``, both engines' default,
    docs/engines.md): the test stays a test of the phased stepping if a default changes."""
    import importlib

    monkeypatch.setattr(importlib.import_module(f"{package}._setup"), "PHASED", True)


@pytest.fixture(scope="module", params=ENGINES)
def runs(request):
    """(engine module, phased run, fixed-step run at the same dt) of :data:`CASE`."""
    mod = pytest.importorskip(request.param)
    scen = scenario_as_run(load_scenario("open-center"), {"t_end": CASE_T_END})
    with pytest.MonkeyPatch.context() as mp:
        phased_on(mp, request.param)
        phased = mod.simulate(scen, **CASE)
    fixed = mod.simulate(scen, **CASE, dt=phased.model["dt"])
    return mod, phased, fixed


def test_the_bound_leaves_one_step_of_travel_and_takes_no_lone_big_step():
    """n = floor(g / (V h)) - 1 big steps at the bound's speed V end at least V h from the
    touch; fewer than MIN_FREE_STEPS are not taken, nor any at a gap <= 0."""
    rule = phases.PhaseRule(1e-6, 1e-5, 50.0, 100)
    rng = np.random.default_rng(5)
    for gap, lam in zip(rng.uniform(1e-5, 1e-1, 200), rng.uniform(1e-3, 1.0, 200)):
        n = rule.free_steps(gap, lam, 1.0)
        v = rule.speed_bound(lam)
        assert n == 0 or (n >= phases.MIN_FREE_STEPS and gap - n * v * 1e-5 >= v * 1e-5)
    assert rule.free_steps(0.0, 0.1, 1.0) == 0 and rule.free_steps(-1e-3, 0.1, 1.0) == 0
    v = rule.speed_bound(0.1)
    assert rule.free_steps(2.5 * v * 1e-5, 0.1, 1.0) == 0  # room for one step only
    assert rule.free_steps(1.0, 0.1, 3.5e-5) == 3  # no further than the run's end


def test_no_phases_for_an_sdof_trunk_or_steps_that_are_nearly_one():
    """The SDOF trunk (no highest mode of its own below its fundamental) and a free step
    under MIN_STEP_RATIO contact steps keep the fixed step."""
    assert phases.phase_rule(1e-6, None, 10.0, 5e-5, 10, 0.05) is None
    w = 2 * np.pi / 10 / 1.2e-6  # h_f = 1.2 dt_c
    assert phases.phase_rule(1e-6, w, 10.0, 5e-5, 10, 0.05) is None
    rule = phases.phase_rule(1e-6, w / 5, 10.0, 5e-5, 10, 0.05)
    assert rule.free_step == pytest.approx(6e-6) and rule.chunk_steps == 100
    assert rule.energy_bound == pytest.approx(10.5)


def test_a_given_dt_or_the_sdof_is_a_fixed_step():
    """Both engines step by phase by default (their reasons: each ``_setup.PHASED``); a
    given --dt, the SDOF trunk and Bullet's Newton impulses are fixed steps."""
    pytest.importorskip("treeimpact.mujoco_models")
    from treeimpact import bullet_models as bt
    from treeimpact import mujoco_models as mj
    from treeimpact.bullet_models import _setup as bullet_setup
    from treeimpact.mujoco_models import _setup as mujoco_setup

    assert mujoco_setup.PHASED and bullet_setup.PHASED
    scen = load_scenario("open-center")
    for mod in (mj, bt):
        assert mod.make_setup(scen, trunk="sdof").phases is None
        setup = mod.make_setup(scen, trunk="chain", segments=4)
        assert setup.phases is not None and setup.phases.contact_step == setup.dt
        assert mod.make_setup(scen, trunk="chain", segments=4, dt=setup.dt).phases is None
    assert bt.make_setup(scen, trunk="chain", segments=4, contact="newton").phases is None


def test_the_phased_run_is_the_fixed_step_run_within_the_stated_tolerances(runs):
    """Every metric compare/runs/tolerances.toml compares two engines' chains by, within its
    tolerance of the fixed-step run; the first contact to the last bit's order (it is
    stepped at the same dt from the same state); the same contact sequence; fewer steps."""
    _, phased, fixed = runs
    for k, tol in _tolerances().items():
        a, b = phased.metrics[k], fixed.metrics[k]
        assert abs(a - b) <= tol * abs(b), (k, a, b, tol)
    assert phased.metrics["first_contact_duration"] == pytest.approx(
        fixed.metrics["first_contact_duration"], rel=1e-9)
    assert phased.metrics["contact_episodes"] == fixed.metrics["contact_episodes"]
    assert phased.extra["stepping"]["steps"] < fixed.extra["stepping"]["steps"]


def test_the_step_switches_at_the_physical_events(runs):
    """Every step that starts or ends with contact force is a contact step; big steps come
    only after the first release, with the bodies apart at both ends; the run's last
    contact ends before its first big step's run of free steps starts, and the steps
    cover the fixed-step run's time."""
    _, phased, fixed = runs
    r = phased.trajectory
    h = np.diff(r.t)
    dt, hf = phased.model["dt"], phased.extra["stepping"]["free_dt"]
    big = np.isclose(h, hf, rtol=1e-9)
    assert np.all(big | np.isclose(h, dt, rtol=1e-9)) and big.any()
    on = r.force > 0.0
    assert not np.any(big & (on[:-1] | on[1:]))  # no big step carries force
    gap = r.x - r.y  # the pad's surface gap along x (m), > 0 apart
    assert np.all(gap[:-1][big] > 0.0) and np.all(gap[1:][big] > 0.0)
    first_big = int(np.argmax(big))
    release = int(np.flatnonzero(on)[0] + np.argmin(on[np.flatnonzero(on)[0]:]))
    assert first_big > release  # the first release comes before any big step
    for start in np.flatnonzero(on[1:] & ~on[:-1]) + 1:  # each touch
        assert not big[start - 1]  # reached with the contact's step
    assert r.t[-1] == pytest.approx(fixed.trajectory.t[-1], abs=dt)


#: Each engine's check after a chunk of big steps that failed: (module, function).
CHECKS = {"treeimpact.mujoco_models": ("treeimpact.mujoco_models._phased", "_clear"),
          "treeimpact.bullet_models": ("treeimpact.bullet_models._phased", "_restore")}


@pytest.mark.parametrize("package", ENGINES)
def test_a_re_touch_inside_a_big_step_is_not_missed(package, monkeypatch):
    """With a broken bound (200 big steps whenever the bodies are apart, whatever the gap),
    the chunks overrun the chattering's re-touches; the check after each chunk catches them
    and steps them again at dt_c: the same contact sequence and the metrics within the
    stated tolerances, no big step carrying force."""
    import importlib

    mod = pytest.importorskip(package)
    where, name = CHECKS[package]
    check_mod = importlib.import_module(where)
    original, failed = getattr(check_mod, name), []

    def counted(*args):
        out = original(*args)
        if name == "_restore" or not out:
            failed.append(1)
        return out

    monkeypatch.setattr(check_mod, name, counted)
    phased_on(monkeypatch, package)
    monkeypatch.setattr(phases.PhaseRule, "free_steps", lambda self, gap, lam, left: min(
        200, int(left / self.free_step)) if gap > 0.0 else 0)
    scen = scenario_as_run(load_scenario("central-leader"), {"t_end": 0.012})
    opts = {"trunk": "chain", "segments": 6, "pendulum": "linear"}
    loose = mod.simulate(scen, **opts)
    fixed = mod.simulate(scen, **opts, dt=loose.model["dt"])
    r = loose.trajectory
    big = np.isclose(np.diff(r.t), loose.extra["stepping"]["free_dt"], rtol=1e-9)
    on = r.force > 0.0
    assert failed and big.any() and not np.any(big & (on[:-1] | on[1:]))
    assert loose.metrics["contact_episodes"] == fixed.metrics["contact_episodes"]
    for k, tol in _tolerances().items():
        assert abs(loose.metrics[k] - fixed.metrics[k]) <= tol * abs(fixed.metrics[k]), k


def test_mujoco_reads_the_gap_and_the_inverse_mass_of_its_own_contact():
    """The switch's gap is the spheres' distance less their radii (MuJoCo's geoms, equal to
    the sensors' site distance the chunk check reads), and lambda_max of J_rel M^-1 J_rel^T
    at rest is the contact's inverse effective mass A (its x row; the z rows vanish at rest)
    to 1e-9; the linear pendulum starts touching, the overlap INITIAL_OVERLAP."""
    pytest.importorskip("treeimpact.mujoco_models")
    from treeimpact import mujoco_models as mj
    from treeimpact.mujoco_models._phased import _Probe
    from treeimpact.mujoco_models._rollout import INITIAL_OVERLAP

    setup = mj.make_setup(load_scenario("open-center"), trunk="chain", segments=4)
    gap, lam, _ = _Probe(setup.mjmodel).at(setup.initial_state)
    assert gap == pytest.approx(-INITIAL_OVERLAP, abs=1e-15)
    assert lam == pytest.approx(setup.inverse_mass, rel=1e-9)
