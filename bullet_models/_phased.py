"""PyBullet stepping by phase (analytic.engine.phases): the chain loop's steps at the
contact's dt_c and at the trunk's free step h_f (``setTimeStep`` through
``setPhysicsEngineParameter(fixedTimeStep=...)``), switched by the gap and the
closing-speed bound. SI units; design notes: docs/engines.md ("Stepping by phase").

Bullet turns the pad's contactStiffness / contactDamping into ERP and CFM at every step
from that step's size (the runner's law, :func:`._contact.erp_cfm`, is calibrated for
dt_c, and every step that can carry contact force is a dt_c step), so nothing of the
contact is recomputed at a switch."""

from __future__ import annotations

import numpy as np

from . import _urdf

#: Closest-point search radius (m): farther than any gap a big step needs to know exactly.
GAP_SEARCH = 1.0


def inverse_mass(setup, full: bool, le, m: float) -> float:
    """lambda = the pad's inverse mass in x plus the pendulum's (1/kg): 1 / apparent mass of
    the chain at a (Bullet's J_a M^-1 J_a^T at rest) and 1 / m, or l_e^2 / I_pivot for the
    full pendulum (I_pivot = m l_e^2 (1 + BOB_INERTIA_FRACTION)); the bodies' masses are
    independent blocks, so Cauchy-Schwarz bounds |vy - vx| by sqrt(2 T lambda)."""
    pend = 1.0 / (m * (1.0 + _urdf.BOB_INERTIA_FRACTION)) if full else 1.0 / m
    return 1.0 / setup.apparent_mass + pend


def gap(world) -> float:
    """The trunk's and the pendulum's closest distance (m; GAP_SEARCH when farther)."""
    pts = world.p.getClosestPoints(world.trunk, world.pendulum, GAP_SEARCH,
                                   physicsClientId=world.cid)
    return min((c[8] for c in pts), default=GAP_SEARCH)


def _restore(world, rec, n: int) -> None:
    """Put the bodies back in the state recorded before step ``n`` (every hinge's and the
    pendulum's angle or slide and rate: the whole state of a world without contact, since
    the torques are set anew each step; ``saveState`` would cost 1 ms a chunk)."""
    p, cid = world.p, world.cid
    z = rec[0][n]
    for j, joint in enumerate(world.trunk_joints):
        p.resetJointState(world.trunk, joint, z[2 * j], z[2 * j + 1], physicsClientId=cid)
    p.resetJointState(world.pendulum, 0, rec[1][2 * n], rec[1][2 * n + 1],
                      physicsClientId=cid)


def phased_steps(world, setup, run, rec, total_time: float, full: bool, le, m: float
                 ) -> np.ndarray:
    """Step the chain by phase for ``total_time`` (s) with ``run(k, h, first)`` (the loop of
    :func:`._loops._chain_steps`) into ``rec``; returns each step's size h (s). A chunk of
    big steps that carried contact force or ended touching is undone (:func:`_restore`, its
    first state) and stepped at dt_c, so no re-touch is taken with a big step."""
    p, cid, rule = world.p, world.cid, setup.phases
    lam = inverse_mass(setup, full, le, m)
    contact_force = rec[2]
    sizes, t, n = [], 0.0, 0
    while total_time - t > 0.5 * rule.contact_step:
        touching = contact_force.get(n - 1, 0.0) > 0.0  # a manifold point may carry none
        k = 0 if touching else rule.free_steps(gap(world), lam, total_time - t)
        if k:
            run(k, rule.free_step, n)
            clear = not any(contact_force.get(i, 0.0) > 0.0 for i in range(n, n + k)) and \
                gap(world) > 0.0
            if clear:
                sizes.append(np.full(k, rule.free_step))
                t, n = t + k * rule.free_step, n + k
                continue
            _restore(world, rec, n)  # step the chunk again at dt_c
            del rec[0][n:], rec[1][2 * n:]
            for i in [i for i in contact_force if i >= n]:
                del contact_force[i]
        k = rule.contact_chunk(total_time - t)
        run(k, rule.contact_step, n)
        sizes.append(np.full(k, rule.contact_step))
        t, n = t + k * rule.contact_step, n + k
    return np.concatenate(sizes)
