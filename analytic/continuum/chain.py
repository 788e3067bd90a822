"""Rigid hinged-segment trunk: the discretisation both engines build (MuJoCo hinges, Bullet revolutes).

Design notes and measured figures: docs/trunk-models.md.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.model.options import Option
from treeimpact.analytic.model.parameters import Trunk
from treeimpact.analytic.model.reduction import TreeSDOF

from .beam import beam_natural_frequencies, beam_static_stiffness

MIN_SEGMENTS = 2
MAX_SEGMENTS = 1000
#: The engines' ``segments`` option: a chain has 2 or more (a sweep's ``segments=1`` is its
#: name for the SDOF trunk, ``--trunk sdof``: compare.studies.sweep.grid reads it so).
SEGMENTS = Option(int, "segments of the hinged trunk (default: the fewest within 0.5 % of "
                  "the beam's static stiffness and first two frequencies)", low=MIN_SEGMENTS,
                  high=MAX_SEGMENTS)
DEFAULT_TOLERANCE = 0.005  # relative: static stiffness at a and the first two frequencies
GAUSS_OFFSET = 1.0 / (2.0 * math.sqrt(3.0))  # Gauss-Legendre points z_c -+ h/(2 sqrt 3)


@dataclass(frozen=True)
class HingedChain:
    """N rigid segments with hinge springs (SI units; index j = segment j, hinge j at its bottom)."""

    trunk: Trunk
    boundaries: tuple  # z_0 = 0 < ... < z_N = l, m
    clamp_index: int  # N_in: boundaries[N_in] == a
    masses: tuple  # rho A h_j, kg
    centres: tuple  # (z_j + z_{j+1}) / 2, m
    inertias: tuple  # rho A h_j^3 / 12 about the bending axis through the centre, kg m^2
    hinge_stiffnesses: tuple  # k_j, N m/rad
    damping_heights: tuple  # two Gauss points per segment, m
    damping_coefficients: tuple  # C h_j / 2 each, N s/m
    damping_segments: tuple  # the segment each damping point belongs to

    @property
    def segments(self) -> int:
        """The number of segments N."""
        return len(self.boundaries) - 1

    @property
    def lower(self) -> np.ndarray:
        """z_j of each segment's bottom, m."""
        return np.asarray(self.boundaries[:-1])

    @property
    def upper(self) -> np.ndarray:
        """z_{j+1} of each segment's top, m."""
        return np.asarray(self.boundaries[1:])

    @property
    def lengths(self) -> np.ndarray:
        """h_j of each segment, m."""
        return np.diff(self.boundaries)

    @property
    def hinge_heights(self) -> np.ndarray:
        """z_j of hinge j (the bottom of segment j), m."""
        return np.asarray(self.boundaries[:-1])

    @property
    def clamp_height(self) -> float:
        """a, the trunk's clamp (impact) height, m."""
        return self.trunk.clamp_height

    @property
    def clamp_mass(self) -> float:
        """m_c, the clamp's point mass at a, kg."""
        return self.trunk.clamp_mass

    @property
    def crown_mass(self) -> float:
        """m_f, the crown's point mass at l, kg."""
        return self.trunk.crown_mass

    @property
    def clamp_segment(self) -> int:
        """The segment whose top is a (carries m_c at its upper end)."""
        return self.clamp_index - 1

    @property
    def crown_segment(self) -> int:
        """The top segment (carries m_f at its upper end, z = l)."""
        return self.segments - 1


def _check_segments(segments) -> int:
    if isinstance(segments, bool) or not isinstance(segments, (int, np.integer)) or not (
            MIN_SEGMENTS <= segments <= MAX_SEGMENTS):
        raise ParameterError(f"segments = {segments!r} is out of range: allowed integers "
                             f"[{MIN_SEGMENTS}, {MAX_SEGMENTS}]")
    return int(segments)


def split_segments(trunk: Trunk, segments: int) -> tuple[int, int]:
    """(N_in, N_out): of ``segments`` in all, those of ``trunk`` in [0, a] and in [a, l]
    (rule in the module docstring)."""
    n = _check_segments(segments)
    a, l = trunk.clamp_height, trunk.length
    if a >= l:
        return n, 0
    n_in = min(max(math.floor(n * a / l + 0.5), 1), n - 1)
    return n_in, n - n_in


def hinged_chain(trunk: Trunk, segments: int) -> HingedChain:
    """The hinged-segment trunk with ``segments`` rigid segments (rules in the module docstring)."""
    if not isinstance(trunk, Trunk):
        raise ParameterError(f"trunk: expected an analytic.Trunk, got {type(trunk).__name__}")
    return _hinged_chain(trunk, _check_segments(segments))


