"""The MuJoCo runner: build the model, roll it out with ``mujoco.rollout``, turn the record into metrics.

Design notes and measured figures: docs/engines.md.
"""

from __future__ import annotations

import functools
import math
import os
import sys
import warnings
from dataclasses import dataclass, field

import mujoco
import numpy as np

from treeimpact.analytic.budget import check_work
from treeimpact.analytic.contact.law import (
    contact_law,
    damping_ratio_for_restitution,
    detection_duration,
    pad_restitution,
    release_time,
)
from treeimpact.analytic.contact.timestep import check_time_step, choose_time_step, sdof_rate
from treeimpact.analytic.continuum.chain import default_segments
from treeimpact.analytic.continuum.modes import beam_reference
from treeimpact.analytic.engine.interface import (
    EngineSetup,
    chain_modes,
    check_choice,
    engine_model,
    trunk_chain,
)
from treeimpact.analytic.errors import ParameterError, SimulationDiverged
from treeimpact.analytic.model.parameters import Scenario
from treeimpact.analytic.model.reduction import reduce_trunk
from treeimpact.analytic.results import SimulationResult

from . import _builder, _contact, _flex
from ._record import _damping_matrices, _rest_potential, _result
from ._rollout import _initial_qpos_qvel, _plan, _run_group, _signature, _state, step_cost
from .options import INTEGRATORS, OPTIONS, TRUNKS  # noqa: F401 - OPTIONS: public here too

_WARNED: set = set()
#: While :func:`run_setups` steps: the MuJoCo warnings of its rollouts (a diverged run's
#: message carries the first; a run that ends well has them told on stderr afterwards).
_COLLECTED: list | None = None


def _warning_to_stderr(message: str) -> None:
    """MuJoCo's warnings on stderr as treeimpact's own one-line warnings, each kind once per
    process: never on stdout (JSON) and never in a MUJOCO_LOG.TXT in the user's working
    directory (MuJoCo's default handler); during a rollout, collected (:data:`_COLLECTED`)."""
    text = " ".join(message.split())
    if _COLLECTED is not None:
        _COLLECTED.append(text)
        return
    kind = text.split(" Time =")[0]
    if kind not in _WARNED:
        _WARNED.add(kind)
        print(f"treeimpact: warning: mujoco: {text}", file=sys.stderr, flush=True)


mujoco.set_mju_user_warning(_warning_to_stderr)


