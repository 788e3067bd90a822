"""MuJoCo's record: the ImpactRecord of a rollout (sensors, the energy ledger of its
integrator, t = 0 at the touch) and the SimulationResult of a run. SI units."""

from __future__ import annotations

import math

import mujoco
import numpy as np

from treeimpact.analytic.contact.law import pad_fields
from treeimpact.analytic.continuum.chain import hinged_chain, lateral_motion
from treeimpact.analytic.engine.interface import (
    ENERGY_GROWTH_LIMIT,
    check_energy,
    engine_result,
    step_means,
    with_crown,
)
from treeimpact.analytic.errors import ParameterError, SimulationDiverged
from treeimpact.analytic.results import ImpactRecord, SimulationResult

from . import _builder, _contact, _flex


def _damping_matrices(m: mujoco.MjModel) -> tuple[np.ndarray, np.ndarray]:
    """(D explicit, B implicit) generalised damping matrices, N m s/rad (N s/m for slides).

    Euler: tendon dampers are explicit; joint dampers are implicit (eulerdamp: B v_{n+1})
    unless the model disables eulerdamp (the SDOF trunk, the chain's distributed damping):
    then MuJoCo applies them explicitly (-b v_n) and they go into D. ``implicit`` and
    ``implicitfast``: every joint and tendon damper is in qDeriv, so all are implicit (B,
    then not diagonal with tendons). RK4: all are explicit, evaluated at each stage (D).
    """
    nv = m.nv
    D = np.zeros((nv, nv))
    for t in range(m.ntendon):
        J = np.zeros(nv)
        adr, num = m.tendon_adr[t], m.tendon_num[t]
        for w in range(adr, adr + num):
            if m.wrap_type[w] != mujoco.mjtWrap.mjWRAP_JOINT:  # pragma: no cover
                raise ParameterError("only fixed tendons are expected")
            J[m.jnt_dofadr[m.wrap_objid[w]]] += m.wrap_prm[w]
        D += m.tendon_damping[t] * np.outer(J, J)
    joint = np.diag(m.dof_damping)
    if m.opt.integrator in _IMPLICIT_ENUMS:
        return np.zeros_like(joint), D + joint
    if m.opt.integrator == mujoco.mjtIntegrator.mjINT_RK4:
        return D + joint, np.zeros_like(joint)
    if m.opt.disableflags & int(mujoco.mjtDisableBit.mjDSBL_EULERDAMP):
        return D + joint, np.zeros_like(joint)
    return D, joint


_IMPLICIT_ENUMS = (mujoco.mjtIntegrator.mjINT_IMPLICIT, mujoco.mjtIntegrator.mjINT_IMPLICITFAST)


def _rest_potential(m: mujoco.MjModel, trunk_root: int) -> float:
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    mujoco.mj_energyPos(m, d)
    g = -m.opt.gravity[2]
    return float(d.energy[0] - m.body_subtreemass[trunk_root] * g * d.subtree_com[trunk_root, 2])


