"""The PyBullet runner: one DIRECT client per process, fixed step, spring and damping forces by hand.

Design notes and measured figures: docs/engines.md.
"""

from __future__ import annotations

import math
import os
import tempfile
from dataclasses import dataclass, field, replace

import numpy as np

from analytic.chain import (chain_matrices, chain_natural_frequencies, default_segments,
                            hinged_chain, lateral_jacobian, lateral_motion)
from analytic.engine_options import check_choice, engine_model
from analytic.model import TwoBodyModel
from analytic.parameters import DEFAULT_CONTACT_DURATION, ParameterError, Scenario
from analytic.records import (ImpactRecord, detection_duration, model_metrics,
                              with_static_shape_crown)
from analytic.reduction import reduce_trunk
from analytic.results import SimulationDiverged, SimulationResult, Trajectory
from analytic.soft_contact import (CALIBRATIONS, collision_duration, contact_law,
                                   effective_damping)
from analytic.timestep import check_time_step, check_work, choose_time_step, sdof_rate

from . import _contact, _urdf

TRUNKS = ("sdof", "chain")
PENDULUMS = ("linear", "full")
CONTACTS = ("soft", "newton")
DAMPINGS = ("distributed", "joint")
RESTITUTION_THRESHOLD_FRACTION = 1e-3  # of u1: slower bounces are plastic (newton mode)
SWING_STEP = 1e-4  # s: step of the full pendulum's free swing before the contact
SWING_SWITCH_STEPS = 20  # switch to the impact step this many swing steps before contact
ENERGY_GROWTH_LIMIT = 0.05  # relative: mechanical energy above (1 + this) E0 = diverged
JOINT_VELOCITY_LIMIT = 1e6  # rad/s or m/s: Bullet clamps joint speeds here (default 100)



# ----------------------------------------------------------------------------------- client
_CLIENT = {"id": None, "dir": None, "files": {}}


def _import_pybullet():
    """``import pybullet`` without its build-time banner on stderr (CLI: one-line errors)."""
    import sys

    if "pybullet" in sys.modules:
        return sys.modules["pybullet"]
    try:
        sys.stderr.flush()
        saved = os.dup(2)
        devnull = os.open(os.devnull, os.O_WRONLY)
    except (OSError, ValueError):  # no real stderr (captured): nothing to keep clean
        import pybullet
        return pybullet
    try:
        os.dup2(devnull, 2)
        import pybullet
    finally:
        os.dup2(saved, 2)
        os.close(saved)
        os.close(devnull)
    return pybullet


def client():
    """This process's PyBullet DIRECT client (created once)."""
    p = _import_pybullet()

    cid = _CLIENT["id"]
    if cid is None or not p.isConnected(cid):
        cid = p.connect(p.DIRECT)
        _CLIENT["id"] = cid
    return p, cid


def load(p, cid, text: str) -> int:
    """Load a model's URDF text as a fixed-base multibody with the URDF's own inertias.

    Without ``URDF_USE_INERTIA_FROM_FILE`` PyBullet replaces every link's inertia by that of
    its collision shapes (a 1 mm default box for the chain segments, the pad's box for the
    clamp segment, the 5 cm sphere for the bob): measured on the central-leader chain, the
    mass matrix then differs from :func:`analytic.chain.chain_matrices` by 6e-4 of its
    largest entry instead of 2e-16. Every link's joint-velocity clamp (Bullet's default is
    100 rad/s or m/s, reached by the chain's segments at impact) is raised to
    :data:`JOINT_VELOCITY_LIMIT`; a run that reaches it is reported as diverged.
    """
    body = p.loadURDF(_urdf_file(text), useFixedBase=True,
                      flags=p.URDF_USE_INERTIA_FROM_FILE, physicsClientId=cid)
    for j in range(p.getNumJoints(body, physicsClientId=cid)):
        p.changeDynamics(body, j, maxJointVelocity=JOINT_VELOCITY_LIMIT, physicsClientId=cid)
    return body


def _urdf_file(text: str) -> str:
    files = _CLIENT["files"]
    if text not in files:
        if _CLIENT["dir"] is None:
            _CLIENT["dir"] = tempfile.mkdtemp(prefix="bullet_models_")
        path = os.path.join(_CLIENT["dir"], f"model_{len(files)}.urdf")
        with open(path, "w") as fh:
            fh.write(text)
        files[text] = path
    return files[text]


