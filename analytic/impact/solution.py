"""What the exact solver found (:func:`analytic.impact.solver.solve_impacts`): the impacts,
phases, closed tails and separations of the impact process (eqs 12-35), and what is read
from them on demand in closed form: the state at any time (eqs 13, 34), the phase integrals
A_x, A_y and the damping work (eqs 15-16), the energy ledger (eqs 49-58), x_max (eq 37).
"""

from __future__ import annotations

import math
from bisect import bisect_right
from dataclasses import dataclass, field

import numpy as np

from treeimpact.analytic.model.two_body import TwoBodyModel

from .events import Motion, Phase
from .oscillator import Oscillator, first_peak_time, gauss_legendre_integral


class _once:  # noqa: N801 - a decorator, named like one
    """functools.cached_property without the lock Python 3.11 takes on every first read (a
    run reads six of them once each, ~1 us apiece): two threads reading one solution at
    once may both compute a value, the same value."""

    def __init__(self, func):
        """``func``: the method whose value is cached on first read."""
        self.func, self.name, self.__doc__ = func, func.__name__, func.__doc__

    def __set_name__(self, owner, name):
        self.name = name

    def __get__(self, obj, objtype=None):
        if obj is None:
            return self
        value = obj.__dict__[self.name] = self.func(obj)
        return value


