"""The MuJoCo runner: build the model, roll it out with ``mujoco.rollout``, turn the record into metrics.

Design notes and measured figures: docs/engines.md.
"""

from __future__ import annotations

import functools
import math
import os
import sys
from dataclasses import dataclass, field, replace

import mujoco
import numpy as np
from mujoco import rollout as mj_rollout

from analytic.chain import default_segments, hinged_chain, lateral_motion
from analytic.engine_options import check_choice, engine_model
from analytic.model import TwoBodyModel
from analytic.parameters import ParameterError, Pendulum, Scenario
from analytic.records import (ImpactRecord, detection_duration, model_metrics,
                              with_static_shape_crown)
from analytic.reduction import reduce_trunk
from analytic.results import SimulationDiverged, SimulationResult, Trajectory
from analytic.soft_contact import (CALIBRATIONS, contact_law, damping_ratio_for_restitution,
                                   pad_restitution, release_time)
from analytic.timestep import check_time_step, check_work, choose_time_step, sdof_rate

from . import _builder, _contact

_WARNED: set = set()


def _warning_to_stderr(message: str) -> None:
    """MuJoCo's warnings on stderr, each kind once per process: never on stdout (JSON) and
    never in a MUJOCO_LOG.TXT in the user's working directory (MuJoCo's default handler)."""
    kind = message.split(" Time =")[0]
    if kind not in _WARNED:
        _WARNED.add(kind)
        print(f"mujoco: {message.strip()}", file=sys.stderr, flush=True)


mujoco.set_mju_user_warning(_warning_to_stderr)

TRUNKS = ("sdof", "chain")
PENDULUMS = ("linear", "full")
DAMPINGS = ("distributed", "joint")
INTEGRATORS = _contact.INTEGRATORS  # the ``integrator`` option (MuJoCo's names)
INITIAL_OVERLAP = 1e-12  # m: the linear pendulum starts touching, the contact active
SWING_STEP = 1e-4  # s: step of the full pendulum's free swing (contact disabled)
SWING_MARGIN = 2e-3  # s: the swing hands over to dt this long before the exact arrival
ENERGY_GROWTH_LIMIT = 0.05  # relative: mechanical energy above (1 + this) E0 = diverged
PLACEHOLDER_DT = 1e-5  # s: time step of the first compile (only its masses are used)
RK4_DAMPING_LIMIT = 2.785  # h lambda: RK4's stability limit on the negative real axis (2.7853)
RK4_RESTITUTION_TOLERANCE = 0.01  # |e - target| of the replayed RK4 free collision (RK4 gets
# the law uncorrected): beyond it the run's contact is not the scenario's (the speed curves stay
# within 1e-3 at >= 3 steps per collision; dt = 1.86e-4 s on a 0.5 ms contact gives 0.22)



@dataclass(frozen=True)
class Setup:
    """A compiled model and everything the run needs (SI units)."""

    scenario: Scenario
    model: TwoBodyModel
    trunk: str
    pendulum: str
    damping: str
    segments: int | None
    dt: float
    t_end: float
    law: _contact.EngineLaw
    collision_duration: float  # s: free collision of the law on mu_eff
    detection_duration: float  # s: analytic.records.detection_duration, common to all rungs
    omega_max: float | None  # rad/s: highest mode of the engine's chain
    inverse_mass: float  # A, 1/kg
    inverse_mass_approx: float  # MuJoCo's diagApprox of the pair, 1/kg
    solref: tuple
    integrator: str
    calibration: str  # "pad" or "effective" (analytic.soft_contact.CALIBRATIONS)
    mjmodel: mujoco.MjModel = field(repr=False, compare=False)
    spec: mujoco.MjSpec = field(repr=False, compare=False)
    # computed once per setup (a run does not rebuild MjData for them):
    initial_state: np.ndarray = field(repr=False, compare=False)  # mjSTATE_FULLPHYSICS, t = 0
    rest_potential: float = field(repr=False, compare=False)  # J: springs + pendulum gravity

    @property
    def effective_mass(self) -> float:
        return 1.0 / self.inverse_mass


