"""The PyBullet engine's setup: validate the options, write the trunk's and pendulum's
URDFs, fix the contact law (soft: Bullet's ERP/CFM for the pad; newton: restitution
impulses) and the time step. Computed without the engine; nothing is stepped here.

Design notes and measured figures: docs/engines.md (``bullet_models/_runner.py``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from treeimpact.analytic.budget import StepCost, check_work
from treeimpact.analytic.contact.law import (
    collision_duration,
    contact_law,
    detection_duration,
    effective_damping,
)
from treeimpact.analytic.contact.timestep import check_time_step, choose_time_step, sdof_rate
from treeimpact.analytic.continuum.chain import (
    chain_matrices,
    chain_natural_frequencies,
    lateral_jacobian,
)
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
from treeimpact.analytic.model.parameters import DEFAULT_CONTACT_DURATION, Scenario
from treeimpact.analytic.model.reduction import reduce_trunk
from treeimpact.analytic.model.two_body import TwoBodyModel

from . import _contact, _urdf
from .options import CONTACTS, ENGINE_NAME, MAX_SEGMENTS

#: Stepping by phase by default (analytic.engine.phases; docs/engines.md "Stepping by
#: phase"): on, as MuJoCo's. Measured (benchmarks/results/chain_phases.json): every metric
#: the engines are compared by stays within its stated tolerance of the fixed step dt on
#: the six report chains and the light pendulum's, as dt / 2 does. The one count that moves
#: is a chattering one: central-leader's chain with the full pendulum contacts 22 times by
#: phase, 23 at dt, 22 at dt / 2 (by phase a 56 us touch at 37.3 ms, 3e-4 of the impulse,
#: joins the next contact; at dt / 2 two others 13 us apart join), so the count is not
#: converged in dt; the ladder's [step.pendulum] compares it within the grazing contacts
#: (compare.bounds.pendulum.contact_sequence: 22 and 23 within 7 of 23) and passes.
#: False: every run at the fixed step dt (the benchmark's other side).
PHASED = True

#: Steps per period of the trunk's highest mode in the default step, as MuJoCo's
#: (mujoco_models._setup.STEPS_PER_PERIOD, docs/time-step.md): 10, a third of the stability
#: limit omega dt = 2.
STEPS_PER_PERIOD = 10


@dataclass(frozen=True)
class Setup(EngineSetup):
    """Everything a run needs, computed without the engine (SI units)."""

    contact: str
    trunk_urdf: str
    pendulum_urdf: str
    contact_stiffness: float | None  # k_c, N/m (soft)
    contact_damping: float | None  # c_c, N s/m (soft, the continuous law)
    bullet: _contact.BulletContact | None
    collision_duration: float  # s: t_c of the soft law (soft) or dt (newton: one-step impulses)
    omega_max: float | None
    apparent_mass: float  # kg: trunk mass seen by the contact
    calibration: str = "pad"  # analytic.contact.law.CALIBRATIONS
    matrices: tuple | None = field(default=None, repr=False)  # chain (M, K, D)
    step_set_by: str = "given"  # what set dt (:data:`STEP_REASONS`)
    #: stepping by phase (analytic.engine.phases); None: every step is dt
    phases: PhaseRule | None = field(default=None, compare=False)


def make_setup(scenario: Scenario, *, trunk="chain", segments=None, pendulum="linear",
               contact="soft", dt=None, trunk_damping_model=None, calibration=None) -> Setup:
    """Validate the options and build everything a run of ``scenario`` needs, without the
    engine: ``trunk``, ``segments``, ``pendulum``, ``contact``, ``dt`` (s),
    ``trunk_damping_model`` and ``calibration`` as in
    :func:`bullet_models._runner.simulate`; ParameterError for a bad one (before any chain
    is built where it can)."""
    check_choice("contact", contact, CONTACTS)
    damping, calibration = trunk_options(trunk, trunk_damping_model, calibration)
    t_end = float(scenario.t_end)
    model = engine_model(scenario, trunk=trunk, pendulum=pendulum,
                         trunk_damping_model=damping,
                         calibration=calibration)
    if contact == "soft" and not model.restitution < 1.0:  # before the chain is built
        raise ParameterError(
            f"contact.restitution = {model.restitution:g}: Bullet's soft "
            "contact steps "
            "implicitly and always dissipates: allowed (0, 1) with --contact soft (e = 1: "
            "--contact newton)")
    bodies = _bodies(scenario, trunk, segments, pendulum)
    segments = bodies.segments
    if contact == "soft":
        k_c, c_c, bullet, dt, col, reason = _soft_contact(model, scenario, bodies, dt, t_end,
                                                          calibration)
    else:
        k_c = c_c = bullet = None
        dt, col, reason = _newton_contact(model, bodies, scenario.contact, dt)
    check_work(t_end, dt, step_cost(segments or 1))
    return Setup(scenario=scenario, model=model, trunk=trunk, pendulum=pendulum,
                 contact=contact, damping=damping, segments=segments, dt=float(dt),
                 t_end=float(t_end), trunk_urdf=bodies.trunk_urdf,
                 pendulum_urdf=bodies.pendulum_urdf, contact_stiffness=k_c,
                 contact_damping=c_c, bullet=bullet, collision_duration=col,
                 omega_max=bodies.omega_max, apparent_mass=bodies.apparent_mass,
                 matrices=bodies.matrices, calibration=calibration,
                 step_set_by=reason,
                 phases=_phases(model, scenario, pendulum, contact, dt, col, bodies, reason))


def _phases(model, scenario, pendulum: str, contact: str, dt: float, col: float, bodies,
            reason: str) -> PhaseRule | None:
    """The run's stepping by phase (analytic.engine.phases) when :data:`PHASED`, for the soft
    contact when the rule chose its step (a given --dt is every step); None otherwise, for
    the SDOF trunk and for Newton's impulses (a restitution impulse per contact, its step
    the contact's)."""
    if not PHASED or reason == "given" or contact != "soft":
        return None
    return phase_rule(dt, bodies.omega_max, input_energy(model, scenario, pendulum), col,
                      STEPS_PER_PERIOD, ENERGY_GROWTH_LIMIT)


