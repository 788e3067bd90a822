"""Tree properties from a whole pendulum-test record: the exact 1-DOF model fitted to it.

The paper's procedure (eqs 39-48, :mod:`analytic.identify.procedure`) reads three numbers off
the record after the bodies move together. Here the exact model of eqs 12-35 (M_T, C_T, K_T,
e, the pendulum of eq 13 at u_1 of eq 48) is fitted to every sample of x(t) by nonlinear
least squares (``scipy.optimize.least_squares``), with the time of the first contact, a
sensor offset and drift as nuisance parameters (:mod:`.fit_parameters`), and to the
pendulum's y(t) too when the record has it. The jobs, one module each:

* :mod:`.staging`: a robust fit, e's profile (:mod:`.profile`), the fit with e free, outliers
  left out, a bent drift if the record calls for it (:mod:`.fitter`: one local fit);
* :mod:`.noise`: the sensor's noise and whether the residual is that noise;
* :mod:`.intervals`: 95 % intervals from the Jacobian, widened over the restitutions the
  record cannot rule out, a one-impact record's ranges (:mod:`.one_impact`);
* :mod:`.diagnosis`: what the fit sees (noise-limited, drift, outliers, a one-impact record,
  a truncated record, optimiser trouble, units, a second mode, a misfit);
* :mod:`.conclusion`: explained or not, and why.

This module runs them in order and gathers the :class:`FitResult`.
docs/identification.md has the method and the measured accuracy.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.stats import chi2

from treeimpact.analytic.model.parameters import check_range

from . import diagnosis as dx
from .conclusion import Conclusion, conclude, not_fitted
from .diagnosis import Diagnosis, DiagnosisKind
from .fit_model import drift_at, model_motion, model_x  # noqa: F401 - model_x: public
from .fit_parameters import DRIFTS, MODEL_SLOTS, Slot
from .fitter import Fitter
from .free_vibration import no_impact
from .intervals import (  # noqa: F401 - DAMPING_RATIO_FORMULAS, log_interval: public
    DAMPING_RATIO_FORMULAS,
    QUANTITIES,
    TREE,
    determined,
    estimates,
    log_interval,
    ridge_estimates,
    widened_over_profile,
)
from .noise import (
    RESOLUTION,
    ImpactTest,
    NoiseJudgement,
    NoiseSource,
    impact_test,
    independent_noise,
    judge,
    rest_noise,
)
from .pendulum_record import Record, read_record  # noqa: F401 - read_record: public here
from .procedure import PendulumTest
from .profile import CHI2_95, find_ridge
from .record_features import (
    JUMP_FACTOR,
    STEP_BLOCK,
    Features,
    features,
    mixed_length_unit,
    mixed_time_unit,
    pendulum_unit_suspicion,
    unit_suspicions,
)
from .staging import OUTLIER_Z, Staged, on_fit_clock, sensor_separable, stage


@dataclass(frozen=True)
class FitResult:
    """The fitted model (SI) with 95 % intervals, and how well it explains the record."""

    values: dict  # intervals.QUANTITIES (and y_offset m with a pendulum record), SI
    intervals: dict  # name -> (low, high)
    residual_rms: float  # m, over the samples fitted (flagged outliers left out)
    peak: float  # m, largest |x - offset| of the record
    explained: bool  # the 1-DOF model explains the record to its noise and its values hold
    model_x: np.ndarray  # m, the fitted x at the record's times
    determined: dict  # name -> False for a quantity the record does not fix (value NaN)
    #               (intervals.determined: a bounded interval narrower than a factor 2)
    point: np.ndarray  # the optimum p (fit_parameters.Slot order); one of many if not fixed
    note: str = ""  # why some quantities are not determined, or ""
    residual_rms_y: float | None = None  # m, of the pendulum's record if it has one
    model_y: np.ndarray | None = None  # m, the fitted y at the record's times
    conclusion: Conclusion = Conclusion.NONE  # explained (and how) or not (and why)
    diagnoses: tuple = ()  # (Diagnosis, ...)
    noise: float = math.nan  # m, the sensor noise estimated from the record
    noise_source: NoiseSource | None = None  # where that noise came from
    misfit_ratio: float = math.nan  # residual RMS / noise (about 1 when explained)
    flagged: np.ndarray = field(default_factory=lambda: np.zeros(0, int))  # outlier rows
    warnings: tuple = ()  # one line each: units, ...
    held: dict = field(default_factory=dict)  # name -> "given" / "held at 0": not fitted,
    #               its interval its value (e given, a drift the record cannot separate)
    starts: int = 0  # least-squares fits run (the profile's points, refinements)
    runs: int = 0  # runs of the model (the exact solver sampled at the record's times)

    def to_json(self) -> dict:
        """Quantity name -> {value, low, high (its 95 % interval), determined}, SI."""
        return {k: {"value": v, "low": self.intervals[k][0], "high": self.intervals[k][1],
                    "determined": self.determined[k]} for k, v in self.values.items()}

    def diagnosis_kinds(self) -> list[DiagnosisKind]:
        """The kinds of the fit's diagnoses, in order."""
        return [d.kind for d in self.diagnoses]

    def findings(self) -> str:
        """What the fit found, one line: its diagnoses' messages joined, or its conclusion
        (for a record not fitted: why, e.g. the unit flags to pass)."""
        return "; ".join(d.message for d in self.diagnoses) or str(self.conclusion)