def compile_spec(spec: mujoco.MjSpec) -> mujoco.MjModel:
    """``spec.compile()`` with a compiler warning (a UserWarning since MuJoCo 4.0; 3.x raised)
    sent to stderr like the runtime ones; the shipped models compile without any (tested)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        model = spec.compile()
    for w in caught:
        _warning_to_stderr(f"compiler: {w.message}")
    return model

PLACEHOLDER_DT = 1e-5  # s: time step of the first compile (only its masses are used)
RK4_DAMPING_LIMIT = 2.785  # h lambda: RK4's stability limit on the negative real axis (2.7853)
RK4_RESTITUTION_TOLERANCE = 0.01  # |e - target| of the replayed RK4 free collision (RK4 gets
# the law uncorrected): beyond it the run's contact is not the scenario's (the speed curves stay
# within 1e-3 at >= 3 steps per collision; dt = 1.86e-4 s on a 0.5 ms contact gives 0.22)


@dataclass(frozen=True)
class Setup(EngineSetup):
    """A compiled model and everything the run needs (SI units)."""
    law: _contact.EngineLaw
    collision_duration: float  # s: free collision of the law on mu_eff
    detection_duration: float  # s: analytic.contact.law.detection_duration, common to all rungs
    omega_max: float | None  # rad/s: highest mode of the engine's chain
    inverse_mass: float  # A, 1/kg
    inverse_mass_approx: float  # MuJoCo's diagApprox of the pair, 1/kg
    solref: tuple
    integrator: str
    calibration: str  # "pad" or "effective" (analytic.contact.law.CALIBRATIONS)
    mjmodel: mujoco.MjModel = field(repr=False, compare=False)
    spec: mujoco.MjSpec = field(repr=False, compare=False)
    # computed once per setup (a run does not rebuild MjData for them):
    initial_state: np.ndarray = field(repr=False, compare=False)  # mjSTATE_FULLPHYSICS, t = 0
    rest_potential: float = field(repr=False, compare=False)  # J: springs + pendulum gravity
    flex: _flex.FlexTrunk | None = field(default=None, repr=False, compare=False)

    @property
    def effective_mass(self) -> float:
        return 1.0 / self.inverse_mass

    @property
    def trunk_root(self) -> str:
        return ROOT_BODIES[self.trunk]


#: The trunk's root body per trunk model (its subtree's gravity is compensated).
ROOT_BODIES = {"sdof": "trunk", "chain": "segment_0", "flex": "trunk_root"}


def cable_refusal() -> ParameterError:
    """``--trunk cable``: the installed MuJoCo has no cable plugin (removed in 4.0)."""
    return ParameterError(
        f"--trunk = 'cable': the installed MuJoCo {mujoco.__version__} has no cable elasticity "
        "plugin (removed in MuJoCo 4.0, superseded by the 1-D flex): use --trunk flex")


def _trunk_spec(scenario: Scenario, trunk: str, segments, damping) -> tuple:
    if trunk == "cable":
        raise cable_refusal()
    if trunk == "flex":
        n = default_segments(scenario.trunk) if segments is None else segments
        rod = _flex.flex_trunk(scenario.trunk, n)
        return _builder.TrunkSpec("flex", None, None, damping, rod), rod.segments
    chain = trunk_chain(scenario, trunk, segments)
    if chain is not None:
        return _builder.TrunkSpec("chain", None, chain, damping), chain.segments
    return _builder.TrunkSpec("sdof", reduce_trunk(scenario.trunk), None, damping), None


def _mass_matrix_at_rest(mjmodel: mujoco.MjModel) -> np.ndarray:
    """The full generalised mass matrix (``mj_fullM``) at the initial configuration."""
    data = mujoco.MjData(mjmodel)
    mujoco.mj_forward(mjmodel, data)
    M = np.zeros((mjmodel.nv, mjmodel.nv))
    mujoco.mj_fullM(mjmodel, data, M)
    return M


def _hinges(mjmodel: mujoco.MjModel) -> list[int]:
    """Ids of the trunk's hinge joints (named hinge_*)."""
    return [j for j in range(mjmodel.njnt)
            if mujoco.mj_id2name(mjmodel, mujoco.mjtObj.mjOBJ_JOINT, j).startswith("hinge_")]


def engine_trunk_matrices(mjmodel: mujoco.MjModel) -> tuple[np.ndarray, np.ndarray]:
    """(M, K) of the trunk's hinges from the engine: ``mj_fullM`` at rest and the joint stiffnesses."""
    hinges = _hinges(mjmodel)
    dofs = [int(mjmodel.jnt_dofadr[j]) for j in hinges]
    M = _mass_matrix_at_rest(mjmodel)
    return M[np.ix_(dofs, dofs)], np.diag(mjmodel.jnt_stiffness[hinges])


def flex_trunk_matrices(mjmodel: mujoco.MjModel, rod: _flex.FlexTrunk
                        ) -> tuple[np.ndarray, np.ndarray]:
    """(M, K) of the flex trunk's dofs (root hinge if any, vertex slides): ``mj_fullM`` at
    rest and the rod's bending Hessian (:func:`mujoco_models._flex.stiffness_matrix`)."""
    root, verts = _flex.flex_dofs(mjmodel)
    dofs = ([root] if root is not None else []) + verts  # slides and hinges: qpos = dof adr
    M = _mass_matrix_at_rest(mjmodel)
    return M[np.ix_(dofs, dofs)], _flex.stiffness_matrix(rod, root is not None)


def highest_frequency(M: np.ndarray, K: np.ndarray) -> float:
    """Largest omega (rad/s) of K v = omega^2 M v."""
    import scipy.linalg

    w2 = scipy.linalg.eigh(K, M, eigvals_only=True)
    return float(math.sqrt(w2[-1]))


def make_setup(scenario: Scenario, *, trunk="chain", segments=None, pendulum="linear",
               contact_stiffness=None, dt=None, restitution=None, t_end=None,
               trunk_damping_model="distributed", integrator="Euler", calibration="pad"
               ) -> Setup:
    """Validate the options and compile the model (rules in the module docstring).

    Setups are cached per (scenario, options) (the last :data:`SETUP_CACHE_SIZE`): a repeated
    run does not recompile. Do not modify ``setup.mjmodel`` in place; copy it.
    """
    if not isinstance(scenario, Scenario):  # before hashing it for the cache
        raise ParameterError("scenario: expected an analytic.Scenario")
    try:
        setup = _cached_setup(scenario, trunk, segments, pendulum, contact_stiffness, dt,
                              restitution, t_end, trunk_damping_model, integrator,
                              calibration)
    except TypeError:  # an unhashable option value: validate and build without the cache
        return _make_setup(scenario, trunk, segments, pendulum, contact_stiffness, dt,
                           restitution, t_end, trunk_damping_model, integrator,
                           calibration)
    _check_work(setup.mjmodel, setup.t_end, setup.dt)  # the budget may have changed since
    return setup