def _record(setup, state0, states, sensors, h=None) -> tuple[ImpactRecord, float, float]:
    """Build the ImpactRecord (t = 0 at the touch); returns (record, initial energy, touch
    index). ``h``: each step's size (s; None: every step ``setup.dt``; stepped by phase,
    analytic.engine.phases). Raises SimulationDiverged on a non-finite or stopped rollout,
    on energy growth or energy the ledger shows the engine created, and when the bodies
    never touched."""
    uniform = h is None  # a fixed step keeps the fixed-step formulas, bit for bit
    h = np.full(len(states), setup.dt) if uniform else np.asarray(h, dtype=float)
    _check_rollout(setup, state0, states, sensors, h)
    m = setup.mjmodel
    nq, nv = m.nq, m.nv
    v_all = np.vstack([state0[1 + nq:1 + nq + nv], states[:, 1 + nq:1 + nq + nv]])  # n..N
    force, x, vx, y, vy, kinetic, potential = _sensed(setup, state0, states, sensors)
    pend, e0 = _pendulum_energy(setup, state0, states, v_all, y, vy, kinetic, potential)
    damping_work, c_power = _damping_work(setup, v_all, force, vy - vx, None if uniform else h)
    k_d = setup.law.stiffness
    overlap = np.where(force > 0.0, np.maximum(y - x, 0.0), 0.0)
    c_pot = 0.5 * k_d * overlap ** 2
    contact_work = _contact_work(setup, kinetic + potential, e0, damping_work, c_power, c_pot,
                                 None if uniform else h)
    if uniform:
        start, t_touch, i1 = _touch(force, x, y, setup.dt)
        t = np.arange(len(force), dtype=float) * setup.dt - t_touch
    else:  # sample n: the state before step n
        grid = np.concatenate([[0.0], np.cumsum(h[:-1])])
        start, t_touch, i1 = _touch(force, x, y, grid)
        t = grid - t_touch
    s = slice(start, None)
    base_d, base_c = damping_work[start], contact_work[start]
    record = ImpactRecord(
        t=t[s], x=x[s], vx=vx[s], y=y[s], vy=vy[s], force=force[s], kinetic=kinetic[s],
        potential=potential[s], damping_work=damping_work[s] - base_d,
        contact_work=contact_work[s] - base_c, contact_potential=c_pot[s],
        pendulum_energy=pend[s])
    if start:  # energy already dissipated before the record starts (none: no contact yet)
        e0 = e0 - base_d - base_c
    return record, e0, i1


def _check_rollout(setup, state0, states, sensors, h) -> None:
    """Raise SimulationDiverged on a non-finite state or sensor, or a rollout that stopped
    advancing time (MuJoCo stops on a warning)."""
    if not (np.all(np.isfinite(states)) and np.all(np.isfinite(sensors))):
        raise SimulationDiverged(f"mujoco: non-finite state (dt = {setup.dt:.3g} s)")
    # a rollout stopped on a warning stops advancing time: every step must add dt (to the
    # round-off of t + dt, not of n dt, which grows with the number of steps)
    steps = np.diff(np.concatenate(([state0[0]], states[:, 0])))
    if not np.all(np.abs(steps - h) <= 1e-6 * h):
        raise SimulationDiverged("mujoco: the rollout stopped on a MuJoCo warning "
                                 f"(dt = {setup.dt:.3g} s)")


def _sensed(setup, state0, states, sensors) -> tuple:
    """(force N, x m, vx m/s, y m, vy m/s, kinetic J, potential J) from the sensors: y moved
    to the bob's contact point, the potential without the trunk's compensated gravity and
    its rest value, with the flex rod's bending energy."""
    m = setup.mjmodel
    sl = _builder.sensor_slices()
    force = sensors[:, sl["force"]][:, 0]
    x = sensors[:, sl["x_pos"]][:, 0]
    vx = sensors[:, sl["x_vel"]][:, 0]
    tr = setup.scenario.trunk
    y = sensors[:, sl["y_pos"]][:, 0] + (tr.diameter / 2.0 + _builder.BOB_RADIUS)
    vy = sensors[:, sl["y_vel"]][:, 0]
    kinetic = sensors[:, sl["kinetic"]][:, 0]
    root = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, setup.trunk_root)
    g = -m.opt.gravity[2]
    trunk_grav = m.body_subtreemass[root] * g * sensors[:, sl["trunk_com"]][:, 2]
    potential = sensors[:, sl["potential"]][:, 0] - trunk_grav - setup.rest_potential
    if setup.flex is not None:  # MuJoCo's e_potential leaves the flex's elastic energy out
        potential = potential + _flex_energy(setup, np.vstack([state0, states[:-1]]))
    return force, x, vx, y, vy, kinetic, potential