@dataclass(frozen=True)
class _Fixed:
    """What the record fixes: values, intervals, which are determined, why not."""

    values: dict
    intervals: dict
    determined: dict
    note: str = ""
    held: dict = field(default_factory=dict)


def fit_record(record: Record, test: PendulumTest, *, start=None,
               restitution: float | None = None,
               free_fit: FitResult | None = None) -> FitResult:
    """The fit of the exact model of the pendulum ``test`` to the whole ``record`` (module
    docstring), to the pendulum's record y too when it has one; ``restitution`` (known e,
    e.g. of the pendulum's pad)
    holds e fixed instead of fitting it (``free_fit``: the free fit of this record, if made:
    its point moved to that e along V_1 and omega_1 is one more start). ``start``: a local
    fit from this p alone (no global stage). A record of x alone whose e profile stays
    within the 95 % threshold up to a one-impact model (the pendulum leaving: M_T and e on
    a ridge) fixes omega_1, the trunk's damping ratio and V_1 but not M_T and e apart: then
    M_T, K_T, C_T, E and e are ranges (:mod:`analytic.identify.one_impact`). A record whose
    numbers look like another unit than ``record.time_unit``/``record.length_unit``, or that
    holds no impact (the tree's free vibration, :func:`free_vibration.no_impact`), is not
    fitted."""
    if restitution is not None:
        check_range("restitution", restitution, low=0.0, high=1.0)
    t_shift = float(record.t[0])
    t, x, y = record.t - t_shift, record.x, record.y  # the fit's clock: 0 at the first sample
    feat = features(t, x)
    warnings = list(getattr(record, "warnings", ()))
    units = _unit_lines(record, feat, test)
    if units:  # no tree's values to find: said so at once (a fit of a record 1000 x too
        # long or too large is slow and meaningless)
        return _not_fitted_result(record, feat, Diagnosis(DiagnosisKind.UNITS, units[0]),
                                  warnings + units)
    free = no_impact(t, x, feat, RESOLUTION * max(feat.span, 1e-300))
    if free:  # the tree's own vibration: no impact to fit (a fit would explain it as one)
        return _not_fitted_result(record, feat, Diagnosis(DiagnosisKind.FREE_VIBRATION, free),
                                  warnings)
    rest = rest_noise(t, x, feat.t_contact)
    fitter = Fitter(t, x, y, test, restitution is not None,
                    separable=sensor_separable(t, feat, rest[1]))
    floor = RESOLUTION * max(feat.span, 1e-300)
    staged = stage(fitter, feat, test, floor=floor, sigma_rest=rest[0],
                   restitution=restitution,
                   start=None if start is None else on_fit_clock(start, t_shift),
                   free_point=None if free_fit is None else on_fit_clock(free_fit.point,
                                                                         t_shift))
    p, keep = staged.best.p, staged.keep
    motion, resid, judged, rms, rms_y = _residuals(staged, test, rest, floor)
    impact = _impact_test(staged, feat, resid, floor)
    fixed = _what_is_fixed(staged, test, floor, rms, rms_y, t_shift, impact.significant)
    explained, diagnoses = _diagnose(staged, test, judged, impact, fixed, record, feat,
                                     t_shift, resid)
    peak = float(np.max(np.abs(x[keep] - p[Slot.X_OFFSET]
                               - drift_at(p, t[keep] - p[Slot.T0]))))
    point = np.array(p, float)
    point[Slot.T0] += t_shift
    return FitResult(
        values=fixed.values, intervals=fixed.intervals, residual_rms=rms, peak=peak,
        explained=explained, model_x=motion[0], determined=fixed.determined, point=point,
        held=fixed.held,
        note=fixed.note, residual_rms_y=rms_y, model_y=motion[2] if y is not None else None,
        conclusion=conclude(explained, diagnoses), diagnoses=tuple(diagnoses),
        noise=judged.noise, noise_source=judged.source, misfit_ratio=judged.ratio,
        flagged=staged.flagged, warnings=tuple(warnings), starts=fitter.fits,
        runs=fitter.runs)


