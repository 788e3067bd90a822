"""MuJoCo stepping: the initial state, the full pendulum's free swing, and multi-threaded
``mujoco.rollout`` of groups of compiled models. SI units."""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np
from mujoco import rollout as mj_rollout

from treeimpact.analytic.engine.interface import swing_time
from treeimpact.analytic.model.parameters import Scenario
from treeimpact.analytic.model.two_body import TwoBodyModel

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


def _rollout(models, states, nsteps, nthread):
    """One multi-threaded rollout of models (same size signature) for max(nsteps) steps."""
    nstep = int(max(nsteps))
    datas = [mujoco.MjData(models[0]) for _ in range(max(1, min(nthread, len(models))))]
    state, sensordata = mj_rollout.rollout(list(models), datas, np.asarray(states),
                                           nstep=nstep)
    return state, sensordata


def _signature(m: mujoco.MjModel) -> tuple:
    return (m.nq, m.nv, m.na, m.nu, m.nsensordata, m.nbody, m.nmocap, m.nuserdata)


@dataclass
class _Plan:
    setup: object  # mujoco_models._runner.Setup
    state0: np.ndarray  # state at the start of the recorded phase (filled after the swing)
    nstep: int
    swing_steps: int = 0


def _initial_qpos_qvel(m: mujoco.MjModel, pendulum: str, model: TwoBodyModel,
                       scenario: Scenario) -> tuple[np.ndarray, np.ndarray]:
    """Trunk at rest; linear pendulum touching at u1, full pendulum at rest at -theta_r."""
    qpos = np.zeros(m.nq)
    qvel = np.zeros(m.nv)
    if pendulum == "linear":
        qpos[-1] = INITIAL_OVERLAP
        qvel[-1] = model.impact_speed
    else:
        qpos[-1] = -scenario.impactor.release_angle
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
    import copy

    out = []
    for p in plans:
        m = copy.deepcopy(p.setup.mjmodel)
        m.opt.timestep = max(SWING_STEP, p.setup.dt)
        m.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
        out.append(m)
    return out


def _run_group(plans: list[_Plan], nthread: int) -> list:
    """Roll out a group of plans with one size signature; returns per plan (states, sensors)."""
    swing = [p for p in plans if p.swing_steps > 0]
    if swing:
        models = _swing_models(swing)
        st, _ = _rollout(models, [p.state0 for p in swing], [p.swing_steps for p in swing],
                         nthread)
        for i, p in enumerate(swing):
            s = st[i, p.swing_steps - 1].copy()
            s[0] = 0.0  # time restarts: the recorded phase is timed by its own steps
            p.state0 = s
    st, sd = _rollout([p.setup.mjmodel for p in plans], [p.state0 for p in plans],
                      [p.nstep for p in plans], nthread)
    return [(p.state0, st[i, :p.nstep], sd[i, :p.nstep]) for i, p in enumerate(plans)]
