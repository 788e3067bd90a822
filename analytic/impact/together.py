"""Moving together (eq 34): the contact force while the bodies share one motion, whether
touching bodies move together or part, and the separation, where that force reaches zero
(docs/solver.md, step 4)."""

from __future__ import annotations

from treeimpact.analytic.model.two_body import TwoBodyModel

from .events import Motion
from .newton import common_velocity
from .oscillator import Oscillator
from .roots import first_zero


def force_coefficients(model: TwoBodyModel) -> tuple[float, float]:
    """Contact force while moving together, N = cx x + cv v (from eq 34 and eq 13), of the
    two-body ``model``: (cx N/m, cv N s/m).

    N = M_T x'' + C_T x' + K_T x with (M_T + m) x'' = -C_T x' - (K_T + k) x, so
    N = [m C_T x' + (m K_T - M_T k) x] / (M_T + m); compressive while N > 0.
    """
    M, m = model.dynamic_mass, model.impactor_mass
    return ((m * model.equivalent_stiffness - M * model.impactor_stiffness) / (M + m),
            m * model.equivalent_damping / (M + m))


def together_or_part(M: float, m: float, cx: float, cv: float, x: float, vx: float,
                     vy: float) -> tuple[Motion, float, float]:
    """(motion, vx, vy) of bodies touching at ``x`` (m) without approach velocity (trunk of
    dynamic mass ``M`` kg at ``vx`` m/s, pendulum of mass ``m`` kg at ``vy``): moving
    together at their :func:`~analytic.impact.newton.common_velocity` when the contact force
    there, N = ``cx`` x + ``cv`` v (:func:`force_coefficients`), presses them together; else
    parting, the velocities unchanged (a free flight from a touch)."""
    vc = common_velocity(M, m, vx, vy)
    if cx * x + cv * vc > 0.0:
        return Motion.TOGETHER, vc, vc
    return Motion.FREE, vx, vy


def separation_time(both: Oscillator, cx: float, cv: float, x0: float, v0: float,
                    t_max: float) -> float | None:
    """Time (s) after the start of a moving-together phase at (``x0`` m, ``v0`` m/s) of the
    joint oscillator ``both`` at which the contact force N = ``cx`` x + ``cv`` v reaches
    zero, or None if not within ``t_max`` (s). N solves the joint motion's equation (eq 34)
    itself: its first zero in closed form (:meth:`Oscillator.first_zero`), or by the
    certified search when N is not compressive at the start (round-off)."""
    f0 = cx * x0 + cv * v0
    if f0 > 0.0:
        s_sep = both.first_zero(f0, cx * v0 + cv * both.acceleration(x0, v0))
        return s_sep if s_sep <= t_max else None
    return _separation_search(both, cx, cv, x0, v0, f0, t_max)


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
