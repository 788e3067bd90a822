"""Exact solver of the paper's impact model (eqs 12-35): impacts by Newton's restitution
(eqs 20-21, loss eq 55; :mod:`.newton`), free flights in closed form (eq 13) to the next
contact found by the certified search of analytic.impact.roots (:mod:`.free_flight`),
chattering sequences closed at their accumulation point, moving together (eq 34) to
separation (:mod:`.together`). This module runs the sequence of events (docs/solver.md); what
it records is :mod:`.events`, what it returns :class:`~.solution.ImpactSolution`.
"""

from __future__ import annotations

import math

from treeimpact.analytic.errors import SimulationDiverged
from treeimpact.analytic.model.two_body import TwoBodyModel

from .events import Impact, Motion, Phase, Separation, TailClosure
from .free_flight import next_contact
from .newton import (
    MAX_CHATTER_IMPACTS,
    TAIL_ENERGY_FRACTION,
    chatter_refused,
    close_tail,
    common_velocity,
    newton_impact,
)
from .oscillator import Oscillator
from .solution import ImpactSolution
from .together import force_coefficients, separation_time, together_or_part

# the names this module has always exported, where they are now
__all__ = ["MAX_CHATTER_IMPACTS", "TAIL_ENERGY_FRACTION", "Impact", "ImpactSolution", "Motion",
           "Phase", "Separation", "TailClosure", "common_velocity", "solve_impacts"]

_MAX_EVENTS = 1_000_000  # a guard against a bug, not a cap on the physics: exceeding it raises
_MAX_STALLED_EVENTS = 1000  # events in a row at one time: a loop that no longer advances


class _Bodies:
    """What every event of one run needs of its ``model``, computed once (a plain class with
    slots: it is built for every run, a record fit builds thousands): M_T, m, e, mu, E0, the
    three oscillators (trunk, pendulum, together) and their fastest rate (1/s), the contact
    force's coefficients (:func:`~.together.force_coefficients`), the tail's energy limit (J)
    and ``t_end`` (s)."""

    __slots__ = ("M", "accelerations", "both", "cv", "cx", "e", "e0", "m", "model", "mu", "pend",
                 "rate", "t_end", "tail_limit", "tree", "u_scale")

    def __init__(self, model: TwoBodyModel, t_end: float):
        self.model, self.t_end = model, t_end
        self.M, self.m = M, m = model.dynamic_mass, model.impactor_mass
        self.e, self.mu, self.e0 = model.restitution, model.reduced_mass, model.initial_energy
        self.tree = tree = Oscillator.from_mck(M, model.equivalent_damping,
                                               model.equivalent_stiffness)
        self.pend = pend = Oscillator.from_mck(m, 0.0, model.impactor_stiffness)
        self.both = Oscillator.from_mck(M + m, model.equivalent_damping,
                                        model.equivalent_stiffness + model.impactor_stiffness)
        self.rate = max(tree.fastest_rate, pend.fastest_rate, 1e-12)
        self.cx, self.cv = force_coefficients(model)
        self.tail_limit = TAIL_ENERGY_FRACTION * self.e0
        self.u_scale = model.impact_speed  # m/s: what "no relative velocity left" is against
        # x'' = -2 beta x' - Omega^2 x of trunk and pendulum: (2 beta, Omega^2) of each
        self.accelerations = (2.0 * tree.beta, tree.omega_sq, 2.0 * pend.beta, pend.omega_sq)


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
    bodies = _Bodies(model, t_end)
    sol = ImpactSolution(model=model, t_end=t_end)
    state = (0.0, 0.0, 0.0, 0.0, model.impact_speed)  # t, x, vx, y, vy at the first contact
    IMPACT, FREE = Motion.IMPACT, Motion.FREE
    mode, free_order = IMPACT, 1
    chatter = 0  # impacts since the bodies last moved together or started
    t_last, stalled = -1.0, 0  # events in a row that did not advance time
    budget = _MAX_EVENTS if max_events is None else min(max_events, _MAX_EVENTS)
    for _ in range(budget):
        t = state[0]
        if t >= t_end:
            break
        stalled = stalled + 1 if t <= t_last else 0
        t_last = t
        if stalled > _MAX_STALLED_EVENTS:
            _stalled(stalled, state)
        if mode is IMPACT:
            chatter += 1
            state, mode, free_order = _impact(bodies, sol, state, chatter)
        elif mode is FREE:
            state, mode, free_order = _free_flight(bodies, sol, state, free_order)
        else:
            chatter = 0
            state, mode, free_order = _move_together(bodies, sol, state, stop_at_separation)
        if mode is None:  # the run ended (t_end, or the separation it was to stop at)
            break
    else:  # the budget given ran out (a record fit's model far off), else a bug
        if max_events is not None:
            raise SimulationDiverged(f"exact solver: more than {budget} events before "
                                     f"t_end = {t_end:.4g} s (the budget given)")
        raise RuntimeError(f"impact solver: more than {_MAX_EVENTS} events before t_end")
    return sol


