"""How a small-e curve is read: the first crossing of the tolerance bracketed by bisection,
whether the curve is monotone before it, the bracket as printed, the verdict's words, and
for a gap that is there at e = 0, from which e it moves away from its e = 0 value. Pure
functions of the (e, error) points; e in 1, errors relative. docs/report.md ("The small-e
curves").
"""

from __future__ import annotations

import math

#: How finely the crossing of the tolerance is located (1, in e): the bracket [lo, hi]
#: printed is at most this wide.
RESOLUTION = 0.005
#: How far (relative error) |error| may fall between two grid points before its first exit
#: and the curve still count as monotone there (round-off of the procedure's sampled
#: reading: its T0 moves by a sample, 20 us, between neighbouring e).
MONOTONE_SLACK = 0.005


def first_crossing(grid, values, evaluate, tolerance: float,
                   resolution: float = RESOLUTION) -> tuple[float, tuple | None]:
    """The largest e up to which an error STAYS within ``tolerance`` (|error| <= it; NaN is
    outside), from its ``values`` on the ``grid`` of e: 0 when the first value is outside,
    the grid's end when none is; else the
    first crossing from e = 0, bracketed by the grid and bisected with ``evaluate(e)``
    until the bracket is at most ``resolution`` wide. Returns (the bracket's inner end, the
    bracket or None). A later return inside the tolerance does not count; an excursion
    narrower than the grid's step is not seen (docs/report.md: the convergence check)."""
    def within(v):
        return math.isfinite(v) and abs(v) <= tolerance

    if not within(values[0]):
        return 0.0, None
    for i in range(1, len(grid)):
        if not within(values[i]):
            lo, hi = float(grid[i - 1]), float(grid[i])
            while hi - lo > resolution:
                mid = 0.5 * (lo + hi)
                if within(evaluate(mid)):
                    lo = mid
                else:
                    hi = mid
            return lo, (lo, hi)
    return float(grid[-1]), None


def monotone_until(points, hi: float) -> bool:
    """Whether |error| of the (e, error) ``points`` never falls by more than MONOTONE_SLACK
    from one e to the next up to ``hi`` (the first exit's bracket end): a crossing of a
    curve that is not is no threshold."""
    mags = [abs(v) for e, v in points if e <= hi + 1e-12 and math.isfinite(v)]
    return all(b >= a - MONOTONE_SLACK for a, b in zip(mags, mags[1:]))


def bracket_text(bracket) -> str:
    """The bracket [lo, hi] of a crossing as printed, rounded outward to 0.001:
    '0.375-0.380'."""
    lo, hi = bracket
    return f"{math.floor(1000 * lo + 1e-6) / 1000:.3f}-{math.ceil(1000 * hi - 1e-6) / 1000:.3f}"


def verdict(holds, bracket, at_zero, grid, tol, monotone=True, strike_from=None) -> str:
    """The curve's verdict in words from :func:`first_crossing`'s (``holds``, ``bracket``),
    its error ``at_zero``, the ``grid``, the tolerance ``tol``, whether it is ``monotone``
    before its first exit and ``strike_from``, the e a counted second strike starts from (or
    None)."""
    if holds == 0.0 and bracket is None:
        if not math.isfinite(at_zero):
            return "no value at e = 0"
        return f"not a small-e effect: {100 * at_zero:+.0f} % at e = 0"
    if bracket is None:
        return f"within {100 * tol:.0f} % over the whole range (e <= {grid[-1]:g})"
    text = f"crosses {100 * tol:.0f} % at e = {bracket_text(bracket)}"
    if not monotone:
        text = f"not monotone before it first leaves {100 * tol:.0f} % (at e = " \
               f"{bracket_text(bracket)}): no threshold"
    if strike_from is not None:
        text += f"; counts a second strike from e = {strike_from:g}"
    return text




def steady_bracket(grid, values, evaluate, tolerance: float) -> tuple[float, tuple | None]:
    """For a gap already there at e = 0 (a 1-DOF trunk's), the largest e up to which it stays
    within ``tolerance`` (relative, as points: 0.05 is 5 points of %) of its e = 0 value,
    read like :func:`first_crossing` on ``values`` (on the ``grid`` of e) minus
    ``values[0]``, bisected with ``evaluate(e)``: (inner end, bracket or None). Up to there the trunk, not e, sets the gap; beyond it e moves it too."""
    v0 = values[0]
    if not math.isfinite(v0):
        return 0.0, None
    return first_crossing(grid, [v - v0 for v in values], lambda e: evaluate(e) - v0,
                          tolerance)


def steady_text(steady, tol: float) -> str:
    """The words for :func:`steady_bracket`'s result (``steady``: (inner end, bracket)) at
    the tolerance ``tol`` (relative)."""
    holds, bracket = steady
    if bracket is None:
        return f"within {100 * tol:.0f} points of it over the whole range of e"
    return f"e moves it by more than {100 * tol:.0f} points from e = {bracket_text(bracket)}"
