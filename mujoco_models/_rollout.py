"""MuJoCo stepping: the initial state, the full pendulum's free swing, and multi-threaded
``mujoco.rollout`` of groups of compiled models. SI units."""

from __future__ import annotations

import copy
import math
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import mujoco
import numpy as np
from mujoco import rollout as mj_rollout

from treeimpact.analytic.budget import StepCost, progress
from treeimpact.analytic.engine.interface import swing_time
from treeimpact.analytic.model.parameters import Scenario
from treeimpact.analytic.model.two_body import TwoBodyModel

from ._phased import phased_rollout

INITIAL_OVERLAP = 1e-12  # m: the linear pendulum starts touching, the contact active
SWING_STEP = 1e-4  # s: step of the full pendulum's free swing (contact disabled)
SWING_MARGIN = 2e-3  # s: the swing hands over to dt this long before the exact arrival


def _state(mjmodel: mujoco.MjModel, qpos, qvel) -> np.ndarray:
    data = mujoco.MjData(mjmodel)
    data.qpos[:] = qpos
    data.qvel[:] = qvel
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    out = np.empty(mujoco.mj_stateSize(mjmodel, spec))
    mujoco.mj_getState(mjmodel, data, out, spec)
    return out


def step_cost(m: mujoco.MjModel) -> StepCost:
    """One Euler step's wall time and the bytes the rollout and its record keep, measured
    (benchmarks/bench_cost.py; docs/budgets.md): 1.5 us + 0.3 us x nv + 5e-9 s x nv^2.6 (the
    chain's dense mass matrix: 6 us at nv = 10, 1.6 ms at 130 on the 2-core reference
    machine) and 300 B + 75 B x nv."""
    return step_cost_of(int(m.nv))


def step_cost_of(nv: int) -> StepCost:
    """:func:`step_cost` of a model with ``nv`` degrees of freedom (before it is built)."""
    return StepCost(1.5e-6 + 0.3e-6 * nv + 5e-9 * nv ** 2.6, 300.0 + 75.0 * nv,
                    f"{nv} degrees of freedom")



#: Estimated seconds of one rollout call: between two calls a signal is answered and the
#: progress told (the solver's warm start is carried over: the chunks step as one call).
CHUNK_SECONDS = 0.5


def _rollout(models, states, nsteps, nthread, tick=lambda n: None):
    """Roll each model (one size signature) from its state for its steps; per model the
    states and sensor values of every step and the wall time (s) its rollout took (on its
    own thread). Each model runs in chunks of about
    :data:`CHUNK_SECONDS` with its own MjData, the solver's warm start carried from chunk to
    chunk (bitwise the steps of one call), on up to ``nthread`` threads (MuJoCo's rollout
    releases the GIL); ``tick(n)`` after every n steps."""


    chunk = max(1000, int(CHUNK_SECONDS / step_cost(models[0]).seconds))
    stop = threading.Event()
    lock = threading.Lock()

    def one(i):
        t0 = time.perf_counter()
        m, data = models[i], mujoco.MjData(models[i])
        state, warm, left = np.asarray(states[i])[None], None, int(nsteps[i])
        st_parts, sd_parts = [], []
        while left > 0 and not stop.is_set():
            n = min(chunk, left)
            st, sd = mj_rollout.rollout(m, data, state, nstep=n, initial_warmstart=warm)
            st_parts.append(st[0])
            sd_parts.append(sd[0])
            state, warm, left = st[:, -1], data.qacc_warmstart.copy()[None], left - n
            with lock:
                tick(n)
        return np.concatenate(st_parts), np.concatenate(sd_parts), time.perf_counter() - t0

    if len(models) == 1 or nthread <= 1:  # in this thread: a signal ends it between chunks
        return [one(i) for i in range(len(models))]
    pool = ThreadPoolExecutor(max_workers=min(nthread, len(models)))
    try:
        return list(pool.map(one, range(len(models))))
    finally:
        stop.set()  # an interrupt in this thread ends the others at their next chunk
        pool.shutdown(wait=True)


def _signature(m: mujoco.MjModel) -> tuple:
    return (m.nq, m.nv, m.na, m.nu, m.nsensordata, m.nbody, m.nmocap, m.nuserdata)


@dataclass
class _Plan:
    setup: object  # mujoco_models._runner.Setup
    state0: np.ndarray  # state at the start of the recorded phase (filled after the swing)
    nstep: int
    swing_steps: int = 0
    swing_s: float = 0.0  # wall time of the free swing (s)


def _initial_qpos_qvel(m: mujoco.MjModel, pendulum: str, model: TwoBodyModel,
                       scenario: Scenario) -> tuple[np.ndarray, np.ndarray]:
    """Trunk at rest; linear pendulum touching at u1, full pendulum at rest at -theta_r."""
    qpos = np.zeros(m.nq)
    qvel = np.zeros(m.nv)
    if pendulum == "linear":
        qpos[-1] = INITIAL_OVERLAP
        qvel[-1] = model.impact_speed
    else:
        qpos[-1] = -scenario.impactor.release_angle_rad
    return qpos, qvel


