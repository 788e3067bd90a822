"""Certified search for the *first* zero of a smooth function on (0, t_max]: the next impact
(gap x - y returning to 0, eq 12) and separation (contact force returning to 0, eq 34).
Derivative bounds certify zero-free intervals, so no impact is skipped; the derivation and
the chattering fast path: docs/solver.md.
"""

from __future__ import annotations

import math
from typing import Callable, Sequence

from treeimpact.analytic.errors import SimulationDiverged

_XTOL_REL = 4e-16
#: Bisections one search may take: certifying (0, t_max] takes a few hundred; beyond this the
#: bounds cannot separate the zero from round-off, and the search ends instead of hanging.
MAX_EVALUATIONS = 100_000
_RTOL = 4.0 * 2.220446049250313e-16  # the smallest rtol brentq accepts


def first_zero(f: Callable[[float], float], df: Callable[[float], float], t_max: float,
               bounds: Sequence[float], rate: float, order: int = 0,
               taylor: Sequence[float] = (),
               local_bounds: Callable[[float], Sequence[float]] | None = None,
               fdf: Callable[[float], tuple[float, float]] | None = None) -> float | None:
    """First t in (0, t_max] with f(t) = 0, or None if f > 0 throughout.

    f, df: scalar function and its derivative; bounds[n] >= sup |f^(n)| on [0, t_max]
    (n = 0..order+2); rate: fastest characteristic rate of f (1/s), which sets the first
    sampling step; order: order p of the zero of f at t = 0 (0 if f(0) > 0); taylor:
    the derivatives f^(n)(0), n = 0..order+2, used next to t = 0; local_bounds(t0):
    bounds valid on [t0, t_max] (tighter once a transient has decayed), used for each
    sampling step after the first; fdf(t) -> (f, f'): when given, a zero bracketed on an
    interval where f is certified monotone is polished by bracketed Newton steps instead
    of Brent's method (same tolerance, fewer evaluations).
    """
    if t_max <= 0.0:
        return None
    polish = _polisher(f, fdf)
    if order == 1 and len(taylor) > 3 and taylor[2] < 0.0:
        t_root = _fast_path(f, t_max, bounds, taylor, polish, fdf)
        if t_root is not None:
            return t_root if t_root > 0.0 else None
    search = _bisection(f, df, polish, t_max, order, taylor, bounds)
    step = min(t_max, 0.3 / rate) if rate > 0 else t_max
    b2 = bounds[2]
    ta, fa = 0.0, (taylor[0] if taylor else f(0.0))
    while ta < t_max:
        if ta > 0.0 and local_bounds is not None:
            b2 = min(bounds[2], local_bounds(ta)[2])
        h = step
        if ta > 0.0 and fa > 0.0 and b2 > 0.0:
            # f >= fa - |f'(ta)| h - b2 h^2 / 2 is not known without f', but the certificate
            # min(fa, fb) > b2 h^2 / 8 holds for a step up to sqrt(8 fa / b2) if fb stays
            # near fa: a far gap (the pendulum swung away) is crossed in long steps, and a
            # step too long is bisected by the search as before
            h = max(step, 0.9 * math.sqrt(8.0 * fa / b2))
        tb = min(t_max, ta + h)
        fb = f(tb)
        root = search(ta, tb, fa, fb, b2, 0)
        if root is not None:
            return root
        ta, fa = tb, fb
    return None


def _bisection(f, df, polish, t_max: float, order: int, taylor: Sequence[float],
               bounds: Sequence[float]):
    """The search of one sampling step of :func:`first_zero` (its ``f``, ``df``, ``t_max``,
    ``order``, ``taylor`` and ``bounds``; ``polish``: :func:`_polisher`):
    search(ta, tb, fa, fb, b2, depth) is the first zero in (ta, tb] (f(ta) = fa,
    f(tb) = fb, b2 >= sup |f''| there), or None once the interval is certified zero-free;
    intervals neither certified nor monotone across a sign change are bisected. One
    counter of bisections for the whole search (:data:`MAX_EVALUATIONS`)."""
    lead = taylor[order] / math.factorial(order) if order > 0 else None
    lip = bounds[order + 1] / math.factorial(order + 1) if order > 0 else None

    def certified(ta, tb, fa, fb, b2):
        if ta == 0.0 and order > 0:
            qb = fb / tb ** order
            return lead > 0.0 and qb > 0.0 and lead + qb > lip * tb
        return fa > 0.0 and fb > 0.0 and min(fa, fb) > b2 * (tb - ta) ** 2 / 8.0

    evaluations = [0]

    def search(ta, tb, fa, fb, b2, depth):
        evaluations[0] += 1
        if evaluations[0] > MAX_EVALUATIONS:
            raise SimulationDiverged(
                f"root search: no certified answer after {MAX_EVALUATIONS} bisections "
                f"on (0, {t_max:.3g}] s (a contact the bounds cannot resolve)")
        if fb <= 0.0 and fa > 0.0 and (ta > 0.0 or order == 0):
            dfa = df(ta)
            if dfa < -b2 * (tb - ta):  # strictly decreasing on [ta, tb]: a single zero
                return polish(ta, tb, fa, fb, None)
        elif certified(ta, tb, fa, fb, b2):
            return None
        if tb - ta <= 1e-14 * max(tb, 1e-300) or depth > 200:
            # An interval too small to resolve: f touches zero here (grazing) or crosses it.
            return tb if fb <= 0.0 else (ta if ta > 0.0 and fa <= 0.0 else None)
        tm = 0.5 * (ta + tb)
        fm = f(tm)
        if ta > 0.0 and fa <= 0.0:
            return ta
        left = search(ta, tm, fa, fm, b2, depth + 1)
        if left is not None:
            return left
        return search(tm, tb, fm, fb, b2, depth + 1)

    return search


