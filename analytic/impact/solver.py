"""Exact solver of the paper's impact model (eqs 12-35): impacts by Newton's restitution
(eqs 20-21, loss eq 55), free flights in closed form (eq 13) to the next contact found by the
certified search of analytic.impact.roots, chattering sequences closed at their accumulation point,
moving together (eq 34) to separation. The sequence of events: docs/solver.md.
"""

from __future__ import annotations

import enum
import math
from bisect import bisect_right
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from treeimpact.analytic.errors import ParameterError, SimulationDiverged
from treeimpact.analytic.model.two_body import TwoBodyModel

from .oscillator import Oscillator, first_peak_time, gauss_legendre_integral
from .roots import first_zero

TAIL_ENERGY_FRACTION = 1e-13  # close a chattering tail once it holds less than this of E0
_MAX_EVENTS = 1_000_000  # a guard against a bug, not a cap on the physics: exceeding it raises
_MAX_STALLED_EVENTS = 1000  # events in a row at one time: a loop that no longer advances
#: Impacts one chattering sequence may take before the solver refuses the model (1 / (1 - e)
#: growth, see the module docstring): ~1 s of work; at most 914 were needed at e = 0.99 over
#: 1500 random models (hypothesis, the ranges of tests/test_properties.py).
MAX_CHATTER_IMPACTS = 100_000


class Motion(enum.Enum):
    """What the bodies do from an instant on: a Newton impact there (eqs 20-21), a free
    flight (eq 13) or moving together (eq 34); a :class:`Phase` is one of the last two."""

    IMPACT = "impact"
    FREE = "free"
    TOGETHER = "together"


@dataclass(frozen=True)
class Impact:
    """One Newton impact (eqs 20-21); velocities in m/s, loss in J (eq 55)."""

    index: int
    t: float  # tau_i, s
    x: float  # contact position, m
    U: float  # tree approach velocity
    u: float  # pendulum approach velocity
    V: float  # tree separation velocity
    v: float  # pendulum separation velocity
    loss: float  # delta_i, J


@dataclass(frozen=True)
class TailClosure:
    """A chattering sequence closed at its accumulation point."""

    after_impact: int  # index of the last resolved impact
    t_start: float  # s, time of that impact
    t_accumulation: float  # s, accumulation point: the bodies move together from here
    gamma: float  # m/s, relative separation velocity left after the last resolved impact
    relative_acceleration: float  # m/s^2, a_rel < 0 (the trunk presses back)
    loss: float  # J, mu gamma^2 / 2
    method: str = "geometric tail: t_inf = t_i + 2 gamma / (|a_rel| (1 - e)), loss = mu gamma^2 / 2"


@dataclass(frozen=True)
class Phase:
    """A stretch of closed-form motion: free (eq 13) or together (eq 34)."""

    kind: Motion
    t0: float
    t1: float
    x0: float
    vx0: float
    y0: float
    vy0: float


