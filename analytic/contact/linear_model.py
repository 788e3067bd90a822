"""The problem the exact linear solver takes: a linear trunk (any M, D, K with the dof the pad
strikes: the 1-DOF trunk of eq 11 or a continuum's mesh) and the linearised pendulum
(eq 13), meeting through the spring-dashpot contact F = max(0, k_c delta + c_c delta'),
delta = y - x >= 0 (:mod:`.law`); its matrices in each contact state. SI units.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


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
    impactor_stiffness: float  # k = m g / l_e, N/m (eq 13; a billet: its own, 0 when free)
    impact_speed: float  # u_1, m/s (eq 48)
    contact_stiffness: float  # k_c, N/m
    contact_damping: float  # c_c, N s/m
    crown_gain: float = 1.0  # crown motion per unit of the crown dof (an SDOF: phi(l))

    @property
    def dofs(self) -> int:
        """Degrees of freedom of the trunk (the size of M)."""
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
    """``(M, C, K, g)`` of ``model``'s trunk and pendulum (N = dofs + 1 coordinates q =
    (trunk, y)) in one contact state (``contact``: touching); delta = g . q. In contact the
    pad's k_c and c_c act along g."""
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
    """(A, g): the state matrix of z = (q, q'), z' = A z, of ``model`` in one contact state
    (``contact``: touching; what the independent references of the tests integrate) and
    delta = g . q."""
    M, C, K, g = matrices(model, contact)
    N = len(g)
    A = np.zeros((2 * N, 2 * N))
    A[:N, N:] = np.eye(N)
    A[N:, :N] = -np.linalg.solve(M, K)
    A[N:, N:] = -np.linalg.solve(M, C)
    return A, g


def initial_state(model: LinearImpactModel) -> np.ndarray:
    """z(0) = (q, q') of ``model``: everything at rest but the pendulum, at u_1 (the first
    touch, delta = 0)."""
    N = model.dofs + 1
    z = np.zeros(2 * N)
    z[2 * N - 1] = model.impact_speed
    return z