def _unit_lines(record: Record, feat: Features, test: PendulumTest) -> list[str]:
    """One line per column whose numbers contradict its declared unit: t and x
    (:func:`record_features.unit_suspicions`), t's step or x's or y's level changing part-way
    by a unit's factor (a column in two units), the pendulum's y
    (:func:`record_features.pendulum_unit_suspicion`)."""
    length_unit = getattr(record, "length_unit", "m")
    mixed = mixed_time_unit(record.t)
    if mixed is not None:  # the other checks read the record's time scale: said alone
        steps = np.diff(record.t)
        before = float(np.median(steps[max(mixed - 1 - STEP_BLOCK, 0):max(mixed - 1, 1)]))
        after = float(np.median(steps[mixed:mixed + STEP_BLOCK]))
        return [f"t's step changes from {before:.3g} s to {after:.3g} s at row "
                f"{record.row(mixed)} (a factor {max(after / before, before / after):.3g}): "
                "the column holds two units; one unit per column"]
    for name, column in (("x", record.x), ("y", record.y)):
        switch = None if column is None else mixed_length_unit(column)
        if switch is not None:  # a column in two units: said alone, as t's
            row, factor = switch
            return [f"{name}'s values change by a factor {factor:.3g} at row "
                    f"{record.row(row)} (from {column[row - 1]:.3g} to {column[row]:.3g} "
                    f"between two samples, a step {JUMP_FACTOR:g} times any other): the "
                    "column holds two units; one unit per column"]
    found = unit_suspicions(feat, test.impact_speed, getattr(record, "time_unit", "s"),
                            length_unit, test.impactor_mass)
    chord = test.impact_speed / math.sqrt(test.omega2_sq)  # 2 l_e sin(theta_0 / 2)
    approach = test.impact_speed * min(feat.t_contact - float(record.t[0]),
                                       1.0 / math.sqrt(test.omega2_sq)) / math.pi
    y_unit = getattr(record, "y_unit", None) or length_unit
    return found + pendulum_unit_suspicion(record.x, record.y, chord, y_unit, approach)


def _residuals(staged: Staged, test: PendulumTest, rest: tuple, floor: float):
    """(motion, x residual on the kept samples, the noise's judgement of it, its RMS, the
    y residual's RMS or None) of the staged fit (:func:`noise.judge`)."""
    fitter, keep = staged.fitter, staged.keep
    y = fitter.y
    motion = model_motion(staged.best.p, test, fitter.t, pendulum=y is not None)
    resid = (motion[0] - fitter.x)[keep]
    resid_y = None if y is None else (motion[2] - y)[keep]
    judged = judge(resid, fitter.dt, rest, floor, resid_y,
                   RESOLUTION * fitter.scale[-1] if y is not None else 0.0)
    rms = math.sqrt(float(np.mean(resid ** 2)))
    rms_y = None if y is None else math.sqrt(float(np.mean(resid_y ** 2)))
    return motion, resid, judged, rms, rms_y


def _impact_test(staged: Staged, feat: Features, resid: np.ndarray, floor: float):
    """The fitted impact against the record without one (:func:`noise.impact_test`), the
    noise estimated apart from the fit (:func:`noise.independent_noise`), never below the
    resolution ``floor``; the no-impact model has the fit's offset and drift terms."""
    fitter, keep, params = staged.fitter, staged.keep, staged.best.problem.params
    noise, source = independent_noise(fitter.t, fitter.x, feat.t_contact)
    impact = [s for s in (*MODEL_SLOTS, Slot.T0) if not params[s].frozen]
    return impact_test(fitter.t[keep], fitter.x[keep], resid, max(noise, floor), source,
                       drift_degree=_drift_degree(params), parameters=len(impact))


def _drift_degree(params) -> int:
    """The degree of the fit's drift polynomial: 0 (held), 1, or 2 (bent)."""
    return sum(not params[s].frozen for s in DRIFTS)


