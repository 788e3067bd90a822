"""The ``exact-full`` evaluation of the exact linear solution: every sample's observables
and energies as it goes (the original implementation, the reference of the tests and the
benchmark), each switch located by Brent's method on the exact solution of its phase
(:mod:`.modal`, the rule of :mod:`.phases`). Design notes: docs/beam-impact.md.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from treeimpact.analytic.errors import SimulationDiverged
from treeimpact.analytic.results import ImpactRecord

from .linear_model import LinearImpactModel, initial_state, matrices
from .modal import LedgerForms, Modal, Observable, decomposed, ledger_forms, observation_rows
from .phases import ContactPhase, Signal, bracket, check_switches, switch

_DELTA = slice(Observable.DELTA, Observable.DELTA_RATE + 1)


@dataclass(frozen=True)
class _StateSolution:
    """One contact state: its :class:`Modal` solution, ledger forms and observation rows."""

    modal: Modal
    forms: LedgerForms
    rows: np.ndarray


@dataclass
class _Samples:
    """The record being written: observables, energies (kinetic, elastic, damping work,
    pad work; J) and the contact flag on the sample grid ``t`` (s)."""

    t: np.ndarray
    obs: np.ndarray
    energy: np.ndarray
    in_contact: np.ndarray


def _state_solution(model: LinearImpactModel, contact: bool) -> _StateSolution:
    M, C, K, g = matrices(model, contact)
    modal = decomposed(M, C, K)  # the ``exact`` run's, when the record is read after it
    return _StateSolution(modal, ledger_forms(model, modal, contact, g),
                          observation_rows(model, modal, g))


def record(model: LinearImpactModel, t_end: float, dt_sample: float):
    """Solve the impact of ``model`` exactly to ``t_end`` (s); an ``ImpactRecord`` every
    ``dt_sample`` (s).

    The ``exact-full`` method: every sample's observables and energies as it goes. Also
    returns the crown deflection (m) at the same times and the number of contact switches.
    """
    states = {c: _state_solution(model, c) for c in (False, True)}
    steps = int(math.ceil(t_end / dt_sample - 1e-9))
    t_grid = np.linspace(0.0, t_end, steps + 1)
    out = _Samples(t_grid, np.zeros((8, t_grid.size)), np.zeros((4, t_grid.size)),
                   np.zeros(t_grid.size, dtype=bool))
    z = initial_state(model)
    t, phase = 0.0, ContactPhase.CONTACT
    works = (0.0, 0.0)  # the trunk's damping, the pad's (J)
    switches = 0
    while True:
        state = states[phase.touching]
        w = state.modal.W @ z
        end = _scan(model, state, phase, out, t, w, works)
        if end is None:
            break
        end_s, nxt = end
        z, works = _advance(state, phase, w, end_s, works, t)
        t += end_s
        phase = nxt
        switches += 1
        check_switches(switches, t)
    return _assemble(model, out), out.obs[Observable.CROWN], switches


def _scan(model, state: _StateSolution, phase: ContactPhase, out: _Samples, t: float,
          w: np.ndarray, works: tuple[float, float]):
    """Write the samples of the phase started at ``t`` (modal coefficients w), scanning
    them in growing chunks for its end; returns (time into the phase, next phase) of the
    switch, or None when the phase lasts to the grid's end."""
    k_c, c_c = model.contact_stiffness, model.contact_damping
    t_grid, modal, rows = out.t, state.modal, state.rows
    j0 = int(np.searchsorted(t_grid, t, side="left"))
    if j0 < t_grid.size and t_grid[j0] == t and t > 0:
        j0 += 1  # that sample was written by the previous phase
    end, j, chunk = None, j0, 64
    while j < t_grid.size and end is None:
        jj = min(t_grid.size, j + chunk)
        s = t_grid[j:jj] - t
        U = modal.modal(w, s)
        d, dd = modal.observe(rows[_DELTA], w, s, U)
        f = k_c * d + c_c * dd
        hit = np.flatnonzero(phase.has_ended(d, f))
        if hit.size:
            k = int(hit[0])
            s_lo = s[k - 1] if k > 0 else (t_grid[j - 1] - t if j > j0 else 0.0)
            end = _locate(model, phase, state, w, s_lo, s[k], d[k], f[k])
            jj = j + k  # samples before the event belong to this phase
        _fill(out, j, jj, t, state, phase.touching, w, works, U[:jj - j])
        j = jj
        chunk *= 4
    return end