@dataclass
class ImpactSolution:
    """Everything the exact solver found; metrics are computed from it on demand."""

    model: TwoBodyModel
    t_end: float
    impacts: list = field(default_factory=list)
    phases: list = field(default_factory=list)
    tails: list = field(default_factory=list)
    separations: list = field(default_factory=list)
    together_starts: list = field(default_factory=list)  # (t, x, V)

    # -- motion -----------------------------------------------------------------------
    @_once
    def _osc(self):
        m = self.model
        return (Oscillator.from_mck(m.dynamic_mass, m.equivalent_damping, m.equivalent_stiffness),
                Oscillator.from_mck(m.impactor_mass, 0.0, m.impactor_stiffness),
                Oscillator.from_mck(m.dynamic_mass + m.impactor_mass, m.equivalent_damping,
                                    m.equivalent_stiffness + m.impactor_stiffness))

    def _phase_state(self, ph: Phase, s, pendulum: bool = True):
        """(x, vx, y, vy) of phase ``ph`` at times s (s) after its start; (x, vx) only
        without ``pendulum``."""
        tree, pend, both = self._osc
        if ph.kind is Motion.TOGETHER:
            dx, vx = both.advance(s, ph.x0, ph.vx0, np)
            return (ph.x0 + dx, vx, ph.x0 + dx, vx) if pendulum else (ph.x0 + dx, vx)
        dx, vx = tree.advance(s, ph.x0, ph.vx0, np)
        if not pendulum:
            return ph.x0 + dx, vx
        dy, vy = pend.advance(s, ph.y0, ph.vy0, np)
        return ph.x0 + dx, vx, ph.y0 + dy, vy

    def _scalar_state(self, t: float) -> tuple[float, float, float, float]:
        """(x, vx, y, vy) at one time t (s): :meth:`state` on the solver's scalar path."""
        k = max(0, bisect_right(self._starts, t) - 1)
        s = t - self.phases[k].t0
        x, vx = self._trunk_at(k, s)
        if self.phases[k].kind is Motion.TOGETHER:
            return x, vx, x, vx
        y, vy = self._pendulum_at(k, s)
        return x, vx, y, vy

    @_once
    def _memo(self) -> tuple[dict, dict]:
        """The trunk's and the pendulum's states already evaluated, {(phase, s): (x, v)}."""
        return {}, {}

    def _trunk_at(self, k: int, s: float) -> tuple[float, float]:
        """(x, vx) of phase k at s (s) after its start: x0 + dx and vx of its oscillator's
        closed form (eq 13 or 34), each (k, s) evaluated once (the ledger, the phase
        integrals and x_max read the phases' end points again and again)."""
        memo = self._memo[0]
        got = memo.get((k, s))
        if got is None:
            ph = self.phases[k]
            tree, _, both = self._osc
            osc = both if ph.kind is Motion.TOGETHER else tree
            dx, vx = osc.scalar_advance(s, ph.x0, ph.vx0)
            got = memo[(k, s)] = (ph.x0 + dx, vx)
        return got

    def _pendulum_at(self, k: int, s: float) -> tuple[float, float]:
        """(y, vy) of free phase k at s (s) after its start (eq 13), as :meth:`_trunk_at`."""
        memo = self._memo[1]
        got = memo.get((k, s))
        if got is None:
            ph = self.phases[k]
            dy, vy = self._osc[1].scalar_advance(s, ph.y0, ph.vy0)
            got = memo[(k, s)] = (ph.y0 + dy, vy)
        return got

    @_once
    def _starts(self) -> list:
        return [ph.t0 for ph in self.phases]

    def state(self, t):
        """(x, vx, y, vy) at times t (s, 0 <= t <= t_end); arrays."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        if np.any(t < 0) or np.any(t > self.t_end * (1 + 1e-12)):
            raise ValueError(f"t: requested times must lie in [0, {self.t_end}] s")
        order = np.argsort(t, kind="stable")
        out = np.empty((4, t.size))
        out[:, order] = self.sorted_state(t[order])
        return out

    def sorted_state(self, t: np.ndarray, *, pendulum: bool = True) -> np.ndarray:
        """:meth:`state` at sorted times t (s, 0 <= t <= t_end, unchecked), each phase
        evaluated once on its run of samples (a sample at a phase's start belongs to the
        phase it opens); rows (x, vx, y, vy), or the trunk's (x, vx) alone without
        ``pendulum`` (what a displacement record needs)."""
        bounds = np.searchsorted(t, self._starts[1:], side="left")
        out = np.empty((4 if pendulum else 2, t.size))
        lo = 0
        for ph, hi in zip(self.phases, [*bounds.tolist(), t.size]):
            if hi > lo:
                out[:, lo:hi] = self._phase_state(ph, t[lo:hi] - ph.t0, pendulum)
                lo = hi
        return out

    # -- quantities -------------------------------------------------------------------
    @property
    def together_start(self):
        """(T0, x0, V) of the first moving-together phase, or None."""
        return self.together_starts[0] if self.together_starts else None

    def _phase_integral(self, which: str, k: int, t1: float) -> float:
        """int over phase k from its start to t1 (absolute time) of x, y or C_T vx^2, in
        closed form from the phase's end points (docs/energy-ledger.md): integrating
        x'' + 2 beta x' + Omega^2 x = 0 gives Omega^2 int x = -(dv + 2 beta dx) (eqs 15-16),
        and C_T int vx^2 is the oscillator's own energy lost (eq 11 times vx)."""
        ix, iy, idamp = self._phase_integrals(k, t1, which)
        return ix if which == "x" else (iy if which == "y" else idamp)

    def _phase_integrals(self, k: int, t1: float, which: str | None = None) -> tuple:
        """(int x, int y, C_T int vx^2) over phase k from its start to t1 (absolute time):
        :meth:`_phase_integral`'s three from one evaluation of the phase's end point (the
        same operations each); ``which`` names the one wanted (the others are then None)."""
        ph = self.phases[k]
        s = t1 - ph.t0
        if s <= 0.0:
            return 0.0, 0.0, 0.0
        tree, pend, both = self._osc
        m = self.model
        together = ph.kind is Motion.TOGETHER
        ix = iy = idamp = None
        if which != "y" or together:
            osc = both if together else tree
            x0, vx0 = ph.x0, ph.vx0
            x1, vx1 = self._trunk_at(k, s)
            ix = -((vx1 - vx0) + 2.0 * osc.beta * (x1 - x0)) / osc.omega_sq
            if together:  # one body: M_T + m on K_T + k, damping C_T; y = x
                iy = ix
                mass, stiff = m.dynamic_mass + m.impactor_mass, m.equivalent_stiffness + (
                    m.impactor_stiffness)
            else:
                mass, stiff = m.dynamic_mass, m.equivalent_stiffness
            idamp = 0.5 * mass * (vx0 ** 2 - vx1 ** 2) + 0.5 * stiff * (x0 ** 2 - x1 ** 2)
        if iy is None and which in (None, "y"):
            if pend.omega_sq > 0.0:  # undamped: y0 sin(w s) / w + 2 v0 sin^2(w s / 2) / w^2
                w = math.sqrt(pend.omega_sq)  # (no difference of nearly equal velocities)
                iy = ph.y0 * math.sin(w * s) / w + 2.0 * ph.vy0 * (math.sin(0.5 * w * s) / w) ** 2
            else:
                iy = ph.y0 * s + 0.5 * ph.vy0 * s * s  # a billet flies freely
        return ix, iy, idamp

    def _phase_integral_quadrature(self, which: str, k: int, t1: float) -> float:
        """:meth:`_phase_integral` by Gauss-Legendre quadrature of the motion itself: the
        independent check of the closed forms (tests, benchmark)."""
        tree, _, both = self._osc
        ph = self.phases[k]
        rate = max(tree.fastest_rate, both.fastest_rate, 1e-9)
        comp = {"x": 0, "y": 2, "damping": 1}[which]

        def fn(s):
            vals = self._phase_state(ph, s)[comp]
            return vals * vals if which == "damping" else vals

        val = gauss_legendre_integral(fn, 0.0, t1 - ph.t0, rate)
        return self.model.equivalent_damping * val if which == "damping" else val

    @_once
    def _cumulative(self) -> dict:
        """Integrals over whole phases, cumulated: {which: [0, I_0, I_0 + I_1, ...]}."""
        acc_x, acc_y, acc_d = [0.0], [0.0], [0.0]
        for k, ph in enumerate(self.phases):
            ix, iy, idamp = self._phase_integrals(k, ph.t1)
            acc_x.append(acc_x[-1] + ix)
            acc_y.append(acc_y[-1] + iy)
            acc_d.append(acc_d[-1] + idamp)
        return {"x": acc_x, "y": acc_y, "damping": acc_d}

    def _integral(self, which: str, t_stop: float) -> float:
        """int_0^{t_stop} of x ('x'), y ('y') or C_T vx^2 ('damping') over the phases."""
        if not self.phases or t_stop <= self.phases[0].t0:
            return 0.0
        k = max(0, bisect_right(self._starts, t_stop) - 1)
        ph = self.phases[k]
        done = self._cumulative[which][k]
        return done + self._phase_integral(which, k, min(ph.t1, t_stop))

    @_once
    def _event_losses(self) -> tuple:
        """(impact times, their losses, tail start times, their losses), each in the order
        found: the solver records both in time order, so the events up to a time are a
        prefix of each."""
        return ([i.t for i in self.impacts], [i.loss for i in self.impacts],
                [c.t_start for c in self.tails], [c.loss for c in self.tails])

    def _terms(self, t: float) -> tuple[float, float, float, float]:
        """(kinetic, potential, damping work, impact losses) at time t (J): :meth:`energy_terms`
        as a tuple. The losses are summed as before (impacts, then tails, each in time order
        from 0: sum() of the same prefix)."""
        m = self.model
        x, vx, y, vy = self._scalar_state(t)
        ti, li, tt, lt = self._event_losses
        losses = sum(li[:bisect_right(ti, t)])
        losses += sum(lt[:bisect_right(tt, t)])
        return (m.kinetic_energy(vx, vy), m.potential_energy(x, y),
                self._integral("damping", t), losses)

    def energy_terms(self, t: float) -> dict:
        """Ledger terms at time t (J): kinetic, potential, damping work, impact losses."""
        return dict(zip(("kinetic", "potential", "damping", "impact_loss"), self._terms(t)))

    def _ledger_times(self) -> list:
        return sorted({0.0, self.t_end, *(i.t for i in self.impacts),
                       *(p.t1 for p in self.phases)})

    def ledger(self) -> list[dict]:
        """Energy ledger at every event: terms and the relative residual."""
        e0 = self.model.initial_energy
        rows = []
        for t in self._ledger_times():
            terms = self.energy_terms(t)
            total = sum(terms.values())
            rows.append({"t": t, **terms, "residual": abs(e0 - total) / e0})
        return rows

    def ledger_residual(self) -> float:
        """The largest relative residual of :meth:`ledger` (the metric ledger_residual),
        without its rows: :meth:`_terms` and :meth:`_integral` inlined (the same operations;
        tests/test_newton_equivalence.py holds the two equal to the bit)."""
        m, phases, starts = self.model, self.phases, self._starts
        e0 = m.initial_energy
        cum = self._cumulative["damping"]
        ti, li, tt, lt = self._event_losses
        residuals = []
        for t in self._ledger_times():
            k = max(0, bisect_right(starts, t) - 1)
            ph = phases[k]
            s = t - ph.t0
            x, vx = self._trunk_at(k, s)
            y, vy = (x, vx) if ph.kind is Motion.TOGETHER else self._pendulum_at(k, s)
            damping = 0.0 if t <= starts[0] else (
                cum[k] + self._phase_integrals(k, min(ph.t1, t), "damping")[2])
            losses = sum(li[:bisect_right(ti, t)])
            losses += sum(lt[:bisect_right(tt, t)])
            total = sum((m.kinetic_energy(vx, vy), m.potential_energy(x, y), damping, losses))
            residuals.append(abs(e0 - total) / e0)
        return max(residuals)

    @_once
    def x_max(self) -> tuple[float, float]:
        """(x_max, t_xmax): largest trunk displacement and its time (eq 37), in closed form:
        per phase the larger of its end points and its first interior maximum."""
        tree, _, both = self._osc
        best = (0.0, 0.0)
        for k, ph in enumerate(self.phases):
            osc = both if ph.kind is Motion.TOGETHER else tree
            duration = ph.t1 - ph.t0
            for s in (0.0, first_peak_time(osc, ph.x0, ph.vx0), duration):
                if 0.0 <= s <= duration:
                    x = self._trunk_at(k, s)[0]
                    if x > best[0]:
                        best = (x, ph.t0 + s)
        return best

    @property
    def n_impacts(self) -> int:
        """Impacts resolved explicitly before the first moving-together phase."""
        ts = self.together_start
        if ts is None:
            return len(self.impacts)
        return sum(1 for i in self.impacts if i.t <= ts[0])

    def inelastic_loss(self) -> float:
        """eq 57: M_T m u_1^2 / (2 (M_T + m))."""
        return self.model.reduced_mass * self.model.impact_speed ** 2 / 2.0
