"""Whether a record holds an impact at all, decided before one is fitted: an impact from rest
starts with the trunk at rest and a jump of its velocity in +x (the impactor's momentum,
eq 21); the tree's own free vibration (a ring-down, a trunk held and released, sway, beating
modes, the tail after the pendulum left) has a velocity that never jumps. A record is "no
impact in this record" when (:func:`no_impact`):

* it stays at its starting level for MIN_REST_SAMPLES samples and then first moves in -x;
* the samples before its rise (``feat.t_contact`` of :func:`record_features.features`, the
  contact read off the rise), MIN_REST_SAMPLES or more, move by more than REST_MOTION of
  the rise and 4 of their standard errors: the tree vibrates before the "contact";
* at rest before the rise (the samples before it still, or a fit of a rest, a velocity jump
  and one damped mode putting the onset MIN_REST_SAMPLES in): the rise up to its peak is a
  trunk held at h until t_r and released at zero velocity (one damped mode) to the noise,
  and a strike (a velocity jump of at least JUMP_MIN of the rise's mean slope at the onset)
  fits it worse by more than CHI2_999 of the noise: an impact's rise is concave from the
  contact (the trunk decelerates on its spring, eqs 12-13), its first velocity at least the
  mean slope;
* in motion from its first sample (a transducer triggered by the impact, or sway): a free
  vibration of one or two damped modes from the first sample,
  x = c + sum_j exp(-q_j w_j s) (A_j cos w_j s + B_j sin w_j s), explains it to its noise,
  stands above the noise (as the impact test of :func:`noise.impact_test`), completes a
  period of every mode within the record with MIN_PERIOD_SAMPLES a period (the record
  shows the oscillation, not a piece of one), and a rest with a velocity jump and as many
  modes does not explain it better by CHI2_999.

A record shorter than a period of its motion from a zero crossing is both a sway and a
triggered one-impact record: it is fitted, and the fit's one-impact ranges say what it
cannot fix. A noisy record that cannot tell a release or a sway from a strike (5 % noise on
a 20 ms rest, measured) is fitted too: the check refuses only what the record rules out.
docs/identification.md, "No impact in this record"."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from .noise import MIN_REST_SAMPLES, NO_IMPACT_ALPHA, difference_noise, dominant_frequency
from .record_features import Features, median3

#: A rest that moves by more than this share of the rise (and more than 4 of its standard
#: errors) is the tree's own motion before the rise, not a trunk at rest: a sensor's drift
#: over the rest is ~1e-3 of a rise (the validation set's 10 % over a whole record), a free
#: vibration's velocity is continuous, so the rest before its "rise" moves as the rise does.
REST_MOTION = 0.05
#: An impact's first velocity is at least the rise's mean slope (a concave rise, module
#: docstring: pi / 2 of it after one impact, x = V_1 sin(w s) / w): a record that rules out a
#: jump of this share of the mean slope at the onset starts from rest at zero velocity.
JUMP_MIN = 1.0
#: Standard errors of a residual's RMS over the noise allowed for "explains the record to its
#: noise": the noise is a median absolute deviation of second differences (relative variance
#: about 1.36 / n, a standard deviation's 0.5 / n), the RMS 0.5 / n: 4 of their joint errors
#: (a false alarm once in 3e4 records).
NOISE_SE = 4.0
#: Samples of the rise needed to read a velocity at its onset (else not judged).
MIN_RISE_SAMPLES = 4
#: Samples a period of a mode the record shows (fewer: a mode fitted to the noise or to a
#: sample or two; a tree's sway recorded that coarsely is not a record to identify from).
MIN_PERIOD_SAMPLES = 8
#: The largest decay rate over the damped frequency, a / w, of a mode fitted: 1, a damping
#: ratio of 1 / sqrt(2). A tree sways (its trunks' damping ratios 0.05-0.6, the shipped
#: trees' 0.27-0.6); a slower decay would be a creep, not a vibration, and let a release
#: mimic a struck trunk's concave rise.
Q_MAX = 1.0
#: Chi-square of one parameter at 99.9 %: the rest and the velocity jump of an impact must
#: lower the cost of a free vibration by this much of the noise's variance to count.
CHI2_999 = 10.827566170662733


@dataclass(frozen=True)
class Explanation:
    """A record explained without an impact: ``what`` it is (one line), the residual's RMS
    over the noise (``ratio``, 1)."""

    what: str
    ratio: float


def no_impact(t: np.ndarray, x: np.ndarray, feat: Features, floor: float) -> str | None:
    """Why the record ``x`` (m, at times ``t``, s, from 0; its features ``feat``) holds no
    impact (one line), or None when it may hold one (module docstring). ``floor``: the
    record's resolution (m), the least noise it is judged against."""
    sigma = max(difference_noise(x), floor)
    backwards = _first_motion_back(x, feat.rest, sigma)
    if backwards:
        return backwards
    pre = t < feat.t_contact - 2.0 * feat.dt
    n_pre = int(np.count_nonzero(pre))
    moving = _rest_moves(t[pre], x[pre], sigma, feat.span) if n_pre >= 3 else None
    if moving and n_pre >= MIN_REST_SAMPLES:
        return moving
    in_motion = n_pre < 3 or moving is not None
    w, _ = dominant_frequency(x - x.mean(), feat.dt)
    w = w if math.isfinite(w) else 2.0 * math.pi / max(float(t[-1] - t[0]), feat.dt)
    _, p = _struck(t, x, feat, [(float(t[0]), w, 0.05)])
    if not in_motion or p[0] - t[0] >= MIN_REST_SAMPLES * feat.dt:  # at rest, then moving
        found = _released(t, x, feat, sigma)
    else:
        found = _free_modes(t, x, feat, sigma)
    if found is None:
        return None
    return (f"{found.what} (its residual {found.ratio:.3g} x the noise {sigma:.3g} m); an "
            "impact starts from rest with a jump of the trunk's velocity: record a few ms of "
            "rest before the contact")


