"""PyBullet's side of a run: one DIRECT client per process, the URDF models loaded with
their own inertias, the world configured for a setup, and the engine's chain matrices."""

from __future__ import annotations

import math
import os
import sys
import tempfile
from dataclasses import dataclass

import numpy as np

from treeimpact.analytic.continuum.chain import hinged_chain
from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.results import FreeCollision

from . import _urdf
from ._contact import combine_damping, combine_stiffness

RESTITUTION_THRESHOLD_FRACTION = 1e-3  # of u1: slower bounces are plastic (newton mode)
JOINT_VELOCITY_LIMIT = 1e6  # rad/s or m/s: Bullet clamps joint speeds here (default 100)


_CLIENT = {"id": None}


def _import_pybullet():
    """``import pybullet`` without its build-time banner on stderr (CLI: one-line errors)."""

    if "pybullet" in sys.modules:
        return sys.modules["pybullet"]
    try:
        sys.stderr.flush()
        saved = os.dup(2)
        devnull = os.open(os.devnull, os.O_WRONLY)
    except (OSError, ValueError):  # no real stderr (captured): nothing to keep clean
        # lazy: pybullet prints a build banner on stderr at import; imported here, once
        import pybullet
        return pybullet
    try:
        os.dup2(devnull, 2)
        # lazy: pybullet prints a build banner on stderr at import; imported here, once
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
    mass matrix then differs from :func:`analytic.continuum.chain.chain_matrices` by 6e-4 of its
    largest entry instead of 2e-16. Every link's joint-velocity clamp (Bullet's default is
    100 rad/s or m/s, reached by the chain's segments at impact) is raised to
    :data:`JOINT_VELOCITY_LIMIT`; a run that reaches it is reported as diverged.
    """
    body = load_urdf(p, cid, text, useFixedBase=True)
    for j in range(p.getNumJoints(body, physicsClientId=cid)):
        p.changeDynamics(body, j, maxJointVelocity=JOINT_VELOCITY_LIMIT, physicsClientId=cid)
    return body


def load_urdf(p, cid, text: str, **options) -> int:
    """``p.loadURDF`` of URDF ``text`` with the file's own inertias: loadURDF reads a file,
    written to a temporary folder that is gone once loaded (in any process, a pool's worker
    too: nothing left behind)."""
    with tempfile.TemporaryDirectory(prefix="bullet_models_") as folder:
        path = os.path.join(folder, "model.urdf")
        with open(path, "w", encoding="utf-8") as fh:
            fh.write(text)
        return p.loadURDF(path, flags=p.URDF_USE_INERTIA_FROM_FILE, physicsClientId=cid,
                          **options)


@dataclass
class World:
    p: object
    cid: int
    trunk: int
    pendulum: int
    trunk_joints: list
    contact_link: int


def build_world(setup, client_id: int | None = None) -> World:
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


def _clamp_link(setup) -> int:
    return hinged_chain(setup.scenario.trunk, setup.segments).clamp_segment


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


#: Bullet world settings for a soft contact with exact restitution (``treeimpact contact``
#: prints them): no gravity, one fixed step, no slop, no global CFM, restitution 0.
WORLD_FLAGS = {"numSubSteps": 0, "numSolverIterations": 50, "contactSlop": 0.0,
               "globalCFM": 0.0, "restitutionVelocityThreshold": 0.0,
               "enableConeFriction": 0, "deterministicOverlappingPairs": 1}
#: Per-link settings beside contactStiffness/contactDamping: no restitution impulse, no
#: friction, none of Bullet's default velocity damping (0.04 per link).
LINK_FLAGS = {"restitution": 0.0, "lateralFriction": 0.0, "linearDamping": 0.0,
              "angularDamping": 0.0}
SPHERE_RADIUS = 0.05  # m: the two-body collision's spheres (geometry only)


def two_body_collision(mass: float, other_mass: float, dt: float, stiffness: float,
                       damping: float, speed: float = 1.0, flags: bool = True,
                       overlap: float = 0.0) -> FreeCollision:
    """Collide sphere a (``mass``) into sphere b (``other_mass``; fixed when infinite) at
    ``speed`` (m/s), starting touching (default: at distance 0, where Bullet's contact
    starts) or ``overlap`` m into b (as MuJoCo's :func:`mujoco_models.two_body_collision`),
    each link given ``stiffness``/``damping`` (per link,
    N/m and N s/m) and, with ``flags``, :data:`WORLD_FLAGS` and :data:`LINK_FLAGS`;
    its :class:`analytic.results.FreeCollision` (restitution, touch duration s, steps with a
    normal force, peak penetration m; NaN where the state left the finite). The duration
    ends where the
    links' combined law force k delta + c delta' first reaches zero, interpolated between
    the steps it acts over (Bullet's implicit force is that of the step's end state)."""
    p, cid = client()
    p.resetSimulation(physicsClientId=cid)
    p.setGravity(0.0, 0.0, 0.0, physicsClientId=cid)
    p.setPhysicsEngineParameter(fixedTimeStep=dt, physicsClientId=cid,
                                **(WORLD_FLAGS if flags else {"numSubSteps": 0}))
    bodies = []
    for m, x in ((mass, overlap - SPHERE_RADIUS), (other_mass, SPHERE_RADIUS)):
        fixed = not math.isfinite(m)
        text = _urdf.sphere_urdf(1.0 if fixed else m, SPHERE_RADIUS)
        body = load_urdf(p, cid, text, basePosition=[x, 0.0, 0.0], useFixedBase=fixed)
        p.changeDynamics(body, -1, contactStiffness=stiffness, contactDamping=damping,
                         physicsClientId=cid, **(LINK_FLAGS if flags else {}))
        bodies.append(body)
    a, b = bodies
    p.resetBaseVelocity(a, [speed, 0.0, 0.0], [0.0, 0.0, 0.0], physicsClientId=cid)
    k, c = combine_stiffness(stiffness, stiffness), combine_damping(damping, damping)

    def state():
        (xa, _, _), _ = p.getBasePositionAndOrientation(a, physicsClientId=cid)
        (xb, _, _), _ = p.getBasePositionAndOrientation(b, physicsClientId=cid)
        va = p.getBaseVelocity(a, physicsClientId=cid)[0][0]
        vb = p.getBaseVelocity(b, physicsClientId=cid)[0][0]
        depth = 2.0 * SPHERE_RADIUS - (xb - xa)
        return k * depth + c * (va - vb), vb - va, depth

    law_prev, _, _ = state()
    pushing, t_release, peak = 0, None, 0.0
    for n in range(1, 1_000_001):
        p.stepSimulation(physicsClientId=cid)
        if sum(cp[9] for cp in p.getContactPoints(a, b, physicsClientId=cid)) > 0.0:
            pushing += 1
        law, sep, depth = state()
        if not (math.isfinite(law) and math.isfinite(sep)):
            return FreeCollision(math.nan, math.nan, pushing, math.nan)
        peak = max(peak, depth)
        if t_release is None and law <= 0.0:
            # the force of state n acted over step n (implicit): it stands at (n - 1) dt
            t_release = (n - 2 + law_prev / (law_prev - law)) * dt
        if t_release is not None and sep > 0.0:
            return FreeCollision(sep / speed, t_release, pushing, peak)
        law_prev = law
    raise ParameterError("--dt: the collision did not end within 1e6 steps")
