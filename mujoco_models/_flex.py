"""The trunk as MuJoCo's own elastic rod: a 1-D ``flex`` with bending stiffness (MuJoCo >= 4.0).

Design notes and measured figures: docs/engines.md ("The flex trunk").
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import mujoco
import numpy as np

from treeimpact.analytic.continuum.chain import hinged_chain
from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.model.parameters import Trunk

#: Length of the clamp edge below z = 0 / the first edge: the rod's bending at its base vertex
#: is that of a Voronoi length (g + h_0) / 2, so g -> 0 gives the clamped half-segment 2 E I / h_0
#: of the Hencky chain (g = h_0 doubles the base flexibility: first-order convergence).
GHOST_FRACTION = 1e-6
#: The project's integrators that MuJoCo steps a rod flex with (4.0's compiler refuses flex
#: elasticity under implicit/implicitfast: "no longer integrated implicitly").
FLEX_INTEGRATORS = ("Euler", "RK4")


@dataclass(frozen=True)
class FlexTrunk:
    """The trunk as a rod of N edges (SI units); vertex 0 at z = 0, vertex N at l."""

    trunk: Trunk
    heights: tuple  # z_0 = 0 < ... < z_N = l, m (the hinged chain's boundaries: a vertex at a)
    clamp_vertex: int  # index of the vertex at a
    masses: tuple  # kg per moving vertex 1..N: rho A (h_{k-1} + h_k) / 2 + m_c at a + m_f at l
    dampers: tuple  # N s/m per moving vertex 1..N: C (h_{k-1} + h_k) / 2 (eq 9, lumped)
    ghost: float  # m: the clamp edge below z = 0 (GHOST_FRACTION h_0)
    root_inertia: float  # kg m^2: of the base body about its hinge (root spring only)

    @property
    def segments(self) -> int:
        return len(self.heights) - 1

    @property
    def rest_points(self) -> np.ndarray:
        """Rest positions (m) of the flex's vertices: the clamp-edge end, then z_0 .. z_N."""
        z = np.concatenate([[-self.ghost], self.heights])
        return np.column_stack([np.zeros_like(z), np.zeros_like(z), z])


def flex_trunk(trunk: Trunk, segments: int) -> FlexTrunk:
    """The rod of ``segments`` edges with the hinged chain's vertex heights (a vertex at a)."""
    return _flex_trunk(trunk, int(segments))


@functools.lru_cache(maxsize=64)
def _flex_trunk(trunk: Trunk, segments: int) -> FlexTrunk:
    chain = hinged_chain(trunk, segments)
    z = np.asarray(chain.boundaries)
    h = np.diff(z)
    rho_a = trunk.density * trunk.area
    share = 0.5 * (h + np.concatenate([h[1:], [0.0]]))  # vertex k = 1..N: (h_{k-1} + h_k) / 2
    masses = rho_a * share
    masses[chain.clamp_index - 1] += trunk.clamp_mass
    masses[-1] += trunk.crown_mass
    return FlexTrunk(trunk=trunk, heights=tuple(float(v) for v in z),
                     clamp_vertex=chain.clamp_index,
                     masses=tuple(float(v) for v in masses),
                     dampers=tuple(float(v) for v in trunk.damping * share),
                     ghost=GHOST_FRACTION * float(h[0]),
                     root_inertia=rho_a * float(h[0]) ** 3 / 12.0)