@dataclass(frozen=True)
class _Bodies:
    """The trunk's and pendulum's URDFs and what the contact needs of the trunk (SI)."""

    trunk_urdf: str
    pendulum_urdf: str
    segments: int | None  # the chain's (None: the SDOF trunk)
    apparent_mass: float  # kg: the trunk's mass seen by the contact at a
    omega_max: float | None  # rad/s: the chain's highest mode (None: the SDOF trunk)
    matrices: tuple | None  # the chain's (M, K, D)


def _bodies(scenario: Scenario, trunk: str, segments, pendulum: str) -> _Bodies:
    """The chain (``segments``, default: the fewest within 0.5 % of the beam) or the SDOF
    trunk of eq 11, and the ``pendulum``'s model."""
    tr = scenario.trunk
    matrices = None
    chain = trunk_chain(scenario, trunk, segments, engine=ENGINE_NAME,
                        max_segments=MAX_SEGMENTS)
    if chain is not None:
        n = chain.segments
        M, K, D = chain_matrices(chain)
        ja = lateral_jacobian(chain, tr.clamp_height)[0]
        apparent = float(1.0 / (ja @ np.linalg.solve(M, ja)))
        omega_max = float(chain_natural_frequencies(chain, chain.segments)[-1])
        trunk_urdf = _urdf.trunk_chain_urdf(chain, name=f"{scenario.name}-trunk-chain-{n}")
        segments = n
        matrices = (M, K, D)
    else:
        tree = reduce_trunk(tr)
        apparent = tree.dynamic_mass
        omega_max = None
        trunk_urdf = _urdf.trunk_sdof_urdf(tree, tr.clamp_height,
                                           name=f"{scenario.name}-trunk-sdof")
    pend_urdf = _urdf.pendulum_urdf(scenario.impactor, tr.clamp_height, pendulum,
                                    name=f"{scenario.name}-pendulum-{pendulum}")
    return _Bodies(trunk_urdf, pend_urdf, segments, apparent, omega_max, matrices)