# ------------------------------------------------------------------------------------ setup
@dataclass(frozen=True)
class Setup:
    """Everything a run needs, computed without the engine (SI units)."""

    scenario: Scenario
    model: TwoBodyModel
    trunk: str
    pendulum: str
    contact: str
    damping: str
    segments: int | None
    dt: float
    t_end: float
    trunk_urdf: str
    pendulum_urdf: str
    contact_stiffness: float | None  # k_c, N/m (soft)
    contact_damping: float | None  # c_c, N s/m (soft, the continuous law)
    bullet: _contact.BulletContact | None
    collision_duration: float  # s: t_c of the soft law (soft) or dt (newton: one-step impulses)
    omega_max: float | None
    apparent_mass: float  # kg: trunk mass seen by the contact
    calibration: str = "pad"  # analytic.soft_contact.CALIBRATIONS
    matrices: tuple | None = field(default=None, repr=False)  # chain (M, K, D)


def make_setup(scenario: Scenario, *, trunk="chain", segments=None, pendulum="linear",
               contact="soft", contact_stiffness=None, dt=None, restitution=None, t_end=None,
               damping="distributed", calibration="pad") -> Setup:
    if not isinstance(scenario, Scenario):
        raise ParameterError("scenario: expected an analytic.Scenario")
    check_choice("trunk", trunk, TRUNKS)
    check_choice("pendulum", pendulum, PENDULUMS)
    check_choice("contact", contact, CONTACTS)
    check_choice("damping", damping, DAMPINGS)
    check_choice("calibration", calibration, CALIBRATIONS)
    model, t_end = engine_model(scenario, pendulum=pendulum, restitution=restitution,
                                t_end=t_end)
    tr = scenario.trunk
    matrices = None
    if trunk == "chain":
        n = default_segments(tr) if segments is None else segments
        chain = hinged_chain(tr, n)
        M, K, D = chain_matrices(chain)
        ja = lateral_jacobian(chain, tr.clamp_height)[0]
        apparent = float(1.0 / (ja @ np.linalg.solve(M, ja)))
        omega_max = float(chain_natural_frequencies(chain, chain.segments)[-1])
        trunk_urdf = _urdf.trunk_chain_urdf(chain, name=f"{scenario.name}-trunk-chain-{n}")
        segments = n
        matrices = (M, K, D)
    else:
        if segments is not None:
            raise ParameterError("--segments: only for --trunk chain")
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
        if not model.restitution < 1.0:
            raise ParameterError(
                f"contact.restitution = {model.restitution:g}: Bullet's soft contact steps "
                "implicitly and always dissipates: allowed (0, 1) with --contact soft (e = 1: "
                "--contact newton)")
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
    # the loop keeps Python floats of every step: 2 per joint and the contact force, ~32 B each
    check_work(t_end, dt, 32.0 * (2 * (segments or 1) + 3))
    return Setup(scenario=scenario, model=model, trunk=trunk, pendulum=pendulum,
                 contact=contact, damping=damping, segments=segments, dt=float(dt),
                 t_end=float(t_end), trunk_urdf=trunk_urdf, pendulum_urdf=pend_urdf,
                 contact_stiffness=k_c, contact_damping=c_c, bullet=bullet,
                 collision_duration=col, omega_max=omega_max, apparent_mass=apparent,
                 matrices=matrices, calibration=calibration)


# ------------------------------------------------------------------------------------ world
@dataclass
class World:
    p: object
    cid: int
    trunk: int
    pendulum: int
    trunk_joints: list
    contact_link: int


def build_world(setup: Setup, client_id: int | None = None) -> World:
    """Load both bodies into this process's client (or ``client_id``), configured for ``setup``."""
    p, cid = client()
    if client_id is not None:
        cid = client_id
    p.resetSimulation(physicsClientId=cid)
    p.setGravity(0.0, 0.0, 0.0, physicsClientId=cid)
    newton = setup.contact == "newton"
    u1 = setup.model.impact_speed
    p.setPhysicsEngineParameter(
        fixedTimeStep=setup.dt, numSubSteps=0, numSolverIterations=50, contactSlop=0.0,
        restitutionVelocityThreshold=RESTITUTION_THRESHOLD_FRACTION * u1 if newton else 0.0,
        contactERP=0.0 if newton else 0.2, globalCFM=0.0, enableConeFriction=0,
        deterministicOverlappingPairs=1, physicsClientId=cid)
    tb = load(p, cid, setup.trunk_urdf)
    pb = load(p, cid, setup.pendulum_urdf)
    nj = p.getNumJoints(tb, physicsClientId=cid)
    joints = list(range(nj))
    p.setJointMotorControlArray(tb, joints, p.VELOCITY_CONTROL, forces=[0.0] * nj,
                                physicsClientId=cid)
    p.setJointMotorControl2(pb, 0, p.VELOCITY_CONTROL, force=0.0, physicsClientId=cid)
    for j in joints:  # no native damping anywhere: the runner applies it
        p.changeDynamics(tb, j, linearDamping=0.0, angularDamping=0.0, jointDamping=0.0,
                         lateralFriction=0.0, physicsClientId=cid)
    p.changeDynamics(pb, 0, linearDamping=0.0, angularDamping=0.0, jointDamping=0.0,
                     lateralFriction=0.0, physicsClientId=cid)
    pad = joints[-1] if setup.trunk == "sdof" else _clamp_link(setup)
    for body, link in ((tb, pad), (pb, 0)):
        if newton:
            rest = setup.model.restitution if body == pb else 1.0
            p.changeDynamics(body, link, restitution=rest, contactProcessingThreshold=0.0,
                             physicsClientId=cid)
        else:
            ks, ds = setup.bullet.per_body
            p.changeDynamics(body, link, restitution=0.0, contactStiffness=ks,
                             contactDamping=ds, physicsClientId=cid)
    return World(p, cid, tb, pb, joints, pad)


