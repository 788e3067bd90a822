"""The PyBullet runner: one DIRECT client per process, fixed step, spring and damping forces
by hand; the engine interface's names in one place.

The setup: :mod:`._setup`; the world: :mod:`._world`; the stepping: :mod:`._loops`; record
-> metrics: :mod:`._record`. Design notes and measured figures: docs/engines.md.
"""

from __future__ import annotations

import concurrent.futures as cf
import math
import multiprocessing as mp
import os
import time

import numpy as np

from treeimpact.analytic.budget import progress
from treeimpact.analytic.engine.interface import chain_modes, trunk_chain
from treeimpact.analytic.errors import ParameterError, SimulationDiverged
from treeimpact.analytic.model.parameters import Scenario
from treeimpact.analytic.results import SimulationResult
from treeimpact.analytic.threads import limit_process

from . import _urdf
from ._loops import _loop_chain, _loop_sdof, _swing
from ._record import _result
from ._setup import Setup, make_setup, step_cost
from ._world import build_world, client, engine_matrices, load
from .options import ENGINE_NAME, MAX_SEGMENTS, OPTIONS

#: The engine interface (treeimpact.analytic.engine.interface.Engine) and what the tests and
#: benchmarks read from the runner.
__all__ = ["OPTIONS", "Setup", "build_world", "client", "engine_matrices", "load",
           "make_setup", "modes", "run", "simulate", "simulate_batch", "step_cost"]


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
    t0 = time.perf_counter()
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
    t1 = time.perf_counter()
    with progress("bullet", n_steps, estimate) as tick:
        rec = loop(world, setup, n_steps, full, le, g, m, tick)
    h = rec.get("h")
    stepping = stepping_record(setup, n_steps if h is None else len(h),
                               time.perf_counter() - t1, t1 - t0,
                               0 if h is None else int(np.count_nonzero(h != dt)))
    return _result(setup, rec, t_shift, e0, inertia, stepping)


def stepping_record(setup: Setup, steps: int, wall_s: float, swing_s: float,
                    free_steps: int = 0) -> dict:
    """What a run's stepping cost (the result's ``extra["stepping"]``, the report's run
    log): ``steps`` after the touch, the contact's step ``dt`` (s) and what set it
    (:data:`._setup.STEP_REASONS`), the ``free_steps`` of them at the trunk's ``free_dt``
    (s; 0 and None at a fixed step, analytic.engine.phases), the loop's ``wall_s`` (s,
    record built after it) and per step (us), and the full pendulum's free swing before
    the touch (``swing_s``, s)."""
    return {"steps": int(steps), "dt": setup.dt, "step_set_by": setup.step_set_by,
            "free_steps": int(free_steps),
            "free_dt": setup.phases.free_step if setup.phases is not None else None,
            "stepping_s": wall_s, "step_us": 1e6 * wall_s / max(steps, 1),
            "swing_s": swing_s}


def simulate(scenario: Scenario, *, trunk="chain", segments=None, pendulum="linear",
             contact="soft", dt=None, trunk_damping_model=None, calibration=None
             ) -> SimulationResult:
    """Run one scenario in PyBullet (rules: docs/engines.md); backend "bullet".

    Args:
        scenario: the tree, pendulum and contact (its e, pad and t_end: a run option that
            overrides one is applied to it before, analytic.model.options.scenario_as_run;
            a pad's stiffness only with the soft contact).
        trunk: "chain" (hinged rigid segments, default) or "sdof" (eq 11 on a prismatic
            joint).
        segments: the chain's segments (None: the fewest within 0.5 % of the beam).
        pendulum: "linear" (eq 13, starting at the touch at u_1) or "full" (released from
            theta_r, swinging to the trunk).
        contact: "soft" (the pad as Bullet's ERP/CFM spring-damper) or "newton" (Bullet's
            restitution impulses).
        dt: the time step, s (None: :mod:`analytic.contact.timestep`'s rule, within what
            Bullet's implicit contact holds).
        trunk_damping_model: "distributed" (None, the default: eq 9's C along the trunk) or
            "joint" (in the chain's hinges); refused with ``trunk = "sdof"``.
        calibration: "pad" (None, the default) the SDOF rung's (k_c, c_c); "effective" c_c
            recalibrated so that e holds on the trunk's effective mass at the clamp; refused
            with ``trunk = "sdof"`` (where both are the same).

    Returns:
        The SimulationResult: metrics, model, record (SI).

    Raises:
        ParameterError: a bad option or a step the engine cannot take (one line).
        SimulationDiverged: the run diverged.
    """
    return run(make_setup(scenario, trunk=trunk, segments=segments, pendulum=pendulum,
                          contact=contact, dt=dt, trunk_damping_model=trunk_damping_model,
                          calibration=calibration))


def _batch_one(args):
    scenario, options = args
    try:
        return simulate(scenario, **options)
    except SimulationDiverged as exc:
        return exc


def simulate_batch(scenarios, *, max_workers=None, **options) -> list:
    """Simulate many scenarios with the same ``options`` (:func:`simulate`'s) over a process
    pool of ``max_workers`` processes (default: one per scenario, at most the CPUs; one
    PyBullet client per process).

    Returns, in order, a SimulationResult or the SimulationDiverged of each scenario;
    bad options raise ParameterError before any process starts.
    """

    scenarios = list(scenarios)
    for s in scenarios:  # validate everything here, with one-line errors
        make_setup(s, **options)
    if not scenarios:
        return []
    workers = max_workers or min(len(scenarios), os.cpu_count() or 1)
    if workers <= 1:
        return [_batch_one((s, options)) for s in scenarios]
    ctx = mp.get_context("spawn")  # a forked child would share the parent's client
    # each process the library's BLAS limit from its start (analytic/threads.py)
    with cf.ProcessPoolExecutor(max_workers=workers, mp_context=ctx,
                                initializer=limit_process) as pool:
        return list(pool.map(_batch_one, [(s, options) for s in scenarios]))


def modes(scenario: Scenario, *, segments=None, n_modes: int = 3) -> dict:
    """Static stiffness at a (N/m) and the lowest ``n_modes`` natural frequencies (rad/s) of
    Bullet's chain of ``segments`` segments (None: the default count) for ``scenario``: mass
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
