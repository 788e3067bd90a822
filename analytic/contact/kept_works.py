"""The energy ledger's works on the kept half of the spectrum: the ``exact`` method's state
u = Re(z), z = V_k exp(lambda_k s) w_k (:func:`.exact_solve._kept_half`: the kept modes'
eigenvectors weighted by 2 for a conjugate pair), and the integral of each work's rate
u^T Q u over a phase in closed form. SI units (J); design notes: docs/beam-impact.md.

With u = (z + conj z) / 2 and Q real symmetric,

    u^T Q u = Re(z^T Q z) / 2 + z^H Q z / 2,

so int_0^s u^T Q u = Re(sum_ij S_ij w_i w_j (e^{(lambda_i + lambda_j) s} - 1) /
(lambda_i + lambda_j)) / 2 + Re(sum_ij R_ij conj(w_i) w_j (e^{(conj lambda_i + lambda_j) s}
- 1) / (conj lambda_i + lambda_j)) / 2, S = V_k^T Q V_k, R = V_k^H Q V_k (m x m each, m the
kept modes: half the full spectrum's (2m)^2 terms); a pair whose exponent is below 1e-9 of
the largest |lambda| (an undamped or rigid pair) integrates to s times its constant term.
A rigid mode's flight s G u(0) adds nothing: the forms do not read its displacement (Q G =
0).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .linear_model import LinearImpactModel


@dataclass(frozen=True)
class KeptWorks:
    """The works' integral coefficients of one contact state over its kept modes: S / sum
    for each form, then R / sum for each (2 forms x m x m; the forms the trunk's damping
    and, in contact, the pad's F delta'), and their secular parts (S and R where the
    exponent vanishes, stacked alike; None when none does)."""

    integral: np.ndarray
    secular: np.ndarray | None

    def integrals(self, w: np.ndarray, s: np.ndarray, a: np.ndarray) -> np.ndarray:
        """int_0^s_p u^T Q_f u of each form f over the phases p started with the kept
        coefficients w (phases x m), lasting s (phases, s), a = exp(lambda s) w: (forms,
        phases), J."""
        n = len(w)
        out = _ends_less_starts(self.integral, np.concatenate([a, w]), n)
        if self.secular is not None:
            out += s * _ends_less_starts(self.secular, w, 0)
        return 0.5 * out


def _ends_less_starts(H: np.ndarray, x: np.ndarray, n: int) -> np.ndarray:
    """Re(x_p^T S_f x_p) + Re(x_p^H R_f x_p) for each form f (H: the S, then the R) and row
    p of x, the rows from n on subtracted from the first n (n = 0: none subtracted)."""
    forms = len(H) // 2
    Hx = H @ x.T
    v = (Hx[:forms] * x.T).sum(axis=1).real + (Hx[forms:] * x.T.conj()).sum(axis=1).real
    return v[:, :n] - v[:, n:] if n else v


def kept_works(model: LinearImpactModel, modal, contact: bool, g: np.ndarray,
               from_kept: np.ndarray) -> KeptWorks:
    """The :class:`KeptWorks` of ``model`` on the decomposition ``modal`` of one contact
    state (``contact``: touching; delta = ``g`` . q), ``from_kept`` the weighted kept
    eigenvectors (2N x m). The forms from Q's structure: the damping acts on the velocities
    only (Z_v^T Phi^T D Phi Z_v, Z_v the velocity rows), the pad's rate 0.5 k_c (gd gv^T +
    gv gd^T) + c_c gv gv^T is of rank 2 (its rows over u, gd and gv, through from_kept)."""
    N, k_c, c_c = modal.N, model.contact_stiffness, model.contact_damping
    D = np.zeros((N, N))
    D[:model.dofs, :model.dofs] = model.D
    Zv = from_kept[N:]
    DZ = (modal.Phi.T @ D @ modal.Phi) @ Zv
    sym, herm = [Zv.T @ DZ], [Zv.conj().T @ DZ]
    if contact:
        a = modal.displacement_row(g) @ from_kept
        b = modal.velocity_row(g) @ from_kept
        ab, ac, bc = np.outer(a, b), a.conj(), b.conj()
        sym.append(0.5 * k_c * (ab + ab.T) + c_c * np.outer(b, b))
        herm.append(0.5 * k_c * (np.outer(ac, b) + np.outer(bc, a)) + c_c * np.outer(bc, b))
    lam = modal.lam[modal.kept]
    scale = 1e-9 * max(1.0, float(np.max(np.abs(modal.lam))))
    stacks = []
    for forms, total in ((np.stack(sym), lam[:, None] + lam[None, :]),
                         (np.stack(herm), lam.conj()[:, None] + lam[None, :])):
        small = np.abs(total) < scale
        stacks.append((np.where(small, 0.0, forms / np.where(small, 1.0, total)),
                       np.where(small, forms, 0.0), small.any()))
    (sym_int, sym_lin, sym_sec), (herm_int, herm_lin, herm_sec) = stacks
    secular = np.concatenate([sym_lin, herm_lin]) if sym_sec or herm_sec else None
    return KeptWorks(np.concatenate([sym_int, herm_int]), secular)
