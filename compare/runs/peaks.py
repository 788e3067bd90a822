"""When the time of the maximum is not a robust quantity: two records whose x(t) has
near-equal maxima, or a flat top (compare.tree.ladder's 'ambiguous' verdict for t_xmax)."""

from __future__ import annotations

import math

import numpy as np


def other_peak(a: list, b: list, t_a: float, t_b: float) -> bool:
    """Whether two records with several near-equal maxima each (times ``a``, ``b``, s) have
    their largest at different peaks: the peak of ``b`` nearest ``a``'s maximum ``t_a``
    is not ``b``'s maximum ``t_b`` (s)."""
    if len(a) < 2 or len(b) < 2 or not (math.isfinite(t_a) and math.isfinite(t_b)):
        return False
    nearest = min(b, key=lambda t: abs(t - t_a))
    return nearest != min(b, key=lambda t: abs(t - t_b))


def within_top(trajectory, t: float, tau: float) -> bool:
    """Whether the record ``trajectory`` (t, x) at time ``t`` (s) is within the relative
    ``tau`` of its maximum x: x(t) >= (1 - tau) max x, x read off the samples linearly."""
    ts, x = np.asarray(trajectory.t, float), np.asarray(trajectory.x, float)
    if not (math.isfinite(t) and ts.size and ts[0] <= t <= ts[-1]):
        return False
    top = float(np.max(x))
    return top > 0 and float(np.interp(t, ts, x)) >= (1.0 - tau) * top