def _stalled(stalled: int, state: tuple) -> None:
    """Raise SimulationDiverged for ``stalled`` events in a row at one time (``state``:
    t, x, vx, y, vy): a grazing contact the solver cannot resolve."""
    t, x, vx, _, vy = state
    raise SimulationDiverged(
        f"exact solver: {stalled} events without advancing time at t = {t:.6g} s "
        f"(x = {x:.3g} m, relative velocity {vy - vx:.3g} m/s): a grazing contact "
        "it cannot resolve")


def _impact(bodies: _Bodies, sol: ImpactSolution, state: tuple, chatter: int):
    """A Newton impact at ``state`` (eqs 20-21), the ``chatter``-th of its sequence,
    recorded in ``sol``; then what follows: moving together (the tail closed at its
    accumulation point, or no relative velocity left) or a free flight. Returns (state,
    motion, the order of the gap's zero at the flight's start)."""
    M, m, e, mu = bodies.M, bodies.m, bodies.e, bodies.mu
    t, x, vx, y, vy = state
    impact = newton_impact(len(sol.impacts) + 1, t, x, vx, vy, M, m, e, mu)
    sol.impacts.append(impact)
    vx, vy = impact.V, impact.v
    if chatter > MAX_CHATTER_IMPACTS:
        raise chatter_refused(e, mu, vx, vy, bodies.e0)
    gamma = vx - vy
    b2t, w2t, b2p, w2p = bodies.accelerations
    a_rel = (-b2t * vx - w2t * x) - (-b2p * vy - w2p * y)
    if gamma <= 1e-15 * bodies.u_scale:  # no relative velocity left (e = 0 or grazing)
        mode, vx, vy = together_or_part(M, m, bodies.cx, bodies.cv, x, vx, vy)
        return (t, x, vx, y, vy), mode, 0
    tail = close_tail(len(sol.impacts), t, gamma, a_rel, e, mu, bodies.tail_limit)
    if tail is not None:
        sol.tails.append(tail)
        vx = vy = common_velocity(M, m, vx, vy)
        return (t, x, vx, y, vy), Motion.TOGETHER, 1
    return (t, x, vx, y, vy), Motion.FREE, 1


def _free_flight(bodies: _Bodies, sol: ImpactSolution, state: tuple, order: int):
    """A free flight (eq 13) from ``state`` to the next contact or ``t_end``, recorded in
    ``sol`` (``order``: the gap's zero at the start, :func:`~.free_flight.next_contact`);
    at the contact, an impact, or for a touch without approach moving together or parting.
    Returns (state, motion or None at t_end, order)."""
    t, x0, vx0, y0, vy0 = state
    tree, pend = bodies.tree, bodies.pend
    s_hit = next_contact(tree, pend, x0, vx0, y0, vy0, order, bodies.t_end - t, bodies.rate)
    s_stop = bodies.t_end - t if s_hit is None else s_hit
    sol.phases.append(Phase(Motion.FREE, t, t + s_stop, x0, vx0, y0, vy0))
    dx, vx = tree.scalar_advance(s_stop, x0, vx0)
    dy, vy = pend.scalar_advance(s_stop, y0, vy0)
    t, x, y = t + s_stop, x0 + dx, y0 + dy
    if s_hit is None:
        return (t, x, vx, y, vy), None, order
    y = x  # in contact: the gap is zero to round-off
    if vy - vx <= 0.0:  # grazing: touching without approach
        mode, vx, vy = together_or_part(bodies.M, bodies.m, bodies.cx, bodies.cv, x, vx, vy)
        return (t, x, vx, y, vy), mode, 0
    return (t, x, vx, y, vy), Motion.IMPACT, order


def _move_together(bodies: _Bodies, sol: ImpactSolution, state: tuple,
                   stop_at_separation: bool):
    """Moving together (eq 34) from ``state`` to the separation or ``t_end``, recorded in
    ``sol``; after a separation a free flight (or the end, with ``stop_at_separation``).
    Returns (state, motion or None at the end, order)."""
    t, x0, v0, _, _ = state
    sol.together_starts.append((t, x0, v0))
    s_sep = separation_time(bodies.both, bodies.cx, bodies.cv, x0, v0, bodies.t_end - t)
    s_stop = bodies.t_end - t if s_sep is None else s_sep
    sol.phases.append(Phase(Motion.TOGETHER, t, t + s_stop, x0, v0, x0, v0))
    dx, v = bodies.both.scalar_advance(s_stop, x0, v0)
    t, x = t + s_stop, x0 + dx
    state = (t, x, v, x, v)
    if s_sep is None:
        return state, None, 1
    sol.separations.append(Separation(t, x, v))
    if stop_at_separation:
        sol.t_end = t
        return state, None, 1
    # the contact force is zero at a separation, so is the relative acceleration:
    # the gap opens as -N' t^3 / (6 mu) (order 3), whatever round-off left in g2
    return state, Motion.FREE, 3