def _check_work(m: mujoco.MjModel, t_end: float, dt: float) -> None:
    """The run's budget (:func:`analytic.budget.check_work`) at :func:`step_cost`."""
    check_work(t_end, dt, step_cost(m))


def _check_work_before_building(model, scenario, chain, k: float, c: float, t_end: float,
                                dt, calibration: str) -> None:
    """The chain's budget from its analytic twin (analytic.continuum.chain: the same masses,
    hinges and clamp), before its MuJoCo model is built and compiled (9 s for 1000
    segments): the pad's touch on the chain's effective mass at the clamp and its highest
    mode set the step as :func:`_make_setup` does, one degree of freedom per segment and
    the pendulum's the cost."""
    import scipy.linalg

    from treeimpact.analytic.continuum.chain import chain_matrices, lateral_jacobian

    from ._rollout import step_cost_of

    M, K, _ = chain_matrices(chain)
    ja = lateral_jacobian(chain, scenario.trunk.clamp_height)[0]
    apparent = float(1.0 / (ja @ np.linalg.solve(M, ja)))
    m = model.impactor_mass
    mu = apparent * m / (apparent + m)
    e = pad_restitution(k, c, mu) if calibration == "pad" else model.restitution
    t_c = release_time(damping_ratio_for_restitution(e)) / math.sqrt(k / mu)
    if dt is None:
        n = chain.segments  # the highest mode only (all of them: 16 s at 1000 segments)
        w2 = scipy.linalg.eigh(K, M, eigvals_only=True, subset_by_index=[n - 1, n - 1])
        dt = choose_time_step(t_c, float(math.sqrt(w2[0])))
    check_work(t_end, dt, step_cost_of(chain.segments + 1))


SETUP_CACHE_SIZE = 64


@functools.lru_cache(maxsize=SETUP_CACHE_SIZE)
def _cached_setup(*args) -> Setup:
    return _make_setup(*args)


def _make_setup(scenario, trunk, segments, pendulum, contact_stiffness, dt, restitution,
                t_end, damping, integrator, calibration) -> Setup:
    check_choice("integrator", integrator, INTEGRATORS)
    model, t_end = engine_model(scenario, trunk=trunk, pendulum=pendulum,
                                trunk_damping_model=damping,
                                calibration=calibration, restitution=restitution,
                                t_end=t_end, trunks=TRUNKS)
    if trunk == "flex":
        _flex.check_flex_options(integrator, damping)
    e = model.restitution
    if not e > 0.0:
        raise ParameterError("--restitution = 0: a soft contact needs e in (0, 1] (e = 0 "
                             "needs infinite damping)")
    k, c_pad = contact_law(model, scenario.contact, stiffness=contact_stiffness)
    tspec, n = _trunk_spec(scenario, trunk, segments, damping)
    if tspec.chain is not None:  # a chain's budget before seconds of building it
        _check_work_before_building(model, scenario, tspec.chain, k, c_pad, t_end, dt,
                                    calibration)
    name = f"{scenario.name}-{trunk}-{pendulum}"
    spec, pair = _builder.build_spec(name, tspec, scenario, pendulum, PLACEHOLDER_DT,
                                     integrator=integrator)
    m1 = compile_spec(spec)
    A, A_hat = _builder.contact_inverse_masses(m1)
    mu = 1.0 / A
    if calibration == "pad":  # the SDOF's (k_c, c_c): the e it gives on this model's mu
        e = pad_restitution(k, c_pad, mu)
    zeta = damping_ratio_for_restitution(e)
    t_c = release_time(zeta) / math.sqrt(k / mu)
    omega_max = highest_frequency(*engine_trunk_matrices(m1)) if trunk == "chain" else \
        highest_frequency(*flex_trunk_matrices(m1, tspec.flex)) if trunk == "flex" else None
    fastest = omega_max if omega_max is not None else sdof_rate(model)
    if dt is None:
        dt = choose_time_step(t_c, fastest)
    dt = check_time_step(dt, t_c, fastest)
    _check_work(m1, t_end, dt)
    law = _contact.engine_law(float(k), float(e), float(mu), float(dt), integrator)
    if abs(law.uncorrected_restitution - e) > RK4_RESTITUTION_TOLERANCE and integrator == "RK4":
        raise ParameterError(
            f"--dt = {dt:.3g} s with --integrator RK4: one free collision rebounds at e = "
            f"{law.uncorrected_restitution:.3g} instead of {e:g} ({law.steps_per_collision} "
            f"steps per collision; allowed |error| <= {RK4_RESTITUTION_TOLERANCE:g}): a "
            "smaller --dt")
    S = _contact.effective_denominator(A, A_hat)
    solref = _contact.solref_for_law(law.stiffness, law.damping, S)
    pair.solref = list(solref)
    spec.option.timestep = dt
    mjmodel = compile_spec(spec)
    if integrator == "RK4":
        _check_rk4_damping(mjmodel, dt)
    root = mujoco.mj_name2id(mjmodel, mujoco.mjtObj.mjOBJ_BODY, ROOT_BODIES[trunk])
    state0 = _state(mjmodel, *_initial_qpos_qvel(mjmodel, pendulum, model, scenario))
    state0.flags.writeable = False
    return Setup(scenario=scenario, model=model, trunk=trunk, pendulum=pendulum,
                 damping=damping, segments=n, dt=float(dt), t_end=float(t_end), law=law,
                 collision_duration=t_c,
                 detection_duration=detection_duration(model, scenario.contact, stiffness=k),
                 omega_max=omega_max, inverse_mass=A, calibration=calibration,
                 inverse_mass_approx=A_hat, solref=tuple(solref), integrator=integrator,
                 mjmodel=mjmodel, spec=spec,
                 initial_state=state0, rest_potential=_rest_potential(mjmodel, root),
                 flex=tspec.flex)


