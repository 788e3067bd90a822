"""The ``exact`` evaluation of the exact linear solution (the default): the same phases,
switches and samples as :mod:`.exact_record`, evaluated only where the metrics read them.

Within a phase the modal coordinates at the samples are exp(lambda i h) times those at a
block's first sample (no exponential per sample), only the observables the metrics and
the phase test read are formed (:data:`_SAMPLED`, the pad's law), and
each switch (the rule of :mod:`.phases`) is refined by Newton's method on the exact
solution. The energies come in closed form where the metrics read them; the energy ledger is
checked at every switch and at t_end. Design notes: docs/beam-impact.md.
"""

from __future__ import annotations

import math
import threading
import weakref
from dataclasses import dataclass
from functools import partial

import numpy as np

from treeimpact.analytic.results import ImpactRecord

from .exact_ledger import (ExactSamples, ExactSolution, PendulumEnergy, PhaseEnds,
                           ledger_solution)
from .exact_record import record
from .exact_switch import locate as _locate
from .linear_model import LinearImpactModel, initial_state, matrices
from .kept_works import kept_works
from .modal import Observable, decomposed, observation_rows
from .phases import ContactPhase, check_switches

#: Elements (samples x modes kept) of the largest block of samples the ``exact`` method
#: evaluates at once (32, 256, ... up to this over the modes, at least 1024 samples): the
#: powers exp(lambda i h) stay in cache (the soft SDOF, 2 modes: 4096 samples a block took
#: half the time of 16384, benchmarks/bench_exact.py).
_BLOCK_ELEMENTS = 2 ** 13
#: The first block of a phase's samples and the factor each next one grows by, to the
#: state's largest (most of the beam's chattering phases last 1-60 samples).
_FIRST_BLOCK, _GROWTH = 32, 8
#: Powers (modes x samples) up to which :func:`_powers` doubles one table: the soft SDOF's
#: 2 x 4097 took 31 us so against 46 as two factors; a 12-element state's 27 x 1025 took
#: 351 us against 82 (its doublings' copies grow with the table).
_ONE_TABLE = 2 ** 14
#: The observables the samples' product forms, in :class:`Observable`'s order: all but
#: delta' (the law's row below carries it; no metric reads it): 8 rows with the law's, the
#: product half the time of 9 (OpenBLAS's 8-row tile: a 12-element state's 1024-sample
#: block 19 us against 35, each kept row's numbers the same, measured).
_SAMPLED = tuple(int(o) for o in Observable if o is not Observable.DELTA_RATE)
#: The rows of delta and of the pad's law F = k_c delta + c_c delta' (N) in the samples'
#: product and on the grid: the law's after the sampled observables' (its row over the
#: modes: k_c delta's + c_c delta''s).
_DELTA, _LAW = _SAMPLED.index(Observable.DELTA), len(_SAMPLED)
#: The newest :func:`_fixed_parts` a decomposition keeps (pads met with it), for states of
#: at most _PARTS_MAX_COORDS energy coordinates (12 elements: 56): a 48-element state's
#: forms hold ~4 MB, and keeping them did not speed its warm run (medians 29.7 kept, 23.1
#: not, interleaved in one process on the loaded machine).
_PARTS_KEPT = 4
_PARTS_MAX_COORDS = 64


