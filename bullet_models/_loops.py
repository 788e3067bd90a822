"""PyBullet's stepping: the full pendulum's swing to the contact, the SDOF and chain loops
(spring and damping torques applied by hand each step), and the chain's damping operators.
SI units."""

from __future__ import annotations

import itertools
import math
from operator import itemgetter

import numpy as np

from treeimpact.analytic.continuum.chain import hinged_chain, lateral_motion
from treeimpact.analytic.errors import SimulationDiverged

SWING_STEP = 1e-4  # s: step of the full pendulum's free swing before the contact
SWING_SWITCH_STEPS = 20  # switch to the impact step this many swing steps before contact


def _swing(world, setup, le: float, g: float):
    """Release the full pendulum at -theta_r; step until it is about to touch (eq 48).

    Swings with :data:`SWING_STEP` (or dt if smaller), switching to dt shortly before the
    contact, and stops at the last step before the bob reaches the trunk. Returns
    (time of touch measured from now, s; initial energy m g l_e (1 - cos theta_r), J).
    """
    p, cid, pb = world.p, world.cid, world.pendulum
    imp = setup.scenario.impactor
    m = imp.mass
    theta_r = imp.release_angle_rad
    p.resetJointState(pb, 0, -theta_r, 0.0, physicsClientId=cid)
    h = max(SWING_STEP, setup.dt)
    p.setPhysicsEngineParameter(fixedTimeStep=h, physicsClientId=cid)
    mgl = m * g * le
    steps_max = int(10.0 * math.pi * math.sqrt(le / g) / setup.dt) + 10
    for _ in range(steps_max):
        th, om = p.getJointState(pb, 0, physicsClientId=cid)[:2]
        if th >= 0.0:
            raise SimulationDiverged("full pendulum passed the trunk before contact")
        remaining = -th / max(om, 1e-12)
        if h > setup.dt and remaining < SWING_SWITCH_STEPS * h:
            h = setup.dt
            p.setPhysicsEngineParameter(fixedTimeStep=h, physicsClientId=cid)
        if h == setup.dt and le * math.sin(-th) <= le * math.cos(th) * om * h:
            # touches within the next step: the record starts here
            return remaining, mgl * (1.0 - math.cos(theta_r))
        p.setJointMotorControl2(pb, 0, p.TORQUE_CONTROL, force=-mgl * math.sin(th),
                                physicsClientId=cid)
        p.stepSimulation(physicsClientId=cid)
    raise SimulationDiverged("full pendulum never reached the trunk")


def _loop_sdof(world, setup, n_steps, full, le, g, m, tick=lambda n: None):
    """Step the SDOF trunk; per step two joint-state reads, two torques, one contact query.

    The PyBullet calls take their arguments by position (keyword parsing costs ~0.7 us per
    call against a ~3 us step) and the loop only keeps what the engine returns; the arrays
    are built after the loop.
    """
    p, cid, tb, pb = world.p, world.cid, world.trunk, world.pendulum
    model = setup.model
    K, C, kp = model.equivalent_stiffness, model.equivalent_damping, model.impactor_stiffness
    mgl = m * g * le if full else 0.0
    gjs, sjm, step, gcp = (p.getJointState, p.setJointMotorControl2, p.stepSimulation,
                           p.getContactPoints)
    TQ = p.TORQUE_CONTROL
    states = []  # x, x', q, q' of each step, flat (floats only: nothing for the GC to track)
    keep = states.append
    contact_force = {}  # step -> summed normal force, N (steps with contact only)
    sin, isfinite = math.sin, math.isfinite
    for n in range(n_steps):
        xs = gjs(tb, 0, cid)
        ps = gjs(pb, 0, cid)
        x, v, y = xs[0], xs[1], ps[0]
        keep(x)
        keep(v)
        keep(y)
        keep(ps[1])
        # setJointMotorControl2(body, joint, mode, targetPosition, targetVelocity, force,
        # positionGain, velocityGain, maxVelocity, client): TORQUE_CONTROL uses force only
        sjm(tb, 0, TQ, 0.0, 0.0, -K * x - C * v, 0.1, 1.0, -1.0, cid)
        sjm(pb, 0, TQ, 0.0, 0.0, -mgl * sin(y) if full else -kp * y, 0.1, 1.0, -1.0, cid)
        step(cid)
        points = gcp(tb, pb, -2, -2, cid)  # -2: any link (PyBullet's default)
        if points:
            contact_force[n] = sum(c[9] for c in points)
        if not (n & 1023) and n:
            tick(1024)  # the progress of a long run
            if not isfinite(x + y):
                raise SimulationDiverged(f"bullet: non-finite state at t = {n * setup.dt:.4g} s")
    states.extend(gjs(tb, 0, cid)[:2] + gjs(pb, 0, cid)[:2])
    x, vx, q, qd = np.array(states).reshape(n_steps + 1, 4).T
    force = np.zeros(n_steps + 1)
    force[list(contact_force)] = list(contact_force.values())
    return {"x": x, "vx": vx, "q": q, "qd": qd, "force": force,
            "joint_speed": max(float(np.max(np.abs(vx))), float(np.max(np.abs(qd))))}