@dataclass(frozen=True)
class Separation:
    """The bodies part after moving together (eq 34's contact force reaches zero)."""

    t: float  # s
    x: float  # m, the common displacement there
    v: float  # m/s, the common velocity there


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
    @cached_property
    def _osc(self):
        m = self.model
        return (Oscillator.from_mck(m.dynamic_mass, m.damping, m.stiffness),
                Oscillator.from_mck(m.impactor_mass, 0.0, m.impactor_stiffness),
                Oscillator.from_mck(m.dynamic_mass + m.impactor_mass, m.damping,
                                    m.stiffness + m.impactor_stiffness))

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
        ph = self.phases[k]
        s = t - ph.t0
        tree, pend, both = self._osc
        if ph.kind is Motion.TOGETHER:
            dx, vx = both.scalar_advance(s, ph.x0, ph.vx0)
            return ph.x0 + dx, vx, ph.x0 + dx, vx
        dx, vx = tree.scalar_advance(s, ph.x0, ph.vx0)
        dy, vy = pend.scalar_advance(s, ph.y0, ph.vy0)
        return ph.x0 + dx, vx, ph.y0 + dy, vy

    @cached_property
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
        ph = self.phases[k]
        s = t1 - ph.t0
        if s <= 0.0:
            return 0.0
        tree, pend, both = self._osc
        m = self.model
        if ph.kind is Motion.TOGETHER:  # one body: M_T + m on K_T + k, damping C_T
            osc, mass, stiff = both, m.dynamic_mass + m.impactor_mass, m.stiffness + (
                m.impactor_stiffness)
        else:
            osc, mass, stiff = tree, m.dynamic_mass, m.stiffness
        dx, vx1 = osc.scalar_advance(s, ph.x0, ph.vx0)
        x1 = ph.x0 + dx
        if which == "damping":
            return (0.5 * mass * (ph.vx0 ** 2 - vx1 ** 2)
                    + 0.5 * stiff * (ph.x0 ** 2 - x1 ** 2))
        if which == "x" or ph.kind is Motion.TOGETHER:  # y = x while moving together
            return -((vx1 - ph.vx0) + 2.0 * osc.beta * (x1 - ph.x0)) / osc.omega_sq
        if pend.omega_sq > 0.0:  # undamped: y0 sin(w s) / w + 2 v0 sin^2(w s / 2) / w^2
            w = math.sqrt(pend.omega_sq)  # (no difference of nearly equal velocities)
            return ph.y0 * math.sin(w * s) / w + 2.0 * ph.vy0 * (math.sin(0.5 * w * s) / w) ** 2
        return ph.y0 * s + 0.5 * ph.vy0 * s * s  # a billet flies freely

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
        return self.model.damping * val if which == "damping" else val

    @cached_property
    def _cumulative(self) -> dict:
        """Integrals over whole phases, cumulated: {which: [0, I_0, I_0 + I_1, ...]}."""
        out = {}
        for which in ("x", "y", "damping"):
            acc = [0.0]
            for k, ph in enumerate(self.phases):
                acc.append(acc[-1] + self._phase_integral(which, k, ph.t1))
            out[which] = acc
        return out

    def _integral(self, which: str, t_stop: float) -> float:
        """int_0^{t_stop} of x ('x'), y ('y') or C_T vx^2 ('damping') over the phases."""
        if not self.phases or t_stop <= self.phases[0].t0:
            return 0.0
        starts = [ph.t0 for ph in self.phases]
        k = max(0, bisect_right(starts, t_stop) - 1)
        ph = self.phases[k]
        done = self._cumulative[which][k]
        return done + self._phase_integral(which, k, min(ph.t1, t_stop))

    def energy_terms(self, t: float) -> dict:
        """Ledger terms at time t (J): kinetic, potential, damping work, impact losses."""
        m = self.model
        x, vx, y, vy = self._scalar_state(t)
        losses = sum(i.loss for i in self.impacts if i.t <= t)
        losses += sum(c.loss for c in self.tails if c.t_start <= t)
        return {
            "kinetic": m.kinetic_energy(vx, vy),
            "potential": m.potential_energy(x, y),
            "damping": self._integral("damping", t),
            "impact_loss": losses,
        }

    def ledger(self) -> list[dict]:
        """Energy ledger at every event: terms and the relative residual."""
        e0 = self.model.initial_energy
        times = sorted({0.0, self.t_end, *(i.t for i in self.impacts),
                        *(p.t1 for p in self.phases)})
        rows = []
        for t in times:
            terms = self.energy_terms(t)
            total = sum(terms.values())
            rows.append({"t": t, **terms, "residual": abs(e0 - total) / e0})
        return rows

    @cached_property
    def x_max(self) -> tuple[float, float]:
        """(x_max, t_xmax): largest trunk displacement and its time (eq 37), in closed form:
        per phase the larger of its end points and its first interior maximum."""
        tree, _, both = self._osc
        best = (0.0, 0.0)
        for ph in self.phases:
            osc = both if ph.kind is Motion.TOGETHER else tree
            duration = ph.t1 - ph.t0
            for s in (0.0, first_peak_time(osc, ph.x0, ph.vx0), duration):
                if 0.0 <= s <= duration:
                    x = ph.x0 + osc.scalar_advance(s, ph.x0, ph.vx0)[0]
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