def _check_rk4_damping(mjmodel: mujoco.MjModel, dt: float) -> None:
    """Refuse a dt at which RK4's explicit dampers are unstable (module docstring)."""
    import scipy.linalg

    C = sum(_damping_matrices(mjmodel))
    rate = float(np.max(scipy.linalg.eigvalsh(C, _mass_matrix_at_rest(mjmodel))))
    if dt * rate >= RK4_DAMPING_LIMIT:
        raise ParameterError(
            f"--integrator = 'RK4': dt = {dt:.3g} s is too large for stability: RK4 applies "
            f"the dampers explicitly, fastest damping rate {rate:.4g} 1/s, allowed (0, "
            f"{RK4_DAMPING_LIMIT / rate:.3g}) s")


def build_model(scenario: Scenario, **options) -> mujoco.MjModel:
    """The compiled MjModel the runner would step for ``scenario`` and ``options``."""
    return make_setup(scenario, **options).mjmodel


# ------------------------------------------------------------------------------------ API
def simulate(scenario: Scenario, *, trunk="chain", segments=None, pendulum="linear",
             contact_stiffness=None, dt=None, restitution=None, t_end=None,
             trunk_damping_model="distributed", integrator="Euler", calibration="pad"
             ) -> SimulationResult:
    """Run one scenario in MuJoCo (rules in the module docstring); backend "mujoco".

    ``integrator``: MuJoCo's ``Euler`` (default), ``implicit``, ``implicitfast`` or ``RK4``.
    ``calibration``: "pad" (default) the SDOF rung's (k_c, c_c); "effective" c_c
    recalibrated so that e holds on the trunk's effective mass at the clamp.
    """
    out = simulate_batch([scenario], trunk=trunk, segments=segments, pendulum=pendulum,
                         contact_stiffness=contact_stiffness, dt=dt, restitution=restitution,
                         t_end=t_end, trunk_damping_model=trunk_damping_model,
                         integrator=integrator,
                         calibration=calibration, max_workers=1)[0]
    if isinstance(out, SimulationDiverged):
        raise out
    return out


def run(setup: Setup) -> SimulationResult:
    """Roll out one compiled setup (the engine interface's ``run``)."""
    out = run_setups([setup], max_workers=1)[0]
    if isinstance(out, SimulationDiverged):
        raise out
    return out