def _plan(setup) -> _Plan:
    n_main = int(math.ceil(setup.t_end / setup.dt)) + 2
    state0 = setup.initial_state.copy()
    if setup.pendulum == "linear":
        return _Plan(setup, state0, n_main)
    imp = setup.scenario.impactor
    t_swing = swing_time(imp)
    h = max(SWING_STEP, setup.dt)
    n_swing = max(0, int((t_swing - SWING_MARGIN) / h))
    remaining = t_swing - n_swing * h
    n_pre = int(math.ceil(1.5 * remaining / setup.dt)) + 2
    return _Plan(setup, state0, n_main + n_pre, swing_steps=n_swing)


def _swing_models(plans):
    out = []
    for p in plans:
        m = copy.deepcopy(p.setup.mjmodel)
        m.opt.timestep = max(SWING_STEP, p.setup.dt)
        m.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
        out.append(m)
    return out


def _run_group(plans: list[_Plan], nthread: int) -> list:
    """Roll out a group of plans with one size signature; returns per plan (initial state,
    states, sensors, per-step h (s), :func:`stepping_record`): at a fixed step or by phase
    (``setup.phases``).
    A run estimated longer than analytic.budget.PROGRESS_AFTER_S reports its progress."""

    swing = [p for p in plans if p.swing_steps > 0]
    if swing:
        models = _swing_models(swing)
        out = _rollout(models, [p.state0 for p in swing], [p.swing_steps for p in swing],
                       nthread)
        for (st, _, wall), p in zip(out, swing):
            s = st[p.swing_steps - 1].copy()
            s[0] = 0.0  # time restarts: the recorded phase is timed by its own steps
            p.state0 = s
            p.swing_s = wall
    total = sum(p.nstep for p in plans)
    estimate = total * step_cost(plans[0].setup.mjmodel).seconds / max(1, min(nthread,
                                                                                 len(plans)))
    fixed = [p for p in plans if p.setup.phases is None]
    phased = [p for p in plans if p.setup.phases is not None]
    runs = {}
    with progress("mujoco", total, estimate) as tick:
        out = _rollout([p.setup.mjmodel for p in fixed], [p.state0 for p in fixed],
                       [p.nstep for p in fixed], nthread, tick) if fixed else []
        for p, (st, sd, wall) in zip(fixed, out):
            runs[id(p)] = (st, sd, None, 0, wall)
        for p, r in zip(phased, _phased_runs(phased, nthread, tick)):
            runs[id(p)] = r
    return [(p.state0, st, sd, h, stepping_record(p, wall, h, big))
            for p in plans for st, sd, h, big, wall in [runs[id(p)]]]


def _phased_runs(plans: list[_Plan], nthread: int, tick) -> list:
    """(states, sensors, per-step h, big steps, wall s) of each plan stepped by phase
    (:func:`._phased.phased_rollout`) for the fixed run's simulated time, on up to
    ``nthread`` threads."""
    stop = threading.Event()
    lock = threading.Lock()

    def locked_tick(n):
        with lock:
            tick(n)

    def one(p):
        t0 = time.perf_counter()
        st, sd, h, big = phased_rollout(p.setup, p.state0, p.nstep * p.setup.dt, stop,
                                        locked_tick)
        return st, sd, h, big, time.perf_counter() - t0

    if len(plans) <= 1 or nthread <= 1:
        return [one(p) for p in plans]
    pool = ThreadPoolExecutor(max_workers=min(nthread, len(plans)))
    try:
        return list(pool.map(one, plans))
    finally:
        stop.set()
        pool.shutdown(wait=True)


def stepping_record(plan: _Plan, wall_s: float, h=None, big: int = 0) -> dict:
    """What a run's stepping cost (the result's ``extra["stepping"]``, the report's run
    log): the ``steps`` of the recorded phase (from the touch, or from just before it after
    the full pendulum's swing), the contact's step ``dt`` (s) and what set it
    (``step_set_by``), the ``free_steps`` taken at the trunk's ``free_dt`` (s; 0 and None
    at a fixed step, analytic.engine.phases), the rollout's ``wall_s`` (s) and per step
    (us), and the free swing's (``swing_s``, s)."""
    setup = plan.setup
    steps = int(plan.nstep if h is None else len(h))
    return {"steps": steps, "dt": setup.dt, "step_set_by": setup.step_set_by,
            "free_steps": int(big),
            "free_dt": setup.phases.free_step if setup.phases is not None else None,
            "stepping_s": wall_s, "step_us": 1e6 * wall_s / max(steps, 1),
            "swing_s": plan.swing_s}