def _trunk_spec(scenario: Scenario, trunk: str, segments, damping) -> tuple:
    tr = scenario.trunk
    if trunk == "chain":
        n = default_segments(tr) if segments is None else segments
        chain = hinged_chain(tr, n)
        return _builder.TrunkSpec("chain", None, chain, damping), chain.segments
    if segments is not None:
        raise ParameterError("--segments: only for --trunk chain")
    return _builder.TrunkSpec("sdof", reduce_trunk(tr), None, damping), None


def engine_trunk_matrices(mjmodel: mujoco.MjModel) -> tuple[np.ndarray, np.ndarray]:
    """(M, K) of the trunk's hinges from the engine: ``mj_fullM`` at rest and the joint stiffnesses."""
    data = mujoco.MjData(mjmodel)
    mujoco.mj_forward(mjmodel, data)
    M = np.zeros((mjmodel.nv, mjmodel.nv))
    mujoco.mj_fullM(mjmodel, M, data.qM)
    hinges = [j for j in range(mjmodel.njnt)
              if mujoco.mj_id2name(mjmodel, mujoco.mjtObj.mjOBJ_JOINT, j).startswith("hinge_")]
    dofs = [int(mjmodel.jnt_dofadr[j]) for j in hinges]
    return M[np.ix_(dofs, dofs)], np.diag(mjmodel.jnt_stiffness[hinges])


def highest_frequency(M: np.ndarray, K: np.ndarray) -> float:
    """Largest omega (rad/s) of K v = omega^2 M v."""
    import scipy.linalg

    w2 = scipy.linalg.eigh(K, M, eigvals_only=True)
    return float(math.sqrt(w2[-1]))


def make_setup(scenario: Scenario, *, trunk="chain", segments=None, pendulum="linear",
               contact_stiffness=None, dt=None, restitution=None, t_end=None,
               damping="distributed", integrator="Euler", calibration="pad") -> Setup:
    """Validate the options and compile the model (rules in the module docstring).

    Setups are cached per (scenario, options) (the last :data:`SETUP_CACHE_SIZE`): a repeated
    run does not recompile. Do not modify ``setup.mjmodel`` in place; copy it.
    """
    if not isinstance(scenario, Scenario):
        raise ParameterError("scenario: expected an analytic.Scenario")
    try:
        return _cached_setup(scenario, trunk, segments, pendulum, contact_stiffness, dt,
                             restitution, t_end, damping, integrator, calibration)
    except TypeError:  # an unhashable option value: validate and build without the cache
        return _make_setup(scenario, trunk, segments, pendulum, contact_stiffness, dt,
                           restitution, t_end, damping, integrator, calibration)


SETUP_CACHE_SIZE = 64


@functools.lru_cache(maxsize=SETUP_CACHE_SIZE)
def _cached_setup(*args) -> Setup:
    return _make_setup(*args)


