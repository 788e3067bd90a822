"""What the record fit sees in a record besides the tree's values: one :class:`Diagnosis`
per finding, of a :class:`DiagnosisKind` (docs/identification.md, "Diagnoses"); the kinds'
names are strings only in the JSON."""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum

import numpy as np

from .fit_model import drift_at, model_motion
from .fit_parameters import DRIFTS, K_RANGE, M_RANGE, XI_RANGE, Slot
from .fitter import REFINE_NFEV
from .intervals import DETERMINED_FACTOR
from .noise import (
    MIN_REST_SAMPLES,
    RESOLUTION,
    ImpactTest,
    NoiseJudgement,
    NoiseSource,
    dominant_frequency,
)
from .procedure import PendulumTest

#: A record that ends before the trunk's first swing back is truncated when it leaves the
#: trunk's damping ratio undetermined (its 95 % interval spanning more than the factor of
#: intervals.DETERMINED_FACTOR): a noise-free record fixes the damping before that, a
#: noisy one cut after the peak does not, one from the impact to the pendulum's separation
#: at 1 % noise does (within a factor 1.4-1.8, docs/identification.md).
TRUNCATED_XI_SPAN = DETERMINED_FACTOR
#: The residual's dominant frequency counts as a mode of its own when its peak stands this
#: far over the white floor (a false alarm once in ~1e3 records of 1e4 samples by chance:
#: exponential ordinates, ln(5e3 / 1e-3) = 15.4) and is 25 % away from the fitted modes.
PEAK_STRENGTH = 15.0
PEAK_SEPARATION = 0.25
#: A fitted drift this large (of the peak) is no sensor's: a slow motion of the tree.
DRIFT_MAX = 0.5


class DiagnosisKind(Enum):
    """What a diagnosis is about (its ``value``: the JSON's and the text output's name)."""

    NOISE_LIMITED = "noise-limited"  # explained: the residual is the sensor's noise
    NO_IMPACT = "no-impact"  # no response above the noise: a record without an impact
    DRIFT = "drift"  # a sensor's drift, fitted and removed
    SENSOR_HELD = "sensor-held"  # offset and drift held at 0: the record cannot tell them
    OUTLIERS = "outliers"  # isolated wild samples, left out
    ONE_IMPACT = "one-impact"  # the pendulum leaves: M_T and e not fixed apart
    TRUNCATED = "truncated"  # too little ring-down to fix the damping
    OPTIMISER = "optimiser"  # a parameter at the end of its range, no convergence
    UNITS = "units"  # numbers that look like another unit: not fitted
    FREE_VIBRATION = "free-vibration"  # the tree's own vibration, no impact: not fitted
    SECOND_MODE = "second-mode"  # the residual has a mode of its own
    MISFIT = "misfit"  # the residual is not noise

    def __str__(self) -> str:
        return self.value


#: The kinds that make a record NOT explained, in the order a conclusion names them.
REFUSING = (DiagnosisKind.UNITS, DiagnosisKind.FREE_VIBRATION, DiagnosisKind.NO_IMPACT, DiagnosisKind.OPTIMISER,
            DiagnosisKind.TRUNCATED, DiagnosisKind.SECOND_MODE, DiagnosisKind.MISFIT)
#: The kinds an explained record's conclusion names beside "explained".
QUALIFYING = (DiagnosisKind.DRIFT, DiagnosisKind.OUTLIERS, DiagnosisKind.ONE_IMPACT)


@dataclass(frozen=True)
class Diagnosis:
    """One finding of the record fit (docs/identification.md).

    Attributes:
        kind: what it is about, a ``DiagnosisKind`` (its ``value`` the JSON's name).
        message: one line saying what was found, with its numbers and their units.
    """

    kind: DiagnosisKind
    message: str

    def to_json(self) -> dict:
        """``{"kind": kind's value, "message": message}``."""
        return {"kind": self.kind.value, "message": self.message}


def optimiser_trouble(p, lower_t0: float, upper_t0: float, dt: float, status: int,
                      noise_limited: bool) -> Diagnosis | None:
    """M_T, K_T or t0 at the end of the fit's range, the trunk's damping ratio at its top, or
    no convergence in REFINE_NFEV evaluations while the residual is not the noise.

    Args:
        p: the fitted parameters (:class:`fit_parameters.Slot` order).
        lower_t0: the earliest contact time the fit allows, s (the fit's clock).
        upper_t0: the latest, s.
        dt: the record's sample interval, s (t0 within one of a bound is at it).
        status: least_squares' status (0: the evaluations ran out).
        noise_limited: whether the residual is the noise.

    Returns:
        The OPTIMISER diagnosis, or None.
    """
    at_bound = [name for name, slot, lim in (("M_T", Slot.LN_DYNAMIC_MASS, M_RANGE),
                                             ("K_T", Slot.LN_EQUIVALENT_STIFFNESS, K_RANGE))
                if min(abs(p[slot] - math.log(lim[0])), abs(p[slot] - math.log(lim[1])))
                < 1e-3]
    if p[Slot.TRUNK_DAMPING_RATIO] > XI_RANGE[1] - 1e-3:
        at_bound.append("trunk_damping_ratio")
    if p[Slot.T0] < lower_t0 + dt or p[Slot.T0] > upper_t0 - dt:
        at_bound.append("t0")
    if not (at_bound or status == 0 and not noise_limited):
        return None
    why = (f"{', '.join(at_bound)} at the end of the fit's range" if at_bound else
           f"no convergence in {REFINE_NFEV} evaluations")
    return Diagnosis(DiagnosisKind.OPTIMISER, f"optimiser trouble: {why}")