def _what_is_fixed(staged: Staged, test: PendulumTest, floor: float, rms: float,
                   rms_y: float | None, t_shift: float, impact: bool) -> _Fixed:
    """Values and 95 % intervals at the best fit, widened over e's profile (the restitutions
    within the likelihood-ratio threshold of the best fit), a one-impact record's ranges;
    t0 on the record's clock; what the record does not determine (:func:`_undetermined`;
    without an ``impact`` above the noise, none of the tree's quantities) not fixed."""
    fitter, best = staged.fitter, staged.best
    pendulum = fitter.y is not None
    s2 = max((max(rms, floor) / fitter.scale[0]) ** 2,
             (rms_y / fitter.scale[1]) ** 2 if pendulum else 0.0)  # the cost's noise
    threshold = 0.5 * CHI2_95 * s2
    basin_threshold = 0.5 * float(chi2.ppf(0.95, len(best.problem.free))) * s2  # joint 95 %
    values, intervals = estimates(best.p, best.problem.covariance(best.p, floor), test,
                                  pendulum=pendulum)
    fixed = _Fixed(values, intervals, dict.fromkeys(values, True))
    if staged.profile is not None:
        intervals = widened_over_profile(best, staged.profile, intervals, test, floor,
                                         threshold, pendulum=pendulum,
                                         basin_threshold=basin_threshold)
        fixed = _Fixed(values, intervals, fixed.determined)
        ridge = None if pendulum or not staged.profile.reaches_top(best, threshold) else \
            find_ridge(fitter, staged.profile, best, staged.keep, test, threshold)
        if ridge is not None:
            fixed = _Fixed(*ridge_estimates(ridge, fitter, staged.keep, test, floor,
                                            values, intervals))
    fixed.values["t0"] += t_shift  # back on the record's own clock
    fixed.intervals["t0"] = tuple(v + t_shift for v in fixed.intervals["t0"])
    return _undetermined(fixed, best.problem.params, impact, best.p)


#: The reported quantities a fit may hold at a value, and the words for it.
_HELD = {Slot.RESTITUTION: ("restitution", "given"), Slot.X_OFFSET: ("x_offset", "held at 0"),
         Slot.X_DRIFT: ("x_drift", "held at 0"), Slot.X_DRIFT2: ("x_drift2", "held at 0")}


#: The reported quantities each fitted parameter moves: a parameter at an end of the fit's
#: range (no tree's value) leaves none of them determined.
_MOVES = {Slot.LN_DYNAMIC_MASS: ("M_T", "C_T", "pair_damping_ratio", "omega_1", "V_1"),
          Slot.LN_EQUIVALENT_STIFFNESS: ("K_T", "C_T", "pair_damping_ratio", "E", "omega_1"),
          Slot.TRUNK_DAMPING_RATIO: ("trunk_damping_ratio", "C_T", "pair_damping_ratio"),
          Slot.RESTITUTION: ("restitution", "V_1"), Slot.T0: ("t0",)}
#: A parameter this close to a bound, in its optimiser scales, is at it.
AT_BOUND = 1e-6


def at_range_end(p, params) -> set:
    """The reported quantities moved by a free parameter of ``params`` that the fitted
    ``p`` leaves at an end of its range (e = 0 excepted: a plastic pad, a physical value)."""
    out = set()
    for slot, names in _MOVES.items():
        q = params[slot]
        if q.frozen:
            continue
        # t0 within a sample of its range's end, as optimiser_trouble reads it: a contact the
        # record does not show (its scale is the sample interval)
        tol = q.scale if slot == Slot.T0 else AT_BOUND * q.scale
        low = p[slot] <= q.low + tol and not (slot == Slot.RESTITUTION and q.low == 0.0)
        if low or p[slot] >= q.high - tol:
            out.update(names)
    return out