def _advance(state: _StateSolution, phase: ContactPhase, w: np.ndarray, end_s: float,
             works: tuple[float, float], t: float):
    """(z, works) at the switch ``end_s`` into the phase started at ``t``: the raw state
    and the damping and pad works so far (J)."""
    forms = state.forms
    wd = float(forms.damping.integral(w, np.array([end_s]))[0])
    wc = float(forms.pad.integral(w, np.array([end_s]))[0]) if phase.touching else 0.0
    z = state.modal.state(w, end_s)
    if not np.all(np.isfinite(z)):
        raise SimulationDiverged(f"beam: non-finite state at t = {t + end_s:.6g} s")
    return z, (works[0] + wd, works[1] + wc)


def _fill(out: _Samples, j: int, jj: int, t: float, state: _StateSolution, contact: bool,
          w: np.ndarray, works: tuple[float, float], U: np.ndarray) -> None:
    """Write samples j..jj-1 of one phase (started at t with modal coefficients w)."""
    if jj <= j:
        return
    s = out.t[j:jj] - t
    forms = state.forms
    out.obs[:, j:jj] = state.modal.observe(state.rows, w, s, U)
    out.energy[0, j:jj] = forms.kinetic.value(w, s, U)
    out.energy[1, j:jj] = forms.elastic.value(w, s, U)
    out.energy[2, j:jj] = works[0] + forms.damping.integral(w, s, U)
    out.energy[3, j:jj] = works[1] + (forms.pad.integral(w, s, U) if contact else 0.0)
    out.in_contact[j:jj] = contact


def _assemble(model: LinearImpactModel, out: _Samples) -> ImpactRecord:
    """The :class:`ImpactRecord` of the written samples."""
    k_c, c_c = model.contact_stiffness, model.contact_damping
    x, y, vx, vy, delta, ddelta, crown, crown_v = out.obs
    force = np.where(out.in_contact, np.maximum(0.0, k_c * delta + c_c * ddelta), 0.0)
    kinetic, potential, damping_work, contact_work = out.energy
    m, kp = model.impactor_mass, model.impactor_stiffness
    return ImpactRecord(
        t=out.t, x=x, vx=vx, y=y, vy=vy, force=force, kinetic=kinetic, potential=potential,
        damping_work=damping_work, contact_work=contact_work,
        contact_potential=np.where(out.in_contact,
                                   0.5 * k_c * np.maximum(delta, 0.0) ** 2, 0.0),
        pendulum_energy=0.5 * m * vy ** 2 + 0.5 * kp * y ** 2, crown=crown,
        crown_velocity=crown_v)


def _locate(model: LinearImpactModel, phase: ContactPhase, state: _StateSolution,
            w: np.ndarray, s_lo: float, s_hi: float, d_hi: float, f_hi: float):
    """(time into the phase, next phase) of the switch bracketed by [s_lo, s_hi]
    (:func:`.phases.switch`), each root by Brent's method."""
    k_c, c_c, modal, rows = model.contact_stiffness, model.contact_damping, state.modal, \
        state.rows

    def d(s):
        return float(modal.observe(rows[Observable.DELTA:Observable.DELTA + 1], w,
                                   np.array([s]))[0, 0])

    def f(s):
        dd = modal.observe(rows[_DELTA], w, np.array([s]))
        return float(k_c * dd[0, 0] + c_c * dd[1, 0])

    signals = {Signal.DELTA: d, Signal.LAW: f}
    return switch(phase, lambda signal: _root(signals[signal], s_lo, s_hi), d, d_hi, f_hi)


def _root(func, lo, hi):
    """Zero of ``func`` in [lo, hi]; a phase that starts on its own boundary (func(lo) = 0)
    is bracketed from just after its start."""
    # lazy: +698 ms at import otherwise (scipy.optimize)
    from scipy.optimize import brentq

    found = bracket(func, lo, hi, func(hi))
    if found is None:
        return hi
    return brentq(func, found[0], hi, xtol=1e-15, rtol=4 * np.finfo(float).eps)