def _polisher(f, fdf):
    """The zero of f on [a, b] where f(a) > 0 >= f(b) and f is monotone."""
    if fdf is None:
        # lazy: +495 ms at import otherwise (scipy.optimize)
        from scipy.optimize import brentq

        return lambda a, b, fa, fb, guess: brentq(f, a, b, xtol=_XTOL_REL * b, rtol=_RTOL)

    def newton(a, b, fa, fb, guess):
        # Newton steps kept inside the bracket (bisection when a step would leave it); the
        # bracket shrinks at every step, so this terminates like bisection at worst.
        t = guess if guess is not None and a < guess < b else (
            a + (b - a) * fa / (fa - fb) if fa != fb else 0.5 * (a + b))
        for _ in range(200):
            ft, dft = fdf(t)
            if ft == 0.0:
                return t
            if ft > 0.0:
                a = t
            else:
                b = t
            step = ft / dft if dft != 0.0 else math.inf
            t_new = t - step
            if not (a < t_new < b):
                t_new = 0.5 * (a + b)
            if abs(t_new - t) <= _XTOL_REL * b + _RTOL * abs(t_new) or b - a <= _XTOL_REL * b:
                return t_new
            t = t_new
        return 0.5 * (a + b)

    return newton


def _fast_path(f, t_max, bounds, taylor, polish, fdf=None):
    """Single short flight: f = gamma t + f''(0) t^2/2 + ..., f''(0) < 0 (see module doc)."""
    gamma, acc, jerk = taylor[1], taylor[2], taylor[3]
    t_mono = 1.5 * abs(acc) / bounds[3] if bounds[3] > 0 else math.inf
    # Zero of the cubic Taylor model gamma + acc t/2 + jerk t^2/6, smallest positive root.
    t_pred = -2.0 * gamma / acc
    if jerk != 0.0:
        disc = (acc / 2.0) ** 2 - 4.0 * (jerk / 6.0) * gamma
        if disc >= 0.0:
            sq = math.sqrt(disc)
            c1 = (-acc / 2.0 + sq) / (2.0 * jerk / 6.0)
            c2 = (-acc / 2.0 - sq) / (2.0 * jerk / 6.0)
            if c1 > 0.0 and (c1 < c2 or c2 <= 0.0):
                t_pred = c1
            elif c2 > 0.0:
                t_pred = c2
    if fdf is not None and gamma > 0.0:
        t_root = _certified_newton(fdf, t_pred, min(t_mono, t_max), bounds[2])
        if t_root is not None:
            return t_root
    t_hi = min(t_mono, t_max, 1.25 * t_pred)
    if t_hi <= 0.0:
        return None
    f_hi = f(t_hi)
    if f_hi > 0.0:
        if t_hi == t_mono or t_hi == t_max:
            return None  # let the general search decide
        t_hi = min(t_mono, t_max, 4.0 * t_pred)
        f_hi = f(t_hi)
        if f_hi > 0.0:
            return None
    # q = f/t is strictly decreasing on (0, t_hi]: f > 0 left of its single zero.
    t_lo = t_hi * 1e-3
    f_lo = f(t_lo)
    while f_lo <= 0.0:  # only possible if the zero is very close to 0
        t_hi, t_lo = t_lo, t_lo * 1e-3
        if t_lo < 1e-300:
            return None
        f_lo = f(t_lo)
    return polish(t_lo, t_hi, f_lo, f_hi, t_pred)


_NEWTON_TOL = 2.220446049250313e-16  # accept a Newton point once its error bound is below
# this fraction of it (one unit in the last place)


def _certified_newton(fdf, t, t_lim, b2, max_steps=8):
    """The single zero of f on (0, t_lim] by Newton steps from t, certified (module doc).

    Precondition: f = t q(t) with q(0) > 0 strictly decreasing on (0, t_lim], so f has at
    most one zero there and is positive before it. Returns None when no step certifies a
    zero inside (0, t_lim] (the caller then brackets it by sampling).
    """
    if not b2 > 0.0 or not math.isfinite(b2):
        return None
    for _ in range(max_steps):
        if not 0.0 < t <= t_lim:
            return None
        ft, dft = fdf(t)
        if ft == 0.0:
            return t
        if not dft < 0.0:  # before the maximum of f: no Newton certificate here
            return None
        slope = -dft
        d = ft / slope  # > 0: the zero lies right of t; < 0: left of t
        t_new = t + d
        if abs(d) * 2.0 * b2 < slope:  # a sign change between t and t + 2d: certified
            if d > 0.0 and t + 2.0 * d > t_lim:
                return None  # the zero may lie past t_lim, where q is not known monotone
            if 2.0 * b2 * d * d <= _NEWTON_TOL * t_new * slope:
                return t_new
        t = t_new
    return None