def _loop_chain(world, setup, n_steps, full, le, g, m, tick=lambda n: None):
    """Step the chain; per step one read of every hinge's state, one array of hinge torques,
    the pendulum's state and torque, one contact query. ``setup.phases``: stepped by phase
    (:mod:`._phased`, the same time as ``n_steps`` steps of dt), else ``n_steps`` of dt.

    The hinge states (theta, theta') are read into one flat float array by ``np.fromiter``
    (no tuple per hinge, no 2-D array to flatten: the torques and the record are the same
    numbers); the record's arrays are built after the loop.
    """
    p, cid, tb, pb = world.p, world.cid, world.trunk, world.pendulum
    M, K, _ = setup.matrices
    kdiag = np.diag(K).copy()
    joints = world.trunk_joints
    nj = len(joints)
    gjss, gjs = p.getJointStates, p.getJointState
    trunk_states = []  # flat arrays theta_0, theta'_0, theta_1, ... of each step
    pendulum_states = []  # q, q' of each step, flat
    contact_force = {}  # step -> summed normal force, N (steps with contact only)
    rec = (trunk_states, pendulum_states, contact_force)
    run = _chain_steps(world, setup, full, le, g, m, rec, tick)
    h = None
    if setup.phases is None:
        run(n_steps, setup.dt, 0)
    else:
        from ._phased import phased_steps  # noqa: PLC0415 - lazy: the phased driver's own module, loaded only when a run steps by phase

        h = phased_steps(world, setup, run, rec, n_steps * setup.dt, full, le, m)
    fromiter, flat, pair, n2 = np.fromiter, itertools.chain.from_iterable, itemgetter(0, 1), 2 * nj
    trunk_states.append(fromiter(flat(map(pair, gjss(tb, joints, cid))), float, n2))
    pendulum_states.extend(gjs(pb, 0, cid)[:2])
    steps = len(trunk_states) - 1
    states = np.array(trunk_states).reshape(steps + 1, nj, 2)
    q, qd = np.array(pendulum_states).reshape(steps + 1, 2).T
    force = np.zeros(steps + 1)
    force[list(contact_force)] = list(contact_force.values())
    out = _chain_record(setup, states[:, :, 0], states[:, :, 1], q, qd, force,
                        (M, kdiag, *damping_operators(setup)))
    if h is not None:
        out["h"] = h
        out["damping_power"] = _phased_damping_power(setup, states, M, kdiag, h)
    return out


def _phased_damping_power(setup, states, M, kdiag, h) -> np.ndarray:
    """The damping's power per step of a run stepped by phase: the operators of each step's
    own size ``h`` (s; the joint damping's implicit operators depend on it)."""
    Q, QD = states[:, :, 0], states[:, :, 1]
    out = np.empty(len(h))
    for size in np.unique(h):
        sel = np.flatnonzero(h == size)
        Dv, Dq = damping_operators(setup, float(size))
        tau = QD[sel] @ Dv.T
        if Dq is not None:
            tau -= Q[sel] @ Dq.T
        out[sel] = np.einsum("ni,ni->n", tau, 0.5 * (QD[sel] + QD[sel + 1]))
    return out


def _chain_steps(world, setup, full, le, g, m, rec, tick):
    """The chain's stepping loop as ``run(k, h, first)``: k steps of size h (s, the world's
    step set to it), numbered from ``first``, appended to ``rec`` (trunk states, pendulum
    states, contact force by step)."""
    p, cid, tb, pb = world.p, world.cid, world.trunk, world.pendulum
    M, K, _ = setup.matrices
    kdiag = np.diag(K).copy()
    kp = setup.model.impactor_stiffness
    mgl = m * g * le if full else 0.0
    joints = world.trunk_joints
    nj = len(joints)
    torques = {}

    def torque_of(h):  # -K theta - (Dv theta' - Dq theta) on (theta_0, theta'_0, ...)
        if h not in torques:
            Dv, Dq = damping_operators(setup, h)
            t = np.empty((nj, 2 * nj))
            t[:, 0::2] = -np.diag(kdiag) + (Dq if Dq is not None else 0.0)
            t[:, 1::2] = -Dv
            torques[h] = t
        return torques[h]

    def run(k, h, first):
        torque = torque_of(h)
        p.setPhysicsEngineParameter(fixedTimeStep=h, physicsClientId=cid)
        gjss, sjma, sjm, gjs, step, gcp = (p.getJointStates, p.setJointMotorControlArray,
                                           p.setJointMotorControl2, p.getJointState,
                                           p.stepSimulation, p.getContactPoints)
        TQ = p.TORQUE_CONTROL
        keep, keep_pendulum = rec[0].append, rec[1].append
        contact_force = rec[2]
        sin = math.sin
        fromiter, flat, pair = np.fromiter, itertools.chain.from_iterable, itemgetter(0, 1)
        n2 = 2 * nj
        for n in range(first, first + k):
            z = fromiter(flat(map(pair, gjss(tb, joints, cid))), float, n2)
            ps = gjs(pb, 0, cid)
            y = ps[0]
            keep(z)
            keep_pendulum(y)
            keep_pendulum(ps[1])
            sjma(tb, joints, TQ, forces=(torque @ z).tolist(), physicsClientId=cid)
            # positional arguments as in _loop_sdof
            sjm(pb, 0, TQ, 0.0, 0.0, -mgl * sin(y) if full else -kp * y, 0.1, 1.0, -1.0, cid)
            step(cid)
            points = gcp(tb, pb, -2, -2, cid)  # -2: any link (PyBullet's default)
            if points:
                contact_force[n] = sum(c[9] for c in points)
            if not (n & 1023) and n:
                tick(1024)  # the progress of a long run
                if not np.all(np.isfinite(z)):
                    raise SimulationDiverged(f"bullet: non-finite state at step {n}")
    return run


