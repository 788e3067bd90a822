"""The record fit's stages (docs/identification.md, "The full-record fit"):

1. a robust fit (soft-l1 loss) from the record's shape at e = 0 (or the given e, or a
   start), on every k-th sample; isolated samples far off it (:data:`OUTLIER_Z` robust
   deviations) are left out;
2. the global stage: e's profile (:class:`profile.RestitutionProfile`) and the fit with e
   free from its lowest point(s); with e given or a start, the local fit from there;
3. outliers checked once more, and a drift bent like t^2 added if the record calls for it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .fit_model import model_motion
from .fit_parameters import K_RANGE, M_RANGE, Slot, padded
from .fitter import Fit, Fitter
from .noise import MIN_REST_SAMPLES
from .one_impact import on_ridge
from .procedure import PendulumTest
from .profile import PROFILE_NFEV_FIRST, PROFILE_SAMPLES, RestitutionProfile
from .record_features import Features, median3, robust_sigma

CHI2_999 = 10.827566170662733  # chi-square of one parameter at 99.9 %: a term added past it
#: A sample this many noise deviations off the robust fit is an outlier: a normal sample
#: gets there once in 5e8, so a record of 1e5 samples flags none by chance.
OUTLIER_Z = 6.0
#: ...unless there are more than this share of them: then the model misses the record.
OUTLIER_SHARE = 0.005


@dataclass
class Staged:
    """The stages' outcome: the best fit, e's profile (None with e given or a start), the
    samples kept and the rows flagged as outliers."""

    fitter: Fitter
    best: Fit
    profile: RestitutionProfile | None
    keep: np.ndarray
    flagged: np.ndarray


def first_guess(feat: Features, test: PendulumTest, e: float, y=None, t=None, *,
                trunk_damping_ratio: float = 0.1) -> np.ndarray:
    """A start on e's own branch from the record's shape (``feat``) with the pendulum of
    ``test``: the contact extrapolated back from
    the 10 % and 40 % crossings, M_T from the slope V there by momentum (one impact,
    V = m (1 + e) u_1 / (M_T + m), when that M_T e exceeds m: the pendulum rebounds; else
    chattering into moving together, V = m u_1 / (M_T + m)), K_T from the contact-to-peak
    time as a quarter period of that branch's motion, the ``trunk_damping_ratio`` as given
    (0.1); the pendulum sensor's offset (if y, m, is recorded at the times ``t``, s) from
    the samples before the contact, less the free swing."""
    m, u1, k = test.impactor_mass, test.impact_speed, test.impactor_stiffness
    V = min(max(feat.velocity, 1e-3 * u1), 1.9 * u1)
    M_one = m * ((1.0 + e) * u1 / V - 1.0)
    one = M_one > 0 and M_one * e > m
    M = M_one if one else m * max(u1 / V - 1.0, 0.05)
    M = min(max(M, 1.5 * M_RANGE[0]), 0.5 * M_RANGE[1])
    omega = 0.5 * math.pi / max(feat.t_peak - feat.t_contact, 2.0 * feat.dt)
    K = omega ** 2 * M if one else omega ** 2 * (M + m) - k
    K = min(max(K, 2.0 * K_RANGE[0]), 0.5 * K_RANGE[1])
    p = np.zeros(len(Slot))
    p[Slot.LN_DYNAMIC_MASS], p[Slot.LN_EQUIVALENT_STIFFNESS] = math.log(M), math.log(K)
    p[Slot.TRUNK_DAMPING_RATIO], p[Slot.RESTITUTION] = trunk_damping_ratio, e
    p[Slot.T0], p[Slot.X_OFFSET] = feat.t_contact, feat.rest
    if y is not None:
        before = t < p[Slot.T0]
        if before.any():
            swing = model_motion(p, test, t[before], pendulum=True)[2]
            p[Slot.Y_OFFSET] = float(np.median(y[before] - swing))
        else:
            p[Slot.Y_OFFSET] = float(y[0])
    return p


def outliers(r: np.ndarray, floor: float, keep: np.ndarray) -> np.ndarray:
    """Rows of the isolated wild samples (among ``keep``) of the residual ``r`` (m): further
    than OUTLIER_Z robust deviations (at least ``floor``, m) both from the fit and from the
    median of their neighbours' residuals (a
    misfit is smooth: its neighbours follow it), if they are few (OUTLIER_SHARE of the
    record at most; more: a misfit)."""
    spread = max(robust_sigma(r[keep]), floor)
    own = np.abs(r - np.median(r[keep]))
    alone = np.abs(r - median3(r))
    far = np.flatnonzero(keep & (own > OUTLIER_Z * spread) & (alone > OUTLIER_Z * spread))
    return far if far.size <= max(1, OUTLIER_SHARE * r.size) else np.zeros(0, int)


def on_fit_clock(p, t_shift: float) -> np.ndarray:
    """p (on the record's clock, possibly short) with every slot, t0 on the fit's clock (the
    record's less ``t_shift``, s)."""
    out = padded(p)
    out[Slot.T0] -= t_shift
    return out


def sensor_separable(t: np.ndarray, feat: Features, rest_samples: int) -> bool:
    """Whether a record (times ``t``, s; features ``feat``) can tell its sensor's offset and
    drift from the motion: it holds a
    rest before the contact (``rest_samples``, at least MIN_REST_SAMPLES) or rings down past
    a period after it (four times the contact-to-peak time, a quarter period, as
    :func:`first_guess` reads it). Elsewhere they trade with the motion (a short record's
    level and slope are either)."""
    quarter = max(feat.t_peak - feat.t_contact, feat.dt)
    return rest_samples >= MIN_REST_SAMPLES or float(t[-1]) - feat.t_contact > 4.0 * quarter


def stage(fitter: Fitter, feat: Features, test: PendulumTest, *, floor: float,
          sigma_rest: float, restitution: float | None = None, start=None,
          free_point=None) -> Staged:
    """The three stages on the ``fitter``'s record (module docstring; its features
    ``feat``, the pendulum ``test``, the residual ``floor`` m, the noise at rest
    ``sigma_rest`` m); ``restitution``: e held at this value (None: fitted); ``start``: p
    to fit from locally (the fit's clock); ``free_point``: the free fit's optimum of this
    record (the fit's clock), moved along V_1 and omega_1 to the given e as one more
    start."""
    t, x = fitter.t, fitter.x
    first = _robust_fit(fitter, feat, test, floor, sigma_rest, restitution, start)
    keep = np.ones(t.size, bool)
    flagged = outliers(model_motion(first.p, test, t)[0] - x, floor, keep)
    keep[flagged] = False
    profile = None
    if start is not None or restitution is not None:
        starts = [first.p]
        if start is None and free_point is not None:
            moved = on_ridge(free_point, restitution, test)
            if np.all(np.isfinite(moved)):
                starts.append(moved)
    else:
        profile = RestitutionProfile(fitter, lambda e, ratio: first_guess(
            feat, test, e, fitter.y, t, trunk_damping_ratio=ratio), keep, first)
        starts = profile.starts()
    polished = sorted((fitter.refine(q, keep) for q in starts), key=lambda f: f.cost)
    new = outliers(model_motion(polished[0].p, test, t)[0] - x, floor, keep)
    if new.size:
        flagged = np.union1d(flagged, new).astype(int)
        keep[flagged] = False
        polished = [fitter.refine(polished[0].p, keep)]
    best = polished[0]
    if not fitter.params[Slot.X_DRIFT].frozen:  # a drift fitted: maybe a bent one
        best = _with_bent_drift(fitter, best, keep, floor)
    return Staged(fitter, best, profile, keep, flagged)


def _robust_fit(fitter: Fitter, feat: Features, test: PendulumTest, floor: float,
                sigma_rest: float, restitution, start) -> Fit:
    """Stage 1's fit: soft-l1, quadratic within 3 noise deviations of the rest (or 0.3 % of
    the peak if more; beyond it a sample counts as |r|, so a wild one pulls little), from
    the start or the first guess at e = 0 (or the given e), e held unless given or started."""
    f_scale = 3.0 * max(sigma_rest if np.isfinite(sigma_rest) else 0.0,
                        1e-3 * feat.span) / fitter.scale[0]
    if start is not None:
        p0 = np.array(start, float)
        if restitution is not None:
            p0[Slot.RESTITUTION] = restitution
    else:
        p0 = first_guess(feat, test, 0.0 if restitution is None else restitution,
                         fitter.y, fitter.t)
    stride = max(1, int(math.ceil(fitter.t.size / PROFILE_SAMPLES)))
    params = fitter.params
    if restitution is None and start is None:
        params = params.freeze(Slot.RESTITUTION)
    return fitter.fit(p0, loss="soft_l1", f_scale=f_scale, max_nfev=PROFILE_NFEV_FIRST,
                      stride=stride, params=params)


def _with_bent_drift(fitter: Fitter, best: Fit, keep, floor: float) -> Fit:
    """``best``, or the fit with a drift bent like t^2 (an integrated accelerometer's, a
    warming sensor's) if the record needs it: the cost falls by more than chi-square 10.83
    (99.9 %) of the noise."""
    curved = fitter.refine(best.p, keep, params=fitter.params.thaw(Slot.X_DRIFT2))
    n = np.count_nonzero(keep)
    s2 = (max(math.sqrt(2.0 * best.cost / n) * fitter.scale[0], floor)
          / fitter.scale[0]) ** 2
    return curved if best.cost - curved.cost > 0.5 * CHI2_999 * s2 else best