def _clamp_link(setup: Setup) -> int:
    return hinged_chain(setup.scenario.trunk, setup.segments).clamp_segment


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
    chain = setup.trunk == "chain"
    if chain:
        rec = _loop_chain(world, setup, n_steps, full, le, g, m)
    else:
        rec = _loop_sdof(world, setup, n_steps, full, le, g, m)
    return _result(setup, rec, t_shift, e0, inertia)


def _swing(world: World, setup: Setup, le: float, g: float):
    """Release the full pendulum at -theta_r; step until it is about to touch (eq 48).

    Swings with :data:`SWING_STEP` (or dt if smaller), switching to dt shortly before the
    contact, and stops at the last step before the bob reaches the trunk. Returns
    (time of touch measured from now, s; initial energy m g l_e (1 - cos theta_r), J).
    """
    p, cid, pb = world.p, world.cid, world.pendulum
    imp = setup.scenario.impactor
    m = imp.mass
    theta_r = imp.release_angle
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


def _loop_sdof(world, setup, n_steps, full, le, g, m):
    """Step the SDOF trunk; per step two joint-state reads, two torques, one contact query.

    The PyBullet calls take their arguments by position (keyword parsing costs ~0.7 us per
    call against a ~3 us step) and the loop only keeps what the engine returns; the arrays
    are built after the loop.
    """
    p, cid, tb, pb = world.p, world.cid, world.trunk, world.pendulum
    model = setup.model
    K, C, kp = model.stiffness, model.damping, model.impactor_stiffness
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
        if not (n & 1023) and not isfinite(x + y):
            raise SimulationDiverged(f"bullet: non-finite state at t = {n * setup.dt:.4g} s")
    states.extend(gjs(tb, 0, cid)[:2] + gjs(pb, 0, cid)[:2])
    x, vx, q, qd = np.array(states).reshape(n_steps + 1, 4).T
    force = np.zeros(n_steps + 1)
    force[list(contact_force)] = list(contact_force.values())
    return {"x": x, "vx": vx, "q": q, "qd": qd, "force": force,
            "joint_speed": max(float(np.max(np.abs(vx))), float(np.max(np.abs(qd))))}


