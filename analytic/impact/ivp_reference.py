"""An independent, conventional solution of the same model: scipy ``solve_ivp`` with events.

It integrates eq 13 numerically (DOP853 at tight tolerances), stops at every gap closure
(eq 12) to apply eqs 20-21, switches to eq 34 when the relative velocity left by an impact
falls below ``gamma_tol`` (the usual threshold of an event-driven integrator: it cannot
resolve infinitely many impacts), separates when the contact force of eq 34 reaches zero,
and goes on to ``t_end``. Used to cross-check :mod:`analytic.impact.solver` in the tests and as
the baseline of ``benchmarks/bench_solver.py``.
"""

from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp

from treeimpact.analytic.model.two_body import TwoBodyModel

from .events import Motion


def solve_ivp_impacts(model: TwoBodyModel, t_end: float, *, rtol: float = 1e-12,
                      gamma_tol: float = 1e-7, stop_at_separation: bool = False,
                      atol: tuple[float, float, float, float] = (1e-15, 1e-12, 1e-15, 1e-12)
                      ) -> dict:
    """Impacts [(t, U, u, V, v)], together start (t, x, V), separations [(t, x, v)] of
    ``model`` integrated to ``t_end`` (s) (SI: s, m, m/s).

    rtol, atol: DOP853 tolerances (atol per state component x, x', y, y'; the default
    1e-15 m on positions, not rtol, sets the accuracy of the impact times at rtol <~ 1e-12).
    ``gamma_tol``: the relative velocity after an impact, in units of u_1, below which the
    bodies move together; ``stop_at_separation``: end at the first separation.
    """
    free, together, gap, force = _equations(model)
    u1 = model.impact_speed
    atol = list(atol)

    def integrate(rhs, t0, t1, s0, event=None):  # DOP853 at the tolerances asked for
        return solve_ivp(rhs, (t0, t1), s0, method="DOP853", rtol=rtol, atol=atol,
                         **({} if event is None else {"events": event}))

    out = {"impacts": [], "together": [], "separations": []}
    t, s = 0.0, np.array([0.0, 0.0, 0.0, u1])
    mode = Motion.IMPACT
    while t < t_end:
        if mode is Motion.IMPACT:
            s, mode, (V, v) = _impact(model, out, t, s, gamma_tol * u1, force)
            if mode is Motion.FREE:
                t_skip = min(t_end, t + _contact_skip(model, s[0], V, v))
                t, s = t_skip, integrate(free, t, t_skip, s).y[:, -1]
            continue
        rhs, event = (free, gap) if mode is Motion.FREE else (together, force)
        sol = integrate(rhs, t, t_end, s, event)
        if sol.t_events[0].size == 0:
            t, s = t_end, sol.y[:, -1]
            break
        t, s = sol.t_events[0][0], sol.y_events[0][0]
        if mode is Motion.FREE:
            mode = Motion.IMPACT
        else:
            out["separations"].append((t, s[0], s[1]))
            if stop_at_separation:
                break
            mode = Motion.FREE
            t_skip = min(t_end, t + 1e-9)
            t, s = t_skip, integrate(free, t, t_skip, s).y[:, -1]
    out["final"] = (t, s)
    return out


def _equations(model: TwoBodyModel):
    """The right-hand sides of ``model``'s free flight (eq 13) and joint motion (eq 34) and
    the terminal events of each: the gap x - y (eq 12) and the contact force N (eq 34)
    falling through zero; state (x, x', y, y')."""
    M, C, K = model.dynamic_mass, model.equivalent_damping, model.equivalent_stiffness
    m, k = model.impactor_mass, model.impactor_stiffness

    def free(_t, s):
        return [s[1], (-K * s[0] - C * s[1]) / M, s[3], -k * s[2] / m]

    def together(_t, s):
        acc = (-(K + k) * s[0] - C * s[1]) / (M + m)
        return [s[1], acc, s[3], acc]

    def gap(_t, s):
        return s[0] - s[2]

    def force(_t, s):
        return ((m * K - M * k) * s[0] + m * C * s[1]) / (M + m)

    gap.terminal, gap.direction = True, -1.0
    force.terminal, force.direction = True, -1.0
    return free, together, gap, force


def _impact(model: TwoBodyModel, out: dict, t: float, s: np.ndarray, gamma_min: float,
            force):
    """A Newton impact (eqs 20-21) at time ``t`` (s) and state ``s``, recorded in ``out``:
    (the state after it, the motion that follows, the separation velocities (V, v) m/s):
    moving together when the relative
    velocity left is below ``gamma_min`` (m/s) and the contact ``force`` compressive (the
    start recorded), else a free flight."""
    M, m, e = model.dynamic_mass, model.impactor_mass, model.restitution
    U, u = s[1], s[3]
    v = ((m - M * e) * u + M * (1 + e) * U) / (M + m)
    V = v + e * (u - U)
    out["impacts"].append((t, U, u, V, v))
    s = np.array([s[0], V, s[0], v])
    if V - v < gamma_min:
        vc = (M * V + m * v) / (M + m)
        s = np.array([s[0], vc, s[0], vc])
        if force(t, s) > 0:
            out["together"].append((t, s[0], vc))
            return s, Motion.TOGETHER, (V, v)
    return s, Motion.FREE, (V, v)


def _contact_skip(model: TwoBodyModel, x: float, V: float, v: float) -> float:
    """How long (s) a free flight from contact at ``x`` (m) with separation velocities ``V``
    (trunk) and ``v`` (pendulum, m/s) runs before the gap is watched again: it starts at
    zero, and within round-off of the positions an event would fire at once. A thousandth
    of the flight 2 gamma / |a_rel| predicted under constant relative acceleration, at most
    1 ns."""
    M, C, K = model.dynamic_mass, model.equivalent_damping, model.equivalent_stiffness
    m, k = model.impactor_mass, model.impactor_stiffness
    a_rel = (-K * x - C * V) / M + k * x / m
    flight = 2.0 * (V - v) / -a_rel if a_rel < 0 else 1e-6
    return min(1e-9, 1e-3 * flight)
