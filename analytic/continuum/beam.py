"""Continuous trunk: the reference the SDOF reduction and the engines are checked against.

Euler-Bernoulli (Hermite cubics, the default) or Timoshenko (:mod:`analytic.continuum.timoshenko`:
shear deformation and rotary inertia) beam theory, ``beam_theory`` of the functions below.
Design notes and measured figures: docs/trunk-models.md, docs/beam-impact.md.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.model.parameters import Trunk

from .timoshenko import check_beam_theory, element_matrices

EULER_BERNOULLI = "euler-bernoulli"

FREQUENCY_ELEMENTS = 160  # elements for the frequencies and mode shapes (rule in the module docstring)
MAX_MODES = 20  # the mesh rule guarantees 1e-8 for n_modes <= 3; more modes are less accurate


def _check_trunk(trunk) -> Trunk:
    if not isinstance(trunk, Trunk):
        raise ParameterError(f"trunk: expected an analytic.Trunk, got {type(trunk).__name__}")
    return trunk


def _check_modes(n_modes) -> int:
    if isinstance(n_modes, bool) or not isinstance(n_modes, (int, np.integer)) or not (
            1 <= n_modes <= MAX_MODES):
        raise ParameterError(f"n_modes = {n_modes!r} is out of range: allowed integers [1, {MAX_MODES}]")
    return int(n_modes)


def mesh(trunk: Trunk, elements: int = FREQUENCY_ELEMENTS) -> np.ndarray:
    """Node heights (m) of ``trunk``'s mesh, a node at ``a``, no element longer than l /
    ``elements``.

    [0, a] gets n_in = ceil(elements a / l) equal elements and [a, l] gets
    n_out = ceil(elements (l - a) / l) (none when a = l), so there are ``elements`` or
    ``elements + 1`` elements in all.
    """
    _check_trunk(trunk)
    a, l = trunk.clamp_height, trunk.length
    if isinstance(elements, bool) or not isinstance(elements, (int, np.integer)) or elements < 1:
        raise ParameterError(f"elements = {elements!r} is out of range: allowed integers >= 1")
    n_in = max(1, math.ceil(elements * a / l - 1e-9))
    inner = np.linspace(0.0, a, n_in + 1)
    if a >= l:
        return inner
    n_out = max(1, math.ceil(elements * (l - a) / l - 1e-9))
    outer = np.linspace(a, l, n_out + 1)
    return np.concatenate([inner, outer[1:]])


def _element_matrices(h: float, ei: float, rho_a: float):
    """Hermite-cubic stiffness and consistent mass, dofs (w1, w1', w2, w2')."""
    k = ei / h ** 3 * np.array([[12.0, 6 * h, -12.0, 6 * h],
                                [6 * h, 4 * h * h, -6 * h, 2 * h * h],
                                [-12.0, -6 * h, 12.0, -6 * h],
                                [6 * h, 2 * h * h, -6 * h, 4 * h * h]])
    m = rho_a * h / 420.0 * np.array([[156.0, 22 * h, 54.0, -13 * h],
                                      [22 * h, 4 * h * h, 13 * h, -3 * h * h],
                                      [54.0, 13 * h, 156.0, -22 * h],
                                      [-13 * h, -3 * h * h, -22 * h, 4 * h * h]])
    return k, m


def _elements(trunk: Trunk, nodes: np.ndarray, beam_theory: str) -> list:
    """Per element (K, M, D), dofs (w1, r1, w2, r2), r the slope w' (Euler-Bernoulli) or the
    section's rotation psi (Timoshenko); D the consistent damping of the distributed C.
    Elements of the same length share one computation (the same matrices)."""
    ei, rho_a = trunk.bending_stiffness, trunk.density * trunk.area
    done: dict = {}
    for h in np.diff(nodes).tolist():
        if h in done:
            continue
        if beam_theory == EULER_BERNOULLI:
            k, m = _element_matrices(h, ei, rho_a)
            done[h] = k, m, _element_matrices(h, 1.0, trunk.damping)[1]
        else:
            k, m, shape = element_matrices(h, ei, rho_a, trunk.density * trunk.second_moment,
                                           trunk.shear_rigidity)
            done[h] = k, m, trunk.damping * shape
    return [done[h] for h in np.diff(nodes).tolist()]


def _scatter(blocks, n: int, l: float) -> np.ndarray:
    """Global matrix (2n x 2n, dofs (w_i, l r_i)) of 4 x 4 element blocks in node order."""
    scale = np.outer(*(2 * [np.tile([1.0, 1.0 / l], 2)]))  # r = (l r) / l
    out = np.zeros((2 * n, 2 * n))
    for e, b in enumerate(blocks):
        out[2 * e:2 * e + 4, 2 * e:2 * e + 4] += b * scale
    return out


def assemble(trunk: Trunk, nodes: np.ndarray, beam_theory: str = EULER_BERNOULLI):
    """Global (K, M) of ``trunk`` on the mesh ``nodes`` (heights, m) in ``beam_theory``
    (:data:`analytic.continuum.timoshenko.BEAM_THEORIES`), on the free dofs.

    Dofs are (w_i, l * r_i) per node, r the slope w' (Euler-Bernoulli) or the section's
    rotation psi (Timoshenko), scaled by the trunk length (which leaves the eigenvalues
    unchanged and balances the matrices); w_0 = 0 always, and r_0 = 0 for a rigid clamp (the
    root spring acts on r_0). Returns ``K, M, free`` where ``free`` maps the 2 * len(nodes)
    full dofs to the kept ones.
    """
    _check_trunk(trunk)
    check_beam_theory(beam_theory)
    nodes = np.asarray(nodes, dtype=float)
    return _assemble(trunk, nodes, _elements(trunk, nodes, beam_theory))


def _assemble(trunk: Trunk, nodes: np.ndarray, els: list):
    """:func:`assemble`'s (K, M, free) from the elements ``els`` of :func:`_elements`."""
    n = len(nodes)
    l = trunk.length
    K = _scatter([k for k, _, _ in els], n, l)
    M = _scatter([m for _, m, _ in els], n, l)
    i_a = int(np.argmin(np.abs(nodes - trunk.clamp_height)))
    M[2 * i_a, 2 * i_a] += trunk.clamp_mass
    M[2 * (n - 1), 2 * (n - 1)] += trunk.crown_mass
    keep = [i for i in range(2 * n) if i != 0]
    if math.isfinite(trunk.base_stiffness):
        K[1, 1] += trunk.base_stiffness / l ** 2
    else:
        keep.remove(1)
    keep = np.array(keep)
    return K[np.ix_(keep, keep)], M[np.ix_(keep, keep)], keep


