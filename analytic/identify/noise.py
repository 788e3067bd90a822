"""The sensor's noise and what it allows: the spread of the samples before the contact, of
the record's second differences, the white floor of a residual's spectrum, the record's
resolution floor; whether a residual is that noise, whether the motion after the contact
stands above it (a test against a record without an impact), the residual's dominant
frequency. docs/identification.md, "Diagnoses"."""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum

import numpy as np

from .record_features import robust_sigma

#: Samples before the contact needed to estimate the noise there (fewer: the residual's
#: spectrum gives it).
MIN_REST_SAMPLES = 12
#: The finest a field record resolves, of its peak (a 14-bit converter's step is 6e-5 of
#: its range): a residual below it is not a misfit, and no interval is narrower than this
#: noise gives (a record without noise: a simulation's, interpolated or rounded).
RESOLUTION = 1e-4


class NoiseSource(Enum):
    """Where the noise a residual is judged against came from."""

    REST = "rest"  # the samples before the contact
    DIFFERENCES = "differences"  # the record's second differences (no rest recorded)
    SPECTRUM = "spectrum"  # the residual spectrum's white floor
    RESOLUTION = "resolution"  # RESOLUTION of the peak: the record has no noise above it


@dataclass(frozen=True)
class NoiseJudgement:
    """The residual against the noise: ``noise`` (m) from ``source``, the residual's RMS over
    it (``ratio``) and whether that is the noise (``limited``); the pendulum's channel
    against its own white floor (``ratio_y``, ``y_limited``; NaN and True without one)."""

    noise: float
    source: NoiseSource
    ratio: float
    limited: bool
    ratio_y: float = math.nan
    y_limited: bool = True


def rest_noise(t: np.ndarray, x: np.ndarray, t_contact: float) -> tuple[float, int]:
    """(sigma m, n): the noise of the n samples of ``x`` (m, at times ``t``, s) recorded
    before the contact at ``t_contact`` (s; two sample intervals of margin), about a
    straight line through them (a drift is not noise), robust to a wild sample; NaN when
    n < MIN_REST_SAMPLES."""
    dt = float(np.median(np.diff(t)))
    sel = t < t_contact - 2.0 * dt
    n = int(np.count_nonzero(sel))
    if n < MIN_REST_SAMPLES:
        return math.nan, n
    ts, xs = t[sel], x[sel]
    line = np.polyval(np.polyfit(ts - ts[0], xs, 1), ts - ts[0])
    r = xs - line
    s = robust_sigma(r)
    keep = np.abs(r - np.median(r)) <= 5.0 * s if s > 0 else np.ones(n, bool)
    return float(np.std(r[keep], ddof=2)) if np.count_nonzero(keep) > 2 else s, n


def difference_noise(x: np.ndarray) -> float:
    """The noise (standard deviation, m) of a record ``x`` (m) from its second differences,
    robustly
    (their median absolute deviation; x_{i+1} - 2 x_i + x_{i-1} of white noise has variance
    6 sigma^2, of a motion sampled at omega dt << 1 only (omega dt)^2 of its amplitude, and
    an impact's kink moves a few of them): independent of any fit. An over-estimate where
    the motion is sampled coarsely (omega dt near 1)."""
    d2 = np.diff(np.asarray(x, float), 2)
    return robust_sigma(d2) / math.sqrt(6.0) if d2.size else math.nan


def independent_noise(t: np.ndarray, x: np.ndarray, t_contact: float
                      ) -> tuple[float, NoiseSource]:
    """The noise (m) of the record ``x`` (m, at times ``t``, s) estimated apart from any fit,
    and its source: of the samples before the contact at ``t_contact`` (s) when there are
    MIN_REST_SAMPLES of them, else of its second differences."""
    sigma, _ = rest_noise(t, x, t_contact)
    if np.isfinite(sigma):
        return sigma, NoiseSource.REST
    return difference_noise(x), NoiseSource.DIFFERENCES


#: The test of the impact against a record without one: its false-alarm probability on a
#: record of noise alone, shared among the record's samples (the contact could be at any),
#: so one record of noise in 1e4 passes it whatever its length.
NO_IMPACT_ALPHA = 1e-4


@dataclass(frozen=True)
class ImpactTest:
    """The fitted impact against a record without one (offset and drift alone): the fall of
    the residual sum of squares over the noise's variance (``statistic``, chi-square under
    no impact), the ``threshold`` it must pass, and the noise (m) and its ``source``."""

    statistic: float
    threshold: float
    noise: float
    source: NoiseSource

    @property
    def significant(self) -> bool:
        """Whether the impact stands above the noise (statistic > threshold)."""
        return self.statistic > self.threshold


