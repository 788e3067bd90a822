"""A free flight (eq 13) to the next contact: the first zero of the gap x - y (eq 12) after
an impact, a touch or a separation, by the certified search of :mod:`analytic.impact.roots`
with the gap's derivative bounds and Taylor terms at the start (docs/solver.md, step 2)."""

from __future__ import annotations

from .oscillator import Oscillator
from .roots import first_zero


def next_contact(tree: Oscillator, pend: Oscillator, x0: float, vx0: float, y0: float,
                 vy0: float, order: int, t_max: float, rate: float) -> float | None:
    """Time (s) from the flight's start at which the trunk (oscillator ``tree``, from
    ``x0`` m, ``vx0`` m/s) and the pendulum (``pend``, from ``y0``, ``vy0``) touch again,
    or None if not within ``t_max`` (s). ``order``: the order of the gap's zero at the start
    (1 after an impact, 3 after a separation, 0 for a touch without relative velocity:
    found here from the gap's Taylor terms); ``rate``: the fastest rate of the two (1/s)."""
    tree_adv, pend_adv = tree.scalar_advance, pend.scalar_advance
    # derivative_bounds(x, v) with its n_max = 5, without the call that picks it (hot path)
    tree_bounds, pend_bounds = tree._bounds5, pend._bounds5
    # accelerations and jerks, x'' = -2 beta x' - Omega^2 x (inlined: the hot path)
    b2t, w2t = 2.0 * tree.beta, tree.omega_sq
    b2p, w2p = 2.0 * pend.beta, pend.omega_sq
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

    return first_zero(gap, dgap, t_max, bounds, rate, order=order, taylor=taylor,
                      local_bounds=local_bounds, fdf=gap_slope)
