"""The MuJoCo engine's setup: validate the options, build and compile the model, fix the
contact law on the model's own effective mass and the time step. Nothing is stepped here.

Design notes and measured figures: docs/engines.md (``mujoco_models/_runner.py``, Setup).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field

import mujoco
import numpy as np
import scipy.linalg

from treeimpact.analytic.budget import check_work
from treeimpact.analytic.contact.law import (
    contact_law,
    damping_ratio_for_restitution,
    detection_duration,
    pad_restitution,
    release_time,
)
from treeimpact.analytic.contact.timestep import check_time_step, choose_time_step, sdof_rate
from treeimpact.analytic.continuum.chain import chain_matrices, default_segments, lateral_jacobian
from treeimpact.analytic.engine.interface import (
    ENERGY_GROWTH_LIMIT,
    EngineSetup,
    check_choice,
    engine_model,
    trunk_chain,
    trunk_options,
)
from treeimpact.analytic.engine.phases import PhaseRule, input_energy, phase_rule
from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.model.parameters import Scenario
from treeimpact.analytic.model.reduction import reduce_trunk
from treeimpact.analytic.model.two_body import TwoBodyModel

from . import _builder, _contact, _flex
from ._matrices import (
    _mass_matrix_at_rest,
    engine_trunk_matrices,
    flex_trunk_matrices,
    highest_frequency,
)
from ._record import _damping_matrices, _rest_potential
from ._rollout import _initial_qpos_qvel, _state, step_cost, step_cost_of
from ._warnings import compile_spec, mujoco_warnings
from .options import INTEGRATORS, TRUNKS

PLACEHOLDER_DT = 1e-5  # s: time step of the first compile (only its masses are used)
RK4_DAMPING_LIMIT = 2.785  # h lambda: RK4's stability limit on the negative real axis (2.7853)
RK4_RESTITUTION_TOLERANCE = 0.01  # |e - target| of the replayed RK4 free collision (RK4 gets
# the law uncorrected): beyond it the run's contact is not the scenario's (the speed curves stay
# within 1e-3 at >= 3 steps per collision; dt = 1.86e-4 s on a 0.5 ms contact gives 0.22)
SETUP_CACHE_SIZE = 64  # setups kept by make_setup (a repeated run does not recompile)
#: Steps per period of the trunk's highest mode in the default step (docs/time-step.md): a
#: chain's highest mode is its discretisation's, far above the beam's resolved modes; 10
#: steps (omega dt = 0.63, a third of the stability limit 2) leave the metrics the ladder
#: compares a 32-segment chain by within 0.5 % of 20 steps' (benchmarks/bench_chains.py);
#: the chains of fewer than about 20 segments are stepped by their contact and do not change.
STEPS_PER_PERIOD = 10

#: Stepping by phase by default (analytic.engine.phases; docs/engines.md "Stepping by
#: phase"): every metric the ladder compares, on every shipped tree and the light
#: pendulum's, within its tolerance of the fixed step (benchmarks/results/chain_phases.json).
PHASED = True

#: The trunk's root body per trunk model (its subtree's gravity is compensated).
ROOT_BODIES = {"sdof": "trunk", "chain": "segment_0", "flex": "trunk_root"}


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
    step_set_by: str = "given"  # what set dt: "given", "contact" or "highest mode"
    #: stepping by phase (analytic.engine.phases); None: every step is dt
    phases: PhaseRule | None = field(default=None, compare=False)

    @property
    def effective_mass(self) -> float:
        """mu_eff = 1 / A, kg: the pair's reduced mass as the contact sees it."""
        return 1.0 / self.inverse_mass

    @property
    def trunk_root(self) -> str:
        """The trunk's root body (:data:`ROOT_BODIES`)."""
        return ROOT_BODIES[self.trunk]


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