def _loop_chain(world, setup, n_steps, full, le, g, m):
    p, cid, tb, pb = world.p, world.cid, world.trunk, world.pendulum
    model = setup.model
    M, K, _ = setup.matrices
    kdiag = np.diag(K).copy()
    Dv, Dq = damping_operators(setup)
    kp = model.impactor_stiffness
    mgl = m * g * le if full else 0.0
    joints = world.trunk_joints
    nj = len(joints)
    gjss, sjma, sjm, gjs, step, gcp = (p.getJointStates, p.setJointMotorControlArray,
                                       p.setJointMotorControl2, p.getJointState,
                                       p.stepSimulation, p.getContactPoints)
    TQ = p.TORQUE_CONTROL
    # the hinge torques -K theta - (Dv theta' - Dq theta) as one operator on the state read
    # from the engine, (theta_0, theta'_0, theta_1, theta'_1, ...)
    torque = np.empty((nj, 2 * nj))
    torque[:, 0::2] = -np.diag(kdiag) + (Dq if Dq is not None else 0.0)
    torque[:, 1::2] = -Dv
    trunk_states = []  # (nj, 2) arrays: theta, theta' of each step
    pendulum_states = []  # q, q' of each step, flat
    keep, keep_pendulum = trunk_states.append, pendulum_states.append
    contact_force = {}  # step -> summed normal force, N (steps with contact only)
    sin = math.sin
    for n in range(n_steps):
        z = np.array([s[:2] for s in gjss(tb, joints, cid)])
        ps = gjs(pb, 0, cid)
        y = ps[0]
        keep(z)
        keep_pendulum(y)
        keep_pendulum(ps[1])
        sjma(tb, joints, TQ, forces=(torque @ z.ravel()).tolist(), physicsClientId=cid)
        # positional arguments as in _loop_sdof
        sjm(pb, 0, TQ, 0.0, 0.0, -mgl * sin(y) if full else -kp * y, 0.1, 1.0, -1.0, cid)
        step(cid)
        points = gcp(tb, pb, -2, -2, cid)  # -2: any link (PyBullet's default)
        if points:
            contact_force[n] = sum(c[9] for c in points)
        if not (n & 1023) and not np.all(np.isfinite(z)):
            raise SimulationDiverged(f"bullet: non-finite state at t = {n * setup.dt:.4g} s")
    keep(np.array([s[:2] for s in gjss(tb, joints, cid)]))
    pendulum_states.extend(gjs(pb, 0, cid)[:2])
    states = np.array(trunk_states)
    Q, QD = states[:, :, 0], states[:, :, 1]
    q, qd = np.array(pendulum_states).reshape(n_steps + 1, 2).T
    force = np.zeros(n_steps + 1)
    force[list(contact_force)] = list(contact_force.values())
    chain = hinged_chain(setup.scenario.trunk, setup.segments)
    x, vx = lateral_motion(chain, Q, QD, chain.clamp_index)
    crown, crown_v = lateral_motion(chain, Q, QD, chain.segments)
    kin = 0.5 * np.einsum("ni,ij,nj->n", QD, M, QD)
    pot = 0.5 * (Q * Q) @ kdiag
    tau_d = QD[:-1] @ Dv.T  # the damping torque applied over each step (resisting)
    if Dq is not None:
        tau_d -= Q[:-1] @ Dq.T
    ddot = np.einsum("ni,ni->n", tau_d, 0.5 * (QD[:-1] + QD[1:]))
    return {"x": x, "vx": vx, "crown": crown, "crown_velocity": crown_v, "q": q, "qd": qd, "force": force, "trunk_kinetic": kin,
            "trunk_potential": pot, "damping_power": ddot,
            "joint_speed": max(float(np.max(np.abs(QD))), float(np.max(np.abs(qd))))}


