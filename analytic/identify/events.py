"""The events the paper's procedure reads off a displacement record (eqs 39-43), found
against the record's own noise: the resting level and the noise (from the rest before the
contact, else from the record's high-pass residual), the slope increases that are impacts
(the first contact, the last one: the bodies move together) and the peak x_max.

A threshold is a multiple of the noise estimated apart from the event it finds, so an event
the noise could have made is not reported, and a record that cannot show one is refused
(ParameterError "not identifiable: ...") rather than read. On a record without noise every
event is where the sample-to-sample reading puts it. docs/identification.md, "The paper's
procedure". SI units.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from treeimpact.analytic.errors import ParameterError

from .noise import MIN_REST_SAMPLES, NoiseSource
from .record_features import robust_sigma

#: False alarms allowed per record: a slope increase is an impact when the noise alone would
#: make one as large at any of the record's samples with this probability (Bonferroni).
FALSE_ALARM = 1e-3
#: The longest stretch (s) a slope is read over on each side of a kink: well inside the
#: impact process the paper reports (under 5 ms) and a tree's quarter period (about 20 ms).
MAX_SLOPE_SPAN = 2e-3
#: A kink read over more than one sample is placed where the lines through this many times
#: as many samples on each side cross.
HINGE_SPANS = 2
#: A kink's jump is read against the median jump within this many spans on each side (its
#: own span left out): the curvature of the motion around it (:func:`curvature_free`).
CURVATURE_SPANS = 4
#: Of a slope increase less that median, the standard deviation over the increase's own
#: on white noise, with a margin: measured 0.99-1.01 on 2e5 samples at spans 1-10 (the
#: jumps' negative correlation with their neighbours offsets the median's own noise;
#: tests/test_identify_procedure_events.py).
CURVATURE_NOISE = 1.05
#: How far (of x_max) the pendulum's record may be off the trunk's while they move
#: together (a record of y with x's kinks sampled a little apart); parted bodies are off
#: by tens of per cent.
TOGETHER_GAP = 0.01
#: The peak is fitted over the samples within this many noise deviations of it.
PEAK_DEPTH = 10.0
#: Of white noise, the variance of the third difference over sigma^2 (1 + 9 + 9 + 1).
THIRD_DIFFERENCE_VARIANCE = 20.0
#: The rest's spread over the high-pass noise beyond which the noise is not white (its
#: samples correlated: the high-pass reading misses most of it) and the rest's is used: a
#: ratio white noise's 12-sample rest passes one time in about 1e6.
COLOURED_NOISE = 2.0
#: How far (of the record's span) a line through the rest may move over it and still be a
#: rest (a sensor's slow drift), not the motion of a record that starts after the contact.
REST_DRIFT = 0.01


@dataclass(frozen=True)
class RecordNoise:
    """The record's noise ``sigma`` (m) the events are found against and where it came from
    (``source``), its resting ``baseline`` (m, the mean of the rest before the first impact;
    0, the sensor's zero, without MIN_REST_SAMPLES of it) and the ``rest_samples``."""

    sigma: float
    source: NoiseSource
    baseline: float = 0.0
    rest_samples: int = 0


@dataclass(frozen=True)
class Impacts:
    """The slope increases that stand above the noise: their ``times`` (s, ascending), the
    ``span`` of samples the slope is read over on each side, and the ``threshold`` (m/s) a
    jump had to pass there."""

    times: np.ndarray
    span: int
    threshold: float


def highpass_noise(x: np.ndarray) -> float:
    """The noise (standard deviation, m) of ``x`` (m) from its third differences, robustly
    (their median absolute deviation): a motion sampled at omega dt << 1 adds only
    (omega dt)^3 of its amplitude (1 % of 1 % noise at 1 kHz for a tree's 80 rad/s), an
    impact's kink moves a few of them."""
    d3 = np.diff(np.asarray(x, float), 3)
    return robust_sigma(d3) / math.sqrt(THIRD_DIFFERENCE_VARIANCE) if d3.size else math.nan


def moves(t: np.ndarray, x: np.ndarray, sel: np.ndarray, sigma: float) -> bool:
    """Whether the samples ``sel`` of ``x`` (m, at ``t`` s) are in motion, not at rest: a line
    through them moves, over them, by more than REST_DRIFT of the record's span and 5 of
    its standard errors on noise ``sigma`` (m)."""
    n = int(np.count_nonzero(sel))
    ts = t[sel] - t[sel].mean()
    drift = abs(float(np.polyfit(ts, x[sel], 1)[0]) * (ts[-1] - ts[0]))
    return drift > max(REST_DRIFT * float(np.ptp(x)), 5.0 * sigma * math.sqrt(12.0 / n))


def rest_before(t: np.ndarray, x: np.ndarray, impacts: Impacts, sigma: float
                ) -> np.ndarray | None:
    """The samples of ``x`` (m, at ``t`` s) at rest before the first of the ``impacts``
    (``span`` + 1 samples of margin: the kink's reading), or None when fewer than
    MIN_REST_SAMPLES or in motion (:func:`moves` on noise ``sigma``, m: a record that
    starts after the contact)."""
    dt = float(np.median(np.diff(t)))
    sel = t < float(impacts.times[0]) - (impacts.span + 1) * dt
    if np.count_nonzero(sel) < MIN_REST_SAMPLES or moves(t, x, sel, sigma):
        return None
    return sel


def rest_of(x: np.ndarray, rest: np.ndarray | None, sigma: float,
            source: NoiseSource) -> RecordNoise:
    """The :class:`RecordNoise` of ``x`` (m) with the noise ``sigma`` (m, from ``source``)
    and the samples at ``rest`` (:func:`rest_before`): their mean (those beyond 5 sigma
    of their median left out) is the baseline; without a rest the baseline is 0."""
    if rest is None:
        return RecordNoise(sigma, source, 0.0, 0)
    r = x[rest]
    keep = np.abs(r - np.median(r)) <= 5.0 * sigma if sigma > 0 else np.ones(r.size, bool)
    return RecordNoise(sigma, source, float(np.mean(r[keep])), int(r.size))


def find_events(t: np.ndarray, x: np.ndarray, jump_fraction: float
                ) -> tuple[RecordNoise, Impacts]:
    """The noise and resting level (:class:`RecordNoise`) and the impacts
    (:func:`slope_increases`, above ``jump_fraction`` of the largest slope) of the record
    ``x`` (m, at ``t`` s). The thresholds come from the high-pass noise of the whole record
    (:func:`highpass_noise`: no event moves it, however long the rest), or from the rest's
    spread about a line where that is COLOURED_NOISE times more (a correlated noise); the
    rest before the first impact gives the baseline."""
    sigma, source = highpass_noise(x), NoiseSource.DIFFERENCES
    impacts = slope_increases(t, x, sigma, source, jump_fraction)
    rest = rest_before(t, x, impacts, sigma)
    if rest is not None:
        ts = t[rest] - t[rest].mean()
        r = x[rest] - np.polyval(np.polyfit(ts, x[rest], 1), ts)
        rest_sigma = robust_sigma(r)
        if rest_sigma > COLOURED_NOISE * sigma:
            sigma, source = rest_sigma, NoiseSource.REST
            impacts = slope_increases(t, x, sigma, source, jump_fraction)
            rest = rest_before(t, x, impacts, sigma)
    return rest_of(x, rest, sigma, source), impacts


def window_slopes(t: np.ndarray, x: np.ndarray, span: int) -> np.ndarray:
    """The least-squares slope (m/s) of ``x`` (m, at times ``t``, s) over samples j..j+``span``,
    for every j."""
    if span == 1:
        return np.diff(x) / np.diff(t)
    tw = np.lib.stride_tricks.sliding_window_view(t, span + 1)
    xw = np.lib.stride_tricks.sliding_window_view(x, span + 1)
    tc = tw - tw.mean(axis=1, keepdims=True)
    return np.sum(tc * (xw - xw.mean(axis=1, keepdims=True)), axis=1) / np.sum(tc * tc, axis=1)


def jump_noise(sigma: float, dt: float, span: int) -> float:
    """The standard deviation (m/s) of a slope increase read over ``span`` samples on each
    side of a kink (the two lines share it), on white noise ``sigma`` (m) sampled every
    ``dt`` (s): sigma sqrt(2 / S + span^2 dt^2 / (2 S^2)), S = dt^2 m (m^2 - 1) / 12,
    m = span + 1 (span 1: sqrt(6) sigma / dt)."""
    m = span + 1
    s = dt * dt * m * (m * m - 1) / 12.0
    return sigma * math.sqrt(2.0 / s + span * span * dt * dt / (2.0 * s * s))


def curvature_free(jumps: np.ndarray, span: int) -> np.ndarray:
    """The slope increases ``jumps`` (m/s, one per sample) less the motion's own curvature
    there (a x'' read over ``span`` samples: a span dt): the median of the jumps within
    CURVATURE_SPANS ``span`` samples on each side, the kink's own samples left out, so a
    kink on a decelerating trunk (the impacts of the chattering, eq 33: their jumps shrink
    like e^i, below the deceleration's a dt for small e) stands out by its own size. The
    record's end values are repeated beyond it (so within CURVATURE_SPANS spans of a
    record's start the reading is biased: :func:`slope_increases`)."""
    w, n = CURVATURE_SPANS * span, jumps.size
    if n <= 2 * (w + span):
        return jumps
    pad = np.pad(jumps, w, mode="edge")
    win = np.lib.stride_tricks.sliding_window_view(pad, 2 * w + 1)
    keep = np.r_[np.arange(w - span), np.arange(w + span + 1, 2 * w + 1)]
    return jumps - np.median(win[:, keep], axis=1)


def _kinks(t, x, span, threshold):
    s = window_slopes(t, x, span)
    jumps = curvature_free(s[span:] - s[:-span], span)  # jumps[k]: the kink at k + span
    idx = np.nonzero(jumps > threshold)[0]
    if idx.size == 0:
        return np.array([]), float(np.max(jumps))
    # Merge the samples of one jump (a slope read over ``span`` samples parts no kinks
    # closer than that); report the sample at the kink.
    groups = np.split(idx, np.nonzero(np.diff(idx) > span)[0] + 1)
    kinks = [int(g[np.argmax(jumps[g])]) + span for g in groups]
    return np.array([hinge(t, x, k, span) for k in kinks]), float(np.max(jumps))


def hinge(t: np.ndarray, x: np.ndarray, k: int, span: int) -> float:
    """The time (s) of a kink found at sample ``k`` of ``x`` (m, at ``t`` s) read over
    ``span`` samples: that sample's time for a one-sample reading (a record without
    noise), else where the lines through the HINGE_SPANS ``span`` samples on each side
    (the kink's own left out) cross, within a sample of ``k``: a reading over more
    samples no longer moves the kink by a sample."""
    if span == 1:
        return float(t[k])
    w = HINGE_SPANS * span
    lo, hi = max(0, k - w), min(t.size, k + w + 1)
    if k - lo < 2 or hi - k - 1 < 2:
        return float(t[k])
    left = np.polyfit(t[lo:k] - t[k], x[lo:k], 1)
    right = np.polyfit(t[k + 1:hi] - t[k], x[k + 1:hi], 1)
    if not right[0] > left[0]:
        return float(t[k])
    crossing = (left[1] - right[1]) / (right[0] - left[0])
    return float(t[k] + np.clip(crossing, t[k - 1] - t[k], t[k + 1] - t[k]))


def slope_increases(t: np.ndarray, x: np.ndarray, sigma: float, source: NoiseSource,
                    jump_fraction: float) -> Impacts:
    """The impacts of the record ``x`` (m, at ``t`` s): slope increases larger than
    ``jump_fraction`` of the largest slope and than white noise ``sigma`` (m, from
    ``source``) would make anywhere in the record but with probability FALSE_ALARM, read
    over the fewest samples on each side (up to MAX_SLOPE_SPAN, and no more than it takes
    the noise's jump below the fraction's) at which any stands out. A record already rising
    at its start (the slope of its first three samples above z times its noise,
    sigma / (sqrt(2) dt): no rest recorded) has its first contact at its first sample,
    before the impacts found later; a record with neither raises ParameterError "not
    identifiable"."""
    dt = float(np.median(np.diff(t)))
    # lazy: +830 ms at import otherwise (scipy.stats)
    from scipy.stats import norm

    z = float(norm.isf(FALSE_ALARM / t.size))
    # No rest: a record already rising at its first samples starts at the contact.
    rising = float(window_slopes(t[:3], x[:3], 2)[0]) > z * sigma * math.sqrt(0.5) / dt
    largest, widest = -math.inf, 1
    for span in range(1, max(1, min(int(MAX_SLOPE_SPAN / dt), (t.size - 1) // 2)) + 1):
        slope_max = float(np.max(window_slopes(t, x, span)))
        noise_jump = z * CURVATURE_NOISE * jump_noise(sigma, dt, span)
        threshold = max(jump_fraction * slope_max, noise_jump)
        times, top = _kinks(t, x, span, threshold)
        if times.size and rising:  # its first contact at t[0]; a kink within two spans
            # of it is that contact's own onset read against the edge's repeated values
            # (the pad's records: samples 1-2), not a second impact (the exact records'
            # second impact comes 3 samples later at e = 0.0025 and 20 us)
            times = np.concatenate([[float(t[0])], times[
                times > t[min(2 * span, t.size - 1)]]])
        if times.size:
            return Impacts(times, span, threshold)
        if top / threshold > largest:
            largest, widest = top / threshold, span
        if noise_jump <= jump_fraction * slope_max:
            break  # the noise no longer sets the threshold: a longer reading only blurs
    if rising:
        return Impacts(np.array([float(t[0])]), 1, jump_fraction * float(np.max(
            window_slopes(t, x, 1))))
    raise ParameterError(
        "not identifiable: no slope increase stands above the noise (the largest is "
        f"{largest:.2g} of its threshold, read over {widest} samples a side; noise "
        f"{sigma:.3g} m from the {source.value}): no impact to start from")


def impact_sequence(times: np.ndarray, t_first: float, t_max: float, dt: float,
                    search_time: float) -> np.ndarray:
    """The impact sequence of the paper's procedure among the impacts at ``times`` (s): the
    first (``t_first``) and the ones after it whose gaps shrink (eq 33: each impact's
    separation speed is e (M_T + m) / (M_T (1 + e)) of the last's, so is the gap), every
    one before the peak (``t_max``, s) or within ``search_time`` (s) of the first; its last
    is where the bodies move together. A gap longer than the one before by more than two
    samples (``dt``, s: the kinks' placement) is a second strike after the bodies parted.
    ParameterError "not identifiable" when one comes before x_max (eqs 35-38 need the bodies
    together from the last impact to the peak) or the sequence runs on to the peak."""
    cand = times[(times >= t_first) & ((times <= t_first + search_time) | (times < t_max))]
    gaps = np.diff(cand)
    grow = np.nonzero(gaps[1:] > gaps[:-1] + 2.0 * dt)[0]
    if grow.size:
        i = int(grow[0]) + 2
        raise ParameterError(
            f"not identifiable: a second strike {1e3 * (cand[i] - cand[i - 1]):.3g} ms after "
            f"the impact at {1e3 * (cand[i - 1] - t_first):.3g} ms, before x_max (the gap "
            "grew: the bodies had parted; eqs 35-38 need them together up to the peak)")
    if cand[-1] >= t_max - dt:
        raise ParameterError(
            f"not identifiable: the impacts run on to the peak ({1e3 * (cand[-1] - t_first):.3g}"
            " ms after the first): the bodies do not move together before x_max")
    return cand


def moving_together(t: np.ndarray, x: np.ndarray, y: np.ndarray, t_together: float,
                    t_max: float, sigma: float) -> None:
    """Raises ParameterError "not identifiable" unless the pendulum's record ``y`` (m, the
    trunk's frame) follows the trunk's ``x`` (m, both at ``t`` s) over the second half of
    the way from ``t_together`` to the peak at ``t_max`` (s): within TOGETHER_GAP of the
    peak plus 5 noise deviations (``sigma`` m of each channel), else the bodies have parted
    (the single impact of a bouncy pad, a rebound before the peak)."""
    sel = (t >= 0.5 * (t_together + t_max)) & (t <= t_max)
    if not np.any(sel):
        return
    gap = float(np.max(np.abs(y[sel] - x[sel])))
    tol = TOGETHER_GAP * float(np.max(x[sel])) + 5.0 * (sigma + highpass_noise(y))
    if gap > tol:
        raise ParameterError(
            f"not identifiable: the bodies do not move together before x_max (the pendulum "
            f"is {1e3 * gap:.3g} mm off the trunk on the way to the peak, above "
            f"{1e3 * tol:.3g} mm)")


def _vertex(t, x, sel):
    """(t, x) at the vertex of the least-squares parabola through x[sel], or None."""
    tc = t[sel] - t[sel].mean()
    c2, c1, c0 = np.polyfit(tc, x[sel], 2)
    if not c2 < 0:
        return None, c2
    dt = -c1 / (2.0 * c2)
    return (float(t[sel].mean() + dt), float(c0 + c1 * dt + c2 * dt * dt)), c2


def _three_point_peak(t, x, i):
    x_max, t_max = float(x[i]), float(t[i])
    if 0 < i < x.size - 1:  # parabola through the three samples around the maximum
        h0, h1 = t[i] - t[i - 1], t[i + 1] - t[i]
        d0, d1 = (x[i] - x[i - 1]) / h0, (x[i + 1] - x[i]) / h1
        curv = (d1 - d0) / (0.5 * (h0 + h1))
        if curv < 0:
            dt = -(0.5 * (d0 + d1)) / curv
            dt = float(np.clip(dt, -h0, h1))
            t_max = float(t[i] + dt)
            x_max = float(x[i] + 0.5 * (d0 + d1) * dt + 0.5 * curv * dt * dt)
    return t_max, x_max


def peak(t: np.ndarray, x: np.ndarray, sigma: float) -> tuple[float, float]:
    """(t_max s, x_max m) of the record ``x`` (m, at ``t`` s; baseline removed) with noise
    ``sigma`` (m): the parabola through the three samples around the largest where fewer
    than 5 samples lie within PEAK_DEPTH sigma of it (a record without noise), else the
    least-squares parabola over the samples within PEAK_DEPTH sigma of the peak (twice: the
    second time chosen by time around the first vertex, not by the noisy values). Raises
    ParameterError "not identifiable" when the record ends before its peak."""
    i = int(np.argmax(x))
    if i == x.size - 1:
        raise ParameterError("not identifiable: the record ends on its rise (its largest "
                             "sample is the last): no x_max")
    depth = PEAK_DEPTH * sigma
    lo, hi = _contiguous(x, i, x[i] - depth) if depth > 0 else (i, i)
    if hi - lo + 1 < 5:
        return _three_point_peak(t, x, i)
    if hi == x.size - 1:
        raise ParameterError("not identifiable: the record ends within its peak's noise "
                             f"({sigma:.3g} m): no x_max")
    first, c2 = _vertex(t, x, np.arange(lo, hi + 1))
    if first is None:
        raise ParameterError("not identifiable: the samples around the largest are not a "
                             f"peak above the noise ({sigma:.3g} m): no x_max")
    half = math.sqrt(depth / -c2)
    sel = np.abs(t - first[0]) <= half
    second, _ = _vertex(t, x, sel) if np.count_nonzero(sel) >= 5 else (None, None)
    if second is None or not t[sel][0] <= second[0] <= t[sel][-1] or sel[-1]:
        raise ParameterError("not identifiable: the peak is not resolved above the noise "
                             f"({sigma:.3g} m): no x_max")
    return second


def _contiguous(x, i, level):
    """(lo, hi): the run of samples around ``i`` with x >= ``level``."""
    below = np.nonzero(x < level)[0]
    left, right = below[below < i], below[below > i]
    return (int(left[-1]) + 1 if left.size else 0,
            int(right[0]) - 1 if right.size else x.size - 1)