def _rest_moves(t: np.ndarray, x: np.ndarray, sigma: float, span: float) -> str | None:
    """Why the samples before the rise (``t`` s, ``x`` m) are not a trunk at rest: their line
    or their motion about it, beyond ``sigma`` (m), moves by more than REST_MOTION of the
    rise ``span`` (m); else None."""
    s = t - t[0]
    coef = np.polyfit(s, x, 1)
    resid = x - np.polyval(coef, s)
    n = x.size
    change = abs(coef[0]) * float(s[-1])
    se = sigma * math.sqrt(12.0 / max(n, 3))  # of the line's change over the rest
    swing = math.sqrt(max(float(np.mean(resid ** 2)) - sigma ** 2, 0.0)) * 2.0 * math.sqrt(2.0)
    excess = float(np.sum(resid ** 2)) / sigma ** 2 - (n - 2)
    moving = (change > REST_MOTION * span and change > 4.0 * se) or (
        swing > REST_MOTION * span and excess > 4.0 * math.sqrt(2.0 * n))
    if not moving:
        return None
    return (f"no impact in this record: the trunk moves before the rise ({max(change, swing):.3g}"
            f" m over the {n} samples before it, {max(change, swing) / span:.2g} of the rise "
            f"{span:.3g} m): the record starts in the tree's own vibration, not at rest")


def _first_motion_back(x: np.ndarray, rest: float, sigma: float) -> str | None:
    """Why a record (``x``, m) that starts at ``rest`` (m) for MIN_REST_SAMPLES or more
    samples holds no impact when it first leaves it in -x (beyond 8 ``sigma`` and a fifth of
    its largest excursion; the median-of-3 copy, so one wild sample does not count): the
    impactor strikes in +x (eq 21: V_1 > 0); else None."""
    dev = median3(x) - rest
    threshold = max(8.0 * sigma, 0.2 * float(np.max(np.abs(dev))))
    away = np.flatnonzero(np.abs(dev) > threshold)
    if not away.size or away[0] < MIN_REST_SAMPLES or dev[away[0]] > 0:
        return None
    return (f"no impact in this record: after {away[0]} samples at its starting level the trunk "
            f"first moves in -x ({dev[away[0]]:.3g} m), away from the impactor; a strike moves "
            "it in +x first (a trunk released from a deflection in +x, or x's sign reversed)")


def _allowance(n: int) -> float:
    return NOISE_SE * math.sqrt((1.36 + 0.5) / max(n, 1))