def _pendulum_energy(setup, state0, states, v_all, y, vy, kinetic, potential) -> tuple:
    """(the pendulum's own energy per sample J, the run's input energy J): the full
    pendulum's from its angle and rate (released at rest from theta_r), the linear one's
    from (y, vy) with the input the first sample's."""
    m = setup.mjmodel
    model = setup.model
    mm = model.impactor_mass
    if setup.pendulum == "full":
        imp = setup.scenario.impactor
        pid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "pendulum")
        inertia = m.body_inertia[pid, 1] + mm * imp.equivalent_length ** 2
        th = np.concatenate([[state0[m.nq]], states[:-1, m.nq]])  # pendulum angle q_n
        om = v_all[:-1, -1]
        pend = 0.5 * inertia * om * om + mm * imp.gravity * imp.equivalent_length * (
            1.0 - np.cos(th))
        e0 = mm * imp.gravity * imp.equivalent_length * (1.0 - math.cos(imp.release_angle_rad))
    else:
        pend = model.pendulum_energy(y, vy)
        e0 = float(kinetic[0] + potential[0])
    return pend, e0


def _damping_work(setup, v_all, force, w, h=None) -> tuple:
    """(the dampers' work so far per sample J, the contact's power per step W or None for
    RK4): exact for Euler's step and the implicit ones (module docstring), a quadrature of
    the sampled power for RK4."""
    m = setup.mjmodel
    D, B = _damping_matrices(m)
    c_power = None
    if m.opt.integrator == mujoco.mjtIntegrator.mjINT_RK4:  # the stage forces are not
        vs = v_all[:-1]  # recorded: damping work by quadrature (docstring)
        d_power = step_means(np.einsum("ni,ni->n", vs @ D, vs), force > 0.0)
    else:  # works over step n (n = 0 .. N-2), with v_n and v_{n+1}
        v0, v1 = v_all[:-2], v_all[1:-1]
        vbar = 0.5 * (v0 + v1)
        d_power = np.einsum("ni,ni->n", v0 @ D, vbar)  # v_n^T D vbar (matmul: BLAS, not einsum)
        if m.opt.integrator in _IMPLICIT_ENUMS:
            d_power += np.einsum("ni,ni->n", v1 @ B, vbar)  # B: joints and tendons
        elif B.any():
            d_power += np.einsum("ni,ni->n", v1 * np.diag(B), vbar)  # B diagonal (joint dampers)
        c_power = force[:-1] * 0.5 * (w[:-1] + w[1:])
    work = np.cumsum(d_power) * setup.dt if h is None else np.cumsum(d_power * h[:len(d_power)])
    return np.concatenate([[0.0], work]), c_power


def _contact_work(setup, mech, e0: float, damping_work, c_power, c_pot, h=None
                  ) -> np.ndarray:
    """The contact's work so far per sample (J): the sum of ``c_power``, or for RK4 (None)
    what left the bodies other than through the dampers. Raises SimulationDiverged when the
    mechanical energy ``mech`` grows past the input ``e0`` or the ledger shows energy the
    engine created (for RK4: a drop of the contact's dissipated energy)."""
    dt = setup.dt
    check_energy("mujoco", mech, e0, dt)
    if c_power is None:
        # the contact's work is what left the bodies other than through the dampers; what it
        # dissipated (work less the elastic energy it still holds) can only grow
        contact_work = e0 - mech - damping_work
        dissipated = contact_work - c_pot
        created = float(np.max(np.maximum.accumulate(dissipated) - dissipated))
    else:
        work = np.cumsum(c_power) * dt if h is None else np.cumsum(c_power * h[:len(c_power)])
        contact_work = np.concatenate([[0.0], work])
        created = float(np.max(mech + damping_work + contact_work)) - e0
    if created > ENERGY_GROWTH_LIMIT * e0:  # the ledger: energy the engine made from nothing
        raise SimulationDiverged(
            f"mujoco: the engine created {created:.4g} J > {ENERGY_GROWTH_LIMIT:g} x the input "
            f"{e0:.4g} J (kinetic + potential + dissipated; dt = {dt:.3g} s)")
    return contact_work