def _make_setup(scenario, trunk, segments, pendulum, contact_stiffness, dt, restitution,
                t_end, damping, integrator, calibration) -> Setup:
    check_choice("trunk", trunk, TRUNKS)
    check_choice("pendulum", pendulum, PENDULUMS)
    check_choice("damping", damping, DAMPINGS)
    check_choice("integrator", integrator, INTEGRATORS)
    check_choice("calibration", calibration, CALIBRATIONS)
    model, t_end = engine_model(scenario, pendulum=pendulum, restitution=restitution,
                                t_end=t_end)
    e = model.restitution
    if not e > 0.0:
        raise ParameterError("--restitution = 0: a soft contact needs e in (0, 1] (e = 0 "
                             "needs infinite damping)")
    k, c_pad = contact_law(model, scenario.contact, stiffness=contact_stiffness)
    tspec, n = _trunk_spec(scenario, trunk, segments, damping)
    name = f"{scenario.name}-{trunk}-{pendulum}"
    spec, pair = _builder.build_spec(name, tspec, scenario, pendulum, PLACEHOLDER_DT,
                                     integrator=integrator)
    m1 = spec.compile()
    A, A_hat = _builder.contact_inverse_masses(m1)
    mu = 1.0 / A
    if calibration == "pad":  # the SDOF's (k_c, c_c): the e it gives on this model's mu
        e = pad_restitution(k, c_pad, mu)
    zeta = damping_ratio_for_restitution(e)
    t_c = release_time(zeta) / math.sqrt(k / mu)
    omega_max = highest_frequency(*engine_trunk_matrices(m1)) if trunk == "chain" else None
    fastest = omega_max if omega_max is not None else sdof_rate(model)
    if dt is None:
        dt = choose_time_step(t_c, fastest)
    dt = check_time_step(dt, t_c, fastest)
    # the rollout keeps the full state and the sensors of every step
    check_work(t_end, dt, 8.0 * (mujoco.mj_stateSize(m1, mujoco.mjtState.mjSTATE_FULLPHYSICS)
                                 + m1.nsensordata))
    law = _contact.engine_law(float(k), float(e), float(mu), float(dt), integrator)
    if abs(law.uncorrected_restitution - e) > RK4_RESTITUTION_TOLERANCE and integrator == "RK4":
        raise ParameterError(
            f"--dt = {dt:.3g} s with --integrator RK4: one free collision rebounds at e = "
            f"{law.uncorrected_restitution:.3g} instead of {e:g} ({law.steps_per_collision} "
            f"steps per collision; allowed |error| <= {RK4_RESTITUTION_TOLERANCE:g}): a "
            "smaller --dt")
    S = _contact.effective_denominator(A, A_hat)
    solref = _contact.solref_for_law(law.stiffness, law.damping, S)
    pair.solref = list(solref)
    spec.option.timestep = dt
    mjmodel = spec.compile()
    if integrator == "RK4":
        _check_rk4_damping(mjmodel, dt)
    root = mujoco.mj_name2id(mjmodel, mujoco.mjtObj.mjOBJ_BODY,
                             "trunk" if trunk == "sdof" else "segment_0")
    state0 = _state(mjmodel, *_initial_qpos_qvel(mjmodel, pendulum, model, scenario))
    state0.flags.writeable = False
    return Setup(scenario=scenario, model=model, trunk=trunk, pendulum=pendulum,
                 damping=damping, segments=n, dt=float(dt), t_end=float(t_end), law=law,
                 collision_duration=t_c,
                 detection_duration=detection_duration(model, scenario.contact, stiffness=k),
                 omega_max=omega_max, inverse_mass=A, calibration=calibration,
                 inverse_mass_approx=A_hat, solref=tuple(solref), integrator=integrator,
                 mjmodel=mjmodel, spec=spec,
                 initial_state=state0, rest_potential=_rest_potential(mjmodel, root))


def _check_rk4_damping(mjmodel: mujoco.MjModel, dt: float) -> None:
    """Refuse a dt at which RK4's explicit dampers are unstable (module docstring)."""
    import scipy.linalg

    data = mujoco.MjData(mjmodel)
    mujoco.mj_forward(mjmodel, data)
    M = np.zeros((mjmodel.nv, mjmodel.nv))
    mujoco.mj_fullM(mjmodel, M, data.qM)
    C = sum(_damping_matrices(mjmodel))
    rate = float(np.max(scipy.linalg.eigvalsh(C, M)))
    if dt * rate >= RK4_DAMPING_LIMIT:
        raise ParameterError(
            f"--integrator = 'RK4': dt = {dt:.3g} s is too large for stability: RK4 applies "
            f"the dampers explicitly, fastest damping rate {rate:.4g} 1/s, allowed (0, "
            f"{RK4_DAMPING_LIMIT / rate:.3g}) s")


def build_model(scenario: Scenario, **options) -> mujoco.MjModel:
    """The compiled MjModel the runner would step for ``scenario`` and ``options``."""
    return make_setup(scenario, **options).mjmodel


