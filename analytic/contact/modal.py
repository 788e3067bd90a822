"""Exact solution of one contact state of the linear impact, M q'' + C q' + K q = 0, in the
energy coordinates of its undamped modes (:class:`Modal`), and what the solvers read from it:
the observables (:func:`observation_rows`) and the energy ledger's quadratic forms and their
integrals in closed form (:func:`ledger_forms`). SI units; design notes:
docs/beam-impact.md.
"""

from __future__ import annotations

import enum
import math
import threading
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from treeimpact.analytic.errors import SimulationDiverged

from .linear_model import LinearImpactModel


class Modal:
    """Exact solution of M q'' + C q' + K q = 0 (one contact state) in the energy
    coordinates of its undamped modes.

    K Phi = M Phi diag(om^2) with Phi^T M Phi = I; the state u = (om eta, eta'), q = Phi eta,
    so that 0.5 |u|^2 is the kinetic plus elastic energy and
    u' = B u with B = [[0, diag(om)], [-diag(om), -Phi^T C Phi]]: a skew-symmetric
    matrix plus a dissipative block, whose eigenvectors are well conditioned (cond(V) 1.4-2.1
    on the shipped trees at 12-48 elements, where those of the state matrix of z = (q, q')
    have 3e7-1e9: their round-off changed the chattering sequence, docs/beam-impact.md).
    B = V diag(lambda) V^-1 and u(s) = V (exp(lambda s) w), w = V^-1 u(0).

    A rigid-body mode (om = 0: a free billet apart from the trunk, its own coordinate
    uncoupled, no spring; :attr:`rigid`) keeps (eta, eta') as its two coordinates, since
    om eta would lose eta: its block of B is G = [[0, 1], [0, 0]] (eta'' = 0), nilpotent and
    not diagonalisable. Its two coordinates get lambda = 0 and unit eigenvectors and the
    flight is added in closed form: u(s) = V (exp(lambda s) w) + s G u(0), i.e.
    eta(s) = eta(0) + s eta'(0), eta'(s) = eta'(0) (:attr:`drift` = G V, so G u(0) = drift w).

    For the raw state z = (q, q') = T u: ``V = T Vu`` and ``W = Vu^-1 T^-1`` (the
    ``exact-full`` loop's interface). The kept half of the spectrum (Im lambda >= 0; a
    conjugate pair counted twice through ``weight``) serves the ``exact`` method.
    """

    def __init__(self, M: np.ndarray, C: np.ndarray, K: np.ndarray):
        N = len(M)
        om2, Phi = _undamped_modes(M, C, K)
        rigid = _rigid_modes(om2, M, C, K)
        om = np.sqrt(np.where(rigid, 0.0, om2))
        B = np.zeros((2 * N, 2 * N))
        B[:N, N:] = np.diag(om)
        B[N:, :N] = -np.diag(om)
        B[N:, N:] = -(Phi.T @ C @ Phi)
        lam, Vu = _eigen(B, np.concatenate([rigid, rigid]))
        Wu = np.linalg.inv(Vu)
        if not (np.all(np.isfinite(Wu)) and np.all(np.isfinite(lam))):
            raise SimulationDiverged("beam: the state matrix could not be diagonalised")
        self.N, self.M, self.Phi, self.om = N, M, Phi, om
        self.rigid = rigid
        #: the displacement coordinate per unit eta: om (an elastic mode) or 1 (rigid)
        self.scale = np.where(rigid, 1.0, om)
        #: 1 on the elastic modes' displacement coordinates, 0 on a rigid mode's (no spring)
        self.elastic = np.where(rigid, 0.0, 1.0)
        self.lam, self.Vu, self.Wu = lam, Vu, Wu
        self.drift = None  # G V over the modes, or None: no rigid mode
        if rigid.any():
            G = np.zeros((2 * N, 2 * N))
            G[np.flatnonzero(rigid), N + np.flatnonzero(rigid)] = 1.0  # eta' drives eta
            self.drift = G @ Vu
        self.kept = np.flatnonzero(lam.imag >= 0.0)
        self.weight = np.where(lam.imag[self.kept] > 0.0, 2.0, 1.0)  # Re(V w) over the pairs

    @cached_property
    def pair_sums(self) -> tuple[np.ndarray, np.ndarray]:
        """(small, total): lambda_i + lambda_j over the pairs (1 where ``small``: below 1e-9
        of the largest |lambda|, an undamped pair whose integrand is constant), as
        :class:`Quadratic` divides by them."""
        total = self.lam[:, None] + self.lam[None, :]
        small = np.abs(total) < 1e-9 * max(1.0, float(np.max(np.abs(self.lam))))
        return small, np.where(small, 1.0, total)

    @cached_property
    def T(self) -> np.ndarray:
        """z = (q, q') = T u."""
        N = self.N
        T = np.zeros((2 * N, 2 * N))
        T[:N, :N], T[N:, N:] = self.Phi / self.scale, self.Phi
        return T

    @cached_property
    def Tinv(self) -> np.ndarray:
        """u = T^-1 z: T^-1 = diag(om Phi^T M, Phi^T M) (1 for om on a rigid mode)."""
        N = self.N
        PtM = self.Phi.T @ self.M
        Tinv = np.zeros((2 * N, 2 * N))
        Tinv[:N, :N], Tinv[N:, N:] = self.scale[:, None] * PtM, PtM
        return Tinv

    @cached_property
    def V(self) -> np.ndarray:
        """Eigenvectors over the raw state z."""
        return self.T @ self.Vu

    @cached_property
    def W(self) -> np.ndarray:
        """Modal coefficients from the raw state z: w = W z."""
        return self.Wu @ self.Tinv

    def transfer(self, other: Modal) -> np.ndarray:
        """The matrix taking ``other``'s energy coordinates to this one's (the same q, q'):
        T^-1 T_other = diag(om X / om_other, X), X = Phi^T M Phi_other (1 for om on a rigid
        mode)."""
        N = self.N
        X = self.Phi.T @ self.M @ other.Phi
        P = np.zeros((2 * N, 2 * N))
        P[:N, :N], P[N:, N:] = self.scale[:, None] * X / other.scale[None, :], X
        return P

    @property
    def condition(self) -> float:
        """cond(V) of the eigenvectors in the energy coordinates (2-norm)."""
        return float(np.linalg.cond(self.Vu))

    def displacement_row(self, r: np.ndarray) -> np.ndarray:
        """The row of u giving r . q (r over the N coordinates)."""
        return np.concatenate([(self.Phi.T @ r) / self.scale, np.zeros(self.N)])

    def velocity_row(self, r: np.ndarray) -> np.ndarray:
        """The row of u giving r . q'."""
        return np.concatenate([np.zeros(self.N), self.Phi.T @ r])

    # --- the exact-full loop's interface (raw coordinates z) ---
    def modal(self, w: np.ndarray, s: np.ndarray) -> np.ndarray:
        """U[k] = exp(lambda s_k) w: the modal coordinates at the times s (len(s) x n)."""
        return np.exp(np.outer(s, self.lam)) * w

    def observe(self, rows: np.ndarray, w: np.ndarray, s: np.ndarray, U=None) -> np.ndarray:
        """Observables ``rows @ u(s)`` for rows over u (r x len(s)) of the solution with
        modal coefficients ``w`` at s = 0; ``U``: :meth:`modal` of (w, s) if known."""
        U = self.modal(w, s) if U is None else U
        out = (U @ (rows @ self.Vu).T).real.T
        if self.drift is not None:  # the rigid modes' flight, s G u(0)
            out = out + np.outer((rows @ self.drift @ w).real, s)
        return out

    def state(self, w: np.ndarray, s: float) -> np.ndarray:
        """The raw state z = (q, q') at ``s`` (s) of the solution with modal coefficients
        ``w`` at s = 0."""
        z = (self.V @ (np.exp(self.lam * s) * w)).real
        if self.drift is not None:  # the rigid modes' flight, s G u(0)
            z = z + s * (self.T @ (self.drift @ w).real)
        return z

    def quadratic(self, Q: np.ndarray) -> Quadratic:
        """The quadratic form u^T Q u (Q over u) on this solution."""
        return Quadratic(self, Q)


