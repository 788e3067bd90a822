"""Two linear bodies struck through the pad, solved exactly between contact switches: a
linear trunk (any M, D, K with the dof the pad strikes: the 1-DOF trunk of eq 11 or a
continuum's mesh) and the linearised pendulum (eq 13), meeting through the spring-dashpot
contact F = max(0, k_c delta + c_c delta'), delta = y - x >= 0 (:mod:`.law`).

In each contact state the system is linear and is solved exactly by the eigen-
decomposition of its state matrix written in the energy coordinates of its undamped modes
(:class:`Modal`); every contact switch is located by root finding on the exact solution.
:func:`solve` evaluates what the metrics read, :func:`record` every sample's state and
energies (the reference). Design notes: docs/beam-impact.md.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from treeimpact.analytic.errors import ParameterError, SimulationDiverged
from treeimpact.analytic.results import ImpactRecord


@dataclass(frozen=True)
class LinearImpactModel:
    """A linear trunk (M, D, K over its dofs; ``clamp`` the dof the pad strikes, ``crown``
    the crown's, times ``crown_gain``) and the linearised pendulum meeting through the pad
    (k_c, c_c): SI units."""

    M: np.ndarray = field(repr=False)  # kg, trunk mass matrix (a mesh: dofs w_i, l w_i')
    D: np.ndarray = field(repr=False)  # N s/m, consistent damping matrix
    K: np.ndarray = field(repr=False)  # N/m, stiffness with the root spring
    clamp: int  # dof of the deflection at a
    crown: int  # dof of the deflection at l
    impactor_mass: float  # m, kg
    impactor_stiffness: float  # k = m g / l_e, N/m (eq 13)
    impact_speed: float  # u_1, m/s (eq 48)
    contact_stiffness: float  # k_c, N/m
    contact_damping: float  # c_c, N s/m
    crown_gain: float = 1.0  # crown motion per unit of the crown dof (an SDOF: phi(l))

    @property
    def dofs(self) -> int:
        return len(self.M)

    @property
    def effective_mass(self) -> float:
        """Instantaneous effective mass of the trunk at the clamp, 1 / (M^-1)_aa, kg."""
        e = np.zeros(self.dofs)
        e[self.clamp] = 1.0
        return float(1.0 / np.linalg.solve(self.M, e)[self.clamp])

    @property
    def initial_energy(self) -> float:
        """The pendulum's kinetic energy at the first touch, 0.5 m u_1^2, J."""
        return 0.5 * self.impactor_mass * self.impact_speed ** 2


def matrices(model: LinearImpactModel, contact: bool):
    """``(M, C, K, g)`` of trunk and pendulum (N = dofs + 1 coordinates q = (trunk, y)) in
    one contact state; delta = g . q. In contact the pad's k_c and c_c act along g."""
    n, N = model.dofs, model.dofs + 1
    K = np.zeros((N, N))
    C = np.zeros((N, N))
    M = np.zeros((N, N))
    K[:n, :n], C[:n, :n], M[:n, :n] = model.K, model.D, model.M
    K[n, n], M[n, n] = model.impactor_stiffness, model.impactor_mass
    g = np.zeros(N)
    g[n], g[model.clamp] = 1.0, -1.0
    if contact:  # F = k_c delta + c_c delta' pushes the trunk (+g_clamp) and the pendulum back
        K = K + model.contact_stiffness * np.outer(g, g)
        C = C + model.contact_damping * np.outer(g, g)
    return M, C, K, g


def system(model: LinearImpactModel, contact: bool) -> tuple[np.ndarray, np.ndarray]:
    """(A, g): the state matrix of z = (q, q'), z' = A z, of one contact state (what the
    independent references of the tests integrate) and delta = g . q."""
    M, C, K, g = matrices(model, contact)
    N = len(g)
    A = np.zeros((2 * N, 2 * N))
    A[:N, N:] = np.eye(N)
    A[N:, :N] = -np.linalg.solve(M, K)
    A[N:, N:] = -np.linalg.solve(M, C)
    return A, g


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

    For the raw state z = (q, q') = T u: ``V = T Vu`` and ``W = Vu^-1 T^-1`` (the
    ``exact-full`` loop's interface). The kept half of the spectrum (Im lambda >= 0; a
    conjugate pair counted twice through ``weight``) serves the ``exact`` method.
    """

    def __init__(self, M: np.ndarray, C: np.ndarray, K: np.ndarray):
        import scipy.linalg

        N = len(M)
        if not (np.any(K[-1, :-1]) or np.any(M[-1, :-1]) or np.any(C[-1, :-1])):
            # the free state: the pendulum's own mode, k / m exactly, beside the trunk's
            # (whose round-off, eps om_max^2, could exceed a slow pendulum's om^2)
            om2_t, Phi_t = scipy.linalg.eigh(K[:-1, :-1], M[:-1, :-1])
            om2 = np.append(om2_t, K[-1, -1] / M[-1, -1])
            Phi = np.zeros((N, N))
            Phi[:-1, :-1], Phi[-1, -1] = Phi_t, 1.0 / math.sqrt(M[-1, -1])
        else:
            om2, Phi = scipy.linalg.eigh(K, M)
        if np.any(om2 <= 0.0):  # the trunk is clamped: only a free billet has no spring
            raise ParameterError("impactor.type = 'billet': the exact linear solver needs a "
                                 "pendulum (a free billet's flight, y'' = 0, has no "
                                 "eigen-decomposition)")
        om = np.sqrt(om2)
        B = np.zeros((2 * N, 2 * N))
        B[:N, N:] = np.diag(om)
        B[N:, :N] = -np.diag(om)
        B[N:, N:] = -(Phi.T @ C @ Phi)
        lam, Vu = np.linalg.eig(B)
        Wu = np.linalg.inv(Vu)
        if not (np.all(np.isfinite(Wu)) and np.all(np.isfinite(lam))):
            raise SimulationDiverged("beam: the state matrix could not be diagonalised")
        self.N, self.M, self.Phi, self.om = N, M, Phi, om
        self.lam, self.Vu, self.Wu = lam, Vu, Wu
        self.kept = np.flatnonzero(lam.imag >= 0.0)
        self.weight = np.where(lam.imag[self.kept] > 0.0, 2.0, 1.0)  # Re(V w) over the pairs

    @cached_property
    def T(self) -> np.ndarray:
        """z = (q, q') = T u."""
        N = self.N
        T = np.zeros((2 * N, 2 * N))
        T[:N, :N], T[N:, N:] = self.Phi / self.om, self.Phi
        return T

    @cached_property
    def Tinv(self) -> np.ndarray:
        """u = T^-1 z: T^-1 = diag(om Phi^T M, Phi^T M)."""
        N = self.N
        PtM = self.Phi.T @ self.M
        Tinv = np.zeros((2 * N, 2 * N))
        Tinv[:N, :N], Tinv[N:, N:] = self.om[:, None] * PtM, PtM
        return Tinv

    @cached_property
    def V(self) -> np.ndarray:
        """Eigenvectors over the raw state z."""
        return self.T @ self.Vu

    @cached_property
    def W(self) -> np.ndarray:
        """Modal coefficients from the raw state z: w = W z."""
        return self.Wu @ self.Tinv

    def transfer(self, other: "Modal") -> np.ndarray:
        """The matrix taking ``other``'s energy coordinates to this one's (the same q, q'):
        T^-1 T_other = diag(om X / om_other, X), X = Phi^T M Phi_other."""
        N = self.N
        X = self.Phi.T @ self.M @ other.Phi
        P = np.zeros((2 * N, 2 * N))
        P[:N, :N], P[N:, N:] = self.om[:, None] * X / other.om[None, :], X
        return P

    @property
    def condition(self) -> float:
        """cond(V) of the eigenvectors in the energy coordinates (2-norm)."""
        return float(np.linalg.cond(self.Vu))

    def displacement_row(self, r: np.ndarray) -> np.ndarray:
        """The row of u giving r . q (r over the N coordinates)."""
        return np.concatenate([(self.Phi.T @ r) / self.om, np.zeros(self.N)])

    def velocity_row(self, r: np.ndarray) -> np.ndarray:
        """The row of u giving r . q'."""
        return np.concatenate([np.zeros(self.N), self.Phi.T @ r])

    # --- the exact-full loop's interface (raw coordinates z) ---
    def modal(self, w: np.ndarray, s: np.ndarray) -> np.ndarray:
        """U[k] = exp(lambda s_k) w: the modal coordinates at the times s (len(s) x n)."""
        return np.exp(np.outer(s, self.lam)) * w

    def observe(self, rows: np.ndarray, w: np.ndarray, s: np.ndarray, U=None) -> np.ndarray:
        """Observables ``rows @ u(s)`` for rows over u (r x len(s))."""
        U = self.modal(w, s) if U is None else U
        return (U @ (rows @ self.Vu).T).real.T

    def state(self, w: np.ndarray, s: float) -> np.ndarray:
        """The raw state z = (q, q') at s."""
        return (self.V @ (np.exp(self.lam * s) * w)).real

    def quadratic(self, Q: np.ndarray) -> "_Quadratic":
        """The quadratic form u^T Q u (Q over u) on this solution."""
        return _Quadratic(self, Q)


class _Quadratic:
    """u(s)^T Q u(s) and its integral from 0 to s, in closed form on a :class:`Modal`:
    int_0^s u^T Q u = sum_ij H_ij w_i w_j (exp((lambda_i + lambda_j) s) - 1) / (lambda_i +
    lambda_j), H = V^T Q V; pairs with lambda_i + lambda_j = 0 (undamped) integrate to s."""

    def __init__(self, modal: Modal, Q: np.ndarray):
        self.modal = modal
        H = modal.Vu.T @ Q @ modal.Vu
        total = modal.lam[:, None] + modal.lam[None, :]
        small = np.abs(total) < 1e-9 * max(1.0, float(np.max(np.abs(modal.lam))))
        self.H = H
        self.H_int = np.where(small, 0.0, H / np.where(small, 1.0, total))
        self.H_lin = np.where(small, H, 0.0)  # secular part: constant integrand

    def value(self, w, s, U=None):
        U = self.modal.modal(w, s) if U is None else U
        return ((U @ self.H) * U).sum(axis=1).real

    def integral(self, w, s, U=None):
        U = self.modal.modal(w, s) if U is None else U
        start = w @ self.H_int @ w
        return (((U @ self.H_int) * U).sum(axis=1) - start
                + np.asarray(s) * (w @ self.H_lin @ w)).real


def _forms(model: LinearImpactModel, modal: Modal, contact: bool, g: np.ndarray,
           names=("kin", "pot", "damp", "contact")) -> dict:
    """The energy ledger's quadratic forms over u of one contact state: kinetic energy,
    elastic energy of the trunk's and pendulum's springs (the pad's excluded), the rates of
    the trunk's damping work and of the pad's work F delta' (contact only). The elastic form
    is written in the modal coordinates exactly (0.5 |u_1|^2 less the pad's spring), not
    as Phi^T K Phi, whose round-off is eps |K| / om_1^2 of the low modes' energy."""
    N, k_c, c_c = modal.N, model.contact_stiffness, model.contact_damping
    kin = np.zeros((2 * N, 2 * N))
    kin[N:, N:] = 0.5 * np.eye(N)
    pot = np.zeros((2 * N, 2 * N))
    pot[:N, :N] = 0.5 * np.eye(N)
    gd, gv = modal.displacement_row(g), modal.velocity_row(g)
    damp = np.zeros((2 * N, 2 * N))
    Dfull = np.zeros((N, N))
    Dfull[:model.dofs, :model.dofs] = model.D
    damp[N:, N:] = modal.Phi.T @ Dfull @ modal.Phi
    if contact:
        pot = pot - 0.5 * k_c * np.outer(gd, gd)
    forms = {"kin": kin, "pot": pot, "damp": damp}
    if contact:
        forms["contact"] = (0.5 * k_c * (np.outer(gd, gv) + np.outer(gv, gd))
                            + c_c * np.outer(gv, gv))
    return {k: modal.quadratic(q) for k, q in forms.items() if k in names}


def _observation_rows(model: LinearImpactModel, modal: Modal, g: np.ndarray) -> np.ndarray:
    """Rows over u of x, y, x', y', delta, delta', crown, crown velocity (8 x 2N)."""
    N = modal.N
    e = np.eye(N)
    clamp, pend, crown = e[model.clamp], e[N - 1], model.crown_gain * e[model.crown]
    return np.array([modal.displacement_row(clamp), modal.displacement_row(pend),
                     modal.velocity_row(clamp), modal.velocity_row(pend),
                     modal.displacement_row(g), modal.velocity_row(g),
                     modal.displacement_row(crown), modal.velocity_row(crown)])


def _initial_state(model: LinearImpactModel) -> np.ndarray:
    """z(0): everything at rest but the pendulum, at u_1 (the first touch, delta = 0)."""
    N = model.dofs + 1
    z = np.zeros(2 * N)
    z[2 * N - 1] = model.impact_speed
    return z


def record(model: LinearImpactModel, t_end: float, dt_sample: float):
    """Solve the impact exactly to ``t_end`` (s); an ``ImpactRecord`` every ``dt_sample``.

    The ``exact-full`` method: every sample's observables and energies as it goes. Also
    returns the crown deflection (m) at the same times and the number of contact switches.
    """
    k_c, c_c = model.contact_stiffness, model.contact_damping
    systems, forms, rows_of = {}, {}, {}
    for contact in (False, True):
        M, C, K, g = matrices(model, contact)
        modal = Modal(M, C, K)
        systems[contact] = modal
        forms[contact] = _forms(model, modal, contact, g)
        rows_of[contact] = _observation_rows(model, modal, g)

    steps = int(math.ceil(t_end / dt_sample - 1e-9))
    t_grid = np.linspace(0.0, t_end, steps + 1)
    obs = np.zeros((8, t_grid.size))
    energy = np.zeros((4, t_grid.size))  # kinetic, potential, damping work, contact work
    in_contact = np.zeros(t_grid.size, dtype=bool)
    z = _initial_state(model)
    t, phase = 0.0, "contact"
    w_damp = w_contact = 0.0
    switches = 0
    max_switches = 100_000
    while True:
        contact = phase == "contact"
        modal, rows = systems[contact], rows_of[contact]
        w = modal.W @ z
        j0 = int(np.searchsorted(t_grid, t, side="left"))
        if j0 < t_grid.size and t_grid[j0] == t and t > 0:
            j0 += 1  # that sample was written by the previous phase
        # scan the samples ahead for the phase's end, in growing chunks
        end_s, nxt, j = None, None, j0
        chunk = 64
        while j < t_grid.size and end_s is None:
            jj = min(t_grid.size, j + chunk)
            s = t_grid[j:jj] - t
            U = modal.modal(w, s)
            d, dd = modal.observe(rows[4:6], w, s, U)
            f = k_c * d + c_c * dd
            if phase == "contact":
                hit = np.flatnonzero(f <= 0.0)
            elif phase == "overlap":
                hit = np.flatnonzero((f > 0.0) | (d < 0.0))
            else:
                hit = np.flatnonzero(d > 0.0)
            if hit.size:
                k = int(hit[0])
                s_hi = s[k]
                s_lo = s[k - 1] if k > 0 else (t_grid[j - 1] - t if j > j0 else 0.0)
                end_s, nxt = _locate(phase, modal, rows, w, s_lo, s_hi, k_c, c_c,
                                     d[k], f[k])
                jj = j + k  # samples before the event belong to this phase
            _fill(t_grid, j, jj, t, modal, rows, w, forms[contact], obs, energy,
                  in_contact, contact, w_damp, w_contact, U[:jj - j])
            j = jj
            chunk *= 4
        if end_s is None:
            break
        # advance the state and the dissipation to the switch
        wd = float(forms[contact]["damp"].integral(w, np.array([end_s]))[0])
        wc = float(forms[contact]["contact"].integral(w, np.array([end_s]))[0]) if contact \
            else 0.0
        z = modal.state(w, end_s)
        if not np.all(np.isfinite(z)):
            raise SimulationDiverged(f"beam: non-finite state at t = {t + end_s:.6g} s")
        w_damp, w_contact = w_damp + wd, w_contact + wc
        t += end_s
        phase = nxt
        switches += 1
        if switches > max_switches:
            raise SimulationDiverged(f"beam: more than {max_switches} contact switches by "
                                     f"t = {t:.6g} s (chatter does not end)")
    x, y, vx, vy, delta, ddelta, crown, crown_v = obs
    force = np.where(in_contact, np.maximum(0.0, k_c * delta + c_c * ddelta), 0.0)
    kinetic, potential, damping_work, contact_work = energy
    m, kp = model.impactor_mass, model.impactor_stiffness
    record = ImpactRecord(
        t=t_grid, x=x, vx=vx, y=y, vy=vy, force=force, kinetic=kinetic, potential=potential,
        damping_work=damping_work, contact_work=contact_work,
        contact_potential=np.where(in_contact, 0.5 * k_c * np.maximum(delta, 0.0) ** 2, 0.0),
        pendulum_energy=0.5 * m * vy ** 2 + 0.5 * kp * y ** 2, crown=crown,
        crown_velocity=crown_v)
    return record, crown, switches


def _fill(t_grid, j, jj, t, modal, rows, w, forms, obs, energy, in_contact, contact,
          w_damp, w_contact, U):
    """Write samples j..jj-1 of one phase (started at t with modal coefficients w)."""
    if jj <= j:
        return
    s = t_grid[j:jj] - t
    obs[:, j:jj] = modal.observe(rows, w, s, U)
    energy[0, j:jj] = forms["kin"].value(w, s, U)
    energy[1, j:jj] = forms["pot"].value(w, s, U)
    energy[2, j:jj] = w_damp + forms["damp"].integral(w, s, U)
    energy[3, j:jj] = w_contact + (forms["contact"].integral(w, s, U) if contact else 0.0)
    in_contact[j:jj] = contact


def _locate(phase, modal, rows, w, s_lo, s_hi, k_c, c_c, d_hi, f_hi):
    """(time into the phase, next phase) of the switch bracketed by [s_lo, s_hi]."""

    def d(s):
        return float(modal.observe(rows[4:5], w, np.array([s]))[0, 0])

    def f(s):
        dd = modal.observe(rows[4:6], w, np.array([s]))
        return float(k_c * dd[0, 0] + c_c * dd[1, 0])

    if phase == "contact":
        s = _root(f, s_lo, s_hi)
        return s, ("overlap" if d(s) > 0.0 else "free")
    if phase == "free":
        return _root(d, s_lo, s_hi), "contact"
    # overlap: whichever of "law rises through 0" and "delta falls through 0" comes first
    cand = []
    if f_hi > 0.0:
        cand.append((_root(f, s_lo, s_hi), "contact"))
    if d_hi < 0.0:
        cand.append((_root(d, s_lo, s_hi), "free"))
    return min(cand)


def _root(func, lo, hi):
    """Zero of ``func`` in [lo, hi]; a phase that starts on its own boundary (func(lo) = 0)
    is bracketed from just after its start."""
    from scipy.optimize import brentq  # here, not at import: `treeimpact --help` is fast

    bracket = _bracket(func, lo, hi, func(hi))
    if bracket is None:
        return hi
    return brentq(func, bracket[0], hi, xtol=1e-15, rtol=4 * np.finfo(float).eps)


def _bracket(value, lo: float, hi: float, f_hi: float):
    """(lo', value(lo')) with value(lo') of the sign opposite to ``f_hi``: lo itself, or, when
    the bracket's low end sits on the previous switch (value 0 there, or the same sign), moved
    in by 1e-9, 1e-8, ... of the interval until the sign differs; None when it never does."""
    f_lo = value(lo)
    if f_lo * f_hi > 0 or f_lo == 0.0:
        step = (hi - lo) * 1e-9
        while step < (hi - lo):
            f_lo = value(lo + step)
            if f_lo * f_hi < 0:
                return lo + step, f_lo
            step *= 10.0
        return None
    return lo, f_lo


#: Largest block of samples the ``exact`` method evaluates at once (32, 256, then this).
_BLOCK = 1024
_EPS = float(np.finfo(float).eps)


class _State:
    """One contact state of the ``exact`` method: its :class:`Modal` solution, the
    observation rows over the kept half of the spectrum, exp(lambda i h) for the sample
    spacing h (i = 0.._BLOCK) and the work integrals of the ledger."""

    def __init__(self, model: LinearImpactModel, contact: bool, h: float):
        M, C, K, g = matrices(model, contact)
        self.modal = modal = Modal(M, C, K)
        self.contact = contact
        forms = _forms(model, modal, contact, g, names=("damp", "contact"))
        # the works' integrals: H_int stacked (damping; and the pad's, in contact)
        self.H_int = np.stack([f.H_int for f in forms.values()])
        self.H_lin = np.stack([f.H_lin for f in forms.values()])
        self.secular = bool(np.any(self.H_lin))  # undamped pairs: the free pendulum's
        k_c, c_c = model.contact_stiffness, model.contact_damping
        kept = modal.kept
        self.lam = modal.lam[kept]
        rows = _observation_rows(model, modal, g) @ modal.Vu  # 8 x 2N over the modes
        self.rows = (rows[:, kept] * modal.weight).T.copy()  # m x 8: obs = Re(U @ rows)
        # delta and the law F = k_c delta + c_c delta', and their slopes
        law = np.stack([self.rows[:, 4], k_c * self.rows[:, 4] + c_c * self.rows[:, 5]])
        self.law = np.concatenate([law, law * self.lam]).T.copy()  # m x 4
        # exp(lambda i h), i = 0.._BLOCK, by doubling (round-off log2(_BLOCK) eps)
        steps = np.ones((_BLOCK + 1, len(kept)), dtype=complex)
        steps[1] = np.exp(self.lam * h)
        n = 1
        while n < _BLOCK:
            m = min(n, _BLOCK - n)
            steps[n + 1:n + 1 + m] = steps[1:1 + m] * steps[n]
            n += m
        self.steps = steps
        self.gd = modal.displacement_row(g)
        self.k_c = k_c

    def works(self, w: np.ndarray, s: float, a: np.ndarray | None = None) -> np.ndarray:
        """The works of the trunk's damping (and of the pad, in contact) over [0, s] of a
        phase started with modal coefficients w (``a`` = exp(lambda s) w if known), J: the
        closed form of :class:`_Quadratic`."""
        a = np.exp(self.modal.lam * s) * w if a is None else a
        out = (self.H_int @ a) @ a - (self.H_int @ w) @ w
        if self.secular:
            out = out + s * ((self.H_lin @ w) @ w)
        return out.real

    def energies(self, u: np.ndarray) -> tuple[float, float, float]:
        """(kinetic, elastic energy of the trunk's and pendulum's springs, the pad's elastic
        energy k_c delta^2 / 2 when in contact; J) of the state u."""
        N = self.modal.N
        kin = 0.5 * float(u[N:] @ u[N:])
        pot = 0.5 * float(u[:N] @ u[:N])
        pad = 0.5 * self.k_c * float(self.gd @ u) ** 2 if self.contact else 0.0
        return kin, pot - pad, pad


@dataclass(frozen=True)
class _Phase:
    """One phase of the solution: start (s), kind ("contact", "overlap", "free"), modal
    coefficients at its start over the full spectrum, damping and contact work so far (J)."""

    t: float
    kind: str
    w: np.ndarray = field(repr=False)
    damping_work: float
    contact_work: float


@dataclass(frozen=True)
class _Solution:
    """The exact solution as its phases, and its values at any time (SI units)."""

    states: dict = field(repr=False)
    phases: tuple
    t_end: float
    ledger: float  # max |energy ledger| / initial energy at every switch and at t_end

    def phase_at(self, t: float) -> _Phase:
        starts = [p.t for p in self.phases]
        return self.phases[max(0, int(np.searchsorted(starts, t, side="right")) - 1)]

    def contact_loss(self, t: float) -> float:
        """The pad's work so far less the elastic energy it holds at ``t`` (s), J."""
        p = self.phase_at(t)
        if p.kind != "contact":
            return p.contact_work
        st = self.states[True]
        work = p.contact_work + float(st.works(p.w, t - p.t)[1])
        u = (st.modal.Vu @ (np.exp(st.modal.lam * (t - p.t)) * p.w)).real
        return work - st.energies(u)[2]


@dataclass(frozen=True)
class _ExactSamples:
    """What :func:`analytic.records.metrics_from_record` reads, from the exact solution:
    the motion on the sample grid (SI) and the energies in closed form where it reads them."""

    t: np.ndarray
    x: np.ndarray
    vx: np.ndarray
    y: np.ndarray
    vy: np.ndarray
    force: np.ndarray
    pendulum_energy: np.ndarray
    crown: np.ndarray
    crown_velocity: np.ndarray
    solution: _Solution = field(repr=False)

    def contact_loss(self, t: float) -> float:
        return self.solution.contact_loss(t)

    def ledger_residual(self, initial_energy: float) -> float:
        return self.solution.ledger


def solve(model: LinearImpactModel, t_end: float, dt_sample: float):
    """The ``exact`` method: the solution's phases and the observables on the sample grid.

    The same phases, switches and samples as :func:`record`, evaluated where needed:
    within a phase the modal coordinates at the samples are exp(lambda i h) times those at a
    block's first sample (no exponential per sample), only the 8 observables are formed, and
    each switch is refined by Newton's method on the exact solution. The energy ledger is
    checked at every switch and at t_end. Returns ``(_ExactSamples, switches)``.
    """
    steps = int(math.ceil(t_end / dt_sample - 1e-9))
    t_grid = np.linspace(0.0, t_end, steps + 1)
    states = {c: _State(model, c, t_end / steps) for c in (False, True)}
    to_state = {True: states[True].modal.transfer(states[False].modal),
                False: states[False].modal.transfer(states[True].modal)}
    n_t = t_grid.size
    obs = np.empty((n_t, 8))
    in_contact = np.zeros(n_t, dtype=bool)
    e0 = model.initial_energy
    u = states[True].modal.Tinv @ _initial_state(model)
    t, kind = 0.0, "contact"
    work = np.zeros(2)  # damping, pad
    phases, ledger = [], 0.0
    switches, max_switches = 0, 100_000
    k_c, c_c = model.contact_stiffness, model.contact_damping
    while True:
        contact = kind == "contact"
        st = states[contact]
        w = st.modal.Wu @ u
        phases.append(_Phase(t, kind, w, float(work[0]), float(work[1])))
        wk = w[st.modal.kept]
        j0 = int(np.searchsorted(t_grid, t, side="left"))
        end = None
        j, block = j0, 32
        base = np.exp(st.lam * (t_grid[j0] - t)) * wk if j0 < n_t else None
        while j < n_t:
            jj = min(n_t, j + block)
            ob = (st.steps[:jj - j] @ (base[:, None] * st.rows)).real
            d, f = ob[:, 4], k_c * ob[:, 4] + c_c * ob[:, 5]
            if contact:
                cond = f <= 0.0
            elif kind == "overlap":
                cond = (f > 0.0) | (d < 0.0)
            else:
                cond = d > 0.0
            if j == j0 and t_grid[j0] == t:
                cond[0] = False  # the phase's own start
            k = int(np.argmax(cond))
            if cond[k]:
                s_hi = t_grid[j + k] - t
                s_lo = max(t_grid[j + k - 1] - t, 0.0) if j + k > j0 else 0.0
                end = _locate_exact(kind, st, wk, s_lo, s_hi, d[k], f[k])
                jj = j + k
                obs[j:jj] = ob[:k]
                in_contact[j:jj] = contact
                break
            obs[j:jj] = ob
            in_contact[j:jj] = contact
            base = base * st.steps[jj - j]
            j, block = jj, min(8 * block, _BLOCK)
        end_s, nxt = end if end is not None else (t_end - t, None)
        # the state and the works at the switch (or at t_end), and the ledger there
        a = np.exp(st.modal.lam * end_s) * w
        work += st.works(w, end_s, a) if contact else (st.works(w, end_s, a)[0], 0.0)
        u = (st.modal.Vu @ a).real
        kin, pot, _ = st.energies(u)
        if not math.isfinite(kin + pot):
            raise SimulationDiverged(f"beam: non-finite state at t = {t + end_s:.6g} s")
        ledger = max(ledger, abs(kin + pot + work.sum() - e0) / e0)
        if nxt is None:
            break
        t += end_s
        if (nxt == "contact") != contact:  # to the other state's energy coordinates
            u = to_state[nxt == "contact"] @ u
        kind = nxt
        switches += 1
        if switches > max_switches:
            raise SimulationDiverged(f"beam: more than {max_switches} contact switches by "
                                     f"t = {t:.6g} s (chatter does not end)")
    x, y, vx, vy, delta, ddelta, crown, crown_v = obs.T
    force = np.where(in_contact, np.maximum(0.0, k_c * delta + c_c * ddelta), 0.0)
    m, kp = model.impactor_mass, model.impactor_stiffness
    solution = _Solution(states=states, phases=tuple(phases), t_end=t_end, ledger=ledger)
    samples = _ExactSamples(t=t_grid, x=x, vx=vx, y=y, vy=vy, force=force,
                            pendulum_energy=0.5 * m * vy ** 2 + 0.5 * kp * y ** 2, crown=crown,
                            crown_velocity=crown_v, solution=solution)
    return samples, switches


def _locate_exact(kind: str, st: _State, wk: np.ndarray, s_lo: float, s_hi: float,
                  d_hi: float, f_hi: float):
    """(time into the phase, next phase) of the switch bracketed by [s_lo, s_hi]: the rule
    of :func:`_locate`, on the exact solution's delta and law with their slopes (Newton)."""
    lam, law = st.lam, st.law

    def at(s):  # delta, F, delta', F'
        return (np.exp(lam * s) * wk) @ law

    def fun(i):
        def value(s):
            v = at(s).real
            return float(v[i]), float(v[i + 2])
        return value

    d, f = fun(0), fun(1)
    if kind == "contact":
        s = _root_exact(f, s_lo, s_hi, f_hi)
        return s, ("overlap" if d(s)[0] > 0.0 else "free")
    if kind == "free":
        return _root_exact(d, s_lo, s_hi, d_hi), "contact"
    cand = []
    if f_hi > 0.0:
        cand.append((_root_exact(f, s_lo, s_hi, f_hi), "contact"))
    if d_hi < 0.0:
        cand.append((_root_exact(d, s_lo, s_hi, d_hi), "free"))
    return min(cand)


def _root_exact(fun, lo: float, hi: float, f_hi: float) -> float:
    """:func:`_root` for ``fun`` returning (value, slope), ``f_hi`` its value at hi: a phase
    that starts on its own boundary (value 0 at lo) is bracketed from just after its start;
    then Newton's steps inside the shrinking bracket (bisection otherwise), to 1e-15 s."""
    bracket = _bracket(lambda u: fun(u)[0], lo, hi, f_hi)
    if bracket is None:
        return hi
    lo, f_lo = bracket
    s = lo - f_lo * (hi - lo) / (f_hi - f_lo)
    tol = 1e-15 + 4 * _EPS * abs(hi)
    for _ in range(100):
        f, slope = fun(s)
        if f == 0.0:
            return s
        if (f > 0.0) == (f_lo > 0.0):
            lo, f_lo = s, f
        else:
            hi = s
        nxt = s - f / slope if slope != 0.0 else 0.5 * (lo + hi)
        if not lo < nxt < hi:
            nxt = 0.5 * (lo + hi)
        if abs(nxt - s) <= tol or hi - lo <= tol:
            return nxt
        s = nxt
    return s


def sampled_record(model: LinearImpactModel, t_end: float, dt_sample: float) -> ImpactRecord:
    """The ``exact`` method's record when first read: :func:`record`'s samples."""
    return record(model, t_end, dt_sample)[0]