def impact_test(t: np.ndarray, x: np.ndarray, resid: np.ndarray, noise: float,
                source: NoiseSource, *, drift_degree: int, parameters: int) -> ImpactTest:
    """Whether the fitted motion stands above the noise: the samples ``x`` (m, at times t,
    the ones fitted) explained by a polynomial of ``drift_degree`` (the fit's offset and
    drift, no impact) leave RSS_0; the fit leaves ``resid``. (RSS_0 - RSS) / noise^2 is
    chi-square with ``parameters`` degrees of freedom (the impact's: M_T, K_T, the damping,
    e, t0) on noise alone, its threshold at NO_IMPACT_ALPHA / n (the contact's time searched
    over the n samples). ``noise`` (m) and its ``source`` are carried into the result."""
    # lazy: +803 ms at import otherwise (scipy.stats)
    from scipy.stats import chi2

    s = (t - t[0]) / max(float(t[-1] - t[0]), 1e-300)
    basis = np.vander(s, drift_degree + 1)
    coef, *_ = np.linalg.lstsq(basis, x, rcond=None)
    rss0 = float(np.sum((x - basis @ coef) ** 2))
    rss = float(np.sum(resid ** 2))
    statistic = (rss0 - rss) / max(noise, 1e-300) ** 2
    threshold = float(chi2.isf(NO_IMPACT_ALPHA / max(t.size, 1), parameters))
    return ImpactTest(statistic, threshold, noise, source)


def periodogram(r: np.ndarray, dt: float, pad: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """(omega rad/s, P): |FFT|^2 / n of r (sampled every ``dt`` s) less its mean, bins 1 to
    N/2 - 1 of its FFT
    zero-padded to N = ``pad`` x n (for white noise of variance s^2 each P is exponential
    with mean s^2; padding interpolates between the independent bins)."""
    r = np.asarray(r, float) - float(np.mean(r))
    n = r.size
    size = pad * n
    p = np.abs(np.fft.rfft(r, size)) ** 2 / n
    k = np.arange(1, max(2, (size + 1) // 2))
    return 2.0 * math.pi * k / (size * dt), p[k]


def spectrum_floor(r: np.ndarray, dt: float) -> float:
    """The white-noise level (standard deviation, r's unit) of r sampled every ``dt`` (s)
    from the median of its periodogram
    (median of an exponential = ln 2 x its mean): a misfit confined to a few frequencies
    does not raise it."""
    _, p = periodogram(r, dt)
    return math.sqrt(float(np.median(p)) / math.log(2.0)) if p.size else math.nan


def dominant_frequency(r: np.ndarray, dt: float) -> tuple[float, float]:
    """(omega rad/s, strength): the frequency of the largest peak of the periodogram of r
    (sampled every ``dt`` s)
    (smoothed over 3 independent bins: a decaying mode is a few bins wide; located on the
    8 x zero-padded spectrum) and its height over the white floor (about 1 for noise,
    ln(n) at most by chance)."""
    w, p = periodogram(r, dt, pad=8)
    if p.size < 24:
        return math.nan, math.nan
    smooth = np.convolve(p, np.ones(17) / 17.0, mode="same")  # 3 bins of the unpadded
    k = int(np.argmax(smooth))
    floor = float(np.median(periodogram(r, dt)[1])) / math.log(2.0)
    return float(w[k]), float(smooth[k] / floor) if floor > 0 else math.inf



def judge(resid: np.ndarray, dt: float, rest: tuple[float, int], floor: float,
          resid_y: np.ndarray | None = None, floor_y: float = 0.0) -> NoiseJudgement:
    """The residual ``resid`` (m, the fitted samples, every ``dt`` s) against the noise: the
    rest's (sigma,
    n) (:func:`rest_noise`) when it has one, else the residual's white floor, never below
    ``floor``; the noise when its RMS is within 4 standard errors of the two estimates
    (relative: 1 / (2 n) each; a false alarm once in 3e4 records) or below ``floor``. The
    pendulum's ``resid_y`` against its own white floor (the spectrum's estimate has a
    relative variance of 1 / n, the RMS 1 / (2 n): 4 of their errors), not below
    ``floor_y``."""
    rms = math.sqrt(float(np.mean(resid ** 2)))
    sigma_rest, n_rest = rest
    if np.isfinite(sigma_rest):
        noise, source, n_noise = sigma_rest, NoiseSource.REST, n_rest
    else:
        noise, source, n_noise = spectrum_floor(resid, dt), NoiseSource.SPECTRUM, resid.size
    if not noise > floor:
        noise, source = floor, NoiseSource.RESOLUTION
    ratio = rms / noise
    allowance = 4.0 * math.sqrt(0.5 / max(n_noise - 2, 1) + 0.5 / resid.size)
    limited = ratio <= 1.0 + allowance or rms <= floor
    if resid_y is None:
        return NoiseJudgement(noise, source, ratio, limited)
    rms_y = math.sqrt(float(np.mean(resid_y ** 2)))
    ratio_y = rms_y / max(spectrum_floor(resid_y, dt), floor_y)
    y_limited = ratio_y <= 1.0 + 4.0 * math.sqrt(1.5 / resid_y.size) or rms_y <= floor_y
    return NoiseJudgement(noise, source, ratio, limited, ratio_y, y_limited)