def solve_impacts(model: TwoBodyModel, t_end: float, *, stop_at_separation: bool = False,
                  max_events: int | None = None) -> ImpactSolution:
    """Run the impact process of eqs 12-35 of ``model`` from the first contact to ``t_end``
    (s); ``stop_at_separation``: end at the first separation (t_end moved there).
    ``max_events``: a budget of events (impacts, flights, moving together) past which the
    run is refused with SimulationDiverged (a record fit's model far from any tree: a
    0.01 kg trunk bouncing off the pendulum a million times), instead of the guard's
    RuntimeError at a million."""
    if not (t_end > 0 and math.isfinite(t_end)):
        raise ValueError(f"t_end = {t_end!r} s: must be a finite positive number")
    M, m = model.dynamic_mass, model.impactor_mass
    e = model.restitution
    mu = model.reduced_mass
    e0 = model.initial_energy
    tree = Oscillator.from_mck(M, model.damping, model.stiffness)
    pend = Oscillator.from_mck(m, 0.0, model.impactor_stiffness)
    both = Oscillator.from_mck(M + m, model.damping, model.stiffness + model.impactor_stiffness)
    rate = max(tree.fastest_rate, pend.fastest_rate, 1e-12)
    tree_adv, pend_adv, both_adv = tree.scalar_advance, pend.scalar_advance, both.scalar_advance
    tree_bounds, pend_bounds = tree.derivative_bounds, pend.derivative_bounds
    # accelerations and jerks, x'' = -2 beta x' - Omega^2 x (inlined: the hot path)
    b2t, w2t = 2.0 * tree.beta, tree.omega_sq
    b2p, w2p = 2.0 * pend.beta, pend.omega_sq
    cx, cv = _force_coefficients(model)
    sol = ImpactSolution(model=model, t_end=t_end)
    impacts, phases = sol.impacts, sol.phases
    u_scale = model.impact_speed
    tail_limit = TAIL_ENERGY_FRACTION * e0

    t, x, vx, y, vy = 0.0, 0.0, 0.0, 0.0, model.impact_speed
    IMPACT, FREE, TOGETHER = Motion.IMPACT, Motion.FREE, Motion.TOGETHER  # the hot loop's
    mode = IMPACT
    free_order = 1
    chatter = 0  # impacts since the bodies last moved together or started
    t_last, stalled = -1.0, 0  # events in a row that did not advance time
    budget = _MAX_EVENTS if max_events is None else min(max_events, _MAX_EVENTS)
    for _ in range(budget):
        if t >= t_end:
            break
        stalled = stalled + 1 if t <= t_last else 0
        t_last = t
        if stalled > _MAX_STALLED_EVENTS:
            raise SimulationDiverged(
                f"exact solver: {stalled} events without advancing time at t = {t:.6g} s "
                f"(x = {x:.3g} m, relative velocity {vy - vx:.3g} m/s): a grazing contact "
                "it cannot resolve")
        if mode is IMPACT:
            U, u = vx, vy
            approach = u - U
            v_new = ((m - M * e) * u + M * (1.0 + e) * U) / (M + m)  # eq 54
            V_new = v_new + e * approach  # eq 21
            loss = 0.5 * mu * (1.0 - e * e) * approach * approach  # eq 55
            impacts.append(Impact(len(impacts) + 1, t, x, U, u, V_new, v_new, loss))
            vx, vy = V_new, v_new
            chatter += 1
            if chatter > MAX_CHATTER_IMPACTS:
                raise ParameterError(
                    f"contact.restitution = {e!r}: the chattering sequence still holds "
                    f"{0.5 * mu * (vx - vy) ** 2 / e0:.1e} of the input energy after "
                    f"{MAX_CHATTER_IMPACTS} impacts (the exact solver's work grows as "
                    f"1 / (1 - e)); allowed here: a smaller e, e <= 0.99 always runs")
            gamma = vx - vy
            a_rel = (-b2t * vx - w2t * x) - (-b2p * vy - w2p * y)
            tail_energy = 0.5 * mu * gamma * gamma
            if gamma <= 1e-15 * u_scale:  # no relative velocity left (e = 0 or grazing)
                mode, vx, vy = _together_or_part(M, m, cx, cv, x, vx, vy)
                free_order = 0
                continue
            if e < 1.0 and a_rel < 0.0 and tail_energy < tail_limit:
                t_inf = t + 2.0 * gamma / (abs(a_rel) * (1.0 - e))
                sol.tails.append(TailClosure(len(impacts), t, t_inf, gamma, a_rel,
                                             tail_energy))
                vx = vy = common_velocity(M, m, vx, vy)
                mode = TOGETHER
                continue
            mode, free_order = FREE, 1
            continue
        if mode is FREE:
            x0, vx0, y0, vy0 = x, vx, y, vy
            g0 = x0 - y0
            bt = tree_bounds(x0, vx0)
            bp = pend_bounds(y0, vy0)
            bounds = [bt[0] + bp[0], bt[1] + bp[1], bt[2] + bp[2], bt[3] + bp[3],
                      bt[4] + bp[4], bt[5] + bp[5]]

            last = [-1.0, 0.0, 0.0, 0.0, 0.0]  # the state at the last sampled s

            def gap(s):
                dx, vxs = tree_adv(s, x0, vx0)
                dy, vys = pend_adv(s, y0, vy0)
                last[0], last[1], last[2], last[3], last[4] = s, dx, vxs, dy, vys
                return g0 + dx - dy

            def dgap(s):
                return tree_adv(s, x0, vx0)[1] - pend_adv(s, y0, vy0)[1]

            def gap_slope(s):
                dx, vxs = tree_adv(s, x0, vx0)
                dy, vys = pend_adv(s, y0, vy0)
                return g0 + dx - dy, vxs - vys

            ax0, ay0 = -b2t * vx0 - w2t * x0, -b2p * vy0 - w2p * y0
            g1 = vx0 - vy0
            g2 = ax0 - ay0
            g3 = (-b2t * ax0 - w2t * vx0) - (-b2p * ay0 - w2p * vy0)
            order = free_order
            if order == 0:  # touching with no relative velocity: find the first non-zero term
                order = 2 if g2 > 1e-12 * bounds[2] else 3
            taylor = (0.0, g1, g2, g3, 0.0, 0.0)

            def local_bounds(s):
                if s == last[0]:  # the search steps on from a point it has sampled
                    _, dx, vxs, dy, vys = last
                else:
                    dx, vxs = tree_adv(s, x0, vx0)
                    dy, vys = pend_adv(s, y0, vy0)
                lt = tree_bounds(x0 + dx, vxs)
                lp = pend_bounds(y0 + dy, vys)
                return [lt[0] + lp[0], lt[1] + lp[1], lt[2] + lp[2], lt[3] + lp[3],
                        lt[4] + lp[4], lt[5] + lp[5]]

            s_hit = first_zero(gap, dgap, t_end - t, bounds, rate, order=order, taylor=taylor,
                               local_bounds=local_bounds, fdf=gap_slope)
            s_stop = t_end - t if s_hit is None else s_hit
            phases.append(Phase(FREE, t, t + s_stop, x0, vx0, y0, vy0))
            dx, vx = tree_adv(s_stop, x0, vx0)
            dy, vy = pend_adv(s_stop, y0, vy0)
            t, x, y = t + s_stop, x0 + dx, y0 + dy
            if s_hit is None:
                break
            y = x  # in contact: the gap is zero to round-off
            if vy - vx <= 0.0:  # grazing: touching without approach
                mode, vx, vy = _together_or_part(M, m, cx, cv, x, vx, vy)
                free_order = 0
                continue
            mode = IMPACT
            continue
        if mode is TOGETHER:
            chatter = 0
            sol.together_starts.append((t, x, vx))
            x0, v0 = x, vx
            f0 = cx * x0 + cv * v0
            if f0 > 0.0:
                # The contact force N = cx x + cv v solves the equation of the joint motion
                # (eq 34) itself: its first zero in closed form (Oscillator.first_zero).
                s_sep = both.first_zero(f0, cx * v0 + cv * both.acceleration(x0, v0))
                if not s_sep <= t_end - t:
                    s_sep = None
            else:  # not compressive at the start (round-off): the certified search decides
                s_sep = _separation_search(both, cx, cv, x0, v0, f0, t_end - t)
            s_stop = t_end - t if s_sep is None else s_sep
            phases.append(Phase(TOGETHER, t, t + s_stop, x0, v0, x0, v0))
            dx, v = both_adv(s_stop, x0, v0)
            t, x, vx, y, vy = t + s_stop, x0 + dx, v, x0 + dx, v
            if s_sep is None:
                break
            sol.separations.append(Separation(t, x, v))
            if stop_at_separation:
                sol.t_end = t
                break
            # the contact force is zero at a separation, so is the relative acceleration:
            # the gap opens as -N' t^3 / (6 mu) (order 3), whatever round-off left in g2
            mode, free_order = FREE, 3
            continue
    else:  # the budget given ran out (a record fit's model far off), else a bug
        if max_events is not None:
            raise SimulationDiverged(f"exact solver: more than {budget} events before "
                                     f"t_end = {t_end:.4g} s (the budget given)")
        raise RuntimeError(f"impact solver: more than {_MAX_EVENTS} events before t_end")
    return sol


