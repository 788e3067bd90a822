"""MJCF models of the trunk, the pendulum and their contact, built with ``mujoco.MjSpec``.

Design notes and measured figures: docs/engines.md.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np
import scipy.linalg

from treeimpact.analytic.continuum.chain import HingedChain, chain_matrices
from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.model.parameters import Billet, Pendulum, Scenario
from treeimpact.analytic.model.reduction import TreeSDOF

from . import _contact, _flex

BOB_RADIUS = 0.05  # m: radius of the pendulum's contact sphere (geometry only)
BOB_INERTIA_FRACTION = 1e-6  # bob inertia about its centre / (m l_e^2)
TOUCH_SITE_FACTOR = 1.5  # touch-sensor zone radius / bob radius: holds the contact point
SENSOR_LAYOUT = (("force", 1), ("x_pos", 3), ("x_vel", 3), ("y_pos", 3), ("y_vel", 3),
                 ("kinetic", 1), ("potential", 1), ("trunk_com", 3))


def sensor_slices() -> dict:
    """Name -> slice into the sensordata vector (layout :data:`SENSOR_LAYOUT`)."""
    out, i = {}, 0
    for name, n in SENSOR_LAYOUT:
        out[name] = slice(i, i + n)
        i += n
    return out


@dataclass(frozen=True)
class TrunkSpec:
    """What the builder needs about the trunk (SI units)."""

    kind: str  # "sdof" | "chain" | "flex"
    sdof: TreeSDOF | None
    chain: HingedChain | None
    damping: str  # "distributed" | "joint"
    flex: _flex.FlexTrunk | None = None


def joint_damping(chain: HingedChain) -> np.ndarray:
    """Hinge dampers beta k_j (N m s/rad): the first mode keeps the damping of D (docstring)."""

    M, K, D = chain_matrices(chain)
    _, vec = scipy.linalg.eigh(K, M, subset_by_index=[0, 0])
    phi = vec[:, 0]
    beta = float(phi @ D @ phi) / float(phi @ K @ phi)
    return beta * np.diag(K)


#: ``integrator`` option value -> MuJoCo's enum.
INTEGRATOR_ENUMS = {"Euler": mujoco.mjtIntegrator.mjINT_EULER,
                    "implicit": mujoco.mjtIntegrator.mjINT_IMPLICIT,
                    "implicitfast": mujoco.mjtIntegrator.mjINT_IMPLICITFAST,
                    "RK4": mujoco.mjtIntegrator.mjINT_RK4}


def _spec(name: str, dt: float, gravity: float, implicit_damping: bool,
          integrator: str = "Euler") -> mujoco.MjSpec:
    spec = mujoco.MjSpec()
    spec.modelname = name
    spec.compiler.degree = False
    spec.compiler.inertiafromgeom = mujoco.mjtInertiaFromGeom.mjINERTIAFROMGEOM_FALSE
    spec.compiler.autolimits = True
    opt = spec.option
    opt.timestep = dt
    opt.integrator = INTEGRATOR_ENUMS[integrator]
    opt.solver = mujoco.mjtSolver.mjSOL_NEWTON
    opt.gravity = [0.0, 0.0, -gravity]
    # no mjENBL_ENERGY: since MuJoCo 3.5 the e_kinetic sensor (position stage) reads the
    # kinetic energy the flag computed in the previous step's velocity stage (one step late);
    # without the flag the sensor computes it from the current state
    if not implicit_damping:
        opt.disableflags = int(mujoco.mjtDisableBit.mjDSBL_EULERDAMP)
    return spec


def _geom(body, name, gtype, size, pos=(0.0, 0.0, 0.0), rgba=None, group=0, fromto=None):
    g = body.add_geom()
    g.name = name
    g.type = gtype
    g.size = list(size) + [0.0] * (3 - len(size))
    g.contype = 0
    g.conaffinity = 0
    g.group = group
    if fromto is not None:
        g.fromto = list(fromto)
    else:
        g.pos = list(pos)
    if rgba is not None:
        g.rgba = list(rgba)
    return g


def _site(body, name, pos, radius):
    s = body.add_site()
    s.name = name
    s.pos = list(pos)
    s.size = [radius, 0.0, 0.0]
    return s


def _inertial(body, mass, com_z, inertia):
    body.explicitinertial = True
    body.mass = float(mass)
    body.ipos = [0.0, 0.0, float(com_z)]
    body.inertia = [float(inertia)] * 3


#: The trunk's colour in MuJoCo's viewer (RGBA).
WOOD = (0.55, 0.4, 0.25, 1.0)


def add_trunk(spec: mujoco.MjSpec, trunk: TrunkSpec, clamp_height: float, diameter: float):
    """Add the trunk to ``spec``; returns the name of its root body."""
    if trunk.kind == "flex":
        return _flex.add_flex_trunk(spec, trunk.flex)
    if trunk.kind == "sdof":
        return _add_sdof(spec, trunk.sdof, clamp_height, diameter / 2.0)
    chain = trunk.chain
    damp = joint_damping(chain) if trunk.damping == "joint" else None
    parent = spec.worldbody
    for j in range(chain.segments):
        parent = _add_segment(parent, chain, j, diameter / 2.0, damp)
    if trunk.damping == "distributed" and chain.trunk.damping > 0:
        _add_dampers(spec, chain)
    return "segment_0"


def _add_sdof(spec: mujoco.MjSpec, tree, clamp_height: float, r: float) -> str:
    """The 1-DOF trunk ``tree`` (M_T, K_T, C_T) as a body on a slide joint at the clamp."""
    body = spec.worldbody.add_body()
    body.name = "trunk"
    body.pos = [0.0, 0.0, clamp_height]
    body.gravcomp = 1.0
    _inertial(body, tree.dynamic_mass, 0.0, 0.5 * tree.dynamic_mass * r * r)
    j = body.add_joint()
    j.name = "trunk_x"
    j.type = mujoco.mjtJoint.mjJNT_SLIDE
    j.axis = [1.0, 0.0, 0.0]
    j.stiffness[0] = tree.equivalent_stiffness
    j.damping[0] = tree.equivalent_damping
    _geom(body, "trunk_pad", mujoco.mjtGeom.mjGEOM_SPHERE, [r], rgba=WOOD)
    _site(body, "impact_point", (0.0, 0.0, 0.0), 0.2 * r)
    return "trunk"


def _add_segment(parent, chain, j: int, r: float, damp):
    """Segment ``j`` of the hinged ``chain`` under ``parent`` (radius ``r`` m; its hinge's
    damping from ``damp`` when given): its masses (wood, the clamp's, the crown's) lumped
    with their inertia about its centre, the pad and impact site on the clamp segment."""
    tr, h = chain.trunk, chain.lengths
    body = parent.add_body()
    body.name = f"segment_{j}"
    body.pos = [0.0, 0.0, 0.0 if j == 0 else float(h[j - 1])]
    body.gravcomp = 1.0
    masses = [(chain.masses[j], h[j] / 2.0)]
    if j == chain.clamp_segment and tr.clamp_mass > 0:
        masses.append((tr.clamp_mass, h[j]))
    if j == chain.crown_segment and tr.crown_mass > 0:
        masses.append((tr.crown_mass, h[j]))
    mass = sum(mm for mm, _ in masses)
    com = sum(mm * zz for mm, zz in masses) / mass
    inertia = chain.inertias[j] + sum(mm * (zz - com) ** 2 for mm, zz in masses)
    _inertial(body, mass, com, inertia)
    hinge = body.add_joint()
    hinge.name = f"hinge_{j}"
    hinge.type = mujoco.mjtJoint.mjJNT_HINGE
    hinge.axis = [0.0, 1.0, 0.0]
    hinge.stiffness[0] = chain.hinge_stiffnesses[j]
    if damp is not None:
        hinge.damping[0] = float(damp[j])
    _geom(body, f"segment_{j}_wood", mujoco.mjtGeom.mjGEOM_CYLINDER, [r],
          fromto=(0.0, 0.0, 0.0, 0.0, 0.0, float(h[j])), rgba=WOOD, group=1)
    if j == chain.clamp_segment:
        _geom(body, "trunk_pad", mujoco.mjtGeom.mjGEOM_SPHERE, [r],
              pos=(0.0, 0.0, float(h[j])), rgba=(0.3, 0.3, 0.3, 0.5))
        _site(body, "impact_point", (0.0, 0.0, float(h[j])), 0.2 * r)
    return body


def _add_dampers(spec: mujoco.MjSpec, chain) -> None:
    """The trunk's distributed damping D (the chain model's, eq 9 at the damping points,
    N m s/rad: analytic.continuum.chain.chain_matrices) as the
    fewest fixed tendons: D = L diag(d) L^T (L unit lower triangular, d > 0; from D's
    Cholesky factor), tendon ``damper_i`` of length sum_{j >= i} L_ji theta_j and damping
    d_i, so the generalised damping force is -D theta' (to round-off). One tendon per hinge
    instead of one per damping point (24 for 12 segments): MuJoCo's cost per step grows with
    the tendons (docs/engines.md, "What an engine run costs")."""
    L, d = damping_factors(chain_matrices(chain)[2])
    n = chain.segments
    for i in range(n):
        ten = spec.add_tendon()
        ten.name = f"damper_{i}"
        ten.damping[0] = float(d[i])
        for j in range(i, n):
            if L[j, i] != 0.0:
                ten.wrap_joint(f"hinge_{j}", float(L[j, i]))


def damping_factors(D: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(L, d) with D = L diag(d) L^T, L unit lower triangular, d > 0 (from the Cholesky
    factor of the positive definite D; raises numpy's LinAlgError otherwise)."""
    C = np.linalg.cholesky(D)
    s = np.diag(C).copy()
    return C / s, s * s