# --------------------------------------------------------------------------------- stepping
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


def _swing_time(imp: Pendulum) -> float:
    """Exact time (s) of the swing from rest at theta_r to the bottom: K(sin(theta_r/2)) sqrt(l_e/g)."""
    from scipy.special import ellipk

    s = math.sin(imp.release_angle / 2.0)
    return float(ellipk(s * s) * math.sqrt(imp.equivalent_length / imp.gravity))


@dataclass
class _Plan:
    setup: Setup
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


def _plan(setup: Setup) -> _Plan:
    n_main = int(math.ceil(setup.t_end / setup.dt)) + 2
    state0 = setup.initial_state.copy()
    if setup.pendulum == "linear":
        return _Plan(setup, state0, n_main)
    imp = setup.scenario.impactor
    t_swing = _swing_time(imp)
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


# ---------------------------------------------------------------------------------- record
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


def _step_means(p: np.ndarray, on: np.ndarray) -> np.ndarray:
    """Mean of a sampled power over each step n (samples n, n+1), n = 0 .. N-2 (RK4 ledger).

    Inside a run of samples with the same contact state ``on`` (the power is smooth there)
    the cubic through four samples of the run is integrated: (-1, 13, 13, -1) / 24 centred,
    (9, 19, -5, 1) / 24 or (1, -5, 19, 9) / 24 at the ends of the run (error O(h^4)); the
    trapezoid where the run is shorter and on a step where the contact state changes.
    """
    N = len(p)
    out = 0.5 * (p[:-1] + p[1:])
    if N < 2:
        return out
    n = np.arange(N - 1)
    run = np.concatenate([[0], np.cumsum(on[1:] != on[:-1])])
    same = run[:-1] == run[1:]

    def inrun(i):
        return (i >= 0) & (i < N) & (run[np.clip(i, 0, N - 1)] == run[n])

    def at(i):
        return p[np.clip(i, 0, N - 1)]

    central = same & inrun(n - 1) & inrun(n + 2)
    forward = same & ~central & inrun(n + 2) & inrun(n + 3)
    backward = same & ~central & ~forward & inrun(n - 2) & inrun(n - 1)
    out = np.where(central, (-at(n - 1) + 13.0 * at(n) + 13.0 * at(n + 1) - at(n + 2)) / 24.0,
                   out)
    out = np.where(forward, (9.0 * at(n) + 19.0 * at(n + 1) - 5.0 * at(n + 2) + at(n + 3))
                   / 24.0, out)
    return np.where(backward, (at(n - 2) - 5.0 * at(n - 1) + 19.0 * at(n) + 9.0 * at(n + 1))
                    / 24.0, out)