def add_flex_trunk(spec: mujoco.MjSpec, rod: FlexTrunk) -> str:
    """Add the rod to ``spec`` (bodies, joints, the flex, the pad); returns its root body.

    The base body ``trunk_root`` (on the hinge ``root_hinge`` with the root spring k_theta,
    or fixed for a rigid clamp) holds the clamp-edge end and vertex 0; vertex k = 1..N is body
    ``vertex_k`` on the slide ``vertex_k_x`` (axis x) with its lumped mass and damper. The
    flex ``trunk`` (dim 1, E and radius d / 2) gives the bending; the pad and ``impact_point``
    are on the vertex at a.
    """
    r = rod.trunk.diameter / 2.0
    _add_root(spec, rod)
    names = ["trunk_root", "trunk_root"]
    vert = [0.0, 0.0, -rod.ghost, 0.0, 0.0, 0.0]
    for k in range(1, rod.segments + 1):
        names.append(_add_vertex(spec, rod, k, r))
        vert += [0.0, 0.0, 0.0]
    for k in range(1, rod.segments + 1):  # MuJoCo refuses joint damping on flex vertices
        if rod.dampers[k - 1] > 0.0:
            ten = spec.add_tendon()
            ten.name = f"damper_{k}"
            ten.damping[0] = rod.dampers[k - 1]
            ten.wrap_joint(f"vertex_{k}_x", 1.0)
    flex = spec.add_flex()
    flex.name = "trunk"
    flex.dim = 1
    flex.radius = r
    flex.young = rod.trunk.youngs_modulus
    flex.poisson = 0.0  # no twist dof here: only the bending (E, I) enters
    flex.vertbody = names
    flex.vert = vert
    flex.elem = [v for k in range(rod.segments + 1) for v in (k, k + 1)]
    flex.contype = 0
    flex.conaffinity = 0
    flex.rgba = [0.55, 0.4, 0.25, 1.0]
    return "trunk_root"


def _add_root(spec: mujoco.MjSpec, rod: FlexTrunk) -> None:
    """The base body ``trunk_root``: vertex 0's share of the mass on the hinge axis, on the
    hinge ``root_hinge`` with the root spring k_theta (fixed for a rigid clamp)."""
    tr = rod.trunk
    root = spec.worldbody.add_body()
    root.name = "trunk_root"
    root.gravcomp = 1.0
    root.explicitinertial = True
    h0 = rod.heights[1] - rod.heights[0]
    root.mass = tr.density * tr.area * h0 / 2.0  # vertex 0's share: on the hinge axis
    root.ipos = [0.0, 0.0, 0.0]  # (set: MjSpec.to_xml writes an <inertial> only then)
    root.inertia = [rod.root_inertia] * 3
    if math.isfinite(tr.base_stiffness):
        j = root.add_joint()
        j.name = "root_hinge"
        j.type = mujoco.mjtJoint.mjJNT_HINGE
        j.axis = [0.0, 1.0, 0.0]
        j.stiffness[0] = tr.base_stiffness


def _add_vertex(spec: mujoco.MjSpec, rod: FlexTrunk, k: int, r: float) -> str:
    """Vertex ``k`` (1..N) as body ``vertex_k`` on the slide ``vertex_k_x`` with its lumped
    mass (radius ``r`` m); the pad and ``impact_point`` on the clamp's vertex. Its name."""
    body = spec.worldbody.add_body()
    body.name = f"vertex_{k}"
    body.pos = [0.0, 0.0, rod.heights[k]]
    body.gravcomp = 1.0
    body.explicitinertial = True
    body.mass = rod.masses[k - 1]
    body.ipos = [0.0, 0.0, 0.0]
    body.inertia = [rod.masses[k - 1] * r * r / 4.0] * 3  # never enters: no rotation dof
    j = body.add_joint()
    j.name = f"vertex_{k}_x"
    j.type = mujoco.mjtJoint.mjJNT_SLIDE
    j.axis = [1.0, 0.0, 0.0]
    if k == rod.clamp_vertex:
        g = body.add_geom()
        g.name = "trunk_pad"
        g.type = mujoco.mjtGeom.mjGEOM_SPHERE
        g.size = [r, 0.0, 0.0]
        g.contype = 0
        g.conaffinity = 0
        g.rgba = [0.3, 0.3, 0.3, 0.5]
        s = body.add_site()
        s.name = "impact_point"
        s.size = [0.2 * r, 0.0, 0.0]
    return body.name


def flex_dofs(m: mujoco.MjModel) -> tuple[int | None, list[int]]:
    """(qpos address of ``root_hinge`` or None, qpos addresses of ``vertex_k_x``, k = 1..N);
    each joint has one dof and the same address in qvel (slides and hinges)."""
    jid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, "root_hinge")
    root = int(m.jnt_qposadr[jid]) if jid >= 0 else None
    ids = []
    k = 1
    while (j := mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, f"vertex_{k}_x")) >= 0:
        ids.append(int(m.jnt_qposadr[j]))
        k += 1
    return root, ids