def _project(basis: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(coefficients, residual) of x by least squares on the columns of ``basis``."""
    coef, *_ = np.linalg.lstsq(basis, x, rcond=None)
    return coef, x - basis @ coef


def _fit(residual, p0, low, high):
    """The nonlinear parameters minimising the variable-projection ``residual``, and it."""
    p0 = np.clip(np.asarray(p0, float), np.asarray(low) * (1 + 1e-9) + 1e-12,
                 np.asarray(high) * (1 - 1e-9))
    fit = least_squares(residual, p0, bounds=(low, high), x_scale="jac", max_nfev=200)
    return fit.x, residual(fit.x)


# -- the impact's own shape, and the free vibrations' -----------------------------------

def _onset_basis(t: np.ndarray, p, jump: bool) -> np.ndarray:
    """Columns of a rest at h until t_r and damped modes (w_j, decay q_j w_j; ``p`` =
    (t_r, w_1, q_1, ...)) after it: h, the centre c (x(t_r) = h, velocity 0 at t_r by the
    first mode), with ``jump`` the velocity v at t_r (an impact's, eq 21), and each further
    mode's pair (held at its t_r value before it); t_r at the first sample with a jump: a
    free vibration of any initial state."""
    s = np.clip(t - p[0], 0.0, None)
    w, q = p[1], p[2]
    decay = np.exp(-q * w * s)
    phi = decay * (np.cos(w * s) + q * np.sin(w * s))  # x(0) = 1, v(0) = 0
    cols = [phi, 1.0 - phi]
    if jump:
        cols.append(decay * np.sin(w * s) / w)  # x(0) = 0, v(0) = 1
    for wj, qj in zip(p[3::2], p[4::2]):
        dj = np.exp(-qj * wj * s)
        cols += [dj * np.cos(wj * s), dj * np.sin(wj * s)]
    return np.stack(cols, 1)


def _struck(t: np.ndarray, x: np.ndarray, feat: Features, starts) -> tuple[float, np.ndarray]:
    """(least residual sum of squares m^2, its p) of ``x`` as a rest, a velocity jump and as
    many damped modes as the ``starts`` have (:func:`_onset_basis`; p = (t_r, w_1, q_1,
    ...)), from the ``starts`` and, for one mode, one at the contact read off the rise: the
    impact's explanation each free vibration is held against."""
    rise = max(feat.t_peak - feat.t_contact, feat.dt)
    modes = (len(starts[0]) - 1) // 2
    low = [float(t[0])] + [0.25 * math.pi / max(float(t[-1] - t[0]), feat.dt), 0.0] * modes
    high = [float(t[-1])] + [math.pi / feat.dt, Q_MAX] * modes
    w0 = 0.5 * math.pi / rise
    extra = [(feat.t_contact, w0, 0.1)] if modes == 1 else []
    fits = [_fit(lambda p: _project(_onset_basis(t, p, True), x)[1], p0, low, high)
            for p0 in (*starts, *extra)]
    p, r = min(fits, key=lambda f: float(f[1] @ f[1]))
    return float(r @ r), p


def _released(t: np.ndarray, x: np.ndarray, feat: Features, sigma: float
              ) -> Explanation | None:
    """The record's rise (to a quarter of the rise past its peak) as a trunk held at rest
    and released at zero velocity, when that explains it to the noise ``sigma`` (m) and a
    strike (a velocity jump at the onset of JUMP_MIN of the rise's mean slope or more) is
    worse by more than CHI2_999 of the noise: the record rules an impact out. Else None (an
    impact, a rise too fast to read, or a record too noisy to tell)."""
    rise = feat.t_peak - feat.t_contact
    if not feat.velocity_resolved or np.count_nonzero(
            (t > feat.t_contact) & (t <= feat.t_peak)) < MIN_RISE_SAMPLES:
        return None
    win = t <= feat.t_peak + 0.25 * rise
    tw, xw = t[win], x[win]
    low = [float(tw[0]), 0.25 * math.pi / max(rise, feat.dt), 0.0]
    high = [float(feat.t_peak), math.pi / feat.dt, Q_MAX]
    w0 = math.pi / rise
    p, resid = min((_fit(lambda q: _project(_onset_basis(tw, q, False), xw)[1], p0, low, high)
                    for p0 in ((feat.t_contact, w0, 0.1),
                               (feat.t_contact - 0.25 * rise, w0, 0.1))),
                   key=lambda f: float(f[1] @ f[1]))
    rss = float(resid @ resid)
    ratio = math.sqrt(rss / xw.size) / sigma
    mean_slope = feat.span / max(rise, feat.dt)
    v_min = JUMP_MIN * mean_slope
    rss_struck = _struck_at_least(tw, xw, feat, v_min, [(*p, v_min)])
    if ratio > 1.0 + _allowance(xw.size) or rss_struck - rss <= CHI2_999 * sigma ** 2:
        return None
    return Explanation(
        f"no impact in this record: the trunk leaves its rest at t = {p[0]:.4g} s without a "
        f"velocity jump (one of {v_min:.3g} m/s or more, the rise's mean slope, is ruled "
        "out): released from a deflection, not struck", ratio)


def _struck_at_least(t: np.ndarray, x: np.ndarray, feat: Features, v_min: float, starts
                     ) -> float:
    """The least residual sum of squares (m^2) of ``x`` as a rest, a velocity jump of at
    least ``v_min`` (m/s) and one damped mode (:func:`_onset_basis`), from the ``starts``
    (t_r, w, q, v) and one at the contact read off the rise at its mean slope."""
    rise = max(feat.t_peak - feat.t_contact, feat.dt)
    low = [float(t[0]), 0.25 * math.pi / rise, 0.0, v_min]
    high = [float(feat.t_peak), math.pi / feat.dt, Q_MAX, math.inf]

    def residual(p):
        s = np.clip(t - p[0], 0.0, None)
        lifted = x - p[3] * np.exp(-p[2] * p[1] * s) * np.sin(p[1] * s) / p[1]
        return _project(_onset_basis(t, p[:3], False), lifted)[1]

    w0 = 0.5 * math.pi / rise
    fits = [_fit(residual, p0, low, high)
            for p0 in (*starts, (feat.t_contact, w0, 0.1, 2.0 * v_min))]
    return min(float(r @ r) for _, r in fits)


# -- in motion from the first sample: the tree's own modes ------------------------------

def _modes_basis(s: np.ndarray, p) -> np.ndarray:
    """Columns of a constant and damped modes (w_j, decay q_j w_j of ``p``) from s = 0."""
    cols = [np.ones_like(s)]
    for w, q in zip(p[::2], p[1::2]):
        decay = np.exp(-q * w * s)
        cols += [decay * np.cos(w * s), decay * np.sin(w * s)]
    return np.stack(cols, 1)


def _mode_fits(s: np.ndarray, x: np.ndarray, dt: float) -> list:
    """[(p, residual)] of the free vibrations of one and two damped modes from s = 0."""
    length = float(s[-1])
    low_w, high_w = 0.25 * math.pi / max(length, dt), math.pi / dt
    w, _ = dominant_frequency(x - x.mean(), dt)
    w = w if math.isfinite(w) else 2.0 * math.pi / max(length, dt)
    p1 = min((_fit(lambda p: _project(_modes_basis(s, p), x)[1], (w * f, 0.05),
                   (low_w, 0.0), (high_w, Q_MAX)) for f in (0.7, 1.0, 1.4)),
             key=lambda f: float(f[1] @ f[1]))
    fits = [p1]
    w2, _ = dominant_frequency(p1[1], dt)
    if math.isfinite(w2):
        fits.append(_fit(lambda p: _project(_modes_basis(s, p), x)[1],
                         (*p1[0], w2, 0.05), (low_w, 0.0) * 2, (high_w, Q_MAX) * 2))
    return fits


def _free_modes(t: np.ndarray, x: np.ndarray, feat: Features, sigma: float
                ) -> Explanation | None:
    """The record as the free vibration of one, else two, damped modes from its first
    sample, when that explains it to the noise ``sigma`` (m), stands above the noise, shows
    every mode (a period within the record, MIN_PERIOD_SAMPLES a period, underdamped) and
    a rest with a velocity jump does not explain it better by CHI2_999; else None."""
    # lazy: +803 ms at import otherwise (scipy.stats)
    from scipy.stats import chi2

    s = t - t[0]
    rss0 = float(np.sum((x - x.mean()) ** 2))
    for p, resid in _mode_fits(s, x, feat.dt):
        rss = float(resid @ resid)
        ratio = math.sqrt(rss / x.size) / sigma
        shown = all(2.0 * math.pi / float(s[-1]) <= w <= 2.0 * math.pi / (
            MIN_PERIOD_SAMPLES * feat.dt) for w in p[::2])
        above = (rss0 - rss) / sigma ** 2 > float(chi2.isf(NO_IMPACT_ALPHA / x.size, p.size + 2))
        if not (ratio <= 1.0 + _allowance(x.size) and above and shown):
            continue
        starts = [(float(t[0]), *p), (feat.t_contact, *p)]  # free, and struck at the rise
        if rss - _struck(t, x, feat, starts)[0] <= CHI2_999 * sigma ** 2:
            return Explanation(_modes_text(p), ratio)
    return None
def _modes_text(p) -> str:
    """'no impact in this record: ... free vibration of ... mode(s) at f Hz ...'."""
    modes = ", ".join(f"{w / (2.0 * math.pi):.3g} Hz (damping ratio "
                      f"{q / math.hypot(1.0, q):.2g})" for w, q in zip(p[::2], p[1::2]))
    count = "one mode" if len(p) == 2 else f"{len(p) // 2} modes"
    return (f"no impact in this record: from its first sample it is the tree's free "
            f"vibration, {count} at {modes}, no rest and no velocity jump")