def _soft_contact(model: TwoBodyModel, scenario: Scenario, bodies: _Bodies, dt,
                  t_end: float, calibration: str) -> tuple:
    """(k_c N/m, c_c N s/m, Bullet's contact, dt s, detection duration s, what set dt
    (:data:`STEP_REASONS`)) of the pad on the trunk's apparent mass: the step from the
    collision Bullet integrates and the fastest mode (given ``dt`` checked), within the step
    Bullet's implicit contact can hold."""
    m = model.impactor_mass
    mu = bodies.apparent_mass * m / (bodies.apparent_mass + m)
    k_c, c_c = contact_law(model, scenario.contact)
    if calibration == "effective":  # e on the trunk's effective mass, not the pad's c_c
        c_c = effective_damping(k_c, model.restitution, mu)
    law_model = TwoBodyModel(bodies.apparent_mass, 0.0, 1.0, m, 0.0, model.impact_speed,
                             model.restitution)
    # the step resolves the collision Bullet integrates: stiffness k_c with the damping
    # that gives e on the apparent mass (as (k_b, c_b) below; the SDOF law's c_c on the
    # chain's light apparent mass would be overdamped and its duration not Bullet's)
    t_c = collision_duration(law_model, k_c, _contact.law_for_restitution(
        model.restitution, k_c, mu))
    fastest = bodies.omega_max if bodies.omega_max is not None else sdof_rate(model)
    reason = "given"
    if dt is None:
        dt = choose_time_step(t_c, fastest, steps_per_period=STEPS_PER_PERIOD)
        reason = step_reason(t_c, fastest)
        limit = _contact.largest_time_step(k_c, c_c, mu)
        if dt > limit:
            dt = 0.9 * limit
            reason = "implicit contact"
    check_time_step(dt, t_c, fastest)
    check_work(t_end, dt, step_cost(bodies.segments or 1))  # before the replays of dt's steps
    bullet = _contact.bullet_contact(k_c, c_c, mu, dt)
    # Impacts are told from moving together on the scale of the SDOF model's free
    # collision, the same for every rung (the chain's local collision, t_c, is shorter).
    return (k_c, c_c, bullet, dt, detection_duration(model, scenario.contact, stiffness=k_c),
            reason)


def _newton_contact(model: TwoBodyModel, bodies: _Bodies, contact, dt) -> tuple:
    """(dt s, detection duration s = dt, what set dt) of Bullet's restitution impulses: the
    step from the default contact duration and the fastest mode (given ``dt`` checked); a
    pad given by its stiffness (``contact.stiffness``) is refused: the impulses have none."""
    if contact.stiffness is not None:
        raise ParameterError(f"contact.stiffness = {contact.stiffness:g} N/m: only for "
                             "--contact soft (Bullet's restitution impulses have no pad)")
    m = model.impactor_mass
    w = bodies.omega_max if bodies.omega_max is not None else math.sqrt(
        (model.equivalent_stiffness + model.impactor_stiffness) / min(model.dynamic_mass, m))
    reason = "given"
    if dt is None:
        dt = choose_time_step(DEFAULT_CONTACT_DURATION, bodies.omega_max,
                              steps_per_period=STEPS_PER_PERIOD)
        reason = step_reason(DEFAULT_CONTACT_DURATION, bodies.omega_max)
    check_time_step(dt, math.pi / w, w)
    return dt, dt, reason


#: What can set a run's step: ``--dt`` given; the collision (t_c / steps per collision);
#: the chain's highest mode (its period / steps per period); Bullet's implicit contact (0.9
#: of the largest step at which it keeps the law's e, :func:`._contact.largest_time_step`).
STEP_REASONS = ("given", "contact", "highest mode", "implicit contact")


def step_reason(collision_duration: float, fastest: float | None) -> str:
    """Which term of :func:`analytic.contact.timestep.choose_time_step` sets the default
    step for a collision of ``collision_duration`` (s) and the ``fastest`` rate (rad/s or
    1/s, the chain's highest mode; None: none): "contact" or "highest mode"."""
    if fastest is None:
        return "contact"
    with_mode = choose_time_step(collision_duration, fastest,
                                 steps_per_period=STEPS_PER_PERIOD)
    return "highest mode" if with_mode < choose_time_step(collision_duration) else "contact"


def step_cost(joints: int) -> StepCost:
    """One step of the Python loop (:mod:`._loops`) over ``joints`` trunk hinges: wall time
    and the bytes its record keeps, measured (benchmarks/bench_cost.py; docs/budgets.md):
    4 us + 2.05 us x joints (the joint-state reads and torques) and 250 B + 64 B x joints."""
    return StepCost(4e-6 + 2.05e-6 * joints, 250.0 + 64.0 * joints, f"{joints} trunk joints")
