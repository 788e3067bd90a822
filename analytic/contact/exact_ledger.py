"""The ``exact`` method's solution as the metrics read it: each phase's end (:class:`PhaseEnds`),
the energy ledger and the pad's work over all phases at once (:func:`ledger_solution`), and
the samples with the energies in closed form (:class:`ExactSamples`). SI units; design
notes: docs/beam-impact.md.
"""

from __future__ import annotations

import bisect
from dataclasses import dataclass, field

import numpy as np

from treeimpact.analytic.errors import SimulationDiverged

from .linear_model import LinearImpactModel
from .phases import ContactPhase


@dataclass
class PhaseEnds:
    """Each phase as the loop leaves it: start (s), kind, the state u at its start and its
    end (in its contact state's energy coordinates) and its duration (s)."""

    t: list
    kind: list
    u0: list
    s: list
    u: list

    def add(self, t: float, kind: ContactPhase, u0, s: float, u) -> None:
        """Record a phase: start ``t`` (s), ``kind``, state ``u0`` at its start, duration
        ``s`` (s) and the state ``u`` at its end."""
        self.t.append(t)
        self.kind.append(kind)
        self.u0.append(u0)
        self.s.append(s)
        self.u.append(u)


@dataclass(frozen=True)
class ExactSolution:
    """The exact solution as its phases (starts s, kinds, modal coefficients at the start,
    the pad's work done before each, J), and its values at any time (SI units)."""

    states: dict = field(repr=False)
    starts: list
    kinds: list
    w: list = field(repr=False)
    contact_work: list
    t_end: float
    ledger: float  # max |energy ledger| / initial energy at every switch and at t_end

    def contact_loss(self, t: float) -> float:
        """The pad's work so far less the elastic energy it holds at ``t`` (s), J."""
        k = max(0, bisect.bisect_right(self.starts, t) - 1)
        if not self.kinds[k].touching:
            return self.contact_work[k]
        st, s = self.states[True], np.array([t - self.starts[k]])
        w = self.w[k][None, :]
        work = self.contact_work[k] + float(st.works(w, s)[1, 0])
        u = st.advance(self.w[k], float(s[0]))
        return work - float(st.energies(u[None, :])[2][0])


def ledger_solution(model: LinearImpactModel, states: dict, ends: PhaseEnds, t_end: float
                    ) -> ExactSolution:
    """The :class:`ExactSolution` to ``t_end`` (s) of ``model`` whose phases ended as
    ``ends`` in the contact ``states`` ({touching: the exact method's state}): each phase's
    works (the closed forms, all phases of a state at once), the pad's work before each
    phase (running sums in phase order) and the energy ledger's largest residual at the
    phases' ends relative to the input energy. Raises SimulationDiverged at a non-finite
    state."""
    P = len(ends.t)
    works, energy = np.zeros((P, 2)), np.zeros(P)
    touching = np.array([k.touching for k in ends.kind])
    U0, U, S = np.array(ends.u0), np.array(ends.u), np.array(ends.s)
    W = [None] * P  # the kept modal coefficients at each phase's start
    for contact, st in states.items():
        idx = np.flatnonzero(touching == contact)
        if not idx.size:
            continue
        Wc = U0[idx] @ st.to_kept.T
        for p, row in zip(idx.tolist(), Wc):
            W[p] = row
        A = np.exp(st.lam * S[idx, None]) * Wc
        works[idx, :1 + contact] = st.works(Wc, S[idx], A).T
        kin, pot, _ = st.energies(U[idx])
        energy[idx] = kin + pot
    if not np.all(np.isfinite(energy)):
        p = int(np.argmin(np.isfinite(energy)))
        raise SimulationDiverged(f"beam: non-finite state at t = {ends.t[p] + ends.s[p]:.6g} s")
    done = np.cumsum(works, axis=0)  # the works to each phase's end, in phase order
    e0 = model.initial_energy
    ledger = float(np.max(np.abs(energy + done.sum(axis=1) - e0)) / e0)
    before = [0.0, *done[:-1, 1].tolist()]
    return ExactSolution(states=states, starts=ends.t, kinds=ends.kind, w=W,
                         contact_work=before, t_end=t_end, ledger=ledger)


@dataclass(frozen=True)
class ExactSamples:
    """What :func:`analytic.records.metrics_from_record` reads, from the exact solution
    ``solution``: the motion on the sample grid (SI), the pendulum's energy where it is read
    and the pad's loss and the ledger in closed form."""

    t: np.ndarray
    x: np.ndarray
    vx: np.ndarray
    y: np.ndarray
    vy: np.ndarray
    force: np.ndarray
    pendulum_energy: PendulumEnergy  # indexed at the samples the metrics read
    crown: np.ndarray
    crown_velocity: np.ndarray
    solution: ExactSolution = field(repr=False)

    def contact_loss(self, t: float) -> float:
        """:meth:`ExactSolution.contact_loss` at ``t`` (s), J."""
        return self.solution.contact_loss(t)

    def ledger_residual(self, initial_energy: float) -> float:
        """The ledger's largest residual relative to the input energy (checked at every
        switch; ``initial_energy``, J, is the solution's own)."""
        return self.solution.ledger


@dataclass(frozen=True)
class PendulumEnergy:
    """The pendulum's energy 0.5 m y'^2 + 0.5 k y^2 (J, eq 13) at the samples the metrics
    read (``energy[i]``), not formed on the whole grid."""

    model: LinearImpactModel = field(repr=False)
    y: np.ndarray = field(repr=False)
    vy: np.ndarray = field(repr=False)

    def __getitem__(self, i):
        m, kp = self.model.impactor_mass, self.model.impactor_stiffness
        return 0.5 * m * self.vy[i] ** 2 + 0.5 * kp * self.y[i] ** 2
