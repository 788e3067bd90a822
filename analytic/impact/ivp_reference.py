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
    M, C, K = model.dynamic_mass, model.damping, model.stiffness
    m, k, e = model.impactor_mass, model.impactor_stiffness, model.restitution
    u1 = model.impact_speed
    atol = list(atol)

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

    out = {"impacts": [], "together": [], "separations": []}
    t, s = 0.0, np.array([0.0, 0.0, 0.0, u1])
    mode = Motion.IMPACT
    while t < t_end:
        if mode is Motion.IMPACT:
            U, u = s[1], s[3]
            v = ((m - M * e) * u + M * (1 + e) * U) / (M + m)
            V = v + e * (u - U)
            out["impacts"].append((t, U, u, V, v))
            s = np.array([s[0], V, s[0], v])
            if V - v < gamma_tol * u1:
                vc = (M * V + m * v) / (M + m)
                s = np.array([s[0], vc, s[0], vc])
                if force(t, s) > 0:
                    mode = Motion.TOGETHER
                    out["together"].append((t, s[0], vc))
                    continue
            mode = Motion.FREE
            # Leave the contact before watching the gap again: it starts at zero, and within
            # round-off of the positions an event would fire at once. Skip a thousandth of
            # the flight 2 gamma / |a_rel| predicted under constant relative acceleration.
            a_rel = (-K * s[0] - C * V) / M + k * s[0] / m
            flight = 2.0 * (V - v) / -a_rel if a_rel < 0 else 1e-6
            t_skip = min(t_end, t + min(1e-9, 1e-3 * flight))
            sol = solve_ivp(free, (t, t_skip), s, method="DOP853", rtol=rtol, atol=atol)
            t, s = t_skip, sol.y[:, -1]
            continue
        rhs, event = (free, gap) if mode is Motion.FREE else (together, force)
        sol = solve_ivp(rhs, (t, t_end), s, method="DOP853", rtol=rtol, atol=atol,
                        events=event)
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
            sol = solve_ivp(free, (t, t_skip), s, method="DOP853", rtol=rtol, atol=atol)
            t, s = t_skip, sol.y[:, -1]
    out["final"] = (t, s)
    return out