def beam_static_stiffness(trunk: Trunk, beam_theory: str = EULER_BERNOULLI) -> float:
    """Force at ``a`` per unit deflection at ``a`` of ``trunk`` in ``beam_theory``, N/m (eq 1
    / eq 8 with the root spring; Timoshenko: 1 / (a^3 / (3 E I) + a / (kappa G A) + a^2 /
    k_theta)).

    Exact (both elements hold the static solution): solved on the mesh {0, a, l}.
    """
    _check_trunk(trunk)
    a, l = trunk.clamp_height, trunk.length
    nodes = np.array([0.0, a, l]) if a < l else np.array([0.0, a])
    K, _, keep = assemble(trunk, nodes, beam_theory)
    f = np.zeros(len(keep))
    i = int(np.nonzero(keep == 2)[0][0])  # deflection dof of the node at a
    f[i] = 1.0
    u = np.linalg.solve(K, f)
    return float(1.0 / u[i])


def flexibility(trunk: Trunk, nodes: np.ndarray, beam_theory: str = EULER_BERNOULLI):
    """Closed-form inverse of the assembled stiffness of ``trunk`` on ``nodes`` (heights,
    m) in ``beam_theory``: the exact flexibility matrix.

    Both elements are nodally exact for nodal forces and moments on a uniform beam, so
    K^-1 of :func:`assemble` equals the influence matrix of the continuous cantilever at the
    nodes (dofs w_i, l r_i); it is built here from the closed-form influence functions
    (unit force / unit moment at zeta, deflection and rotation at z, plus the rigid rotation
    of the root spring; Timoshenko adds the shear deflection min(z, zeta) / (kappa G A) of a
    unit force), which avoids the h^-4 conditioning of K. Returns ``F, keep``.
    """
    _check_trunk(trunk)
    check_beam_theory(beam_theory)
    z = np.asarray(nodes, dtype=float)
    ei, l, base_stiffness = trunk.bending_stiffness, trunk.length, trunk.base_stiffness
    zz, ze = z[:, None], z[None, :]  # response at zz, load at ze
    lo = np.minimum(zz, ze)
    below = zz <= ze
    # unit force at ze
    w_f = np.where(below, zz ** 2 * (3 * ze - zz), ze ** 2 * (3 * zz - ze)) / (6 * ei)
    t_f = np.where(below, zz * (2 * ze - zz), ze ** 2) / (2 * ei)
    # unit moment at ze
    w_m = np.where(below, zz ** 2 / 2, ze ** 2 / 2 + ze * (zz - ze)) / ei
    t_m = lo / ei
    if beam_theory != EULER_BERNOULLI and math.isfinite(trunk.shear_rigidity):
        w_f = w_f + lo / trunk.shear_rigidity  # shear force 1 below zeta: w' - psi = 1 / kGA
    if math.isfinite(base_stiffness):  # root rotation = base moment / k_theta, rigid above it
        w_f = w_f + zz * ze / base_stiffness
        t_f = t_f + ze / base_stiffness + 0 * zz
        w_m = w_m + zz / base_stiffness + 0 * ze
        t_m = t_m + 1.0 / base_stiffness
    n = len(z)
    F = np.zeros((2 * n, 2 * n))
    F[0::2, 0::2] = w_f
    F[1::2, 0::2] = t_f * l  # scaled slope l w'
    F[0::2, 1::2] = w_m * l  # per unit of the force conjugate to l w' (a moment of 1/l)
    F[1::2, 1::2] = t_m * l * l
    keep = [i for i in range(2 * n) if i != 0]
    if not math.isfinite(base_stiffness):
        keep.remove(1)
    keep = np.array(keep)
    return F[np.ix_(keep, keep)], keep