def _record(setup: Setup, state0, states, sensors) -> tuple[ImpactRecord, float, float]:
    """Build the ImpactRecord (t = 0 at the touch); returns (record, initial energy, touch index)."""
    m = setup.mjmodel
    sl = _builder.sensor_slices()
    nq, nv = m.nq, m.nv
    v_all = np.vstack([state0[1 + nq:1 + nq + nv], states[:, 1 + nq:1 + nq + nv]])  # n..N
    if not (np.all(np.isfinite(states)) and np.all(np.isfinite(sensors))):
        raise SimulationDiverged(f"mujoco: non-finite state (dt = {setup.dt:.3g} s)")
    # a rollout stopped on a warning stops advancing time: every step must add dt (to the
    # round-off of t + dt, not of n dt, which grows with the number of steps)
    steps = np.diff(np.concatenate(([state0[0]], states[:, 0])))
    if not np.all(np.abs(steps - setup.dt) <= 1e-6 * setup.dt):
        raise SimulationDiverged("mujoco: the rollout stopped on a MuJoCo warning "
                                 f"(dt = {setup.dt:.3g} s)")
    force = sensors[:, sl["force"]][:, 0]
    x = sensors[:, sl["x_pos"]][:, 0]
    vx = sensors[:, sl["x_vel"]][:, 0]
    tr = setup.scenario.trunk
    y = sensors[:, sl["y_pos"]][:, 0] + (tr.diameter / 2.0 + _builder.BOB_RADIUS)
    vy = sensors[:, sl["y_vel"]][:, 0]
    kinetic = sensors[:, sl["kinetic"]][:, 0]
    root = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY,
                             "trunk" if setup.trunk == "sdof" else "segment_0")
    g = -m.opt.gravity[2]
    trunk_grav = m.body_subtreemass[root] * g * sensors[:, sl["trunk_com"]][:, 2]
    potential = sensors[:, sl["potential"]][:, 0] - trunk_grav - setup.rest_potential
    model = setup.model
    mm = model.impactor_mass
    if setup.pendulum == "full":
        imp = setup.scenario.impactor
        pid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "pendulum")
        inertia = m.body_inertia[pid, 1] + mm * imp.equivalent_length ** 2
        th = np.concatenate([[state0[nq]], states[:-1, nq]])  # pendulum angle q_n
        om = v_all[:-1, -1]
        pend = 0.5 * inertia * om * om + mm * imp.gravity * imp.equivalent_length * (
            1.0 - np.cos(th))
        e0 = mm * imp.gravity * imp.equivalent_length * (1.0 - math.cos(imp.release_angle))
    else:
        pend = 0.5 * mm * vy * vy + 0.5 * model.impactor_stiffness * y * y
        e0 = float(kinetic[0] + potential[0])
    D, B = _damping_matrices(m)
    w = vy - vx
    dt = setup.dt
    rk4 = m.opt.integrator == mujoco.mjtIntegrator.mjINT_RK4
    if rk4:  # the stage forces are not recorded: damping work by quadrature (docstring)
        vs = v_all[:-1]
        d_power = _step_means(np.einsum("ni,ni->n", vs @ D, vs), force > 0.0)
    else:  # works over step n (n = 0 .. N-2), with v_n and v_{n+1}
        v0, v1 = v_all[:-2], v_all[1:-1]
        vbar = 0.5 * (v0 + v1)
        d_power = np.einsum("ni,ni->n", v0 @ D, vbar)  # v_n^T D vbar (matmul: BLAS, not einsum)
        if m.opt.integrator in _IMPLICIT_ENUMS:
            d_power += np.einsum("ni,ni->n", v1 @ B, vbar)  # B: joints and tendons
        elif B.any():
            d_power += np.einsum("ni,ni->n", v1 * np.diag(B), vbar)  # B diagonal (joint dampers)
        c_power = force[:-1] * 0.5 * (w[:-1] + w[1:])
    damping_work = np.concatenate([[0.0], np.cumsum(d_power) * dt])
    k_d = setup.law.stiffness
    overlap = np.where(force > 0.0, np.maximum(y - x, 0.0), 0.0)
    c_pot = 0.5 * k_d * overlap ** 2
    mech = kinetic + potential
    if not np.all(np.isfinite(mech)) or np.max(mech) > (1.0 + ENERGY_GROWTH_LIMIT) * e0:
        raise SimulationDiverged(
            f"mujoco: mechanical energy reached {np.nanmax(mech):.4g} J > "
            f"{1 + ENERGY_GROWTH_LIMIT:g} x the input {e0:.4g} J (dt = {dt:.3g} s)")
    if rk4:
        # the contact's work is what left the bodies other than through the dampers; what it
        # dissipated (work less the elastic energy it still holds) can only grow
        contact_work = e0 - mech - damping_work
        dissipated = contact_work - c_pot
        created = float(np.max(np.maximum.accumulate(dissipated) - dissipated))
    else:
        contact_work = np.concatenate([[0.0], np.cumsum(c_power) * dt])
        created = float(np.max(mech + damping_work + contact_work)) - e0
    if created > ENERGY_GROWTH_LIMIT * e0:  # the ledger: energy the engine made from nothing
        raise SimulationDiverged(
            f"mujoco: the engine created {created:.4g} J > {ENERGY_GROWTH_LIMIT:g} x the input "
            f"{e0:.4g} J (kinetic + potential + dissipated; dt = {dt:.3g} s)")
    # t = 0 at the touch: the first sample with force, interpolated on the overlap y - x
    on = np.flatnonzero(force > 0.0)
    if not on.size:
        raise SimulationDiverged("mujoco: the pendulum never touched the trunk")
    i1 = int(on[0])
    n = np.arange(len(force), dtype=float)
    if i1 == 0:
        start, t_touch = 0, 0.0
    else:
        g0, g1 = (y - x)[i1 - 1], (y - x)[i1]
        frac = min(1.0, max(0.0, -g0 / (g1 - g0))) if g1 != g0 else 1.0
        start, t_touch = i1 - 1, (i1 - 1 + frac) * dt
    t = n * dt - t_touch
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