@mujoco_warnings
def make_setup(scenario: Scenario, *, trunk="chain", segments=None, pendulum="linear",
               dt=None, trunk_damping_model=None, integrator="Euler", calibration=None
               ) -> Setup:
    """Validate the options and compile the model of ``scenario`` (rules in the module
    docstring): ``trunk``, ``segments``, ``pendulum``, ``dt`` (s), ``trunk_damping_model``,
    ``integrator`` and ``calibration`` as in :func:`mujoco_models._runner.simulate`;
    ParameterError for a bad one.

    Setups are cached per (scenario, options) (the last :data:`SETUP_CACHE_SIZE`): a repeated
    run does not recompile. Do not modify ``setup.mjmodel`` in place; copy it.
    """
    if not isinstance(scenario, Scenario):  # before hashing it for the cache
        raise ParameterError("scenario: expected an analytic.Scenario")
    try:
        setup = _cached_setup(scenario, trunk, segments, pendulum, dt, trunk_damping_model,
                              integrator, calibration)
    except TypeError:  # an unhashable option value: validate and build without the cache
        return _make_setup(scenario, trunk, segments, pendulum, dt, trunk_damping_model,
                           integrator, calibration)
    _check_work(setup.mjmodel, setup.t_end, setup.dt)  # the budget may have changed since
    return setup


def build_model(scenario: Scenario, **options) -> mujoco.MjModel:
    """The compiled MjModel the runner would step for ``scenario`` and ``options``."""
    return make_setup(scenario, **options).mjmodel


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
        dt = choose_time_step(t_c, float(math.sqrt(w2[0])), steps_per_period=STEPS_PER_PERIOD)
    check_work(t_end, dt, step_cost_of(chain.segments + 1))


@functools.lru_cache(maxsize=SETUP_CACHE_SIZE)
def _cached_setup(*args) -> Setup:
    return _make_setup(*args)


def _make_setup(scenario, trunk, segments, pendulum, dt, damping, integrator, calibration
                ) -> Setup:
    """:func:`make_setup` without its cache (the options in its order, positional)."""
    check_choice("integrator", integrator, INTEGRATORS)
    damping, calibration = trunk_options(trunk, damping, calibration)
    t_end = float(scenario.t_end)
    model = engine_model(scenario, trunk=trunk, pendulum=pendulum,
                         trunk_damping_model=damping,
                         calibration=calibration, trunks=TRUNKS)
    if trunk == "flex":
        _flex.check_flex_options(integrator, damping)
    if not model.restitution > 0.0:
        raise ParameterError("contact.restitution = 0: a soft contact needs e in (0, 1] (e = 0 "
                             "needs infinite damping)")
    k, c_pad = contact_law(model, scenario.contact)
    tspec, n = _trunk_spec(scenario, trunk, segments, damping)
    if tspec.chain is not None:  # a chain's budget before seconds of building it
        _check_work_before_building(model, scenario, tspec.chain, k, c_pad, t_end, dt,
                                    calibration)
    spec, pair = _builder.build_spec(f"{scenario.name}-{trunk}-{pendulum}", tspec, scenario,
                                     pendulum, PLACEHOLDER_DT, integrator=integrator)
    fit = _fit_contact(compile_spec(spec), model, tspec, k, c_pad, dt, t_end, integrator,
                       calibration)
    pair.solref = list(fit.solref)
    spec.option.timestep = fit.dt
    mjmodel = compile_spec(spec)
    if integrator == "RK4":
        _check_rk4_damping(mjmodel, fit.dt)
    root = mujoco.mj_name2id(mjmodel, mujoco.mjtObj.mjOBJ_BODY, ROOT_BODIES[trunk])
    state0 = _state(mjmodel, *_initial_qpos_qvel(mjmodel, pendulum, model, scenario))
    state0.flags.writeable = False
    return Setup(scenario=scenario, model=model, trunk=trunk, pendulum=pendulum,
                 damping=damping, segments=n, dt=float(fit.dt), t_end=float(t_end),
                 law=fit.law, collision_duration=fit.collision_duration,
                 detection_duration=detection_duration(model, scenario.contact, stiffness=k),
                 omega_max=fit.omega_max, inverse_mass=fit.inverse_mass,
                 calibration=calibration, inverse_mass_approx=fit.inverse_mass_approx,
                 solref=tuple(fit.solref), integrator=integrator, mjmodel=mjmodel, spec=spec,
                 initial_state=state0, rest_potential=_rest_potential(mjmodel, root),
                 flex=tspec.flex, step_set_by=fit.step_set_by,
                 phases=_phases(fit, model, scenario, pendulum, integrator))


