"""MuJoCo stepping by phase (analytic.engine.phases): ``mujoco.rollout`` segments at the
contact's step dt_c and at the trunk's free step h_f, switched by the gap and the
closing-speed bound. SI units; design notes: docs/engines.md ("Stepping by phase")."""

from __future__ import annotations

import copy

import mujoco
import numpy as np
from mujoco import rollout as mj_rollout

from . import _builder

_FULL = mujoco.mjtState.mjSTATE_FULLPHYSICS


class _Probe:
    """The gap (m) between the pad's and the bob's spheres and lambda_max(J_rel M^-1
    J_rel^T) (1/kg) at a state of the contact model ``m``, from MuJoCo's own kinematics."""

    def __init__(self, m: mujoco.MjModel):
        self.m, self.d = m, mujoco.MjData(m)
        self.geoms = (int(m.pair_geom1[0]), int(m.pair_geom2[0]))
        self.bodies = [int(m.geom_bodyid[g]) for g in self.geoms]
        self.jac = np.zeros((2, 3, m.nv))
        self.radii = float(sum(m.geom_size[g, 0] for g in self.geoms))

    def at(self, state: np.ndarray) -> tuple[float, float, float]:
        """(gap m, lambda 1/kg, contact force N) at ``state`` (mjSTATE_FULLPHYSICS)."""
        m, d = self.m, self.d
        mujoco.mj_setState(m, d, state, _FULL)
        mujoco.mj_forward(m, d)
        c = [d.geom_xpos[g] for g in self.geoms]
        gap = float(np.linalg.norm(c[1] - c[0])) - self.radii
        for k in range(2):
            mujoco.mj_jac(m, d, self.jac[k], None, c[k], self.bodies[k])
        J = self.jac[1] - self.jac[0]
        X = np.zeros_like(J)
        mujoco.mj_solveM(m, d, X, J)
        lam = float(np.max(np.linalg.eigvalsh(J @ X.T)))
        force = float(d.sensordata[_builder.sensor_slices()["force"]][0])
        return gap, lam, force


def free_model(m: mujoco.MjModel, h_free: float) -> mujoco.MjModel:
    """A copy of the contact model ``m`` stepped at ``h_free`` (s); nothing else differs."""
    out = copy.deepcopy(m)
    out.opt.timestep = h_free
    return out


def _clear(sensors: np.ndarray, final_gap: float, radii: float) -> bool:
    """True when no sample of a big-step chunk touched: no force, the spheres' centres
    (the sensors' framepos) farther apart than their radii, and a gap at its end."""
    sl = _builder.sensor_slices()
    dist = np.linalg.norm(sensors[:, sl["y_pos"]] - sensors[:, sl["x_pos"]], axis=1)
    return bool(np.all(sensors[:, sl["force"]][:, 0] == 0.0) and np.all(dist > radii)
                and final_gap > 0.0)


def phased_rollout(setup, state0: np.ndarray, total_time: float, stop, tick):
    """Roll ``setup`` from ``state0`` for ``total_time`` (s) by phase: returns (states,
    sensors, per-step h (s), big steps). Each check reads the gap and lambda at the state
    reached (:class:`_Probe`), takes the big steps :meth:`PhaseRule.free_steps` allows,
    verifies every one of their samples (:func:`_clear`) and steps a failed chunk again at
    dt_c; otherwise :attr:`PhaseRule.chunk_steps` contact steps. ``stop``: an Event that
    ends the run between segments; ``tick(n)`` after every n steps."""
    rule, mc = setup.phases, setup.mjmodel
    mf = free_model(mc, rule.free_step)
    dc, df, probe = mujoco.MjData(mc), mujoco.MjData(mf), _Probe(mc)
    state, warm, t = np.asarray(state0), None, 0.0
    parts, big = [], 0
    while total_time - t > 0.5 * rule.contact_step and not stop.is_set():
        gap, lam, force = probe.at(state)
        n = rule.free_steps(gap, lam, total_time - t) if force == 0.0 else 0
        if n:
            st, sd = mj_rollout.rollout(mf, df, state[None], nstep=n, initial_warmstart=warm)
            if _clear(sd[0], probe.at(st[0, -1])[0], probe.radii):
                parts.append((st[0], sd[0], np.full(n, rule.free_step)))
                state, warm, t, big = st[0, -1], df.qacc_warmstart.copy()[None], \
                    t + n * rule.free_step, big + n
                tick(n)
                continue
        n = rule.contact_chunk(total_time - t)
        st, sd = mj_rollout.rollout(mc, dc, state[None], nstep=n, initial_warmstart=warm)
        parts.append((st[0], sd[0], np.full(n, rule.contact_step)))
        state, warm, t = st[0, -1], dc.qacc_warmstart.copy()[None], t + n * rule.contact_step
        tick(n)
    return (np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts]),
            np.concatenate([p[2] for p in parts]), big)
