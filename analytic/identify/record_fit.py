"""Tree properties from a whole pendulum-test record: the exact 1-DOF model fitted to it.

The paper's procedure (eqs 39-48, :mod:`analytic.identify.procedure`) reads three numbers off
the record after the bodies move together. Here the exact model of eqs 12-35 (M_T, C_T, K_T,
e, the pendulum of eq 13 at u_1 of eq 48) is fitted to every sample of x(t) by nonlinear
least squares (``scipy.optimize.least_squares``), with the time of the first contact, a
sensor offset and drift as nuisance parameters, and to the pendulum's y(t) too when the
record has it. In three stages:

1. a robust fit (soft-l1 loss) at e = 0 from the record's shape, on every k-th sample;
   isolated samples far off it (:data:`OUTLIER_Z` robust deviations) are left out;
2. the global stage: e's profile (:class:`_Profile`), the cost with e held on a grid
   (:data:`PROFILE_RESTITUTIONS`; e has a local minimum per number of impacts), swept from
   that fit and from fresh first guesses on each branch, zoomed around its lowest valleys;
3. the fit with e free from the profile's lowest point(s), outliers checked once more, a
   drift bent like t^2 added if the record calls for it.

What the record fixes is decided from the data: the restitutions whose profile cost is
within the 95 % likelihood-ratio threshold of the optimum are those it cannot rule out;
when they reach the top of the grid with a one-impact model there (the pendulum leaving:
M_T and e on a ridge of equal residual) M_T and e are not fixed apart. 95 % intervals come
from the Jacobian at the optimum (cov = s^2 (J^T J)^-1, s^2 = RSS / (n - p), never below the
record's resolution floor), widened over the profile, in logarithms for the positive
quantities, in asin(sqrt(e)) for e: they stay in the physical range. The residual is
judged against the sensor's noise estimated from the record itself
(:mod:`analytic.identify.diagnose`), and the fit says what it sees
(:attr:`FitResult.diagnoses`): noise-limited, drift, outliers, a one-impact record, a
truncated record, optimiser trouble, units, a second mode, a misfit.
docs/identification.md has the method and the measured accuracy.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from treeimpact.analytic.errors import ParameterError, SimulationDiverged
from treeimpact.analytic.model.parameters import check_range

from . import diagnose
from .fit_model import NAMES, drift_at, model_motion, model_x  # noqa: F401 - model_x: public
from .one_impact import RIDGE, on_ridge, one_impact
from .pendulum_record import Record, read_record  # noqa: F401 - read_record: public here
from .procedure import PendulumTest

Z95 = 1.959963984540054  # two-sided 95 % normal quantile
CHI2_95 = Z95 * Z95  # 3.84: the likelihood-ratio threshold of one parameter at 95 %
CHI2_999 = 10.827566170662733  # ... at 99.9 %: a term added to the model only past it
DIFF_STEP = 1e-6  # relative forward-difference step of the fit's Jacobian
#: The global stage, e's profile: the cost with e held at each of these (the others fitted), since e
#: has a local minimum per number of impacts before the bodies move together or part
#: (docs/identification.md); its lowest point starts the fit with e free, and the points
#: within the 95 % likelihood-ratio threshold widen the intervals (a profile likelihood).
#: Finer below 0.2, where a pad's e usually is and a chattering branch per impact lies.
PROFILE_RESTITUTIONS = (0.0, 0.05, 0.1, 0.15, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9)
PROFILE_SAMPLES = 2000  # the profile fits every k-th sample, at most this many
#: (e, xi) fitted from a first guess too (the first at e = 0 is the robust fit's): each
#: branch, and a lightly damped start (a short record has a basin per damping too)
PROFILE_FRESH = ((0.0, 0.1), (0.3, 0.1), (0.3, 0.02), (0.6, 0.1), (0.9, 0.1))
PROFILE_NFEV_FIRST = 20  # evaluations of the robust fit from the first guess at e = 0
PROFILE_NFEV_FRESH = 15  # ... of a fit from a first guess
PROFILE_NFEV = 6  # ... from a neighbour's optimum: a few steps
PROFILE_ZOOM = 3  # halvings of the grid's spacing around its lowest local minima ...
PROFILE_BASINS = 2  # ... this many of them
REFINE_NFEV = 100  # evaluations of the fit with e free
REFINE_SAMPLES = 20_000  # ... on every k-th sample, at most this many
POLISH_NFEV = 4  # then evaluations on all the samples (a Gauss-Newton step or two)
#: A sample this many noise deviations off the robust fit is an outlier: a normal sample
#: gets there once in 5e8, so a record of 1e5 samples flags none by chance.
OUTLIER_Z = 6.0
#: ...unless there are more than this share of them: then the model misses the record.
OUTLIER_SHARE = 0.005
#: The finest a field record resolves, of its peak (a 14-bit converter's step is 6e-5 of
#: its range): a residual below it is not a misfit, and no interval is narrower than this
#: noise gives (a record without noise: a simulation's, interpolated or rounded).
RESOLUTION = 1e-4
#: A record that ends before the trunk's first swing back is truncated when it leaves xi
#: this uncertain (its 95 % interval spanning more than this factor, +-20 %): a noise-free
#: record fixes the damping before that, a noisy one cut after the peak does not.
TRUNCATED_XI_SPAN = 1.5
#: The residual's dominant frequency counts as a mode of its own when its peak stands this
#: far over the white floor (a false alarm once in ~1e3 records of 1e4 samples by chance:
#: exponential ordinates, ln(5e3 / 1e-3) = 15.4) and is 25 % away from the fitted modes.
PEAK_STRENGTH = 15.0
PEAK_SEPARATION = 0.25
#: The two damping ratios a fit reports, by name: the trunk's own (the fit's parameter) and
#: the moving-together pair's, the paper's xi = b / omega_n (eqs 42-43), which the paper's
#: procedure and the report's truth give (docs/glossary.md).
DAMPING_RATIOS = ("trunk_damping_ratio", "pair_damping_ratio")
DAMPING_RATIO_FORMULAS = {
    "trunk_damping_ratio": "C_T / (2 sqrt(K_T M_T)): the trunk alone",
    "pair_damping_ratio": "b / omega_n = C_T / (2 sqrt((K_T + k)(M_T + m))): the trunk and "
                          "pendulum moving together, the paper's xi (eqs 42-43)"}
#: A fitted drift this large (of the peak) is no sensor's: a slow motion of the tree.
DRIFT_MAX = 0.5
#: Allowed parameter ranges of the fit (SI): a value at a bound is no tree's.
M_RANGE, K_RANGE, XI_RANGE, E_MAX = (1e-2, 1e5), (1.0, 1e10), (1e-3, 5.0), 0.95

#: Every kind a diagnosis may have (docs/identification.md, "Diagnoses").
DIAGNOSES = ("noise-limited", "drift", "outliers", "one-impact", "truncated", "optimiser",
             "units", "second-mode", "misfit")


@dataclass(frozen=True)
class FitResult:
    """The fitted model (SI) with 95 % intervals, and how well it explains the record."""

    values: dict  # M_T kg, K_T N/m, C_T N s/m, xi 1, e 1, E Pa, omega_1 rad/s, V_1 m/s,
    #               t0 s, x_offset m, x_drift m/s, x_drift2 m/s^2 (and y_offset m with a
    #               pendulum record)
    intervals: dict  # name -> (low, high)
    residual_rms: float  # m, over the samples fitted (flagged outliers left out)
    peak: float  # m, largest |x - offset| of the record
    explained: bool  # the 1-DOF model explains the record to its noise and its values hold
    model_x: np.ndarray  # m, the fitted x at the record's times
    determined: dict  # name -> False for a quantity the record does not fix (value NaN)
    point: np.ndarray  # the optimum p (fit_model.NAMES); one of many if not all fixed
    note: str = ""  # why some quantities are not determined, or ""
    residual_rms_y: float | None = None  # m, of the pendulum's record if it has one
    model_y: np.ndarray | None = None  # m, the fitted y at the record's times
    verdict: str = ""  # one line: explained (and how) or NOT explained (and why)
    diagnoses: tuple = ()  # ({"kind": DIAGNOSES entry, "message": one line}, ...)
    noise: float = math.nan  # m, the sensor noise estimated from the record
    noise_source: str = ""  # "rest" (samples before the contact), "spectrum" (the residual's
    #                         white floor) or "resolution" (RESOLUTION: no noise above it)
    misfit_ratio: float = math.nan  # residual RMS / noise (about 1 when explained)
    flagged: np.ndarray = field(default_factory=lambda: np.zeros(0, int))  # outlier rows
    warnings: tuple = ()  # one line each: units, ...
    starts: int = 0  # least-squares fits run (the profile's points, refinements)
    runs: int = 0  # runs of the model (the exact solver sampled at the record's times)

    def to_json(self) -> dict:
        return {k: {"value": v, "low": self.intervals[k][0], "high": self.intervals[k][1],
                    "determined": self.determined[k]} for k, v in self.values.items()}

    def diagnosis_kinds(self) -> list[str]:
        return [d["kind"] for d in self.diagnoses]


# -- starts -----------------------------------------------------------------------------

def first_guess(feat: diagnose.Features, test: PendulumTest, e: float, y=None, t=None, *,
                xi: float = 0.1) -> np.ndarray:
    """A start on e's own branch from the record's shape: the contact extrapolated back from
    the 10 % and 40 % crossings, M_T from the slope V there by momentum (one impact,
    V = m (1 + e) u_1 / (M_T + m), when that M_T e exceeds m: the pendulum rebounds; else
    chattering into moving together, V = m u_1 / (M_T + m)), K_T from the contact-to-peak
    time as a quarter period of that branch's motion, xi 0.1; the pendulum sensor's offset
    (if y is recorded) from the samples before the contact, less the free swing."""
    m, u1, k = test.impactor_mass, test.impact_speed, test.impactor_stiffness
    V = min(max(feat.velocity, 1e-3 * u1), 1.9 * u1)
    M_one = m * ((1.0 + e) * u1 / V - 1.0)
    one = M_one > 0 and M_one * e > m
    M = M_one if one else m * max(u1 / V - 1.0, 0.05)
    M = min(max(M, 1.5 * M_RANGE[0]), 0.5 * M_RANGE[1])
    omega = 0.5 * math.pi / max(feat.t_peak - feat.t_contact, 2.0 * feat.dt)
    K = omega ** 2 * M if one else omega ** 2 * (M + m) - k
    K = min(max(K, 2.0 * K_RANGE[0]), 0.5 * K_RANGE[1])
    p = np.array([math.log(M), math.log(K), xi, e, feat.t_contact, feat.rest, 0.0, 0.0, 0.0])
    if y is not None:
        before = t < p[4]
        if before.any():
            swing = model_motion(p, test, t[before], pendulum=True)[2]
            p[6] = float(np.median(y[before] - swing))
        else:
            p[6] = float(y[0])
    return p


class _Problem:
    """Residuals of a record, (x_model - x) / scale[0] and, if it has y, (y_model - y) /
    scale[1], and their Jacobian in the free parameters (indices ``free`` of p, the others
    held at ``fixed``)."""

    def __init__(self, t, x, y, test: PendulumTest, scale, upper, fixed, free):
        self.t, self.test, self.upper = t, test, upper
        self.pendulum = y is not None
        self.data = np.concatenate([x, y]) if self.pendulum else np.asarray(x)
        n = t.size
        self.weight = np.repeat(1.0 / np.asarray(scale[: 2 if self.pendulum else 1]), n)
        self.fixed, self.free = np.asarray(fixed, float), list(free)
        self._last = {}  # the motion at the last point evaluated: the Jacobian is asked there
        self.runs = 0

    def full(self, q) -> np.ndarray:
        p = self.fixed.copy()
        p[self.free] = q
        return p

    def _motion(self, p):
        self.runs += 1
        return model_motion(p, self.test, self.t, pendulum=self.pendulum)

    def residual(self, q) -> np.ndarray:
        p = self.full(q)
        self._last.clear()
        try:
            self._last[p.tobytes()] = m = self._motion(p)
        except (ParameterError, SimulationDiverged, ValueError, ArithmeticError):
            # (SimulationDiverged: also a model over the solver's event budget)
            return np.full(self.data.shape, 1e3)  # a model the solver refuses: far off
        model = np.concatenate([m[0], m[2]]) if self.pendulum else m[0]
        return (model - self.data) * self.weight

    def jacobian(self, q) -> np.ndarray:
        """Forward differences in ln M_T, ln K_T, xi, e (relative step DIFF_STEP, turned
        back at an upper bound); exact columns for t0 (minus the velocities and the drift:
        the record shifts with the contact), the offsets (1 on their channel) and the
        drift (t - t0 on x)."""
        p = self.full(q)
        if p.tobytes() not in self._last:
            self.residual(q)
        m = self._last.get(p.tobytes())
        jac = np.zeros((self.data.size, len(self.free)))
        if m is None:  # p itself refused: no motion to differentiate
            return jac
        n = self.t.size
        model = np.concatenate([m[0], m[2]]) if self.pendulum else m[0]
        r0 = (model - self.data) * self.weight
        for col, j in enumerate(self.free):
            if j == 4:
                vx = m[1] + p[7] + 2.0 * p[8] * (self.t - p[4])
                jac[:, col] = -(np.concatenate([vx, m[3]]) if self.pendulum else vx)
            elif j in (5, 6):
                jac[(j - 5) * n:(j - 4) * n, col] = 1.0
            elif j in (7, 8):
                jac[:n, col] = (self.t - p[4]) ** (j - 6)
            else:
                h = DIFF_STEP * max(1.0, abs(p[j])) * (1.0 if p[j] >= 0 else -1.0)
                if p[j] + h > self.upper[j]:
                    h = -h
                step = q.copy()
                step[col] += h
                jac[:, col] = (self.residual(step) - r0) / (step[col] - q[col])
                continue
            jac[:, col] *= self.weight
        self._last.clear()
        self._last[p.tobytes()] = m
        return jac

    def covariance(self, p, floor: float = 0.0, *, given_e: bool = False) -> np.ndarray:
        """Covariance of p (zero rows for fixed parameters), the free block
        (J^T W J)^-1 with J = d model / d p in metres and W = 1 / s_c^2 per channel,
        s_c^2 = max(RSS_c / n_c x n / (n - k), floor^2) (one channel: s^2 (J^T J)^-1);
        with ``given_e`` the covariance of the others at this e (e's row and column of
        J^T W J left out: the profile's point of view)."""
        return self.covariances(p, floor)[1 if given_e else 0]

    def covariances(self, p, floor: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        """(:meth:`covariance`, the same given e) from one Jacobian."""
        key = (p.tobytes(), floor)
        if getattr(self, "_cov_key", None) == key:
            return self._cov
        q = p[self.free]
        r = self.residual(q) / self.weight  # metres
        J = self.jacobian(q) / self.weight[:, None]
        n, k = r.size, len(self.free)
        channels = r.reshape(2 if self.pendulum else 1, -1)
        s2 = np.maximum(np.mean(channels ** 2, axis=1) * n / max(n - k, 1), floor ** 2)
        w = np.repeat(1.0 / s2, self.t.size)
        info = J.T @ (J * w[:, None])
        out = []
        for given_e in (False, True):
            use = [i for i, j in enumerate(self.free) if not (given_e and j == 3)]
            cov = np.zeros((p.size, p.size))
            block = np.ix_([self.free[i] for i in use], [self.free[i] for i in use])
            try:
                cov[block] = np.linalg.inv(info[np.ix_(use, use)])
            except np.linalg.LinAlgError:
                cov[block] = np.nan
            out.append(cov)
        self._cov_key, self._cov = key, tuple(out)
        return self._cov


@dataclass
class _Fit:
    p: np.ndarray
    cost: float  # the least-squares cost, 1/2 sum of the scaled residuals squared
    status: int
    problem: _Problem


class _Fitter:
    """One record's fits: its bounds and scales, and a local fit from a start."""

    def __init__(self, t, x, y, test, restitution):
        self.t, self.x, self.y, self.test = t, x, y, test
        dt = float(np.median(np.diff(t)))
        self.dt = dt
        self.lower = np.array([math.log(M_RANGE[0]), math.log(K_RANGE[0]), XI_RANGE[0], 0.0,
                               t[0] - 10 * dt, -np.inf, -np.inf, -np.inf, -np.inf])
        self.upper = np.array([math.log(M_RANGE[1]), math.log(K_RANGE[1]), XI_RANGE[1], E_MAX,
                               t[-1] - 10 * dt, np.inf, np.inf, np.inf, np.inf])
        # x_drift2 only when the record calls for it (fit_record: a likelihood-ratio test)
        self.free = [j for j in range(len(NAMES) - 1) if not (j == 3 and restitution is not None)
                     and not (j == 6 and y is None)]
        self.runs = 0
        self.fits = 0
        # one scale per channel for every fit of the record: their costs compare
        rest = diagnose.features(t, x).rest
        self.scale = [max(float(np.max(np.abs(x - rest))), 1e-300)]
        if y is not None:
            self.scale.append(max(float(np.max(np.abs(y - np.median(y)))), 1e-300))

    def refine(self, p0, keep, free=None) -> _Fit:
        """The fit with all free from p0 on the kept samples: on every k-th of them (at
        most REFINE_SAMPLES), then a few steps on all of them if that left some out."""
        stride = max(1, int(math.ceil(np.count_nonzero(keep) / REFINE_SAMPLES)))
        f = self.fit(p0, keep=keep, stride=stride, free=free)
        return f if stride == 1 else self.fit(f.p, keep=keep, max_nfev=POLISH_NFEV, free=free)

    def fit(self, p0, *, keep=None, stride: int = 1, free=None, loss="linear",
            f_scale=1.0, max_nfev=REFINE_NFEV) -> _Fit:
        from scipy.optimize import least_squares

        free = self.free if free is None else free
        idx = np.arange(self.t.size)
        if keep is not None:
            idx = idx[keep]
        if stride > 1:
            idx = idx[::stride]
        scale = self.scale
        span = float(self.t[-1] - self.t[0])
        prob = _Problem(self.t[idx], self.x[idx], None if self.y is None else self.y[idx],
                        self.test, scale, self.upper, p0, free)
        x_scale = np.array([1, 1, 0.1, 0.1, self.dt, 1e-2 * scale[0], 1e-2 * scale[-1],
                            1e-2 * scale[0] / span, 1e-2 * scale[0] / span ** 2])[free]
        lo, hi = self.lower[free], self.upper[free]
        q0 = np.clip(np.asarray(p0, float)[free], lo + 1e-9, hi - 1e-9)
        res = least_squares(prob.residual, q0, jac=prob.jacobian, bounds=(lo, hi),
                            x_scale=x_scale, max_nfev=max_nfev, loss=loss, f_scale=f_scale)
        self.runs += prob.runs
        self.fits += 1
        p = prob.full(res.x)
        r = prob.residual(res.x)
        return _Fit(p, 0.5 * float(r @ r), int(res.status), prob)


# -- the fit ------------------------------------------------------------------------------

def fit_record(record: Record, test: PendulumTest, *, start=None,
               restitution: float | None = None,
               free_fit: FitResult | None = None) -> FitResult:
    """The fit of the exact model to the whole record (module docstring), to the pendulum's
    record y too when it has one; ``restitution`` (known e, e.g. of the pendulum's pad)
    holds e fixed instead of fitting it (``free_fit``: the free fit of this record, if made:
    its point moved to that e along V_1 and omega_1 is one more start). ``start``: a local
    fit from this p alone (no global stage). A record of x alone whose e profile stays
    within the 95 % threshold up to a one-impact model (the pendulum leaving: M_T and e on
    a ridge) fixes omega_1, xi and V_1 but not M_T and e apart: then M_T, K_T, C_T, E and e
    are ranges (:mod:`analytic.identify.one_impact`). A record whose numbers look like
    another unit than ``record.time_unit``/``record.length_unit`` is not fitted."""
    if restitution is not None:
        check_range("restitution", restitution, low=0.0, high=1.0)
    t_orig, x, y = record.t, record.x, record.y
    t = t_orig - t_orig[0]  # the fit's clock starts at the first sample (epoch times)
    feat = diagnose.features(t, x)
    warnings = list(getattr(record, "warnings", ()))
    units = diagnose.unit_suspicions(feat, test.impact_speed,
                                     getattr(record, "time_unit", "s"),
                                     getattr(record, "length_unit", "m"))
    if units:  # no tree's values to find: said so at once (a fit of a record 1000 x too
        # long or too large is slow and meaningless)
        return _unit_result(record, feat, units, warnings + units, test)
    fitter = _Fitter(t, x, y, test, restitution)
    sigma_rest, n_rest = diagnose.rest_noise(t, x, feat.t_contact)
    floor = RESOLUTION * max(feat.span, 1e-300)
    # the robust loss is quadratic within this of the fit (3 noise deviations or 0.3 % of
    # the peak if more): beyond it a sample counts as |r|, so a wild one pulls little
    f_scale = 3.0 * max(sigma_rest if np.isfinite(sigma_rest) else 0.0,
                        1e-3 * feat.span) / fitter.scale[0]

    # 1: outliers: samples far off a robust fit (the first start, on every k-th sample),
    # left out from here on
    if start is not None:
        p0 = _full(start, float(t_orig[0]))
        if restitution is not None:
            p0[3] = restitution
    else:
        p0 = first_guess(feat, test, 0.0 if restitution is None else restitution, y, t)
    stride = max(1, int(math.ceil(t.size / PROFILE_SAMPLES)))
    first = fitter.fit(p0, loss="soft_l1", f_scale=f_scale, max_nfev=PROFILE_NFEV_FIRST,
                       stride=stride, free=fitter.free if restitution is not None or
                       start is not None else [j for j in fitter.free if j != 3])
    keep = np.ones(t.size, bool)
    flagged = _outliers(model_motion(first.p, test, t)[0] - x, floor, keep)
    keep[flagged] = False

    # 2: the global stage: the profile over e (or the given e or start), then all free
    profile = None
    if start is not None or restitution is not None:
        starts = [first.p]
        if start is None and free_fit is not None:
            moved = on_ridge(_full(free_fit.point, t_orig[0]), restitution, test)
            if np.all(np.isfinite(moved)):
                starts.append(moved)
    else:
        profile = _Profile(fitter, feat, test, keep, first)
        starts = profile.starts()
    polished = sorted((fitter.refine(q, keep) for q in starts), key=lambda f: f.cost)

    # 3: outliers the fit now shows, and least squares once more without them
    new = _outliers(model_motion(polished[0].p, test, t)[0] - x, floor, keep)
    if new.size:
        flagged = np.union1d(flagged, new).astype(int)
        keep[flagged] = False
        polished = [fitter.refine(polished[0].p, keep)]
    best = polished[0]
    # a drift bent like t^2 (an integrated accelerometer's, a warming sensor's) if the
    # record needs it: the cost falls by more than chi-square 10.83 (99.9 %) of the noise
    curved = fitter.refine(best.p, keep, free=fitter.free + [8])
    s2 = (max(math.sqrt(2.0 * best.cost / np.count_nonzero(keep)) * fitter.scale[0], floor)
          / fitter.scale[0]) ** 2
    if best.cost - curved.cost > 0.5 * CHI2_999 * s2:
        best = curved
    p = best.p
    tk, xk = t[keep], x[keep]
    motion = model_motion(p, test, t, pendulum=y is not None)
    fitted = motion[0]
    resid = (fitted - x)[keep]
    rms = math.sqrt(float(np.mean(resid ** 2)))
    peak = float(np.max(np.abs(xk - p[5] - drift_at(p, tk - p[4]))))
    rms_y = None
    if y is not None:
        rms_y = math.sqrt(float(np.mean(((motion[2] - y)[keep]) ** 2)))

    # the noise: before the contact if recorded there, else the residual's white floor
    after = tk > p[4]
    sigma_floor = diagnose.spectrum_floor(resid, fitter.dt)
    if np.isfinite(sigma_rest):
        noise, source, n_noise = sigma_rest, "rest", n_rest
    else:
        noise, source, n_noise = sigma_floor, "spectrum", resid.size
    if not noise > floor:
        noise, source = floor, "resolution"
    ratio = rms / noise
    # the ratio's allowance: 4 standard errors of the two estimates (relative: 1 / (2 n)
    # each), a false alarm on noise once in 3e4 records
    allowance = 4.0 * math.sqrt(0.5 / max(n_noise - 2, 1) + 0.5 / resid.size)
    noise_limited = ratio <= 1.0 + allowance or rms <= floor
    y_limited, ratio_y = True, math.nan
    if y is not None:  # the pendulum's channel against its own white floor (the spectrum's
        # estimate has a relative variance of 1 / n, the RMS 1 / (2 n): 4 of their errors)
        resid_y = (motion[2] - y)[keep]
        floor_y = RESOLUTION * fitter.scale[1]
        ratio_y = rms_y / max(diagnose.spectrum_floor(resid_y, fitter.dt), floor_y)
        y_limited = ratio_y <= 1.0 + 4.0 * math.sqrt(1.5 / resid_y.size) or rms_y <= floor_y

    # 4: what the record fixes: e's profile against the best fit (likelihood ratio)
    s2 = max((max(rms, floor) / fitter.scale[0]) ** 2,
             (rms_y / fitter.scale[1]) ** 2 if y is not None else 0.0)  # the cost's noise
    threshold = 0.5 * CHI2_95 * s2
    cov = best.problem.covariance(p, floor)
    values, intervals = _estimates(p, cov, test, pendulum=y is not None)
    determined = dict.fromkeys(values, True)
    note = ""
    ridge = None
    if profile is not None:
        # each e the record cannot rule out, with the others' uncertainty at that e
        given = best.problem.covariance(p, floor, given_e=True)
        inside = profile.inside(best, threshold)
        local = 0.02 < p[3] < E_MAX - 0.02 and intervals["restitution"][1] - intervals["restitution"][0] < 0.2
        if not local:  # e at a bound or the cost not quadratic in it: the profile alone
            _, intervals = _estimates(p, given, test, pendulum=y is not None)
        for q in inside:
            _, iv = _estimates(q, given, test, pendulum=y is not None)
            for k in RIDGE + DAMPING_RATIOS + ("omega_1", "V_1"):
                intervals[k] = (min(intervals[k][0], iv[k][0]), max(intervals[k][1], iv[k][1]))
        lo, hi = profile.e_range(best, threshold)
        intervals["restitution"] = ((min(intervals["restitution"][0], lo),
                                     max(intervals["restitution"][1], hi)) if local
                                    else (min(lo, p[3]), max(hi, p[3])))
        if y is None and profile.reaches_top(best, threshold):
            ridge = _ridge(fitter, profile, best, keep, test, threshold)
    if ridge is not None:
        values, intervals, determined, note = _ridge_estimates(ridge, fitter, keep, test,
                                                               floor, values, intervals)
    values["t0"] += float(t_orig[0])  # back on the record's own clock
    intervals["t0"] = tuple(v + float(t_orig[0]) for v in intervals["t0"])

    # 5: diagnoses
    diagnoses = []
    at_bound = [n for n, j, lim in (("M_T", 0, M_RANGE), ("K_T", 1, K_RANGE))
                if min(abs(p[j] - math.log(lim[0])), abs(p[j] - math.log(lim[1]))) < 1e-3]
    if p[2] > XI_RANGE[1] - 1e-3:
        at_bound.append("xi")
    if p[4] < fitter.lower[4] + fitter.dt or p[4] > fitter.upper[4] - fitter.dt:
        at_bound.append("t0")
    if at_bound or best.status == 0 and not noise_limited:
        why = (f"{', '.join(at_bound)} at the end of the fit's range" if at_bound else
               f"no convergence in {REFINE_NFEV} evaluations")
        diagnoses.append({"kind": "optimiser", "message": f"optimiser trouble: {why}"})
    t_back = _swing_back(p, test)
    xi_lo, xi_hi = intervals["trunk_damping_ratio"]
    if t[-1] < t_back and not xi_hi <= TRUNCATED_XI_SPAN * xi_lo:
        diagnoses.append({"kind": "truncated", "message": (
            f"truncated record: it ends {t[-1] - p[4]:.3g} s after the contact, before the "
            f"trunk's first swing back ({t_back - p[4]:.3g} s): too little ring-down to fix "
            f"the damping (xi between {xi_lo:.3g} and {xi_hi:.3g})")})
    peak_w, strength = diagnose.dominant_frequency((fitted - x)[keep][after], fitter.dt)
    if noise_limited and not y_limited:
        diagnoses.append({"kind": "misfit", "message": (
            f"the pendulum's record is not explained: its residual is {ratio_y:.3g} x its "
            f"noise")})
        noise_limited = False
    elif not noise_limited:
        own = [math.sqrt(math.exp(p[1] - p[0])),
               math.sqrt((math.exp(p[1]) + test.impactor_stiffness)
                         / (math.exp(p[0]) + test.impactor_mass))]
        if strength > PEAK_STRENGTH and all(abs(peak_w / w - 1.0) > PEAK_SEPARATION
                                            for w in own):
            diagnoses.append({"kind": "second-mode", "message": (
                f"the residual has a mode of its own at {peak_w:.4g} rad/s "
                f"({peak_w / (2 * math.pi):.4g} Hz), the fit's omega_1 is {own[0]:.4g} rad/s: "
                f"a second mode (of the trunk, the crown, the flexible trunk's contact) the "
                f"1-DOF model does not have")})
        else:
            diagnoses.append({"kind": "misfit", "message": (
                f"the residual is {ratio:.3g} x the noise, not noise: the 1-DOF model does "
                f"not explain the record (largest at {peak_w:.4g} rad/s)")})
    # the drift over the record (from its value at the contact) at its largest, and the
    # standard error there
    s_all = t - p[4]
    curve = drift_at(p, s_all)
    k = int(np.argmax(np.abs(curve)))
    g = np.array([s_all[k], s_all[k] ** 2])
    drift_sd = math.sqrt(max(float(g @ cov[7:9, 7:9] @ g), 0.0))
    if abs(curve[k]) > DRIFT_MAX * feat.span:
        diagnoses.append({"kind": "misfit", "message": (
            f"the fitted drift reaches {abs(curve[k]) / feat.span:.0%} of the peak: a slow "
            f"motion the 1-DOF model does not have (a mode below the fit's omega_1), not a "
            f"sensor's drift")})
    elif abs(curve[k]) > max(noise, 4.0 * drift_sd):
        diagnoses.append({"kind": "drift", "message": (
            f"the sensor drifts by up to {curve[k]:.3g} m ({abs(curve[k]) / feat.span:.1%} "
            f"of the peak, at t = {t_orig[k]:.4g} s; {p[7]:.3g} m/s and {p[8]:.3g} m/s^2 "
            f"from the contact) from an offset of {p[5]:.3g} m: fitted and removed")})
    explained = noise_limited and not any(d["kind"] in (
        "units", "optimiser", "truncated", "second-mode", "misfit") for d in diagnoses)
    if explained:
        diagnoses.insert(0, {"kind": "noise-limited", "message": (
            f"residual {rms:.3g} m = {ratio:.2f} x the noise {noise:.3g} m ("
            + {"rest": "of the samples before the contact", "spectrum": "the residual "
               "spectrum's white floor", "resolution": f"the resolution floor, {RESOLUTION:g}"
               " of the peak: the record has no noise above it"}[source] + ")")})
    if flagged.size:
        rows = ", ".join(str(record.row(int(i))) for i in flagged[:5])
        diagnoses.append({"kind": "outliers", "message": (
            f"{flagged.size} sample(s) more than {OUTLIER_Z:g} noise deviations off the fit "
            f"left out (file rows {rows}{', ...' if flagged.size > 5 else ''})")})
    if ridge is not None:
        diagnoses.append({"kind": "one-impact", "message": note})
    verdict = _verdict(explained, diagnoses)
    return FitResult(values=values, intervals=intervals, residual_rms=rms, peak=peak,
                     explained=explained, model_x=fitted, determined=determined,
                     point=_shifted(p, float(t_orig[0])), note=note, residual_rms_y=rms_y,
                     model_y=motion[2] if y is not None else None, verdict=verdict,
                     diagnoses=tuple(diagnoses), noise=noise, noise_source=source,
                     misfit_ratio=ratio, flagged=flagged, warnings=tuple(warnings + units),
                     starts=fitter.fits, runs=fitter.runs)


def _unit_result(record: Record, feat, units: list, warnings: list, test) -> FitResult:
    """The result for a record whose numbers look like another unit: no values (NaN),
    not explained, the suspicion as its diagnosis."""
    names = ("M_T", "K_T", "C_T") + DAMPING_RATIOS + ("restitution", "E", "omega_1", "V_1", "t0", "x_offset",
             "x_drift", "x_drift2") + (("y_offset",) if record.y is not None else ())
    nan = math.nan
    message = units[0]
    return FitResult(
        values=dict.fromkeys(names, nan), intervals=dict.fromkeys(names, (nan, nan)),
        residual_rms=nan, peak=feat.span, explained=False,
        model_x=np.full(record.t.size, nan), determined=dict.fromkeys(names, False),
        point=np.full(len(NAMES), nan), note="", model_y=None if record.y is None else np.full(
            record.t.size, nan), verdict="NOT explained (units): not fitted; declare the units",
        diagnoses=({"kind": "units", "message": message},), warnings=tuple(warnings))


def _outliers(r: np.ndarray, floor: float, keep: np.ndarray) -> np.ndarray:
    """Rows of the isolated wild samples (among ``keep``): further than OUTLIER_Z robust
    deviations both from the fit and from the median of their neighbours' residuals (a
    misfit is smooth: its neighbours follow it), if they are few (OUTLIER_SHARE of the
    record at most; more: a misfit)."""
    spread = max(diagnose.robust_sigma(r[keep]), floor)
    own = np.abs(r - np.median(r[keep]))
    alone = np.abs(r - diagnose.median3(r))
    far = np.flatnonzero(keep & (own > OUTLIER_Z * spread) & (alone > OUTLIER_Z * spread))
    return far if far.size <= max(1, OUTLIER_SHARE * r.size) else np.zeros(0, int)


def _full(p, t_shift: float = 0.0) -> np.ndarray:
    """p padded with zeros to every parameter of NAMES, t0 moved to the fit's clock."""
    out = np.zeros(len(NAMES))
    out[: len(p)] = np.asarray(p, float)
    out[4] -= t_shift
    return out


def _shifted(p, t_shift: float) -> np.ndarray:
    out = np.array(p, float)
    out[4] += t_shift
    return out


def _swing_back(p, test: PendulumTest) -> float:
    """The time (the fit's clock) of the fitted motion's first minimum after its largest
    displacement: the swing back a record must reach to fix the damping (inf if none
    within four periods of the slower of the trunk's own and the joint motion)."""
    M, K = math.exp(p[0]), math.exp(p[1])
    w = min(math.sqrt(K / M), math.sqrt((K + test.impactor_stiffness)
                                        / (M + test.impactor_mass)))
    s = p[4] + np.linspace(0.0, 8.0 * math.pi / w, 4001)[1:]
    x = model_motion(np.concatenate([p[:5], [0.0, 0.0, 0.0]]), test, s)[0]
    top = int(np.argmax(x))
    rising = np.flatnonzero(np.diff(x[top:]) > 0)
    return float(s[top + rising[0]]) if rising.size else math.inf


def _verdict(explained: bool, diagnoses: list) -> str:
    kinds = [d["kind"] for d in diagnoses]
    if explained:
        extra = [k for k in kinds if k in ("drift", "outliers", "one-impact")]
        return "explained" + (f" ({', '.join(extra)})" if extra else "")
    for kind in ("units", "optimiser", "truncated", "second-mode", "misfit"):
        if kind in kinds:
            return f"NOT explained ({kind}): the values are the best 1-DOF fit, not the tree's"
    return "NOT explained"  # pragma: no cover - one of the kinds above is always there


class _Profile:
    """The fit's cost with e held at each of :data:`PROFILE_RESTITUTIONS` (the others
    fitted) on every k-th kept sample (at most :data:`PROFILE_SAMPLES`). Fresh fits from a
    first guess at each of :data:`PROFILE_FRESH` (the branches: chattering into moving
    together, or the pendulum leaving); a sweep up the grid, each point from its
    neighbour's optimum or the fresh fit there, whichever is better; a sweep down, each
    point kept if it improves; then around its two lowest local minima at half, a quarter
    and an eighth of the grid's spacing (e's cost has a kink wherever an impact appears,
    and narrow dips between). Its lowest point starts the fit with e free; the points within
    the likelihood-ratio threshold of the optimum are the restitutions the record cannot
    rule out (a profile likelihood)."""

    def __init__(self, fitter: _Fitter, feat, test: PendulumTest, keep, first: _Fit):
        self.fitter, self.test, self.keep = fitter, test, keep
        self.stride = max(1, int(math.ceil(np.count_nonzero(keep) / PROFILE_SAMPLES)))
        self._free = [j for j in fitter.free if j != 3]
        grid = PROFILE_RESTITUTIONS
        fresh = {grid[0]: self._at(first.p, grid[0])}
        for e, xi in PROFILE_FRESH[1:]:
            f = fitter.fit(first_guess(feat, test, e, fitter.y, fitter.t, xi=xi), keep=keep,
                           stride=self.stride, free=self._free, max_nfev=PROFILE_NFEV_FRESH)
            if e not in fresh or f.cost < fresh[e].cost:
                fresh[e] = f
        points = []
        for e in grid:
            f = self._at(points[-1].p, e) if points else fresh[e]
            if e in fresh and fresh[e].cost < f.cost:
                f = fresh[e]
            points.append(f)
        for i in range(len(grid) - 2, -1, -1):
            f = self._at(points[i + 1].p, grid[i])
            if f.cost < points[i].cost:
                points[i] = f
        self.points = points
        # the lowest local minima of the grid (a point no higher than its neighbours), one
        # per valley (a flat stretch between two, the one-impact ridge, is one valley)
        minima = sorted((i for i in range(len(grid)) if all(
            points[j].cost >= points[i].cost for j in (i - 1, i + 1) if 0 <= j < len(grid))),
            key=lambda i: points[i].cost)

        def same_valley(i, j):
            top = max(points[i].cost, points[j].cost) * (1.0 + 1e-4)
            return all(points[k].cost <= top for k in range(min(i, j), max(i, j) + 1))

        chosen = []
        for i in minima:
            if not any(same_valley(i, j) for j in chosen):
                chosen.append(i)
        centres = [points[i] for i in chosen[:PROFILE_BASINS]]
        h = 0.1
        for _ in range(PROFILE_ZOOM):
            h *= 0.5
            for k, c in enumerate(centres):
                have = {round(float(f.p[3]), 9) for f in self.points}
                new = [self._at(c.p, e) for e in (c.p[3] - h, c.p[3] + h)
                       if 0.0 <= e <= E_MAX and round(e, 9) not in have]
                self.points.extend(new)
                centres[k] = min([c, *new], key=lambda f: f.cost)
        self.points.sort(key=lambda f: f.p[3])
        self.best = min(self.points, key=lambda f: f.cost)
        self.centres = sorted(centres, key=lambda f: f.cost)
        self._floor = None

    def starts(self) -> list:
        """Where the fit with e free starts: the lowest point, and the other basin's lowest
        when it is as low within the 95 % threshold (its noise from the cost itself)."""
        n = self.best.problem.data.size
        threshold = 0.5 * CHI2_95 * 2.0 * self.best.cost / max(n, 1)
        return [c.p for c in self.centres if c.cost <= self.best.cost + threshold] or [
            self.best.p]

    def _at(self, p, e: float) -> _Fit:
        p0 = np.array(p, float)
        p0[3] = e
        return self.fitter.fit(p0, keep=self.keep, stride=self.stride, free=self._free,
                               max_nfev=PROFILE_NFEV)

    def _min(self, best: _Fit) -> float:
        """The lowest cost on the profile's samples: its points' and the free fit's."""
        if self._floor is None:
            prob = self.points[0].problem
            r = prob.residual(best.p[prob.free])
            self._floor = min(0.5 * float(r @ r), min(f.cost for f in self.points))
        return self._floor

    def inside(self, best: _Fit, threshold: float) -> list:
        """The points (p) of the restitutions the record cannot rule out: the profile's
        within the threshold and, at each end of that range, the point where the cost
        crosses it (the neighbours' optima interpolated linearly)."""
        level = self._min(best) + threshold
        out = [f.p for f in self.points if f.cost <= level]
        return out + [q for q, _ in self._ends(level) if q is not None]

    def reaches_top(self, best: _Fit, threshold: float) -> bool:
        top = self.points[-1]
        return top.p[3] >= PROFILE_RESTITUTIONS[-1] and top.cost <= self._min(best) + threshold

    def e_range(self, best: _Fit, threshold: float) -> tuple[float, float]:
        """(low, high): the restitutions within the threshold (the profile's and the free
        fit's own), to the first point outside it on each side (the crossing lies between:
        a range as wide as the profile's spacing there can tell, not narrower; 0 and 1 past
        the ends of the profile)."""
        level = self._min(best) + threshold
        es = [float(f.p[3]) for f in self.points] + [float(best.p[3])]
        ok = [f.cost <= level for f in self.points] + [True]
        order = np.argsort(es, kind="stable")
        es, ok = [es[i] for i in order], [ok[i] for i in order]
        i = ok.index(True)
        j = len(ok) - 1 - ok[::-1].index(True)
        return (0.0 if i == 0 else es[i - 1], 1.0 if j == len(es) - 1 else es[j + 1])

    def _ends(self, level: float) -> list:
        """[(p or None, e)] at the low and the high end of the range within ``level``: the
        crossing of the cost, the neighbours' optima interpolated linearly in it."""
        cost = [f.cost for f in self.points]
        ins = [i for i, c in enumerate(cost) if c <= level]
        if not ins:
            return [(None, math.nan), (None, math.nan)]

        def cross(a, b):  # a inside, b outside
            frac = min(max((level - cost[a]) / max(cost[b] - cost[a], 1e-300), 0.0), 1.0)
            q = self.points[a].p + frac * (self.points[b].p - self.points[a].p)
            return q, float(q[3])

        i, j = ins[0], ins[-1]
        return [(None, 0.0) if i == 0 else cross(i, i - 1),
                (None, 1.0) if j == len(cost) - 1 else cross(j, j + 1)]


@dataclass
class _Ridge:
    one: np.ndarray  # a one-impact optimum (M_T and e free along the ridge)
    low: np.ndarray  # the lowest-e point explaining the record as well (on or off the ridge)
    e_low: float


def _ridge(fitter: _Fitter, profile: _Profile, best: _Fit, keep, test,
           threshold: float) -> _Ridge | None:
    """The ridge when the profile's top point, within the threshold, is a one-impact model
    (the pendulum leaves and does not return within the record): M_T and e not fixed
    apart; None when it is not (a flat profile of a record that still fixes M_T)."""
    one = profile.points[-1].p
    if not one_impact(one, test, float(fitter.t[keep][-1] - one[4])):
        return None
    low = profile.inside(best, threshold)[0]
    return _Ridge(one=one, low=low, e_low=profile.e_range(best, threshold)[0])


def _ridge_estimates(ridge: _Ridge, fitter: _Fitter, keep, test, floor: float, values,
                     intervals):
    """Values and ranges of a one-impact record: the fixed quantities as fitted, M_T, K_T,
    C_T, E and e not fixed: ranges from the 95 % low at the profile's lowest acceptable e
    to the 95 % high at e = 1 on the ridge (the Jacobian in the other parameters at both
    ends), and over the profile's points between."""
    fixed_e = [j for j in fitter.free if j != 3]
    tk, xk = fitter.t[keep], fitter.x[keep]
    intervals = dict(intervals)
    determined = {k: k not in RIDGE for k in values}
    for pe in (ridge.low, on_ridge(ridge.one, 1.0, test)):
        prob = _Problem(tk, xk, None, test, fitter.scale, fitter.upper, pe, fixed_e)
        _, iv = _estimates(pe, prob.covariance(pe, floor), test)
        for k in RIDGE:
            intervals[k] = (min(intervals[k][0], iv[k][0]), max(intervals[k][1], iv[k][1]))
    values = {k: (math.nan if k in RIDGE else v) for k, v in values.items()}
    intervals["restitution"] = (min(ridge.e_low, intervals["restitution"][0]), 1.0)
    note = (f"the pendulum leaves after one impact and does not return within the record: "
            f"it fixes omega_1, xi and the trunk's velocity after the impact V_1 = m (1 + e) "
            f"u_1 / (M_T + m) (eqs 21, 54), not M_T and e apart; M_T, K_T, C_T and E are "
            f"ranges over e in [{intervals['restitution'][0]:.3g}, 1] (a smaller e fits the record "
            f"worse); a known e (--restitution) or a record of the pendulum (column y) "
            f"fixes them")
    return values, intervals, determined, note


def _estimates(p, cov, test: PendulumTest, *, pendulum: bool = False) -> tuple[dict, dict]:
    """Values (SI) and 95 % intervals of every reported quantity at p with covariance cov,
    by the delta method in a variable spanning the physical range: logarithms for the
    positive ones (M_T, K_T, C_T, the damping ratios, E, omega_1, V_1), asin(sqrt(e)) in
    [0, pi/2] for e; the pendulum sensor's offset too if ``pendulum``. The two damping ratios
    are :data:`DAMPING_RATIOS`."""
    M, K, xi, e = math.exp(p[0]), math.exp(p[1]), float(p[2]), float(p[3])
    m, u1, k = test.impactor_mass, test.impact_speed, test.impactor_stiffness
    C = 2.0 * xi * math.sqrt(K * M)
    pair = C / (2.0 * math.sqrt((K + k) * (M + m)))  # b / omega_n, eqs 42-43
    I = math.pi * test.diameter ** 4 / 64.0
    e_mod = K * test.clamp_height ** 3 / (3.0 * I)  # eq 47
    omega = math.sqrt(K / M)  # eq 14: omega_1^2 = K_T / M_T
    v1 = m * (1.0 + e) * u1 / (M + m)  # eq 21 at the first impact, trunk at rest

    def sd(*g):  # standard deviation of g . p
        g = np.concatenate([g, np.zeros(cov.shape[0] - len(g))])
        return math.sqrt(max(float(g @ cov @ g), 0.0))

    z = Z95

    def symmetric(j):
        w = z * sd(*([0] * j + [1]))
        return p[j] - w, p[j] + w

    values = {"M_T": M, "K_T": K, "C_T": C, "trunk_damping_ratio": xi,
              "pair_damping_ratio": pair, "restitution": e, "E": e_mod, "omega_1": omega,
              "V_1": v1, "t0": float(p[4]), "x_offset": float(p[5]),
              "x_drift": float(p[7]), "x_drift2": float(p[8])}
    intervals = {
        "M_T": log_interval(M, z * sd(1)),
        "K_T": log_interval(K, z * sd(0, 1)),
        "C_T": log_interval(C, z * sd(0.5, 0.5, 1.0 / xi)),
        "trunk_damping_ratio": log_interval(xi, z * sd(0, 0, 1.0 / xi)),
        "pair_damping_ratio": log_interval(pair, z * sd(0.5 * m / (M + m), 0.5 * k / (K + k),
                                                        1.0 / xi)),
        "restitution": restitution_interval(e, z * sd(0, 0, 0, 1)),
        "E": log_interval(e_mod, z * sd(0, 1)),
        "omega_1": log_interval(omega, z * sd(-0.5, 0.5)),
        "V_1": log_interval(v1, z * sd(-M / (M + m), 0, 0, 1.0 / (1.0 + e))),
        "t0": symmetric(4),
        "x_offset": symmetric(5),
        "x_drift": symmetric(7),
        "x_drift2": symmetric(8),
    }
    if pendulum:
        values["y_offset"] = float(p[6])
        intervals["y_offset"] = symmetric(6)
    return values, {k: (float(lo), float(hi)) for k, (lo, hi) in intervals.items()}


def log_interval(value: float, half_width: float) -> tuple[float, float]:
    """(value e^-w, value e^w) for a parameter fitted in logarithm with half-width w: a w
    beyond float range (a direction the record does not determine) gives (0, inf) as
    such, not an overflow; NaN stays NaN."""
    w = float(half_width)
    if not w < 700.0:  # e^700 ~ 1e304; NaN fails the test too and stays NaN below
        return (0.0, math.inf) if w == w else (math.nan, math.nan)
    return value * math.exp(-w), value * math.exp(w)


def restitution_interval(e: float, half_width: float) -> tuple[float, float]:
    """The interval of e with half-width w (in e) mapped through phi = asin(sqrt(e)), whose
    range [0, pi/2] is e's [0, 1]: phi +- w dphi/de, clipped to that range, mapped back. At
    e = 0 or 1 (dphi/de infinite) it reaches the far end of the range; NaN stays NaN."""
    w = float(half_width)
    if w != w:
        return math.nan, math.nan
    phi = math.asin(math.sqrt(min(max(e, 0.0), 1.0)))
    slope = 0.5 / math.sqrt(e * (1.0 - e)) if 0.0 < e < 1.0 else math.inf
    half = w * slope if w > 0 else 0.0
    lo, hi = max(0.0, phi - half), min(0.5 * math.pi, phi + half)
    return math.sin(lo) ** 2, math.sin(hi) ** 2