def _phases(fit, model, scenario, pendulum: str, integrator: str) -> PhaseRule | None:
    """The run's stepping by phase (analytic.engine.phases) when :data:`PHASED` and the
    rule chose its step
    (a given --dt is every step) and the integrator is Euler's or an implicit one (RK4 gets
    the contact law uncorrected and applies its dampers explicitly at each stage: not
    phased); None otherwise and for the SDOF trunk."""
    if not PHASED or fit.step_set_by == "given" or integrator == "RK4":
        return None
    return phase_rule(fit.dt, fit.omega_max, input_energy(model, scenario, pendulum),
                      fit.collision_duration, STEPS_PER_PERIOD, ENERGY_GROWTH_LIMIT)


@dataclass(frozen=True)
class _ContactFit:
    """The contact law fixed on a compiled model's own effective mass, and the time step."""

    inverse_mass: float  # A, 1/kg
    inverse_mass_approx: float  # MuJoCo's diagApprox of the pair, 1/kg
    collision_duration: float  # s: free collision of the law on mu_eff = 1 / A
    omega_max: float | None  # rad/s: highest mode of the engine's trunk (None: SDOF)
    dt: float  # s
    law: _contact.EngineLaw
    solref: tuple
    step_set_by: str  # "given", "contact" (t_c) or "highest mode" (omega_max)


def _fit_contact(m1: mujoco.MjModel, model: TwoBodyModel, tspec, k: float, c_pad: float, dt,
                 t_end: float, integrator: str, calibration: str) -> _ContactFit:
    """The pad (k, c_pad) on the placeholder model ``m1``'s effective mass 1 / A: its e
    (calibration "pad") or the scenario's, the free collision, the step (given ``dt`` checked,
    or chosen), the law MuJoCo's integrator needs and its solref."""
    A, A_hat = _builder.contact_inverse_masses(m1)
    mu = 1.0 / A
    e = model.restitution
    if calibration == "pad":  # the SDOF's (k_c, c_c): the e it gives on this model's mu
        e = pad_restitution(k, c_pad, mu)
    zeta = damping_ratio_for_restitution(e)
    t_c = release_time(zeta) / math.sqrt(k / mu)
    omega_max = highest_frequency(*engine_trunk_matrices(m1)) if tspec.kind == "chain" else \
        highest_frequency(*flex_trunk_matrices(m1, tspec.flex)) if tspec.kind == "flex" else None
    fastest = omega_max if omega_max is not None else sdof_rate(model)
    reason = "given"
    if dt is None:
        dt = choose_time_step(t_c, fastest, steps_per_period=STEPS_PER_PERIOD)
        reason = "highest mode" if dt < choose_time_step(t_c) else "contact"
    dt = check_time_step(dt, t_c, fastest)
    _check_work(m1, t_end, dt)
    law = _contact.engine_law(float(k), float(e), float(mu), float(dt), integrator)
    if abs(law.uncorrected_restitution - e) > RK4_RESTITUTION_TOLERANCE and integrator == "RK4":
        raise ParameterError(
            f"--dt = {dt:.3g} s with --integrator RK4: one free collision rebounds at e = "
            f"{law.uncorrected_restitution:.3g} instead of {e:g} ({law.steps_per_collision} "
            f"steps per collision; allowed |error| <= {RK4_RESTITUTION_TOLERANCE:g}): a "
            "smaller --dt")
    solref = _contact.solref_for_law(law.stiffness, law.damping,
                                     _contact.effective_denominator(A, A_hat))
    return _ContactFit(A, A_hat, t_c, omega_max, dt, law, solref, reason)


def _check_rk4_damping(mjmodel: mujoco.MjModel, dt: float) -> None:
    """Refuse a dt at which RK4's explicit dampers are unstable (module docstring)."""

    C = sum(_damping_matrices(mjmodel))
    rate = float(np.max(scipy.linalg.eigvalsh(C, _mass_matrix_at_rest(mjmodel))))
    if dt * rate >= RK4_DAMPING_LIMIT:
        raise ParameterError(
            f"--integrator = 'RK4': dt = {dt:.3g} s is too large for stability: RK4 applies "
            f"the dampers explicitly, fastest damping rate {rate:.4g} 1/s, allowed (0, "
            f"{RK4_DAMPING_LIMIT / rate:.3g}) s")