def damping_operators(setup: Setup) -> tuple[np.ndarray, np.ndarray | None]:
    """(Dv, Dq): the chain's damping torque over step n is -(Dv theta'_n - Dq theta_n).

    ``distributed``: explicit, Dv = D of :func:`analytic.chain.chain_matrices`, Dq = None
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
    B = np.diag(_joint_damping(M, K, D))
    G = B @ np.linalg.inv(M + setup.dt * B)
    return G @ M, -setup.dt * (G @ K)


def _joint_damping(M, K, D) -> np.ndarray:
    """Hinge dampers beta k_j (stiffness-proportional) with the first mode's damping of D.

    The documented alternative to the distributed damping: beta = phi^T D phi / phi^T K phi
    for the first mode phi, so mode 1 keeps its damping ratio; higher modes get more.
    """
    import scipy.linalg

    w2, vec = scipy.linalg.eigh(K, M, subset_by_index=[0, 0])
    phi = vec[:, 0]
    beta = float(phi @ D @ phi) / float(phi @ K @ phi)
    return beta * np.diag(K)


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
    mech = kinetic + potential
    if not np.all(np.isfinite(mech)) or np.max(mech) > (1.0 + ENERGY_GROWTH_LIMIT) * e0:
        raise SimulationDiverged(
            f"bullet: mechanical energy reached {np.nanmax(mech):.4g} J > "
            f"{1 + ENERGY_GROWTH_LIMIT:g} x the input {e0:.4g} J (dt = {dt:.3g} s)")
    # the force of step n acts from sample n to n + 1; the last sample repeats it
    force_rec = force.copy()
    force_rec[-1] = force[-2]
    record = ImpactRecord(t=t, x=x, vx=vx, y=y, vy=vy, force=force_rec, kinetic=kinetic,
                          potential=potential, damping_work=damping_work,
                          contact_work=contact_work, contact_potential=c_pot,
                          pendulum_energy=pend_kin + pend_pot)
    imp = setup.scenario.impactor
    if setup.trunk == "sdof":  # the static shape carries the crown (eq 5)
        record = with_static_shape_crown(record, setup.scenario.trunk)
    else:  # the chain's top
        record = replace(record, crown=rec["crown"], crown_velocity=rec["crown_velocity"])
    metrics = model_metrics(record, model, imp, collision_duration=setup.collision_duration,
                            initial_energy=e0)
    b = setup.bullet
    model_dict = {**model.as_dict(), "segments": setup.segments, "dt": dt,
                  "contact_stiffness": b.stiffness if b else None,
                  "contact_damping": b.damping if b else None,
                  "trunk": setup.trunk, "pendulum": setup.pendulum, "damping": setup.damping, "calibration": setup.calibration,
                  "effective_mass": b.reduced_mass if b else None,
                  "law_stiffness": setup.contact_stiffness,
                  "law_damping": setup.contact_damping,
                  "collision_duration": setup.collision_duration,
                  "integrator": "semi-implicit Euler",  # Bullet's only one (module docstring)
                  "omega_max": setup.omega_max,
                  "contact": setup.contact, "apparent_mass": setup.apparent_mass,
                  "contact_erp": b.erp if b else 0.0,
                  "contact_cfm": b.cfm if b else 0.0,
                  "restitution_velocity_threshold": (
                      RESTITUTION_THRESHOLD_FRACTION * model.impact_speed
                      if setup.contact == "newton" else 0.0)}
    scen = setup.scenario.to_dict()
    scen["contact"]["restitution"] = model.restitution
    scen["t_end"] = setup.t_end
    return SimulationResult(
        backend="bullet", metrics=metrics, model=model_dict, scenario=scen,
        trajectory=Trajectory(t=t, x=x, vx=vx, y=y, vy=vy, force=force_rec),
        record=record, collision_duration=setup.collision_duration,
        extra={"initial_energy": e0})


def simulate(scenario: Scenario, *, trunk="chain", segments=None, pendulum="linear",
             contact="soft", contact_stiffness=None, dt=None, restitution=None, t_end=None,
             damping="distributed", calibration="pad") -> SimulationResult:
    """Run one scenario in PyBullet (rules in the module docstring); backend "bullet".

    ``calibration``: "pad" (default) the SDOF rung's (k_c, c_c); "effective" c_c
    recalibrated so that e holds on the trunk's effective mass at the clamp.
    """
    return run(make_setup(scenario, trunk=trunk, segments=segments, pendulum=pendulum,
                          contact=contact, contact_stiffness=contact_stiffness, dt=dt,
                          restitution=restitution, t_end=t_end, damping=damping,
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
    """Static stiffness at a (N/m) and natural frequencies (rad/s) of Bullet's chain.

    Mass matrix from the engine (``calculateMassMatrix`` at rest), stiffness from the hinge
    springs the runner applies, the clamp point's lateral Jacobian from the engine
    (``calculateJacobian``): K_a = 1 / (J K^-1 J^T), omega^2 = eig(K, M). ``beam``: the
    continuous-beam reference of :func:`analytic.modes.beam_reference`.
    """
    import scipy.linalg

    from analytic.modes import beam_reference

    tr = scenario.trunk
    n = default_segments(tr) if segments is None else segments
    chain = hinged_chain(tr, n)
    if isinstance(n_modes, bool) or not isinstance(n_modes, int) or not 1 <= n_modes <= n:
        raise ParameterError(f"n_modes = {n_modes!r} is out of range: allowed [1, {n}]")
    M, J = engine_matrices(chain)
    kd = np.asarray(chain.hinge_stiffnesses)
    static = float(1.0 / np.sum(J ** 2 / kd))
    w2 = scipy.linalg.eigh(np.diag(kd), M, eigvals_only=True, subset_by_index=[0, n_modes - 1])
    return {"model": {"static_stiffness": static, "omegas": [float(v) for v in np.sqrt(w2)],
                      "segments": n},
            "beam": beam_reference(scenario, n_modes)}


def engine_matrices(chain) -> tuple[np.ndarray, np.ndarray]:
    """(mass matrix at rest from Bullet, kg m^2; d x(a) / d theta from Bullet, m/rad)."""
    p, cid = client()
    p.resetSimulation(physicsClientId=cid)
    text = _urdf.trunk_chain_urdf(chain)
    body = load(p, cid, text)
    n = chain.segments
    zeros = [0.0] * n
    M = np.asarray(p.calculateMassMatrix(body, zeros, physicsClientId=cid))
    link = chain.clamp_segment
    # the top of the clamp segment, z = a, in the link's URDF frame (which is where PyBullet
    # 3.2.7 takes localPosition from, measured: not the centre-of-mass frame)
    local = (0.0, 0.0, float(chain.lengths[link]))
    lin, _ = p.calculateJacobian(body, link, local, zeros, zeros, zeros, physicsClientId=cid)
    return M, np.asarray(lin)[0]