def run_setups(setups: list[Setup], *, max_workers=None) -> list:
    """Roll out compiled setups; a SimulationResult or SimulationDiverged per setup, in order."""
    nthread = max_workers or os.cpu_count() or 1
    plans = [_plan(s) for s in setups]
    groups: dict = {}
    for i, p in enumerate(plans):
        groups.setdefault(_signature(p.setup.mjmodel), []).append(i)
    out = [None] * len(plans)
    global _COLLECTED
    _COLLECTED = seen = []
    try:
        for idx in groups.values():
            for i, (s0, st, sd) in zip(idx, _run_group([plans[i] for i in idx], nthread)):
                try:
                    out[i] = _result(setups[i], s0, st, sd)
                except SimulationDiverged as exc:
                    out[i] = exc
    finally:
        _COLLECTED = None
    return _with_warnings(out, seen)


def _with_warnings(out: list, seen: list) -> list:
    """``out`` with MuJoCo's first warning in each diverged run's message (one line, not a
    line of its own before it); told on stderr when a run ended well."""
    if not seen:
        return out
    diverged = [isinstance(r, SimulationDiverged) for r in out]
    out = [SimulationDiverged(f"{r} (MuJoCo warned: {seen[0]})") if bad else r
           for r, bad in zip(out, diverged)]
    if not all(diverged):
        for text in seen:
            _warning_to_stderr(text)
    return out


def simulate_batch(scenarios, *, max_workers=None, **options) -> list:
    """Simulate many scenarios with the same options through multi-threaded ``mujoco.rollout``.

    Models of one size signature (same trunk kind and segments) step together in one rollout
    call over ``max_workers`` threads (default: all CPUs). Returns, in order, a
    SimulationResult or the SimulationDiverged of each scenario; bad options raise
    ParameterError before anything is stepped.
    """
    setups = [make_setup(s, **options) for s in scenarios]
    return run_setups(setups, max_workers=max_workers)


def modes(scenario: Scenario, *, trunk="chain", segments=None, n_modes: int = 3) -> dict:
    """Static stiffness at a (N/m) and natural frequencies (rad/s) of MuJoCo's trunk from
    the engine: ``mj_fullM`` at rest with the compiled hinge stiffnesses and the impact
    point's ``mj_jacSite`` (chain, :func:`analytic.engine.interface.chain_modes`) or the
    rod's bending Hessian (flex, :func:`flex_modes`); ``beam``: the continuous beam."""
    if not isinstance(scenario, Scenario):
        raise ParameterError("scenario: expected an analytic.Scenario")
    check_choice("trunk", trunk, ("chain", "flex", "cable"))
    tspec, _ = _trunk_spec(scenario, trunk, segments, "distributed")
    spec, _ = _builder.build_spec(f"{scenario.name}-{trunk}-modes", tspec, scenario, "linear",
                                  PLACEHOLDER_DT)
    m = compile_spec(spec)
    if trunk == "flex":
        return flex_modes(scenario, m, tspec.flex, n_modes)
    M, K = engine_trunk_matrices(m)
    return chain_modes(scenario, M, np.diag(K), impact_jacobian(m), n_modes)


def flex_modes(scenario: Scenario, m: mujoco.MjModel, rod: _flex.FlexTrunk, n_modes) -> dict:
    """The flex trunk's static stiffness at a, 1 / (K^-1)_aa (N/m), and its lowest
    frequencies, eig(K, M) (rad/s), beside the beam's."""
    import scipy.linalg

    M, K = flex_trunk_matrices(m, rod)
    n = len(K)
    if isinstance(n_modes, bool) or not isinstance(n_modes, int) or not 1 <= n_modes <= n:
        raise ParameterError(f"n_modes = {n_modes!r} is out of range: allowed [1, {n}]")
    a = n - rod.segments + rod.clamp_vertex - 1  # the clamp vertex's slide among the dofs
    static = float(1.0 / np.linalg.solve(K, np.eye(n)[a])[a])
    w2 = scipy.linalg.eigh(K, M, eigvals_only=True, subset_by_index=[0, n_modes - 1])
    return {"model": {"static_stiffness": static, "omegas": [float(v) for v in np.sqrt(w2)],
                      "segments": rod.segments},
            "beam": beam_reference(scenario, n_modes)}


def impact_jacobian(m: mujoco.MjModel) -> np.ndarray:
    """d x(a) / d theta of the trunk's hinges from ``mj_jacSite`` at rest (m/rad)."""
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    jac = np.zeros((3, m.nv))
    mujoco.mj_jacSite(m, d, jac, None,
                      mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, "impact_point"))
    return jac[0, [int(m.jnt_dofadr[j]) for j in _hinges(m)]]