#: Decompositions :func:`decomposed` keeps (the newest): a sweep over the pad (e, contact
#: duration) meets the same free state at every point; 8 states of a 48-element mesh hold
#: about 40 MB.
CACHE_SIZE = 8
_CACHE: dict = {}
_CACHE_LOCK = threading.Lock()


def decomposed(M: np.ndarray, C: np.ndarray, K: np.ndarray) -> Modal:
    """The :class:`Modal` of (M, C, K) (kg, N s/m, N/m), shared with every earlier call on
    the same matrices, bit for bit (one of the :data:`CACHE_SIZE` newest; the same
    arithmetic, so the same solution)."""
    key = (M.shape, M.tobytes(), C.tobytes(), K.tobytes())
    with _CACHE_LOCK:
        modal = _CACHE.pop(key, None)
    if modal is None:
        modal = Modal(M, C, K)
    with _CACHE_LOCK:
        _CACHE[key] = modal
        while len(_CACHE) > CACHE_SIZE:
            del _CACHE[next(iter(_CACHE))]
    return modal


def clear_cache() -> None:
    """Forget every decomposition :func:`decomposed` keeps (a cold start, for benchmarks)."""
    with _CACHE_LOCK:
        _CACHE.clear()


def _undamped_modes(M: np.ndarray, C: np.ndarray, K: np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray]:
    """(om^2, Phi): K Phi = M Phi diag(om^2), Phi^T M Phi = I. In the free state (the
    pendulum, the last coordinate, uncoupled) the pendulum's own mode is k / m exactly,
    beside the trunk's (whose round-off, eps om_max^2, could exceed a slow pendulum's om^2)."""
    N = len(M)
    if np.any(K[-1, :-1]) or np.any(M[-1, :-1]) or np.any(C[-1, :-1]):
        return _generalized_eigh(K, M)
    om2_t, Phi_t = _generalized_eigh(K[:-1, :-1], M[:-1, :-1])
    Phi = np.zeros((N, N))
    Phi[:-1, :-1], Phi[-1, -1] = Phi_t, 1.0 / math.sqrt(M[-1, -1])
    return np.append(om2_t, K[-1, -1] / M[-1, -1]), Phi


