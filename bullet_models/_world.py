"""PyBullet's side of a run: one DIRECT client per process, the URDF models loaded with
their own inertias, the world configured for a setup, and the engine's chain matrices."""

from __future__ import annotations

import os
import tempfile
from dataclasses import dataclass

import numpy as np

from treeimpact.analytic.continuum.chain import hinged_chain

from . import _urdf

RESTITUTION_THRESHOLD_FRACTION = 1e-3  # of u1: slower bounces are plastic (newton mode)
JOINT_VELOCITY_LIMIT = 1e6  # rad/s or m/s: Bullet clamps joint speeds here (default 100)


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
    mass matrix then differs from :func:`analytic.continuum.chain.chain_matrices` by 6e-4 of its
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