@functools.lru_cache(maxsize=256)
def _hinged_chain(trunk: Trunk, segments: int) -> HingedChain:
    n_in, n_out = split_segments(trunk, segments)
    a, l = trunk.clamp_height, trunk.length
    z = np.linspace(0.0, a, n_in + 1)
    if n_out:
        z = np.concatenate([z, np.linspace(a, l, n_out + 1)[1:]])
    z[n_in] = a
    z[-1] = l
    h = np.diff(z)
    rho_a, ei = trunk.density * trunk.area, trunk.bending_stiffness
    k = np.empty(len(h))
    k[1:] = 2.0 * ei / (h[:-1] + h[1:])
    k[0] = 1.0 / (h[0] / (2.0 * ei) + (1.0 / trunk.base_stiffness
                                         if math.isfinite(trunk.base_stiffness) else 0.0))
    c = 0.5 * (z[:-1] + z[1:])
    dz = np.column_stack([c - GAUSS_OFFSET * h, c + GAUSS_OFFSET * h]).ravel()
    dc = np.repeat(trunk.damping * h / 2.0, 2)
    return HingedChain(
        trunk=trunk,
        boundaries=tuple(float(v) for v in z),
        clamp_index=n_in,
        masses=tuple(float(v) for v in rho_a * h),
        centres=tuple(float(v) for v in c),
        inertias=tuple(float(v) for v in rho_a * h ** 3 / 12.0),
        hinge_stiffnesses=tuple(float(v) for v in k),
        damping_heights=tuple(float(v) for v in dz),
        damping_coefficients=tuple(float(v) for v in dc),
        damping_segments=tuple(int(v) for v in np.repeat(np.arange(len(h)), 2)),
    )


def lateral_jacobian(chain: HingedChain, z) -> np.ndarray:
    """d x(z) / d theta of ``chain`` at the heights ``z`` (m): rows (z - z_j) for hinges
    below z, else 0 (m/rad), shape (len(z), N)."""
    z = np.atleast_1d(np.asarray(z, dtype=float))
    return np.maximum(z[:, None] - chain.hinge_heights[None, :], 0.0)


def lateral_motion(chain: HingedChain, angles, rates, segments: int):
    """(x, x') in m, m/s of the top of ``chain``'s segment ``segments - 1`` for hinge
    ``angles`` (rad, each relative to the segment below) and their ``rates`` (rad/s) per
    sample, rows of shape (N,): exact kinematics, x = sum_j h_j sin(phi_j) with phi the
    cumulative angles."""
    h = chain.lengths[:segments]
    phi = np.cumsum(angles, axis=-1)[..., :segments]
    phid = np.cumsum(rates, axis=-1)[..., :segments]
    return np.sin(phi) @ h, (np.cos(phi) * phid) @ h


def rotation_jacobian(chain: HingedChain) -> np.ndarray:
    """d(rotation of segment s) / d theta_j = 1 for j <= s of ``chain``: lower-triangular
    ones, (N, N)."""
    return np.tril(np.ones((chain.segments, chain.segments)))