def add_pendulum(spec: mujoco.MjSpec, impactor, kind: str, clamp_height: float,
                 diameter: float) -> str:
    """Add the pendulum (or billet) touching the trunk at rest; returns its body name."""
    x0 = -(diameter / 2.0 + BOB_RADIUS)
    steel = (0.6, 0.65, 0.75, 1.0)
    m = impactor.mass
    body = spec.worldbody.add_body()
    body.name = "pendulum"
    if kind == "linear":
        body.pos = [x0, 0.0, clamp_height]
        _inertial(body, m, 0.0, 0.4 * m * BOB_RADIUS ** 2)
        j = body.add_joint()
        j.name = "pendulum_x"
        j.type = mujoco.mjtJoint.mjJNT_SLIDE
        j.axis = [1.0, 0.0, 0.0]
        j.stiffness[0] = impactor.stiffness
        bob_z = 0.0
    else:
        le = impactor.equivalent_length
        body.pos = [x0, 0.0, clamp_height + le]
        _inertial(body, m, -le, BOB_INERTIA_FRACTION * m * le * le)
        j = body.add_joint()
        j.name = "pendulum_hinge"
        j.type = mujoco.mjtJoint.mjJNT_HINGE
        j.axis = [0.0, -1.0, 0.0]
        bob_z = -le
        _geom(body, "pendulum_rod", mujoco.mjtGeom.mjGEOM_CAPSULE, [0.01],
              fromto=(0.0, 0.0, 0.0, 0.0, 0.0, bob_z + BOB_RADIUS), rgba=steel, group=1)
    _geom(body, "bob", mujoco.mjtGeom.mjGEOM_SPHERE, [BOB_RADIUS], pos=(0.0, 0.0, bob_z),
          rgba=steel)
    _site(body, "contact_point", (0.0, 0.0, bob_z), 0.2 * BOB_RADIUS)
    _site(body, "touch_zone", (0.0, 0.0, bob_z), TOUCH_SITE_FACTOR * BOB_RADIUS)
    return "pendulum"