def common_velocity(M: float, m: float, vx: float, vy: float) -> float:
    """The velocity (m/s) of trunk (dynamic mass M, velocity vx) and pendulum (m, vy)
    moving together with their momentum (eq 20 with V = v)."""
    return (M * vx + m * vy) / (M + m)


def _together_or_part(M: float, m: float, cx: float, cv: float, x: float, vx: float,
                      vy: float) -> tuple[Motion, float, float]:
    """(motion, vx, vy) of bodies touching at x (m) without approach velocity: moving
    together at their :func:`common_velocity` when the contact force there, N = cx x + cv v
    (:func:`_force_coefficients`), presses them together; else parting, the velocities
    unchanged (a free flight from a touch)."""
    vc = common_velocity(M, m, vx, vy)
    if cx * x + cv * vc > 0.0:
        return Motion.TOGETHER, vc, vc
    return Motion.FREE, vx, vy


def _separation_search(both: Oscillator, cx: float, cv: float, x0: float, v0: float,
                       f0: float, t_max: float) -> float | None:
    """First zero of the contact force N = cx x + cv v while moving together, by the
    certified search of :mod:`analytic.impact.roots` (used when N(0) = f0 is not positive)."""
    adv = both.scalar_advance
    bb = both.derivative_bounds(x0, v0)
    fb = [abs(cx) * bb[n] + abs(cv) * bb[n + 1] for n in range(len(bb) - 1)]

    def force(s):
        dx, v = adv(s, x0, v0)
        return cx * (x0 + dx) + cv * v

    def dforce(s):
        dx, v = adv(s, x0, v0)
        return cx * v + cv * both.acceleration(x0 + dx, v)

    def local_force_bounds(s):
        dx, v = adv(s, x0, v0)
        lb = both.derivative_bounds(x0 + dx, v)
        return [abs(cx) * lb[n] + abs(cv) * lb[n + 1] for n in range(len(lb) - 1)]

    return first_zero(force, dforce, t_max, fb, both.fastest_rate, order=0,
                      taylor=(f0,), local_bounds=local_force_bounds)


def _force_coefficients(model: TwoBodyModel) -> tuple[float, float]:
    """Contact force while moving together, N = cx x + cv v (from eq 34 and eq 13).

    N = M_T x'' + C_T x' + K_T x with (M_T + m) x'' = -C_T x' - (K_T + k) x, so
    N = [m C_T x' + (m K_T - M_T k) x] / (M_T + m); compressive while N > 0.
    """
    M, m = model.dynamic_mass, model.impactor_mass
    return ((m * model.stiffness - M * model.impactor_stiffness) / (M + m),
            m * model.damping / (M + m))