def _undetermined(fixed: _Fixed, params, impact: bool, p) -> _Fixed:
    """``fixed`` with each quantity the record does not determine (:func:`intervals.
    determined`; any of the tree's without an ``impact``; any a parameter at an end of its
    range moves, :func:`at_range_end` of the fitted ``p``) not fixed: its value NaN, its
    interval its range. A held parameter (``params`` frozen: e given, a drift not fitted)
    is determined, its interval its value."""
    held = {name: how for slot, (name, how) in _HELD.items() if params[slot].frozen}
    ends = at_range_end(p, params)
    values, ok = dict(fixed.values), dict(fixed.determined)
    for name, interval in fixed.intervals.items():
        if name in held:
            ok[name] = True
            continue
        ok[name] = (ok[name] and determined(name, interval) and (impact or name not in TREE)
                    and name not in ends)
        if not ok[name]:
            values[name] = math.nan
    note = fixed.note if impact else ("no impact above the noise: the record fixes none of "
                                      "the tree's quantities")
    if ends & set(fixed.values):
        note = "; ".join(filter(None, [note, (
            f"{', '.join(sorted(ends & set(fixed.values)))}: the fit ends at its range's "
            "end, no tree's value")]))
    return _Fixed(values, fixed.intervals, ok, note, held)


def _diagnose(staged: Staged, test: PendulumTest, judged: NoiseJudgement,
              impact: ImpactTest, fixed: _Fixed, record: Record, feat: Features,
              t_shift: float, resid: np.ndarray):
    """(explained, diagnoses): the findings of :mod:`.diagnosis` on the staged fit (its
    residual ``resid`` on the kept samples); explained when the impact stands above the
    noise, the residual is the noise on every channel and no refusing kind
    (:data:`diagnosis.REFUSING`) applies. A record without an impact gets no diagnosis of
    its fit but that."""
    fitter = staged.fitter
    found = [dx.no_impact(impact, _drift_degree(staged.best.problem.params))]
    if impact.significant:
        found += _fit_findings(staged, test, judged, fixed, feat, t_shift, resid)
    if fitter.params[Slot.X_OFFSET].frozen:
        t0 = float(staged.best.p[Slot.T0])
        found.append(dx.sensor_held(float(fitter.t[-1] - feat.t_contact),
                                   max(feat.t_peak - feat.t_contact, feat.dt),
                                   int(np.count_nonzero(fitter.t < t0 - 2.0 * feat.dt)),
                                   feat.t_contact + t_shift, t0 + t_shift))
    diagnoses = [d for d in found if d is not None]
    explained = judged.limited and judged.y_limited and not any(
        d.kind in dx.REFUSING for d in diagnoses)
    if explained:
        diagnoses.insert(0, dx.noise_limited(math.sqrt(float(np.mean(resid ** 2))), judged))
    if staged.flagged.size:
        rows = [record.row(int(i)) for i in staged.flagged[:5]]
        diagnoses.append(dx.outliers(rows, staged.flagged.size, OUTLIER_Z))
    if fixed.note and impact.significant:
        diagnoses.append(Diagnosis(DiagnosisKind.ONE_IMPACT, fixed.note))
    return explained, diagnoses


def _fit_findings(staged: Staged, test: PendulumTest, judged: NoiseJudgement, fixed: _Fixed,
                  feat: Features, t_shift: float, resid: np.ndarray) -> list:
    """The fit's own findings: optimiser trouble, a truncated record, a residual that is
    not the noise (a second mode, a misfit), a drift."""
    fitter, p, keep = staged.fitter, staged.best.p, staged.keep
    t = fitter.t
    lower, upper = fitter.params[Slot.T0].low, fitter.params[Slot.T0].high
    cov = staged.best.problem.covariance(p, RESOLUTION * max(feat.span, 1e-300))
    return [
        dx.optimiser_trouble(p, lower, upper, fitter.dt, staged.best.status, judged.limited),
        dx.truncation(p, test, float(t[-1]), fixed.intervals["trunk_damping_ratio"]),
        dx.residual_diagnosis(p, test, judged, resid[t[keep] > p[Slot.T0]], fitter.dt),
        dx.drift(p, cov, t, t + t_shift, judged.noise, feat.span)]


def _not_fitted_result(record: Record, feat: Features, found: Diagnosis,
                       warnings: list) -> FitResult:
    """The result for a record not fitted (its numbers look like another unit, or it holds
    no impact): no values (NaN), not explained, the reason (``found``) its diagnosis."""
    names = QUANTITIES + (("y_offset",) if record.y is not None else ())
    nan = math.nan
    return FitResult(
        values=dict.fromkeys(names, nan), intervals=dict.fromkeys(names, (nan, nan)),
        residual_rms=nan, peak=feat.span, explained=False,
        model_x=np.full(record.t.size, nan), determined=dict.fromkeys(names, False),
        point=np.full(len(Slot), nan), note="",
        model_y=None if record.y is None else np.full(record.t.size, nan),
        conclusion=not_fitted(found), diagnoses=(found,), warnings=tuple(warnings))