def add_contact_and_sensors(spec: mujoco.MjSpec, solref, trunk_root: str):
    d = _contact.IMPEDANCE
    pair = _contact.add_impact_pair(spec, "bob", "trunk_pad", solref,
                                    [d, d, *_contact.SOLIMP_TAIL])
    S = mujoco.mjtSensor
    O = mujoco.mjtObj
    for name, stype, otype, obj in (
            ("contact_force", S.mjSENS_TOUCH, O.mjOBJ_SITE, "touch_zone"),
            ("x_pos", S.mjSENS_FRAMEPOS, O.mjOBJ_SITE, "impact_point"),
            ("x_vel", S.mjSENS_FRAMELINVEL, O.mjOBJ_SITE, "impact_point"),
            ("y_pos", S.mjSENS_FRAMEPOS, O.mjOBJ_SITE, "contact_point"),
            ("y_vel", S.mjSENS_FRAMELINVEL, O.mjOBJ_SITE, "contact_point"),
            ("kinetic", S.mjSENS_E_KINETIC, O.mjOBJ_UNKNOWN, ""),
            ("potential", S.mjSENS_E_POTENTIAL, O.mjOBJ_UNKNOWN, ""),
            ("trunk_com", S.mjSENS_SUBTREECOM, O.mjOBJ_BODY, trunk_root)):
        s = spec.add_sensor()
        s.name = name
        s.type = stype
        s.objtype = otype
        if obj:
            s.objname = obj
    return pair


