"""The PyBullet runner: one DIRECT client per process, fixed step, spring and damping forces by hand.

Design notes and measured figures: docs/engines.md.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field

import numpy as np

from treeimpact.analytic.budget import StepCost, check_work, progress
from treeimpact.analytic.contact.law import (
    collision_duration,
    contact_law,
    detection_duration,
    effective_damping,
    pad_fields,
)
from treeimpact.analytic.contact.timestep import check_time_step, choose_time_step, sdof_rate
from treeimpact.analytic.continuum.chain import (
    chain_matrices,
    chain_natural_frequencies,
    lateral_jacobian,
)
from treeimpact.analytic.engine.interface import (
    EngineSetup,
    chain_modes,
    check_choice,
    check_energy,
    engine_model,
    engine_result,
    trunk_chain,
    with_crown,
)
from treeimpact.analytic.errors import ParameterError, SimulationDiverged
from treeimpact.analytic.model.parameters import DEFAULT_CONTACT_DURATION, Scenario
from treeimpact.analytic.model.reduction import reduce_trunk
from treeimpact.analytic.model.two_body import TwoBodyModel
from treeimpact.analytic.results import ImpactRecord, SimulationResult

from . import _contact, _urdf
from ._loops import _loop_chain, _loop_sdof, _swing
from ._world import (
    JOINT_VELOCITY_LIMIT,
    RESTITUTION_THRESHOLD_FRACTION,
    build_world,
    client,
    engine_matrices,
    load,
)
from .options import CONTACTS, ENGINE_NAME, MAX_SEGMENTS, OPTIONS  # noqa: F401 - OPTIONS: public

__all__ = ["OPTIONS", "build_world", "client", "engine_matrices", "load", "make_setup",
           "modes", "run", "simulate", "simulate_batch"]


# ------------------------------------------------------------------------------------ setup
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


def make_setup(scenario: Scenario, *, trunk="chain", segments=None, pendulum="linear",
               contact="soft", contact_stiffness=None, dt=None, restitution=None, t_end=None,
               trunk_damping_model="distributed", calibration="pad") -> Setup:
    check_choice("contact", contact, CONTACTS)
    damping = trunk_damping_model
    model, t_end = engine_model(scenario, trunk=trunk, pendulum=pendulum,
                                trunk_damping_model=damping,
                                calibration=calibration, restitution=restitution,
                                t_end=t_end)
    if contact == "soft" and not model.restitution < 1.0:  # before the chain is built
        raise ParameterError(
            f"e = {model.restitution:g} (--restitution, contact.restitution): Bullet's soft "
            "contact steps "
            "implicitly and always dissipates: allowed (0, 1) with --contact soft (e = 1: "
            "--contact newton)")
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
    m = model.impactor_mass
    mu = apparent * m / (apparent + m)
    k_c = c_c = bullet = None
    if contact == "soft":
        k_c, c_c = contact_law(model, scenario.contact, stiffness=contact_stiffness)
        if calibration == "effective":  # e on the trunk's effective mass, not the pad's c_c
            c_c = effective_damping(k_c, model.restitution, mu)
        law_model = TwoBodyModel(apparent, 0.0, 1.0, m, 0.0, model.impact_speed,
                                 model.restitution)
        # the step resolves the collision Bullet integrates: stiffness k_c with the damping
        # that gives e on the apparent mass (as (k_b, c_b) below; the SDOF law's c_c on the
        # chain's light apparent mass would be overdamped and its duration not Bullet's)
        t_c = collision_duration(law_model, k_c, _contact.law_for_restitution(
            model.restitution, k_c, mu))
        fastest = omega_max if omega_max is not None else sdof_rate(model)
        if dt is None:
            dt = choose_time_step(t_c, fastest)
            limit = _contact.largest_time_step(k_c, c_c, mu)
            if dt > limit:
                dt = 0.9 * limit
        check_time_step(dt, t_c, fastest)
        check_work(t_end, dt, step_cost(segments or 1))  # before the replays of dt's steps
        bullet = _contact.bullet_contact(k_c, c_c, mu, dt)
        # Impacts are told from moving together on the scale of the SDOF model's free
        # collision, the same for every rung (the chain's local collision, t_c, is shorter).
        col = detection_duration(model, scenario.contact, stiffness=k_c)
    else:
        if contact_stiffness is not None:
            raise ParameterError("--contact-stiffness: only for --contact soft")
        w = omega_max if omega_max is not None else math.sqrt(
            (model.stiffness + model.impactor_stiffness) / min(model.dynamic_mass, m))
        if dt is None:
            dt = choose_time_step(DEFAULT_CONTACT_DURATION, omega_max)
        check_time_step(dt, math.pi / w, w)
        col = dt
    check_work(t_end, dt, step_cost(segments or 1))
    return Setup(scenario=scenario, model=model, trunk=trunk, pendulum=pendulum,
                 contact=contact, damping=damping, segments=segments, dt=float(dt),
                 t_end=float(t_end), trunk_urdf=trunk_urdf, pendulum_urdf=pend_urdf,
                 contact_stiffness=k_c, contact_damping=c_c, bullet=bullet,
                 collision_duration=col, omega_max=omega_max, apparent_mass=apparent,
                 matrices=matrices, calibration=calibration)


def step_cost(joints: int) -> StepCost:
    """One step of the Python loop (:mod:`._loops`) over ``joints`` trunk hinges: wall time
    and the bytes its record keeps, measured (benchmarks/bench_cost.py; docs/budgets.md):
    4 us + 2.05 us x joints (the joint-state reads and torques) and 250 B + 64 B x joints."""
    return StepCost(4e-6 + 2.05e-6 * joints, 250.0 + 64.0 * joints, f"{joints} trunk joints")


# ------------------------------------------------------------------------------------- run
def run(setup: Setup) -> SimulationResult:
    """Simulate ``setup``; the record starts at the first contact (t = 0)."""
    world = build_world(setup)
    p, cid = world.p, world.cid
    dt = setup.dt
    model = setup.model
    full = setup.pendulum == "full"
    imp = setup.scenario.impactor
    m = model.impactor_mass
    pb = world.pendulum
    if full:
        le, g = imp.equivalent_length, imp.gravity
        inertia = m * le * le * (1.0 + _urdf.BOB_INERTIA_FRACTION)
        t_shift, e0 = _swing(world, setup, le, g)
    else:
        le = g = inertia = None
        p.resetJointState(pb, 0, 0.0, model.impact_speed, physicsClientId=cid)
        t_shift, e0 = 0.0, model.initial_energy
    n_steps = int(math.ceil(setup.t_end / dt))
    loop = _loop_chain if setup.trunk == "chain" else _loop_sdof
    estimate = n_steps * step_cost(setup.segments or 1).seconds
    with progress("bullet", n_steps, estimate) as tick:
        rec = loop(world, setup, n_steps, full, le, g, m, tick)
    return _result(setup, rec, t_shift, e0, inertia)


def _result(setup: Setup, rec: dict, t_shift: float, e0: float, inertia) -> SimulationResult:
    model = setup.model
    dt = setup.dt
    m = model.impactor_mass
    full = setup.pendulum == "full"
    n = rec["x"].size
    t = np.arange(n) * dt - t_shift
    x, vx = rec["x"], rec["vx"]
    if full:
        imp = setup.scenario.impactor
        le, g = imp.equivalent_length, imp.gravity
        th, om = rec["q"], rec["qd"]
        y, vy = le * np.sin(th), le * np.cos(th) * om
        pend_kin = 0.5 * inertia * om * om
        pend_pot = m * g * le * (1.0 - np.cos(th))
    else:
        y, vy = rec["q"], rec["qd"]
        pend_kin = 0.5 * m * vy * vy
        pend_pot = 0.5 * model.impactor_stiffness * y * y
    if setup.trunk == "chain":
        trunk_kin, trunk_pot = rec["trunk_kinetic"], rec["trunk_potential"]
        d_power = rec["damping_power"]
    else:
        trunk_kin = 0.5 * model.dynamic_mass * vx * vx
        trunk_pot = 0.5 * model.stiffness * x * x
        d_power = model.damping * vx[:-1] * 0.5 * (vx[:-1] + vx[1:])
    force = rec["force"]
    rel = vy - vx
    c_power = force[:-1] * 0.5 * (rel[:-1] + rel[1:])
    damping_work = np.concatenate([[0.0], np.cumsum(d_power) * dt])
    contact_work = np.concatenate([[0.0], np.cumsum(c_power) * dt])
    if setup.contact == "soft":
        overlap = np.where(force > 0.0, np.maximum(y - x, 0.0), 0.0)
        c_pot = 0.5 * setup.bullet.stiffness * overlap ** 2  # Bullet's spring k_b
    else:
        c_pot = np.zeros(n)
    if not rec["joint_speed"] < 0.5 * JOINT_VELOCITY_LIMIT:  # NaN included
        raise SimulationDiverged(
            f"bullet: a joint speed reached {rec['joint_speed']:.4g} (rad/s or m/s), near "
            f"Bullet's clamp {JOINT_VELOCITY_LIMIT:g} (dt = {dt:.3g} s)")
    kinetic = trunk_kin + pend_kin
    potential = trunk_pot + pend_pot
    check_energy("bullet", kinetic + potential, e0, dt)
    # the force of step n acts from sample n to n + 1; the last sample repeats it
    force_rec = force.copy()
    force_rec[-1] = force[-2]
    record = ImpactRecord(t=t, x=x, vx=vx, y=y, vy=vy, force=force_rec, kinetic=kinetic,
                          potential=potential, damping_work=damping_work,
                          contact_work=contact_work, contact_potential=c_pot,
                          pendulum_energy=pend_kin + pend_pot)
    if setup.trunk == "chain":  # the chain's top
        record = with_crown(record, rec["crown"], rec["crown_velocity"])
    b = setup.bullet
    return engine_result(
        "bullet", record, scenario=setup.scenario, model=model, t_end=setup.t_end,
        collision_duration=setup.collision_duration,
        detection_duration=setup.collision_duration, initial_energy=e0, model_fields={
            "segments": setup.segments, "dt": dt,
            "contact_stiffness": setup.contact_stiffness,
            "contact_damping": setup.contact_damping,
            "engine_contact_stiffness": b.stiffness if b else None,
            "engine_contact_damping": b.damping if b else None,
            "trunk": setup.trunk, "pendulum": setup.pendulum,
            "trunk_damping_model": setup.damping,
            "calibration": setup.calibration,
            **pad_fields(setup.contact_stiffness, setup.contact_damping,
                         b.reduced_mass if b else None),
            "touch_duration": setup.collision_duration,
            "integrator": "semi-implicit Euler",  # Bullet's only one (docs/engines.md)
            "omega_max": setup.omega_max,
            "contact": setup.contact, "apparent_mass": setup.apparent_mass,
            "contact_erp": b.erp if b else 0.0, "contact_cfm": b.cfm if b else 0.0,
            "restitution_velocity_threshold": (
                RESTITUTION_THRESHOLD_FRACTION * model.impact_speed
                if setup.contact == "newton" else 0.0)})


def simulate(scenario: Scenario, *, trunk="chain", segments=None, pendulum="linear",
             contact="soft", contact_stiffness=None, dt=None, restitution=None, t_end=None,
             trunk_damping_model="distributed", calibration="pad") -> SimulationResult:
    """Run one scenario in PyBullet (rules in the module docstring); backend "bullet".

    ``calibration``: "pad" (default) the SDOF rung's (k_c, c_c); "effective" c_c
    recalibrated so that e holds on the trunk's effective mass at the clamp.
    """
    return run(make_setup(scenario, trunk=trunk, segments=segments, pendulum=pendulum,
                          contact=contact, contact_stiffness=contact_stiffness, dt=dt,
                          restitution=restitution, t_end=t_end,
                          trunk_damping_model=trunk_damping_model,
                          calibration=calibration))


def _batch_one(args):
    scenario, options = args
    try:
        return simulate(scenario, **options)
    except SimulationDiverged as exc:
        return exc


def simulate_batch(scenarios, *, max_workers=None, **options) -> list:
    """Simulate many scenarios over a process pool (one PyBullet client per process).

    Returns, in order, a SimulationResult or the SimulationDiverged of each scenario;
    bad options raise ParameterError before any process starts.
    """
    import concurrent.futures as cf
    import multiprocessing as mp

    scenarios = list(scenarios)
    for s in scenarios:  # validate everything here, with one-line errors
        make_setup(s, **options)
    if not scenarios:
        return []
    workers = max_workers or min(len(scenarios), os.cpu_count() or 1)
    if workers <= 1:
        return [_batch_one((s, options)) for s in scenarios]
    ctx = mp.get_context("spawn")  # a forked child would share the parent's client
    with cf.ProcessPoolExecutor(max_workers=workers, mp_context=ctx) as pool:
        return list(pool.map(_batch_one, [(s, options) for s in scenarios]))


def modes(scenario: Scenario, *, segments=None, n_modes: int = 3) -> dict:
    """Static stiffness at a (N/m) and natural frequencies (rad/s) of Bullet's chain: mass
    matrix (``calculateMassMatrix`` at rest) and clamp Jacobian (``calculateJacobian``) from
    the engine, the hinge springs the runner applies
    (:func:`analytic.engine.interface.chain_modes`);
    ``beam``: the continuous beam."""
    if not isinstance(scenario, Scenario):
        raise ParameterError("scenario: expected an analytic.Scenario")
    chain = trunk_chain(scenario, "chain", segments, engine=ENGINE_NAME,
                        max_segments=MAX_SEGMENTS)
    M, J = engine_matrices(chain)
    return chain_modes(scenario, M, chain.hinge_stiffnesses, J, n_modes)