class _State:
    """One contact state of the ``exact`` method: its :class:`Modal` solution (shared by
    :func:`.modal.decomposed`), the observation rows over the kept half of the spectrum (as
    the real operand of the samples' product), exp(lambda i h) for the sample spacing h
    (i = 0..block) and the work integrals of the ledger."""

    def __init__(self, model: LinearImpactModel, contact: bool, h: float):
        M, C, K, g = matrices(model, contact)
        self.modal = modal = decomposed(M, C, K)
        self.contact = contact
        (self.kept_works, self.rows, self.rows_conj, self.law, self.gd,
         self.drift_rows) = _fixed_parts(model, modal, contact, g)
        self.lam = modal.lam[modal.kept]
        self.block = max(1024, 1 << (_BLOCK_ELEMENTS // len(self.lam)).bit_length() - 1)
        # (re, im) of step^i interleaved per mode, i along the columns: 2m x (block + 1);
        # step^b of each block's length b (32, 256, ..., block), a block's base to the next
        # (in this thread's scratch memory, see _scratch; released by :meth:`done`)
        self.steps_ri, self.jumps_conj = _powers(np.exp(self.lam * h), self.block, contact,
                                                 modal)
        self.k_c = model.contact_stiffness
        self.to_kept, self.from_kept, self.drift_kept = _kept_half(modal)

    def advance(self, wk: np.ndarray, s: float) -> np.ndarray:
        """The state u at ``s`` (s) of the phase started with the kept modal coefficients
        ``wk``: Re(V exp(lambda s) w) over the kept half (a conjugate pair twice its kept
        member's real part), plus s G u(0) for a rigid mode's flight."""
        u = (self.from_kept @ (np.exp(self.lam * s) * wk)).real
        if self.drift_kept is not None:
            u += s * (self.drift_kept @ wk).real
        return u

    def done(self) -> None:
        """Drop the powers (the solve is over: their scratch memory serves the next)."""
        self.steps_ri = self.jumps_conj = None

    def works(self, w: np.ndarray, s: np.ndarray, a: np.ndarray | None = None
              ) -> np.ndarray:
        """The works of the trunk's damping (and of the pad, in contact) over [0, s_p] of
        the phases p started with the kept modal coefficients w (phases x m, s: phases;
        ``a`` = exp(lambda s) w if known), J: (works, phases), the closed form of
        :class:`.kept_works.KeptWorks`."""
        a = np.exp(self.lam * s[:, None]) * w if a is None else a
        return self.kept_works.integrals(w, s, a)

    def energies(self, u: np.ndarray) -> tuple:
        """(kinetic, elastic energy of the trunk's and pendulum's springs, the pad's elastic
        energy k_c delta^2 / 2 when in contact; J) of the states u (phases x 2N): arrays
        over the phases."""
        N = self.modal.N
        kin = 0.5 * (u[:, N:] * u[:, N:]).sum(axis=1)
        du = u[:, :N] * self.modal.elastic  # a rigid mode's coordinate has no spring
        pot = 0.5 * (du * du).sum(axis=1)
        pad = 0.5 * self.k_c * (u @ self.gd) ** 2 if self.contact else np.zeros(len(u))
        return kin, pot - pad, pad


def _fixed_parts(model: LinearImpactModel, modal, contact: bool, g: np.ndarray) -> tuple:
    """What a :class:`_State` reads that is fixed by its decomposition ``modal`` and the
    model's pad, damping and observed points (delta = ``g`` . q): the works' integrals over
    the kept modes (:class:`.kept_works.KeptWorks`: damping; and the pad's, in contact), the
    observation rows over the kept modes (m x 8: the :data:`_SAMPLED` observables and the
    law F, complex)
    and their conjugate transpose,
    the law's rows (m x 6: delta, F, their first and second derivatives), delta's row over
    u and the observation rows of a rigid mode's flight over the kept modes (8 x m: the sampled observables' and the law's
    rates Re(rows G V w), or None without a rigid mode). Kept on a small
    ``modal`` (read-only arrays) for the next solve with the same inputs: the same
    arithmetic, so the same numbers."""
    k_c, c_c = model.contact_stiffness, model.contact_damping
    key = (contact, k_c, c_c, model.D.tobytes(), g.tobytes(), model.clamp, model.crown,
           model.crown_gain, model.dofs)
    cache = modal.__dict__.setdefault("_state_parts", {})
    parts = cache.get(key)
    if parts is not None:
        return parts
    kept = modal.kept
    from_kept = _kept_half(modal)[1]
    works = kept_works(model, modal, contact, g, from_kept)
    # m x 8: obs = Re(U @ rows) over the kept modes; complex even when every kept mode is
    # real (an overdamped pad: eig returns real vectors), as _scan's (Re, Im) product reads it
    rows = np.array((observation_rows(model, modal, g) @ from_kept).T, dtype=complex)
    # delta and the law F = k_c delta + c_c delta', and their slopes
    delta, rate = rows[:, Observable.DELTA], rows[:, Observable.DELTA_RATE]
    law = np.stack([delta, k_c * delta + c_c * rate])
    rows = np.column_stack([rows[:, _SAMPLED], law[1]])  # m x 8: the sampled, the law
    rows_conj = rows.T.conj().copy()  # 8 x m: see _scan
    lam = modal.lam[kept]
    law = np.concatenate([law, law * lam, law * lam ** 2]).T.copy()  # m x 6
    gd = modal.displacement_row(g)
    drift = None
    if modal.drift is not None:  # the flight s G u(0) of a rigid mode, over the kept modes
        drift = (observation_rows(model, modal, g) @ modal.drift)[:, kept]
        law_rate = k_c * drift[Observable.DELTA] + c_c * drift[Observable.DELTA_RATE]
        drift = np.vstack([drift[_SAMPLED, :], law_rate])  # 8 x m, as the rows
    for a in (rows, rows_conj, law, gd, drift, *vars(works).values()):
        if a is not None:
            a.setflags(write=False)
    parts = (works, rows, rows_conj, law, gd, drift)
    if 2 * modal.N <= _PARTS_MAX_COORDS:
        cache[key] = parts
        while len(cache) > _PARTS_KEPT:  # a sweep over the pad meets one free state often
            cache.pop(next(iter(cache)), None)
    return parts


def _kept_half(modal) -> tuple:
    """The kept half of ``modal``'s spectrum as the loop reads it: the rows of V^-1 giving
    the kept coefficients from u (m x 2N), the columns of V weighted by :attr:`.Modal.weight`
    (2N x m: u = Re(V_k (weight exp(lambda s) w_k))) and those of the flight G V, or None
    without a rigid mode; kept on ``modal`` (read-only) for the next solve."""
    kept = modal.__dict__.get("_kept_half")
    if kept is None:
        k = modal.kept
        drift = None if modal.drift is None else modal.drift[:, k] * modal.weight
        kept = (modal.Wu[k], modal.Vu[:, k] * modal.weight, drift)
        for a in kept:
            if a is not None:
                a.setflags(write=False)
        modal.__dict__["_kept_half"] = kept
    return kept


def _transfer(modal, other) -> np.ndarray:
    """:meth:`.modal.Modal.transfer` from ``other`` to ``modal``, kept on ``modal`` for
    the next solve with the same ``other`` (the same live object; read-only)."""
    kept = modal.__dict__.get("_transfer")
    if kept is None or kept[0]() is not other:
        P = modal.transfer(other)
        P.setflags(write=False)
        # a weak reference: the two states holding each other would outlive the
        # decompositions' cache until a garbage collection (their memory not reused)
        kept = modal.__dict__["_transfer"] = (weakref.ref(other), P)
    return kept[1]


def _powers(step: np.ndarray, count: int, slot, owner) -> tuple[np.ndarray, dict]:
    """step^i, i = 0..count, as step^(c a) step^b (i = c a + b, b < c ~ sqrt(count); each
    factor's table by doubling: round-off ~log2(count) eps; one doubled table for at most
    :data:`_ONE_TABLE` powers in all), as the interleaved (Re, Im)
    rows of each step (2m x (count + 1), in the scratch memory ``slot``); and {b:
    conj(step^b)} for the block lengths b = 32, 256, ... (x 8), count. The slot's last table
    is taken again when the same decomposition ``owner`` (the same live object: a new one
    after :func:`.modal.clear_cache`) asks for the same steps and count: the same
    numbers."""
    tag = (step.tobytes(), count)
    kept = _SCRATCH.__dict__.setdefault("tables", {}).pop(slot, None)  # refilled below
    if kept is not None and kept[0]() is owner and kept[1] == tag:
        _SCRATCH.tables[slot] = kept
        return kept[2], kept[3]
    m, n = len(step), count + 1
    if m * n <= _ONE_TABLE:
        steps = _doubled(step, n)
    else:
        c = 1 << (n.bit_length() + 1) // 2  # the inner factor's length, a power of 2
        rows = -(-n // c)
        low = _doubled(step, c)  # step^b, b < c
        high = _doubled(low[:, -1] * step, rows)  # step^(c a), a < rows
        steps = _scratch("powers", (m, rows, c), complex)
        np.multiply(high[:, :, None], low[:, None, :], out=steps)
        steps = steps.reshape(m, rows * c)[:, :n]
    ri = _scratch(("rows", slot), (m, 2, n), float)
    ri[:, 0], ri[:, 1] = steps.real, steps.imag
    jumps, b = {count: steps[:, count].conj()}, _FIRST_BLOCK
    while b < count:
        jumps[b], b = steps[:, b].conj(), _GROWTH * b
    ri = ri.reshape(2 * m, count + 1)
    # the owner weakly: a table must not keep a dropped decomposition's memory from reuse
    _SCRATCH.tables[slot] = (weakref.ref(owner), tag, ri, jumps)
    return ri, jumps


def _doubled(step: np.ndarray, count: int) -> np.ndarray:
    """step^i, i = 0..count - 1 (m x count, complex), by doubling: each pass multiplies the
    powers so far by the last."""
    out = np.empty((len(step), count), dtype=complex)
    out[:, 0] = 1.0
    if count > 1:
        out[:, 1] = step
    n = 2
    while n < count:
        k = min(n, count - n)
        np.multiply(out[:, :k], out[:, n - 1:n] * step[:, None], out=out[:, n:n + k])
        n += k
    return out


#: Per thread, arrays that outlive one solve to serve the next (:func:`_scratch`).
_SCRATCH = threading.local()


def _scratch(slot, shape: tuple, dtype) -> np.ndarray:
    """An uninitialised array of ``shape`` in this thread's memory ``slot``, reused by the
    next call on the slot: the power tables (about 1 MB a state at 12 elements) are not
    allocated afresh by every solve (each fresh page costs a fault, about 1-2 us here)."""
    pool = _SCRATCH.__dict__.setdefault("pool", {})
    size = math.prod(shape)
    buf = pool.get(slot)
    if buf is None or buf.size < size or buf.dtype != dtype:
        buf = pool[slot] = np.empty(size, dtype)
    return buf[:size].reshape(shape)


@dataclass
class _Grid:
    """The sample grid (s) and what is written on it: the observables and the pad's law
    (8 x n, one row per :data:`_SAMPLED` observable, then the law F, N) and the pad's force (N;
    max(0, F) in contact, 0 apart: :meth:`write_force`)."""

    t: np.ndarray
    obs: np.ndarray
    force: np.ndarray

    def write_force(self, j0: int, j1: int, contact: bool) -> None:
        """The force on the samples j0..j1 - 1 of one phase, from its law (once a phase:
        the next phase overwrites a sample it starts on, as it does the observables)."""
        if contact:
            np.maximum(self.obs[_LAW, j0:j1], 0.0, out=self.force[j0:j1])
        else:
            self.force[j0:j1] = 0.0


def solve(model: LinearImpactModel, t_end: float, dt_sample: float):
    """The ``exact`` method on ``model``: the solution's phases and the observables on the
    sample grid every ``dt_sample`` to ``t_end`` (s). Returns ``(ExactSamples, switches)``
    (the number of contact switches)."""
    steps = int(math.ceil(t_end / dt_sample - 1e-9))
    t_grid = np.linspace(0.0, t_end, steps + 1)
    states = {c: _State(model, c, t_end / steps) for c in (False, True)}
    to_state = {True: _transfer(states[True].modal, states[False].modal),
                False: _transfer(states[False].modal, states[True].modal)}
    grid = _Grid(t_grid, np.empty((_LAW + 1, t_grid.size)), np.empty(t_grid.size))
    u = states[True].modal.Tinv @ initial_state(model)
    t, kind = 0.0, ContactPhase.CONTACT
    ends = PhaseEnds([], [], [], [], [])
    while True:
        st = states[kind.touching]
        wk = st.to_kept @ u
        end = _scan(model, st, kind, grid, t, wk)
        end_s, nxt = end if end is not None else (t_end - t, None)
        u_end = st.advance(wk, end_s)
        ends.add(t, kind, u, end_s, u_end)
        if nxt is None:
            break
        t += end_s
        # to the other state's energy coordinates
        u = to_state[nxt.touching] @ u_end if nxt.touching != kind.touching else u_end
        kind = nxt
        check_switches(len(ends.t), t)
    for st in states.values():
        st.done()
    solution = ledger_solution(model, states, ends, t_end)
    return _samples(model, grid, solution), len(ends.t) - 1


def _scan(model: LinearImpactModel, st: _State, kind: ContactPhase, grid: _Grid, t: float,
          wk: np.ndarray):
    """Write the observables and the law of the phase started at ``t`` (modal coefficients
    ``wk`` over the kept spectrum) block by block until it ends; returns (time into the
    phase, next phase) of the switch, or None when it lasts to the grid's end.

    A block's observables are Re(sum_k step_k^i c_k) with c_k = base_k rows_k:
    one real product of the interleaved (Re, Im) of c, conjugated, (8 x 2m) and of the
    powers (2m x block), half the flops of the complex product's real part; the law F is
    its last row, and the force is written from it once the phase's end is known.
    :meth:`ContactPhase.has_ended` written out (the same comparisons)."""
    t_grid, n_t, obs = grid.t, grid.t.size, grid.obs
    j0 = int(t_grid.searchsorted(t))
    if j0 >= n_t:
        return None
    j, block = j0, _FIRST_BLOCK
    # conj(exp(lambda s) wk), as the product reads it (conj of a product: exact)
    base = (np.exp(st.lam * (t_grid[j0] - t)) * wk).conj()
    rows_conj, steps_ri, jumps_conj = st.rows_conj, st.steps_ri, st.jumps_conj
    contact, free = kind is ContactPhase.CONTACT, kind is ContactPhase.FREE
    rate, flight = _flight(st, wk)
    own_start = t_grid[j0] == t
    while j < n_t:
        jj = min(n_t, j + block)
        ob = np.matmul((rows_conj * base).view(float), steps_ri[:, :jj - j],
                       out=obs[:, j:jj])
        if rate is not None:
            ob += np.outer(rate, t_grid[j:jj] - t)
        if free:
            ended = ob[_DELTA] > 0.0
        elif contact:
            ended = ob[_LAW] <= 0.0
        else:
            ended = (ob[_LAW] > 0.0) | (ob[_DELTA] < 0.0)
        if own_start and j == j0:
            ended[0] = False  # the phase's own start
        k = int(ended.argmax())
        if ended[k]:
            grid.write_force(j0, j + k, contact)
            s_lo = max(float(t_grid[j + k - 1]) - t, 0.0) if j + k > j0 else 0.0
            # a sample of this phase: its delta and law as the product formed them
            lo_values = (tuple(obs[_DELTA:_LAW + 1:_LAW - _DELTA, j + k - 1].tolist())
                         if s_lo > 0.0 else None)
            d_hi, f_hi = ob[_DELTA:_LAW + 1:_LAW - _DELTA, k].tolist()
            return _locate(kind, st, wk, s_lo, float(t_grid[j + k]) - t, d_hi, f_hi,
                           lo_values, flight)
        if jj < n_t:
            base = base * jumps_conj[block]
        j, block = jj, min(_GROWTH * block, st.block)
    grid.write_force(j0, n_t, contact)
    return None


def _flight(st: _State, wk: np.ndarray):
    """(rates, flight) of a rigid mode's flight (a free billet) in the phase started with
    modal coefficients ``wk``: the sampled observables' and the law's rates Re(rows G V w) (m/s,
    m/s^2, N/s; added as rate * s) and those of delta and of the law (m/s, N/s); (None,
    (0, 0)) without one."""
    if st.drift_rows is None:
        return None, (0.0, 0.0)
    rate = (st.drift_rows @ wk).real
    return rate, (rate[_DELTA], rate[_LAW])


def _samples(model: LinearImpactModel, grid: _Grid, solution: ExactSolution) -> ExactSamples:
    """The :class:`ExactSamples` of the written grid."""
    x, y, vx, vy, _, crown, crown_v, _ = grid.obs
    return ExactSamples(t=grid.t, x=x, vx=vx, y=y, vy=vy, force=grid.force,
                        pendulum_energy=PendulumEnergy(model, y, vy), crown=crown,
                        crown_velocity=crown_v, solution=solution)


def sampled_record(model: LinearImpactModel, t_end: float, dt_sample: float) -> ImpactRecord:
    """The ``exact`` method's record when first read: :func:`.exact_record.record`'s
    samples of ``model`` every ``dt_sample`` to ``t_end`` (s)."""
    return record(model, t_end, dt_sample)[0]


def deferred_record(model: LinearImpactModel, t_end: float, dt_sample: float) -> ImpactRecord:
    """An :class:`ImpactRecord` of ``model`` every ``dt_sample`` to ``t_end`` (s), computed
    by :func:`sampled_record` when first read."""
    return ImpactRecord.deferred(partial(sampled_record, model, t_end, dt_sample))