def _consistent_mass(trunk: Trunk, nodes: np.ndarray, keep: np.ndarray,
                     beam_theory: str = EULER_BERNOULLI) -> np.ndarray:
    n = len(nodes)
    M = _scatter([m for _, m, _ in _elements(trunk, nodes, beam_theory)], n, trunk.length)
    i_a = int(np.argmin(np.abs(nodes - trunk.clamp_height)))
    M[2 * i_a, 2 * i_a] += trunk.clamp_mass
    M[2 * (n - 1), 2 * (n - 1)] += trunk.crown_mass
    return M[np.ix_(keep, keep)]


def _halved(nodes: np.ndarray) -> np.ndarray:
    """The mesh with every element split in two."""
    mid = 0.5 * (nodes[:-1] + nodes[1:])
    return np.insert(nodes, np.arange(1, len(nodes)), mid)


@functools.lru_cache(maxsize=64)
def _modes(trunk: Trunk, n_modes: int, beam_theory: str = EULER_BERNOULLI):
    """Lowest modes of K v = w^2 M v, solved as the largest of F M v = v / w^2 (F = K^-1).

    Euler-Bernoulli on :func:`mesh` (h^4 convergence). Timoshenko: the element's shear
    strain is constant, so its frequencies converge as h^2 (1e-7 to 7e-5 off at 160
    elements for modes 1-3); they are extrapolated from 80 elements and those halved,
    (4 w_h/2 - w_h) / 3 (Richardson), to 1e-8 (modes 1-2) and 1e-7 (3) of the exact
    frequency equation (tests/test_timoshenko.py); the shapes are the halved mesh's.
    """
    if beam_theory == EULER_BERNOULLI:
        return _mesh_modes(trunk, n_modes, beam_theory, mesh(trunk))
    coarse = mesh(trunk, FREQUENCY_ELEMENTS // 2)
    w_h = _mesh_modes(trunk, n_modes, beam_theory, coarse)[0]
    w, nodes, full = _mesh_modes(trunk, n_modes, beam_theory, _halved(coarse))
    return (4.0 * w - w_h) / 3.0, nodes, full


def _mesh_modes(trunk: Trunk, n_modes: int, beam_theory: str, nodes: np.ndarray):
    """(omegas, nodes, nodal (w, r) of each mode) on ``nodes`` (see :func:`_modes`)."""
    # lazy: +286 ms at import otherwise (scipy.linalg)
    import scipy.linalg

    F, keep = flexibility(trunk, nodes, beam_theory)
    M = _consistent_mass(trunk, nodes, keep, beam_theory)
    L = np.linalg.cholesky(M)
    A = L.T @ F @ L
    A = 0.5 * (A + A.T)
    mu, y = scipy.linalg.eigh(A, subset_by_index=[len(A) - n_modes, len(A) - 1])
    mu, y = mu[::-1], y[:, ::-1]
    vec = scipy.linalg.solve_triangular(L.T, y, lower=False)  # v = L^-T y
    full = np.zeros((2 * len(nodes), n_modes))
    full[keep] = vec
    full[1::2] /= trunk.length  # back to slopes (rotations), 1/m
    return 1.0 / np.sqrt(mu), nodes, full


def beam_natural_frequencies(trunk: Trunk, n_modes: int = 3,
                             beam_theory: str = EULER_BERNOULLI) -> np.ndarray:
    """The first ``n_modes`` natural frequencies of the continuous ``trunk`` in
    ``beam_theory``, rad/s, ascending.

    Relative accuracy better than 1e-8 for n_modes <= 3 (mesh rule in the module docstring;
    Timoshenko: :func:`_modes`).
    """
    n_modes = _check_modes(n_modes)
    w, _, _ = _modes(_check_trunk(trunk), n_modes, check_beam_theory(beam_theory))
    return w.copy()


def _hermite(nodes: np.ndarray, full: np.ndarray, z: np.ndarray) -> np.ndarray:
    """Deflection at heights z from nodal (w, w') with the Hermite shape functions."""
    e = np.clip(np.searchsorted(nodes, z, side="right") - 1, 0, len(nodes) - 2)
    z0, h = nodes[e], nodes[e + 1] - nodes[e]
    s = (z - z0) / h
    n1 = 1 - 3 * s ** 2 + 2 * s ** 3
    n2 = h * (s - 2 * s ** 2 + s ** 3)
    n3 = 3 * s ** 2 - 2 * s ** 3
    n4 = h * (-s ** 2 + s ** 3)
    w1, t1 = full[2 * e], full[2 * e + 1]
    w2, t2 = full[2 * e + 2], full[2 * e + 3]
    return (n1[:, None] * w1 + n2[:, None] * t1 + n3[:, None] * w2 + n4[:, None] * t2).T


def _peak(nodes: np.ndarray, full: np.ndarray) -> np.ndarray:
    """Signed value of largest magnitude of each interpolated mode (nodes and interior extrema)."""
    h = np.diff(nodes)[:, None]
    w1, t1, w2, t2 = full[0:-2:2], full[1:-2:2], full[2::2], full[3::2]
    # d w / d s = c0 + c1 s + c2 s^2 on each element, s in [0, 1]
    c0 = h * t1
    c1 = -6 * w1 - 4 * h * t1 + 6 * w2 - 2 * h * t2
    c2 = 6 * w1 + 3 * h * t1 - 6 * w2 + 3 * h * t2
    cand = [nodes]
    for e in range(len(nodes) - 1):
        for m in range(full.shape[1]):
            for r in np.roots([c2[e, m], c1[e, m], c0[e, m]]):
                if abs(r.imag) < 1e-12 and 0.0 < r.real < 1.0:
                    cand.append(np.array([nodes[e] + r.real * h[e, 0]]))
    z = np.concatenate(cand)
    vals = _hermite(nodes, full, z)
    return vals[np.arange(full.shape[1]), np.argmax(np.abs(vals), axis=1)]


def beam_mode_shapes(trunk: Trunk, n_modes: int = 3, z=None, *, normalise: str = "max"):
    """``(omegas, z, shapes)`` of the first ``n_modes`` modes of ``trunk``: frequencies
    (rad/s), heights (m), lateral deflections.

    ``shapes[i]`` is mode i at the heights ``z`` (default: the element nodes, which include
    ``a``), interpolated with the Hermite shape functions. ``normalise="max"``: the value of
    largest magnitude along the trunk (nodes and the interior extrema of the cubics) is +1;
    ``normalise="clamp"``: the value at ``a`` is 1 (ParameterError if the mode has a node at
    ``a``, |phi(a)| < 1e-6 max|phi|: normalising there would amplify by more than 1e6).
    """
    n_modes = _check_modes(n_modes)
    trunk = _check_trunk(trunk)
    if normalise not in ("max", "clamp"):
        raise ParameterError(f"normalise = {normalise!r}: allowed 'max' or 'clamp'")
    w, nodes, full = _modes(trunk, n_modes)
    if z is None:
        z = nodes.copy()
    else:
        z = np.atleast_1d(np.asarray(z, dtype=float))
        if z.ndim != 1 or not np.all(np.isfinite(z)) or z.min() < 0 or z.max() > trunk.length:
            raise ParameterError(f"z: heights must be finite and in [0, {trunk.length}] m")
    shapes = _hermite(nodes, full, z)
    peak = _peak(nodes, full)
    if normalise == "max":
        shapes = shapes / peak[:, None]
    else:
        at_a = _hermite(nodes, full, np.array([trunk.clamp_height]))[:, 0]
        if np.any(np.abs(at_a) < 1e-6 * np.abs(peak)):
            raise ParameterError("normalise = 'clamp': a mode has a node at the clamp height a; use 'max'")
        shapes = shapes / at_a[:, None]
    return w.copy(), z, shapes


def beam_matrices(trunk: Trunk, elements: int, beam_theory: str = EULER_BERNOULLI):
    """``(M, D, K, nodes, keep)`` of ``trunk`` in ``beam_theory`` on :func:`mesh` of
    ``elements`` elements (kg, N s/m, N/m, SI dofs).

    Dofs as in :func:`assemble` (w_i, l r_i); ``D`` is the consistent damping matrix of the
    distributed damping C (eq 9: force C w' per unit length), the lateral mass matrix's
    shape functions with C in place of rho A (no rotary part), no point masses.
    """
    nodes = mesh(trunk, elements)
    check_beam_theory(beam_theory)
    els = _elements(trunk, nodes, beam_theory)
    K, M, keep = _assemble(trunk, nodes, els)
    D = _scatter([d for _, _, d in els], len(nodes), trunk.length)
    return M, D[np.ix_(keep, keep)], K, nodes, keep


def deflection_dof(nodes: np.ndarray, keep: np.ndarray, height: float) -> int:
    """Index among the kept dofs ``keep`` (:func:`assemble`) of the deflection at the node
    of ``nodes`` (heights, m) nearest ``height`` (m)."""
    i = int(np.argmin(np.abs(np.asarray(nodes) - height)))
    return int(np.nonzero(np.asarray(keep) == 2 * i)[0][0])