def swing_back(p, test: PendulumTest) -> float:
    """The time (s, the fit's clock) of the first minimum after the largest displacement of
    the motion fitted as ``p`` (:class:`fit_parameters.Slot` order) with the pendulum of
    ``test``: the swing back a record must reach to fix the damping (inf if none within
    four periods of the slower of the trunk's own and the joint motion)."""
    M, K = math.exp(p[Slot.LN_DYNAMIC_MASS]), math.exp(p[Slot.LN_EQUIVALENT_STIFFNESS])
    w = min(math.sqrt(K / M), math.sqrt((K + test.impactor_stiffness)
                                        / (M + test.impactor_mass)))
    s = p[Slot.T0] + np.linspace(0.0, 8.0 * math.pi / w, 4001)[1:]
    model = np.zeros(len(Slot))
    model[: Slot.T0 + 1] = p[: Slot.T0 + 1]  # the tree and the contact, no sensor terms
    x = model_motion(model, test, s)[0]
    top = int(np.argmax(x))
    rising = np.flatnonzero(np.diff(x[top:]) > 0)
    return float(s[top + rising[0]]) if rising.size else math.inf


def truncation(p, test: PendulumTest, t_end: float, damping_interval) -> Diagnosis | None:
    """A record ending (``t_end``, s, the fit's clock) before the first swing back
    (:func:`swing_back` of ``p`` and ``test``) that leaves the trunk's damping ratio's
    ``damping_interval`` (low, high) wider than TRUNCATED_XI_SPAN: the TRUNCATED diagnosis,
    or None."""
    t_back = swing_back(p, test)
    xi_lo, xi_hi = damping_interval
    if not (t_end < t_back and not xi_hi <= TRUNCATED_XI_SPAN * xi_lo):
        return None
    t0 = p[Slot.T0]
    return Diagnosis(DiagnosisKind.TRUNCATED, (
        f"truncated record: it ends {t_end - t0:.3g} s after the contact, before the "
        f"trunk's first swing back ({t_back - t0:.3g} s): too little ring-down to fix "
        f"the damping (trunk_damping_ratio between {xi_lo:.3g} and {xi_hi:.3g})"))


def residual_diagnosis(p, test: PendulumTest, judged: NoiseJudgement, resid_after,
                       dt: float) -> Diagnosis | None:
    """Why a residual that is not the noise is not: the pendulum's channel, a mode of its
    own (:data:`PEAK_STRENGTH` over the white floor, :data:`PEAK_SEPARATION` from the fit's
    modes) or a misfit; None when both channels are at their noise.

    Args:
        p: the fitted parameters (:class:`fit_parameters.Slot` order).
        test: the pendulum test (its mass and spring set the joint mode).
        judged: the residual against the noise (:class:`noise.NoiseJudgement`).
        resid_after: the trunk channel's residual after the contact, m.
        dt: its sample interval, s.

    Returns:
        A MISFIT or SECOND_MODE diagnosis, or None.
    """
    if judged.limited and judged.y_limited:
        return None
    if judged.limited:
        return Diagnosis(DiagnosisKind.MISFIT, (
            f"the pendulum's record is not explained: its residual is {judged.ratio_y:.3g} x "
            f"its noise"))
    peak_w, strength = dominant_frequency(resid_after, dt)
    M, K = math.exp(p[Slot.LN_DYNAMIC_MASS]), math.exp(p[Slot.LN_EQUIVALENT_STIFFNESS])
    own = [math.sqrt(math.exp(p[Slot.LN_EQUIVALENT_STIFFNESS] - p[Slot.LN_DYNAMIC_MASS])),
           math.sqrt((K + test.impactor_stiffness) / (M + test.impactor_mass))]
    if strength > PEAK_STRENGTH and all(abs(peak_w / w - 1.0) > PEAK_SEPARATION for w in own):
        return Diagnosis(DiagnosisKind.SECOND_MODE, (
            f"the residual has a mode of its own at {peak_w:.4g} rad/s "
            f"({peak_w / (2 * math.pi):.4g} Hz), the fit's omega_1 is {own[0]:.4g} rad/s: "
            f"a second mode (of the trunk, the crown, the flexible trunk's contact) the "
            f"1-DOF model does not have"))
    return Diagnosis(DiagnosisKind.MISFIT, (
        f"the residual is {judged.ratio:.3g} x the noise, not noise: the 1-DOF model does "
        f"not explain the record (largest at {peak_w:.4g} rad/s)"))