def build_spec(name: str, trunk: TrunkSpec, scenario: Scenario, pendulum: str, dt: float,
               solref=(-1.0, -1.0), integrator: str = "Euler") -> tuple[mujoco.MjSpec, object]:
    """The MjSpec of one model (see module docstring); returns (spec, contact pair)."""
    imp = scenario.impactor
    if pendulum == "full" and not isinstance(imp, Pendulum):
        raise ParameterError("--pendulum = 'full': the scenario's impactor is a billet")
    g = imp.gravity if isinstance(imp, Pendulum) else 9.81
    tr = scenario.trunk
    if integrator not in INTEGRATOR_ENUMS:
        raise ParameterError(f"--integrator = {integrator!r}: allowed "
                             f"{', '.join(INTEGRATOR_ENUMS)}")
    spec = _spec(name, dt, g, implicit_damping=trunk.kind == "chain" and trunk.damping == "joint",
                 integrator=integrator)
    root = add_trunk(spec, trunk, tr.clamp_height, tr.diameter)
    if isinstance(imp, Billet):
        imp = _BilletAsSpring(imp.mass, imp.stiffness)
    add_pendulum(spec, imp, pendulum, tr.clamp_height, tr.diameter)
    pair = add_contact_and_sensors(spec, solref, root)
    return spec, pair


@dataclass(frozen=True)
class _BilletAsSpring:
    mass: float
    stiffness: float = 0.0


def mjcf_text(spec: mujoco.MjSpec) -> str:
    """``spec.to_xml()`` (numbers: MuJoCo's writer keeps 6 significant digits; since MuJoCo
    4.0 it names the energy sensors <e_kinetic>/<e_potential>, as its reader does)."""
    return spec.to_xml()


def contact_inverse_masses(model: mujoco.MjModel) -> tuple[float, float]:
    """(A, A_hat), 1/kg: exact J M^-1 J^T of the contact normal (x) at rest, and MuJoCo's
    diagApprox of the pair (sum of the bodies' translational ``body_invweight0``).

    J is the x row of (bob point - trunk point) velocity Jacobians; for rotations about y the
    x velocity depends on the height only, so the sites' centres stand for the contact point.
    """
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    nv = model.nv
    jac = np.zeros((2, 3, nv))
    for k, site in enumerate(("contact_point", "impact_point")):
        sid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, site)
        mujoco.mj_jacSite(model, data, jac[k], None, sid)
    J = (jac[1, 0] - jac[0, 0]).reshape(1, nv)
    X = np.zeros_like(J)
    mujoco.mj_solveM(model, data, X, J)
    A = float((J @ X.T)[0, 0])
    gid = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, g) for g in ("bob", "trunk_pad")]
    A_hat = float(sum(model.body_invweight0[model.geom_bodyid[g], 0] for g in gid))
    return A, A_hat