def bending_energy(rod: FlexTrunk, theta: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Elastic energy (J) of the rod per sample: root angle ``theta`` (rad, shape (n,)) and
    vertex deflections ``x`` (m, shape (n, N)).

    MuJoCo's discrete elastic rod: sum over interior vertices i of E I |kb_i|^2 / (l_{i-1} +
    l_i), kb_i = 2 e_{i-1} x e_i / (|e_{i-1}| |e_i| + e_{i-1} . e_i), rest lengths l (its
    passive force is minus the gradient of this, checked to 1e-10 in the tests).
    """
    x = np.atleast_2d(x)
    n = x.shape[0]
    z = np.asarray(rod.heights)
    P = np.zeros((n, rod.segments + 2, 2))  # (x, z) of every flex vertex
    P[:, 0, 0] = -rod.ghost * np.sin(theta)
    P[:, 0, 1] = -rod.ghost * np.cos(theta)
    P[:, 2:, 0] = x
    P[:, 2:, 1] = z[1:]
    e = np.diff(P, axis=1)
    le = np.hypot(e[..., 0], e[..., 1])
    l0 = np.concatenate([[rod.ghost], np.diff(z)])
    a, b = e[:, :-1], e[:, 1:]
    cross = a[..., 1] * b[..., 0] - a[..., 0] * b[..., 1]  # the y component (planar rod)
    dot = np.einsum("nij,nij->ni", a, b)
    kb = 2.0 * cross / (le[:, :-1] * le[:, 1:] + dot)
    return rod.trunk.bending_stiffness * np.sum(kb * kb / (l0[:-1] + l0[1:]), axis=1)


def stiffness_matrix(rod: FlexTrunk, with_root: bool) -> np.ndarray:
    """The Hessian at rest of :func:`bending_energy` (plus the root spring) in the dofs
    (theta if ``with_root``, x_1..x_N): N m/rad, N/m. Linearised, kb_i is the turning angle
    phi_i at vertex i and the energy sum_i (2 E I / (l_{i-1} + l_i)) phi_i^2 / 2."""
    z = np.asarray(rod.heights)
    l0 = np.concatenate([[rod.ghost], np.diff(z)])
    N = rod.segments
    off = 1 if with_root else 0
    K = np.zeros((N + off, N + off))
    for i in range(1, N + 1):  # interior flex vertex i (0 is the clamp-edge end): z_{i-1}
        g = np.zeros(N + off)  # d phi_i / d dofs; slope of edge j = (x_{j+1} - x_j) / l_j
        # edge i-1 (from flex vertex i-1 to i) and edge i (i to i+1); x of flex vertex v is
        # dof v - 2 + off for v >= 2 (v = 1 is z = 0, fixed; v = 0 turns with theta)
        for edge, sign in ((i, 1.0), (i - 1, -1.0)):
            if edge == 0:  # the clamp edge: its slope is theta
                if with_root:
                    g[0] += sign
                continue
            for v, s in ((edge + 1, 1.0), (edge, -1.0)):
                if v >= 2:
                    g[v - 2 + off] += sign * s / l0[edge]
        K += 2.0 * rod.trunk.bending_stiffness / (l0[i - 1] + l0[i]) * np.outer(g, g)
    if with_root:
        K[0, 0] += rod.trunk.base_stiffness
    return K


def check_flex_options(integrator: str, damping: str) -> None:
    """One-line errors for what the flex trunk does not take."""
    if integrator not in FLEX_INTEGRATORS:
        raise ParameterError(f"--integrator = {integrator!r} with --trunk flex: allowed "
                             f"{', '.join(FLEX_INTEGRATORS)} (MuJoCo 4.0 no longer integrates "
                             "flex elasticity under implicit/implicitfast)")
    if damping != "distributed":
        raise ParameterError(f"--trunk-damping-model = {damping!r} with --trunk flex: allowed distributed "
                             "(the rod's C lumped on its vertices)")