def chain_matrices(chain: HingedChain) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Linearised (M, K, D) of ``chain`` in the hinge angles: kg m^2, N m/rad, N m s/rad.

    M = sum_s m_s J(c_s)^T J(c_s) + I_s R_s^T R_s + m_c J(a)^T J(a) + m_f J(l)^T J(l),
    K = diag(k_j), D = sum_p c_p J(z_p)^T J(z_p), with J the lateral Jacobian.
    """
    jc = lateral_jacobian(chain, chain.centres)
    r = rotation_jacobian(chain)
    M = (jc.T * np.asarray(chain.masses)) @ jc + (r.T * np.asarray(chain.inertias)) @ r
    ends = lateral_jacobian(chain, [chain.trunk.clamp_height, chain.trunk.length])
    M += np.outer(ends[0], ends[0]) * chain.trunk.clamp_mass
    M += np.outer(ends[1], ends[1]) * chain.trunk.crown_mass
    jd = lateral_jacobian(chain, chain.damping_heights)
    D = (jd.T * np.asarray(chain.damping_coefficients)) @ jd
    K = np.diag(np.asarray(chain.hinge_stiffnesses))
    return 0.5 * (M + M.T), K, 0.5 * (D + D.T)


def chain_static_stiffness(chain: HingedChain) -> float:
    """Force at a per unit deflection at a of ``chain``, N/m: 1 / (J(a) K^-1 J(a)^T)."""
    ja = lateral_jacobian(chain, chain.trunk.clamp_height)[0]
    return float(1.0 / np.sum(ja ** 2 / np.asarray(chain.hinge_stiffnesses)))


def chain_static_mode(chain: HingedChain) -> np.ndarray:
    """Hinge angles of ``chain``'s static deflection under a load at a, normalised to 1 at
    a (rad/m)."""
    ja = lateral_jacobian(chain, chain.trunk.clamp_height)[0]
    u = ja / np.asarray(chain.hinge_stiffnesses)
    return u / float(ja @ u)


def chain_natural_frequencies(chain: HingedChain, n_modes: int = 3) -> np.ndarray:
    """The lowest ``n_modes`` natural frequencies of the linearised chain, rad/s, ascending.

    Solves K v = omega^2 M v as the largest eigenvalues 1/omega^2 of K^-1/2 M K^-1/2 (K is
    diagonal), which keeps the low modes accurate for many segments.
    """
    if isinstance(n_modes, bool) or not isinstance(n_modes, (int, np.integer)) or not (
            1 <= n_modes <= chain.segments):
        raise ParameterError(f"n_modes = {n_modes!r} is out of range: allowed integers "
                             f"[1, {chain.segments}] (the number of segments)")
    M, K, _ = chain_matrices(chain)
    s = 1.0 / np.sqrt(np.diag(K))
    A = s[:, None] * M * s[None, :]
    # lazy: +194 ms at import otherwise (scipy.linalg)
    import scipy.linalg

    n = chain.segments  # only the n_modes largest: a fraction of the full solve's time
    mu = scipy.linalg.eigh(A, eigvals_only=True, subset_by_index=[n - n_modes, n - 1])[::-1]
    return 1.0 / np.sqrt(mu)


def chain_reduced_sdof(chain: HingedChain) -> TreeSDOF:
    """The chain projected on its own static mode at a: the chain's analogue of eq 11.

    M_T = u^T M u, C_T = u^T D u, K_T = u^T K u (= :func:`chain_static_stiffness`), with u the
    static mode normalised to 1 at a.
    """
    M, K, D = chain_matrices(chain)
    u = chain_static_mode(chain)
    return TreeSDOF(dynamic_mass=float(u @ M @ u), equivalent_damping=float(u @ D @ u),
                    equivalent_stiffness=float(u @ K @ u))


def chain_errors(trunk: Trunk, segments: int) -> dict:
    """Relative errors (1) of the chain of ``segments`` segments against the beam of
    ``trunk`` (:mod:`analytic.continuum.beam`): static stiffness at a, omega_1, omega_2."""
    chain = hinged_chain(trunk, segments)
    w_beam = beam_natural_frequencies(trunk, 2)
    w_chain = chain_natural_frequencies(chain, 2)
    return {"static_stiffness": chain_static_stiffness(chain) / beam_static_stiffness(trunk) - 1.0,
            "omega_1": float(w_chain[0] / w_beam[0] - 1.0),
            "omega_2": float(w_chain[1] / w_beam[1] - 1.0)}


def default_segments(trunk: Trunk, tolerance: float = DEFAULT_TOLERANCE) -> int:
    """The smallest N whose static stiffness at a and first two frequencies are within
    ``tolerance`` (0.5 %) of the beam (:func:`chain_errors`; errors fall as 1/N^2, the
    convergence table: docs/trunk-models.md), found by doubling N from 2 and bisecting: at
    most 2 log2(N) dense eigen-solves, so a tree that needs hundreds of segments is known in
    a second, not a search of minutes."""
    if not isinstance(trunk, Trunk):
        raise ParameterError(f"trunk: expected an analytic.Trunk, got {type(trunk).__name__}")
    if isinstance(tolerance, bool) or not isinstance(tolerance, (int, float)) or not (
            1e-4 <= tolerance <= 0.5):
        raise ParameterError(f"tolerance = {tolerance!r} is out of range: allowed [0.0001, 0.5] "
                             "(relative)")
    return _default_segments(trunk, float(tolerance))


@functools.lru_cache(maxsize=64)
def _default_segments(trunk: Trunk, tolerance: float) -> int:
    def within(n: int) -> bool:
        return all(abs(v) <= tolerance for v in chain_errors(trunk, n).values())

    fail, n = MIN_SEGMENTS - 1, MIN_SEGMENTS  # invariant: fail fails (or is below the range)
    while not within(n):
        if n == MAX_SEGMENTS:
            raise ParameterError(
                f"the hinged chain: no chain with <= {MAX_SEGMENTS} segments is within "
                f"{tolerance:g} of the beam's static stiffness and first two frequencies "
                "(a trunk this slender or long: --trunk sdof, or --backend beam)")
        fail, n = n, min(2 * n, MAX_SEGMENTS)
    while n - fail > 1:  # the errors fall monotonically with N (1/N^2): bisect
        mid = (fail + n) // 2
        fail, n = (fail, mid) if within(mid) else (mid, n)
    return n