def _generalized_eigh(K: np.ndarray, M: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(om^2, Phi) of K Phi = M Phi diag(om^2), Phi^T M Phi = I (K, M real symmetric, M
    positive definite; their lower triangles read): ``scipy.linalg.eigh(K, M)``'s own call,
    LAPACK's dsygvd with its defaults (itype 1, vectors, lower), the same numbers without
    its argument handling (~10 us a call, two calls a run). Raises ValueError on a
    non-finite input (as eigh does) and LinAlgError where LAPACK fails."""
    # lazy: +212 ms at import otherwise (scipy.linalg)
    from scipy.linalg import lapack

    if not (np.isfinite(K).all() and np.isfinite(M).all()):
        raise ValueError("array must not contain infs or NaNs")
    om2, Phi, info = lapack.dsygvd(K, M)
    if info != 0:
        raise np.linalg.LinAlgError(f"dsygvd failed (info {info}): M is not positive "
                                    "definite or the eigenproblem did not converge")
    return om2, Phi


def _rigid_modes(om2: np.ndarray, M: np.ndarray, C: np.ndarray, K: np.ndarray
                 ) -> np.ndarray:
    """Which modes of :func:`_undamped_modes` are rigid-body modes (om^2 = 0): the last
    coordinate's own mode when it is uncoupled and has neither spring nor damper (a free
    billet apart from the trunk, y'' = 0). Any other mode of om^2 <= 0 (a trunk without
    support) raises SimulationDiverged."""
    rigid = np.zeros(len(om2), dtype=bool)
    last = len(M) - 1
    uncoupled = not (np.any(K[last, :last]) or np.any(M[last, :last]) or np.any(C[last, :last]))
    if uncoupled and K[last, last] == 0.0 and C[last, last] == 0.0:
        rigid[last] = True
    if np.any(om2[~rigid] <= 0.0):
        raise SimulationDiverged("beam: a mode of the linear model has no stiffness (om^2 "
                                 "<= 0) and is not a free billet's flight")
    return rigid


def _eigen(B: np.ndarray, rigid: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(lambda, V): B = V diag(lambda) V^-1 over the coordinates not ``rigid``; the rigid
    modes' coordinates (their rows and columns of B zero but G's, :class:`Modal`) get
    lambda = 0 and unit vectors. Without rigid modes, numpy's eig of B itself."""
    if not rigid.any():
        return np.linalg.eig(B)
    keep = np.flatnonzero(~rigid)
    lam_k, V_k = np.linalg.eig(B[np.ix_(keep, keep)])
    lam = np.zeros(len(B), dtype=complex)
    V = np.zeros(B.shape, dtype=complex)
    lam[keep] = lam_k
    V[np.ix_(keep, keep)] = V_k
    V[np.flatnonzero(rigid), np.flatnonzero(rigid)] = 1.0
    return lam, V