def _crown_motion(setup: Setup, states: np.ndarray, n: int) -> dict:
    """The chain top's x (m) and x' (m/s) over the last ``n`` states (the record's)."""
    m = setup.mjmodel
    chain = hinged_chain(setup.scenario.trunk, setup.segments)
    ids = [mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, f"hinge_{j}")
           for j in range(chain.segments)]
    q = states[-n:, [1 + int(m.jnt_qposadr[i]) for i in ids]]
    v = states[-n:, [1 + m.nq + int(m.jnt_dofadr[i]) for i in ids]]
    crown, velocity = lateral_motion(chain, q, v, chain.segments)
    return {"crown": crown, "crown_velocity": velocity}


def _result(setup: Setup, state0, states, sensors) -> SimulationResult:
    record, e0, i1 = _record(setup, state0, states, sensors)
    model = setup.model
    imp = setup.scenario.impactor
    if setup.trunk == "sdof":  # the static shape carries the crown (eq 5)
        record = with_static_shape_crown(record, setup.scenario.trunk)
    else:  # the chain's top, from the hinge angles of the recorded states
        record = replace(record, **_crown_motion(setup, states, record.t.size))
    metrics = model_metrics(record, model, imp, collision_duration=setup.detection_duration,
                            initial_energy=e0)
    law = setup.law
    model_dict = {**model.as_dict(), "segments": setup.segments, "dt": setup.dt,
                  "contact_stiffness": law.stiffness, "contact_damping": law.damping,
                  "trunk": setup.trunk, "pendulum": setup.pendulum, "damping": setup.damping,
                  "integrator": setup.integrator, "calibration": setup.calibration,
                  "effective_mass": setup.effective_mass,
                  "law_stiffness": law.law_stiffness, "law_damping": law.law_damping,
                  "solref": list(setup.solref),
                  "solimp": [_contact.IMPEDANCE, _contact.IMPEDANCE, *_contact.SOLIMP_TAIL],
                  "collision_duration": setup.collision_duration,
                  "omega_max": setup.omega_max}
    scen = setup.scenario.to_dict()
    scen["contact"]["restitution"] = model.restitution
    scen["t_end"] = setup.t_end
    r = record
    return SimulationResult(
        backend="mujoco", metrics=metrics, model=model_dict, scenario=scen,
        trajectory=Trajectory(t=r.t, x=r.x, vx=r.vx, y=r.y, vy=r.vy, force=r.force),
        record=record, collision_duration=setup.collision_duration,
        extra={"initial_energy": e0, "impact_speed_measured": float(r.vy[0] - r.vx[0]),
               "law": law})


