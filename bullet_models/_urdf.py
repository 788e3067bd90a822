"""URDF of the Bullet models (built with xml.etree, never string templates).

Design notes and measured figures: docs/engines.md.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

from treeimpact.analytic.continuum.chain import HingedChain, default_segments, hinged_chain
from treeimpact.analytic.engine.generated_files import URDF_DIGITS, fixed_precision_xml
from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.model.parameters import Billet, Pendulum
from treeimpact.analytic.model.reduction import TreeSDOF, reduce_trunk

CONTACT_RADIUS = 0.05  # m: radius of the pendulum's contact sphere (geometry only)
PAD_HALF = (0.02, 0.05, 0.05)  # m: half extents (x, y, z) of the trunk's contact pad
BOB_INERTIA_FRACTION = 1e-6  # bob inertia about its centre / (m l_e^2)
POINT_INERTIA = 1e-9  # kg m^2: inertia of links on prismatic joints (irrelevant, > 0)


def _num(v: float) -> str:
    """Shortest round-trip text of a float: the runner's URDF holds the model's numbers
    exactly (the checked-in files are rounded, :func:`scenario_urdfs`)."""
    return repr(float(v))


def _vec(*vs) -> str:
    return " ".join(_num(v) for v in vs)


def _robot(name: str) -> ET.Element:
    robot = ET.Element("robot", name=name)
    base = ET.SubElement(robot, "link", name="ground")  # the fixed base: massless, no collision
    inertial = ET.SubElement(base, "inertial")
    ET.SubElement(inertial, "mass", value="0")
    ET.SubElement(inertial, "inertia", ixx="0", ixy="0", ixz="0", iyy="0", iyz="0", izz="0")
    return robot


def _inertial(link: ET.Element, mass: float, com_z: float, iyy: float, com_x: float = 0.0):
    inertial = ET.SubElement(link, "inertial")
    ET.SubElement(inertial, "origin", xyz=_vec(com_x, 0.0, com_z), rpy="0 0 0")
    ET.SubElement(inertial, "mass", value=_num(mass))
    ET.SubElement(inertial, "inertia", ixx=_num(iyy), ixy="0", ixz="0", iyy=_num(iyy),
                  iyz="0", izz=_num(iyy))


def _box(link: ET.Element, centre, half):
    col = ET.SubElement(link, "collision", name="contact_pad")
    ET.SubElement(col, "origin", xyz=_vec(*centre), rpy="0 0 0")
    geom = ET.SubElement(col, "geometry")
    ET.SubElement(geom, "box", size=_vec(*(2 * h for h in half)))


def _sphere(link: ET.Element, centre, radius):
    col = ET.SubElement(link, "collision", name="contact_sphere")
    ET.SubElement(col, "origin", xyz=_vec(*centre), rpy="0 0 0")
    geom = ET.SubElement(col, "geometry")
    ET.SubElement(geom, "sphere", radius=_num(radius))


def _joint(robot, name, kind, parent, child, xyz, axis, limit=None):
    j = ET.SubElement(robot, "joint", name=name, type=kind)
    ET.SubElement(j, "parent", link=parent)
    ET.SubElement(j, "child", link=child)
    ET.SubElement(j, "origin", xyz=_vec(*xyz), rpy="0 0 0")
    ET.SubElement(j, "axis", xyz=_vec(*axis))
    if limit is not None:  # prismatic joints need limits in URDF; they are never reached
        ET.SubElement(j, "limit", lower=_num(-limit), upper=_num(limit), effort="1e12",
                      velocity="1e6")
    ET.SubElement(j, "dynamics", damping="0", friction="0")
    return j


def _text(robot: ET.Element) -> str:
    ET.indent(robot, space="  ")
    return ET.tostring(robot, encoding="unicode") + "\n"


SLIDE_LIMIT = 1.0  # m: travel of the prismatic joints (the motions are millimetres)


def trunk_sdof_urdf(tree: TreeSDOF, clamp_height: float, name: str = "trunk-sdof") -> str:
    """The SDOF trunk of eq 11: mass M_T sliding along x at height a (K_T, C_T by the runner)."""
    robot = _robot(name)
    link = ET.SubElement(robot, "link", name="impact_point")
    _inertial(link, tree.dynamic_mass, 0.0, POINT_INERTIA)
    _box(link, (PAD_HALF[0], 0.0, 0.0), PAD_HALF)
    _joint(robot, "trunk_slide", "prismatic", "ground", "impact_point",
           (0.0, 0.0, clamp_height), (1.0, 0.0, 0.0), limit=SLIDE_LIMIT)
    return _text(robot)


def chain_link_inertia(chain: HingedChain, j: int) -> tuple[float, float, float]:
    """(mass kg, centre-of-mass height above the hinge m, inertia about the COM kg m^2) of link j."""
    h = float(chain.lengths[j])
    m_rod = chain.masses[j]
    point = 0.0
    if j == chain.clamp_segment and chain.clamp_index < chain.segments:
        point += chain.clamp_mass
    if j == chain.crown_segment:
        point += chain.crown_mass
        if chain.clamp_index == chain.segments:  # a = l: both masses at the top
            point += chain.clamp_mass
    mass = m_rod + point
    com = (m_rod * h / 2.0 + point * h) / mass
    inertia = chain.inertias[j] + m_rod * (h / 2.0 - com) ** 2 + point * (h - com) ** 2
    return mass, com, inertia


def trunk_chain_urdf(chain: HingedChain, name: str = "trunk-chain") -> str:
    """The hinged-segment trunk (springs and damping by the runner), contact pad at a."""
    robot = _robot(name)
    parent, z_parent = "ground", 0.0
    for j in range(chain.segments):
        child = f"segment_{j}"
        link = ET.SubElement(robot, "link", name=child)
        mass, com, inertia = chain_link_inertia(chain, j)
        _inertial(link, mass, com, inertia)
        z_j = chain.boundaries[j]
        if j == chain.clamp_segment:
            h = float(chain.lengths[j])
            _box(link, (PAD_HALF[0], 0.0, h), PAD_HALF)
        _joint(robot, f"hinge_{j}", "continuous", parent, child, (0.0, 0.0, z_j - z_parent),
               (0.0, 1.0, 0.0))
        parent, z_parent = child, z_j
    return _text(robot)


def pendulum_urdf(impactor: Pendulum | Billet, clamp_height: float, kind: str = "linear",
                  name: str | None = None) -> str:
    """The impactor: ``linear`` (prismatic, eq 13; also the billet) or ``full`` (revolute)."""
    r = CONTACT_RADIUS
    m = impactor.mass
    if kind == "linear":
        robot = _robot(name or "pendulum-linear")
        link = ET.SubElement(robot, "link", name="bob")
        _inertial(link, m, 0.0, POINT_INERTIA)
        _sphere(link, (-r, 0.0, 0.0), r)
        _joint(robot, "pendulum_slide", "prismatic", "ground", "bob",
               (0.0, 0.0, clamp_height), (1.0, 0.0, 0.0), limit=SLIDE_LIMIT)
        return _text(robot)
    if kind == "full":
        if not isinstance(impactor, Pendulum):
            raise ParameterError("pendulum = 'full': needs a pendulum impactor, not a billet")
        le = impactor.equivalent_length
        robot = _robot(name or "pendulum-full")
        link = ET.SubElement(robot, "link", name="bob")
        _inertial(link, m, -le, BOB_INERTIA_FRACTION * m * le * le)
        _sphere(link, (0.0, 0.0, -le), r)
        _joint(robot, "pendulum_pivot", "continuous", "ground", "bob",
               (-r, 0.0, clamp_height + le), (0.0, -1.0, 0.0))
        return _text(robot)
    raise ParameterError(f"pendulum = {kind!r}: allowed 'linear' or 'full'")


def scenario_urdfs(scenario) -> dict[str, str]:
    """File name -> URDF text of every model of a scenario (the checked-in set), numbers at
    :data:`analytic.engine.generated_files.URDF_DIGITS` significant digits."""
    trunk = scenario.trunk
    n = default_segments(trunk)
    out = {
        f"{scenario.name}-trunk-sdof.urdf": trunk_sdof_urdf(
            reduce_trunk(trunk), trunk.clamp_height, name=f"{scenario.name}-trunk-sdof"),
        f"{scenario.name}-trunk-chain.urdf": trunk_chain_urdf(
            hinged_chain(trunk, n), name=f"{scenario.name}-trunk-chain-{n}"),
        f"{scenario.name}-pendulum-linear.urdf": pendulum_urdf(
            scenario.impactor, trunk.clamp_height, "linear",
            name=f"{scenario.name}-pendulum-linear"),
    }
    if isinstance(scenario.impactor, Pendulum):
        out[f"{scenario.name}-pendulum-full.urdf"] = pendulum_urdf(
            scenario.impactor, trunk.clamp_height, "full", name=f"{scenario.name}-pendulum-full")
    return {n: fixed_precision_xml(text, URDF_DIGITS) for n, text in out.items()}


def sphere_urdf(mass: float, radius: float, name: str = "sphere") -> str:
    """A one-link URDF: a sphere of ``mass`` (kg) and ``radius`` (m), its collision shape
    named ``contact_sphere``, the solid-sphere inertia 2/5 m r^2 (for the two-body collision
    of ``treeimpact contact``)."""
    robot = ET.Element("robot", name=name)
    link = ET.SubElement(robot, "link", name="body")
    _inertial(link, mass, 0.0, 0.4 * mass * radius * radius)
    _sphere(link, (0.0, 0.0, 0.0), radius)
    return _text(robot)