def drift(p, cov, t: np.ndarray, t_record: np.ndarray, noise: float,
          span: float) -> Diagnosis | None:
    """The fitted drift at its largest over the record (from its value at the contact; t
    the fit's clock, ``t_record`` the record's, s): a misfit beyond DRIFT_MAX of the peak
    ``span`` (m), a sensor's drift beyond the ``noise`` (m) and 4 of its standard errors
    (from ``cov``, the fit's covariance in slot order, of the parameters ``p``)."""
    s_all = t - p[Slot.T0]
    curve = drift_at(p, s_all)
    k = int(np.argmax(np.abs(curve)))
    g = np.array([s_all[k], s_all[k] ** 2])
    drift_sd = math.sqrt(max(float(g @ cov[np.ix_(DRIFTS, DRIFTS)] @ g), 0.0))
    if abs(curve[k]) > DRIFT_MAX * span:
        return Diagnosis(DiagnosisKind.MISFIT, (
            f"the fitted drift reaches {abs(curve[k]) / span:.0%} of the peak: a slow "
            f"motion the 1-DOF model does not have (a mode below the fit's omega_1), not a "
            f"sensor's drift"))
    if abs(curve[k]) > max(noise, 4.0 * drift_sd):
        return Diagnosis(DiagnosisKind.DRIFT, (
            f"the sensor drifts by up to {curve[k]:.3g} m ({abs(curve[k]) / span:.1%} "
            f"of the peak, at t = {t_record[k]:.4g} s; {p[Slot.X_DRIFT]:.3g} m/s and "
            f"{p[Slot.X_DRIFT2]:.3g} m/s^2 from the contact) from an offset of "
            f"{p[Slot.X_OFFSET]:.3g} m: fitted and removed"))
    return None


_SOURCES = {NoiseSource.REST: "of the samples before the contact",
            NoiseSource.DIFFERENCES: "of the record's second differences",
            NoiseSource.SPECTRUM: "the residual spectrum's white floor",
            NoiseSource.RESOLUTION: f"the resolution floor, {RESOLUTION:g} of the peak: the "
                                    f"record has no noise above it"}


def noise_limited(rms: float, judged: NoiseJudgement) -> Diagnosis:
    """The residual ``rms`` (m) of an explained record, the noise and where it came from
    (``judged``): the NOISE_LIMITED diagnosis."""
    return Diagnosis(DiagnosisKind.NOISE_LIMITED, (
        f"residual {rms:.3g} m = {judged.ratio:.2f} x the noise {judged.noise:.3g} m ("
        f"{_SOURCES[judged.source]})"))


def no_impact(test: ImpactTest, drift_degree: int) -> Diagnosis | None:
    """A record whose fitted impact does not stand above its noise (``test``, against the
    null of an offset with a drift of ``drift_degree`` 0, 1 or 2): the fit's values are the
    noise's, not a tree's; None when the impact is significant."""
    if test.significant:
        return None
    null = ("an offset", "an offset and a drift", "an offset and a bent drift")[drift_degree]
    return Diagnosis(DiagnosisKind.NO_IMPACT, (
        f"no impact above the noise: {null} alone explain the record within "
        f"{test.statistic:.3g} noise variances of the fit (an impact needs more than "
        f"{test.threshold:.3g}; noise {test.noise:.3g} m, {_SOURCES[test.source]}): its "
        f"motion is the sensor's noise, not a tree's response"))


def sensor_held(t_end: float, feat_quarter: float, rest_fit: int = 0,
                t_read: float = math.nan, t0: float = math.nan) -> Diagnosis:
    """No sensor offset or drift fitted: the record (ending ``t_end`` s after the contact)
    showed no rest before the contact read from its shape (at ``t_read`` s) and no ring-down
    past a period (about 4 x ``feat_quarter`` s); ``rest_fit``: the samples before the
    fit's contact ``t0`` (s): when they are a rest the shape's reading missed (the noise
    hid it), said so."""
    if rest_fit >= MIN_REST_SAMPLES:
        rest = (f"the contact read from the record's shape at {t_read:.3g} s left no rest "
                f"before it (the noise hides it), though the fit puts the contact at "
                f"{t0:.3g} s, after {rest_fit} samples; the record ")
    else:
        rest = "the record has no rest before the contact and "
    return Diagnosis(DiagnosisKind.SENSOR_HELD, (
        f"the sensor's offset and drift held at 0 (its zero taken as the trunk's rest): "
        f"{rest}ends {t_end:.3g} s after it, within a "
        f"period of the motion (about {4.0 * feat_quarter:.3g} s), where an offset or a "
        f"drift cannot be told from the motion; a record from before the impact or past a "
        f"period fits them"))


def outliers(rows: list, count: int, z: float) -> Diagnosis:
    """``count`` samples left out, more than ``z`` noise deviations off, at file ``rows``."""
    shown = ", ".join(str(r) for r in rows[:5])
    return Diagnosis(DiagnosisKind.OUTLIERS, (
        f"{count} sample(s) more than {z:g} noise deviations off the fit "
        f"left out (file rows {shown}{', ...' if count > 5 else ''})"))