class Quadratic:
    """u(s)^T Q u(s) and its integral from 0 to s, in closed form on a :class:`Modal`:
    int_0^s u^T Q u = sum_ij H_ij w_i w_j (exp((lambda_i + lambda_j) s) - 1) / (lambda_i +
    lambda_j), H = V^T Q V; pairs with lambda_i + lambda_j = 0 (undamped) integrate to s.
    On a state with a rigid mode the forms do not read its displacement coordinate (Q G = 0:
    the kinetic energy, the elastic without it, the damping), so its flight adds nothing.
    ``modal``: the solution; ``Q``: the form over u (or None and ``H``, V^T Q V, given)."""

    def __init__(self, modal: Modal, Q: np.ndarray | None, H: np.ndarray | None = None):
        self.modal = modal
        H = modal.Vu.T @ Q @ modal.Vu if H is None else H
        small, total = modal.pair_sums
        self.H = H
        self.H_int = np.where(small, 0.0, H / total)
        self.H_lin = np.where(small, H, 0.0)  # secular part: constant integrand

    def value(self, w, s, U=None):
        """u(s)^T Q u(s) at the times ``s`` of the solution with modal coefficients ``w`` at
        s = 0 (``U``: its :meth:`Modal.modal` if known)."""
        U = self.modal.modal(w, s) if U is None else U
        return ((U @ self.H) * U).sum(axis=1).real

    def integral(self, w, s, U=None):
        """int_0^s u^T Q u at the times ``s`` of the solution with modal coefficients ``w``
        at s = 0 (``U``: its :meth:`Modal.modal` if known), in closed form."""
        U = self.modal.modal(w, s) if U is None else U
        start = w @ self.H_int @ w
        return (((U @ self.H_int) * U).sum(axis=1) - start
                + np.asarray(s) * (w @ self.H_lin @ w)).real


@dataclass(frozen=True)
class LedgerForms:
    """The energy ledger's quadratic forms over u of one contact state (J; the works' rates
    in W): kinetic energy, elastic energy of the trunk's and pendulum's springs (the pad's
    excluded), the rate of the trunk's damping work and (in contact, else None) of the
    pad's work F delta'."""

    kinetic: Quadratic
    elastic: Quadratic
    damping: Quadratic
    pad: Quadratic | None


def ledger_forms(model: LinearImpactModel, modal: Modal, contact: bool,
                 g: np.ndarray) -> LedgerForms:
    """The :class:`LedgerForms` of ``model`` on its solution ``modal`` in one contact state
    (``contact``: touching; delta = g . q). The elastic form is
    written in the modal coordinates exactly (0.5 |u_1|^2 less the pad's spring), not as
    Phi^T K Phi, whose round-off is eps |K| / om_1^2 of the low modes' energy."""
    N, k_c, c_c = modal.N, model.contact_stiffness, model.contact_damping
    kin = np.zeros((2 * N, 2 * N))
    kin[N:, N:] = 0.5 * np.eye(N)
    pot = np.zeros((2 * N, 2 * N))
    pot[:N, :N] = 0.5 * np.diag(modal.elastic)  # a rigid mode's coordinate has no spring
    gd, gv = modal.displacement_row(g), modal.velocity_row(g)
    damp = np.zeros((2 * N, 2 * N))
    Dfull = np.zeros((N, N))
    Dfull[:model.dofs, :model.dofs] = model.D
    damp[N:, N:] = modal.Phi.T @ Dfull @ modal.Phi
    pad = None
    if contact:
        pot = pot - 0.5 * k_c * np.outer(gd, gd)
        pad = modal.quadratic(0.5 * k_c * (np.outer(gd, gv) + np.outer(gv, gd))
                              + c_c * np.outer(gv, gv))
    return LedgerForms(modal.quadratic(kin), modal.quadratic(pot), modal.quadratic(damp), pad)


class Observable(enum.IntEnum):
    """The rows of :func:`observation_rows` (SI: m and m/s)."""

    X = 0  # the trunk at the clamp
    Y = 1  # the pendulum
    VX = 2
    VY = 3
    DELTA = 4  # the overlap y - x
    DELTA_RATE = 5
    CROWN = 6  # the crown's deflection
    CROWN_VELOCITY = 7


def observation_rows(model: LinearImpactModel, modal: Modal, g: np.ndarray) -> np.ndarray:
    """Rows over u of the :class:`Observable` quantities of ``model`` on its solution
    ``modal`` (delta = ``g`` . q), in their order (8 x 2N): the points' rows r over q (the
    clamp, the pendulum, delta, the crown) as :meth:`Modal.displacement_row` and
    :meth:`Modal.velocity_row` of each, all at once."""
    N = modal.N
    points = np.zeros((4, N))
    points[0, model.clamp], points[1, N - 1] = 1.0, 1.0
    points[2], points[3, model.crown] = g, model.crown_gain
    per_eta = points @ modal.Phi  # r . q per unit eta, each point
    rows = np.zeros((8, 2 * N))
    rows[[Observable.X, Observable.Y, Observable.DELTA, Observable.CROWN], :N] = (
        per_eta / modal.scale)
    rows[[Observable.VX, Observable.VY, Observable.DELTA_RATE, Observable.CROWN_VELOCITY],
         N:] = per_eta
    return rows