def _touch(force, x, y, grid) -> tuple[int, float, int]:
    """(first sample kept, touch time s, first sample with force) on the samples' times
    ``grid`` (s; a float: the fixed step dt): t = 0 at the touch, the first sample with
    force, interpolated on the overlap y - x. Raises SimulationDiverged
    when the pendulum never touched the trunk."""
    on = np.flatnonzero(force > 0.0)
    if not on.size:
        raise SimulationDiverged("mujoco: the pendulum never touched the trunk")
    i1 = int(on[0])
    if i1 == 0:
        return 0, 0.0, i1
    g0, g1 = (y - x)[i1 - 1], (y - x)[i1]
    frac = min(1.0, max(0.0, -g0 / (g1 - g0))) if g1 != g0 else 1.0
    if np.ndim(grid) == 0:
        return i1 - 1, (i1 - 1 + frac) * grid, i1
    return i1 - 1, float(grid[i1 - 1] + frac * (grid[i1] - grid[i1 - 1])), i1


def _flex_energy(setup, states: np.ndarray) -> np.ndarray:
    """The rod's bending energy (J) at the states whose sensors are recorded (state n's
    sensors are those of the state before step n)."""
    root, verts = _flex.flex_dofs(setup.mjmodel)
    theta = states[:, 1 + root] if root is not None else np.zeros(len(states))
    return _flex.bending_energy(setup.flex, theta, states[:, [1 + v for v in verts]])


def _with_flex_crown(setup, record: ImpactRecord, states: np.ndarray) -> ImpactRecord:
    """``record`` with the rod top's x (m) and x' (m/s) over its last states."""
    m = setup.mjmodel
    _, verts = _flex.flex_dofs(m)
    n = record.t.size
    top = verts[-1]
    return with_crown(record, states[-n:, 1 + top], states[-n:, 1 + m.nq + top])


def _with_crown(setup, record: ImpactRecord, states: np.ndarray) -> ImpactRecord:
    """``record`` with the chain top's x (m) and x' (m/s) over its last states."""
    m = setup.mjmodel
    chain = hinged_chain(setup.scenario.trunk, setup.segments)
    ids = [mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, f"hinge_{j}")
           for j in range(chain.segments)]
    n = record.t.size
    q = states[-n:, [1 + int(m.jnt_qposadr[i]) for i in ids]]
    v = states[-n:, [1 + m.nq + int(m.jnt_dofadr[i]) for i in ids]]
    return with_crown(record, *lateral_motion(chain, q, v, chain.segments))


def _result(setup, state0, states, sensors, stepping: dict | None = None, h=None
            ) -> SimulationResult:
    """The run's SimulationResult from its rollout (the initial state, every step's states
    and sensors, each step's size ``h``, s, None: ``setup.dt``), the model as MuJoCo ran
    it; ``stepping``: what the stepping cost (:func:`._rollout.stepping_record`), kept in
    ``extra``."""
    record, e0, _ = _record(setup, state0, states, sensors, h)
    if setup.trunk == "chain":  # the chain's top, from the hinge angles of the recorded states
        record = _with_crown(setup, record, states)
    elif setup.trunk == "flex":  # the rod's top vertex
        record = _with_flex_crown(setup, record, states)
    law = setup.law
    return engine_result(
        "mujoco", record, scenario=setup.scenario, model=setup.model, t_end=setup.t_end,
        collision_duration=setup.collision_duration,
        detection_duration=setup.detection_duration, initial_energy=e0, model_fields={
            "segments": setup.segments, "dt": setup.dt,
            "contact_stiffness": law.law_stiffness, "contact_damping": law.law_damping,
            "engine_contact_stiffness": law.stiffness, "engine_contact_damping": law.damping,
            "trunk": setup.trunk, "pendulum": setup.pendulum,
            "trunk_damping_model": setup.damping,
            "integrator": setup.integrator, "calibration": setup.calibration,
            **pad_fields(law.law_stiffness, law.law_damping, setup.effective_mass),
            "solref": list(setup.solref),
            "solimp": [_contact.IMPEDANCE, _contact.IMPEDANCE, *_contact.SOLIMP_TAIL],
            "touch_duration": setup.collision_duration, "omega_max": setup.omega_max},
        extra={"impact_speed_measured": float(record.vy[0] - record.vx[0]),
               **({"stepping": stepping} if stepping else {})})
