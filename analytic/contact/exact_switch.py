"""The ``exact`` method's switches: the time a phase ends inside the bracket its samples
give, each root by Halley's method on the exact solution of the phase (the rule of
:mod:`.phases`). SI units; design notes: docs/beam-impact.md.
"""

from __future__ import annotations

import math

import numpy as np

from .phases import ContactPhase, Signal, bracket, switch

_EPS = float(np.finfo(float).eps)
#: A switch time is refined until Newton's (Halley's) step is below this (s), plus 4 eps of
#: the time itself.
_ROOT_TOL = 1e-15


def locate(kind: ContactPhase, st, wk: np.ndarray, s_lo: float, s_hi: float,
           d_hi: float, f_hi: float, lo_values: tuple | None,
           flight: tuple[float, float] = (0.0, 0.0)):
    """(time into the phase, next phase) of the switch bracketed by [``s_lo``, ``s_hi``]
    (s; :func:`.phases.switch`, ``d_hi`` and ``f_hi`` the gap delta, m, and the law, N, at
    ``s_hi``) of the ``kind`` phase started with the kept modal coefficients ``wk``
    on the state ``st`` (its kept eigenvalues ``lam`` and law rows ``law``, m x 6), each
    root by Halley's method on the exact solution's delta and law with their first two
    derivatives; ``lo_values``: (delta, law) at s_lo from the samples, or
    None (s_lo the phase's start: evaluated, and bracketed by :func:`.phases.bracket`);
    ``flight``: the rates (m/s, N/s) a rigid mode's flight adds to delta and the law."""
    lam = st.lam
    # m x 6: (delta, F, delta', F', delta'', F'') = Re(exp(lambda s) @ c)
    c = wk[:, None] * st.law
    exp, dot = np.exp, np.dot
    d_rate, f_rate = float(flight[0]), float(flight[1])
    last = [None, None]  # the last evaluation: s, its six values

    def values(s):
        v = last[1] if s == last[0] else dot(exp(lam * s), c).real.tolist()
        last[0], last[1] = s, v
        return v

    def delta(s):
        v = values(s)
        return v[0] + d_rate * s, v[2] + d_rate, v[4]

    def law(s):
        v = values(s)
        return v[1] + f_rate * s, v[3] + f_rate, v[5]

    def delta_at(s):
        """delta at s: at a root within a Newton step of the last evaluation, its value
        carried there by its slope (the step is below 1e-15 s: its square is round-off)."""
        if last[0] is not None and s != last[0] and abs(s - last[0]) <= _ROOT_TOL:
            v = last[1]
            return v[0] + d_rate * last[0] + (v[2] + d_rate) * (s - last[0])
        return delta(s)[0]

    d_lo, f_lo = lo_values if lo_values is not None else (None, None)

    def root(signal):
        if signal is Signal.DELTA:
            return _halley_root(delta, s_lo, s_hi, d_hi, d_lo)
        return _halley_root(law, s_lo, s_hi, f_hi, f_lo)

    return switch(kind, root, delta_at, d_hi, f_hi)


def _halley_root(fun, lo: float, hi: float, f_hi: float, f_lo: float | None = None
                 ) -> float:
    """Zero of ``fun`` (returning value, slope and curvature) in [lo, hi], ``f_hi`` its
    value at hi (``f_lo`` at lo, if known): a phase that starts on its own boundary (value 0
    at lo) is bracketed from just after its start; then Halley's steps (Newton's where its
    denominator vanishes) inside the shrinking bracket (bisection otherwise), to
    :data:`_ROOT_TOL` (s) and 4 eps of the time: done when a step or the bracket is below
    that."""
    if f_lo is not None and f_lo * f_hi <= 0 and f_lo != 0.0:
        found = lo, f_lo  # what bracket() returns for a sign change at lo
    else:
        found = bracket(lambda u: fun(u)[0], lo, hi, f_hi)
    if found is None:
        return hi
    lo, f_lo = found
    s = lo - f_lo * (hi - lo) / (f_hi - f_lo)
    tol = _ROOT_TOL + 4 * _EPS * abs(hi)
    for _ in range(100):
        f, slope, curve = fun(s)
        if f == 0.0:
            return s
        if (f > 0.0) == (f_lo > 0.0):
            lo, f_lo = s, f
        else:
            hi = s
        denom = 2.0 * slope * slope - f * curve
        step = (2.0 * f * slope / denom if denom != 0.0 else
                f / slope if slope != 0.0 else math.inf)
        if abs(step) <= tol:  # converged: the correction is below the tolerance (or below
            return min(max(s - step, lo), hi)  # a unit of s, where a bisection would restart)
        nxt = s - step
        if not lo < nxt < hi:
            nxt = 0.5 * (lo + hi)
        if abs(nxt - s) <= tol or hi - lo <= tol:
            return nxt
        s = nxt
    return s