# ------------------------------------------------------------------------------------ API
def simulate(scenario: Scenario, *, trunk="chain", segments=None, pendulum="linear",
             contact_stiffness=None, dt=None, restitution=None, t_end=None,
             damping="distributed", integrator="Euler", calibration="pad"
             ) -> SimulationResult:
    """Run one scenario in MuJoCo (rules in the module docstring); backend "mujoco".

    ``integrator``: MuJoCo's ``Euler`` (default), ``implicit``, ``implicitfast`` or ``RK4``.
    ``calibration``: "pad" (default) the SDOF rung's (k_c, c_c); "effective" c_c
    recalibrated so that e holds on the trunk's effective mass at the clamp.
    """
    out = simulate_batch([scenario], trunk=trunk, segments=segments, pendulum=pendulum,
                         contact_stiffness=contact_stiffness, dt=dt, restitution=restitution,
                         t_end=t_end, damping=damping, integrator=integrator,
                         calibration=calibration, max_workers=1)[0]
    if isinstance(out, SimulationDiverged):
        raise out
    return out


def run_setups(setups: list[Setup], *, max_workers=None) -> list:
    """Roll out compiled setups; a SimulationResult or SimulationDiverged per setup, in order."""
    nthread = max_workers or os.cpu_count() or 1
    plans = [_plan(s) for s in setups]
    groups: dict = {}
    for i, p in enumerate(plans):
        groups.setdefault(_signature(p.setup.mjmodel), []).append(i)
    out = [None] * len(plans)
    for idx in groups.values():
        for i, (s0, st, sd) in zip(idx, _run_group([plans[i] for i in idx], nthread)):
            try:
                out[i] = _result(setups[i], s0, st, sd)
            except SimulationDiverged as exc:
                out[i] = exc
    return out


def simulate_batch(scenarios, *, max_workers=None, **options) -> list:
    """Simulate many scenarios with the same options through multi-threaded ``mujoco.rollout``.

    Models of one size signature (same trunk kind and segments) step together in one rollout
    call over ``max_workers`` threads (default: all CPUs). Returns, in order, a
    SimulationResult or the SimulationDiverged of each scenario; bad options raise
    ParameterError before anything is stepped.
    """
    setups = [make_setup(s, **options) for s in scenarios]
    return run_setups(setups, max_workers=max_workers)


def modes(scenario: Scenario, *, segments=None, n_modes: int = 3) -> dict:
    """Static stiffness at a (N/m) and natural frequencies (rad/s) of MuJoCo's chain.

    From the engine: the mass matrix ``mj_fullM`` at rest, the hinge stiffnesses of the
    compiled model and the impact point's x Jacobian ``mj_jacSite``: K_a = 1 / (J K^-1 J^T),
    omega^2 = eig(K, M). ``beam``: :func:`analytic.modes.beam_reference`.
    """
    import scipy.linalg

    from analytic.modes import beam_reference

    if not isinstance(scenario, Scenario):
        raise ParameterError("scenario: expected an analytic.Scenario")
    tspec, n = _trunk_spec(scenario, "chain", segments, "distributed")
    if isinstance(n_modes, bool) or not isinstance(n_modes, int) or not 1 <= n_modes <= n:
        raise ParameterError(f"n_modes = {n_modes!r} is out of range: allowed [1, {n}]")
    spec, _ = _builder.build_spec(f"{scenario.name}-chain-modes", tspec, scenario, "linear",
                                  PLACEHOLDER_DT)
    m = spec.compile()
    M, K = engine_trunk_matrices(m)
    J = impact_jacobian(m)
    kd = np.diag(K)
    static = float(1.0 / np.sum(J ** 2 / kd))
    w2 = scipy.linalg.eigh(K, M, eigvals_only=True, subset_by_index=[0, n_modes - 1])
    return {"model": {"static_stiffness": static, "omegas": [float(v) for v in np.sqrt(w2)],
                      "segments": n},
            "beam": beam_reference(scenario, n_modes)}


def impact_jacobian(m: mujoco.MjModel) -> np.ndarray:
    """d x(a) / d theta of the trunk's hinges from ``mj_jacSite`` at rest (m/rad)."""
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    jac = np.zeros((3, m.nv))
    mujoco.mj_jacSite(m, d, jac, None,
                      mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, "impact_point"))
    hinges = [j for j in range(m.njnt)
              if mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, j).startswith("hinge_")]
    return jac[0, [int(m.jnt_dofadr[j]) for j in hinges]]