def _chain_record(setup, Q, QD, q, qd, force, operators) -> dict:
    """The chain run's record from its hinge angles ``Q`` and rates ``QD`` (steps x hinges),
    the pendulum's ``q``, ``qd`` and the contact ``force`` per step (N): the clamp's and
    crown's lateral motion, the trunk's energies and the damping's power (``operators``:
    the mass matrix M, the hinge stiffnesses, Dv and Dq of :func:`damping_operators`)."""
    M, kdiag, Dv, Dq = operators
    chain = hinged_chain(setup.scenario.trunk, setup.segments)
    x, vx = lateral_motion(chain, Q, QD, chain.clamp_index)
    crown, crown_v = lateral_motion(chain, Q, QD, chain.segments)
    kin = 0.5 * np.einsum("ni,ij,nj->n", QD, M, QD)
    pot = 0.5 * (Q * Q) @ kdiag
    tau_d = QD[:-1] @ Dv.T  # the damping torque applied over each step (resisting)
    if Dq is not None:
        tau_d -= Q[:-1] @ Dq.T
    ddot = np.einsum("ni,ni->n", tau_d, 0.5 * (QD[:-1] + QD[1:]))
    return {"x": x, "vx": vx, "crown": crown, "crown_velocity": crown_v, "q": q, "qd": qd,
            "force": force, "trunk_kinetic": kin, "trunk_potential": pot, "damping_power": ddot,
            "joint_speed": max(float(np.max(np.abs(QD))), float(np.max(np.abs(qd))))}


def damping_operators(setup, dt: float | None = None) -> tuple[np.ndarray, np.ndarray | None]:
    """(Dv, Dq): the chain's damping torque over step n is -(Dv theta'_n - Dq theta_n), at
    the step ``dt`` (s; None: ``setup.dt``).

    ``distributed``: explicit, Dv = D of :func:`analytic.continuum.chain.chain_matrices`, Dq = None
    (its largest rate, eig(M^-1 D) ~ C / (rho A) ~ 350 1/s, is far inside stability).
    ``joint``: the hinge dampers B = diag(beta k_j) (:func:`_joint_damping`) are stiff (beta
    omega_max^2 dt >> 2 at the default step: explicit, the run diverges), so they act
    implicitly, as MuJoCo's Euler step treats joint damping: the torque is -B theta'_{n+1}
    with theta'_{n+1} = (M + dt B)^-1 (M theta'_n - dt K theta_n), the step's velocity
    without the contact, M the chain's mass matrix at rest (Bullet's own, to round-off). So
    Dv = B (M + dt B)^-1 M and Dq = -dt B (M + dt B)^-1 K.
    """
    M, K, D = setup.matrices
    if setup.damping != "joint":
        return D, None
    dt = setup.dt if dt is None else dt
    B = np.diag(_joint_damping(M, K, D))
    G = B @ np.linalg.inv(M + dt * B)
    return G @ M, -dt * (G @ K)


def _joint_damping(M, K, D) -> np.ndarray:
    """Hinge dampers beta k_j (stiffness-proportional) with the first mode's damping of D.

    The documented alternative to the distributed damping: beta = phi^T D phi / phi^T K phi
    for the first mode phi, so mode 1 keeps its damping ratio; higher modes get more.
    """
    # lazy: +137 ms at import otherwise (scipy.linalg)
    import scipy.linalg

    w2, vec = scipy.linalg.eigh(K, M, subset_by_index=[0, 0])
    phi = vec[:, 0]
    beta = float(phi @ D @ phi) / float(phi @ K @ phi)
    return beta * np.diag(K)
