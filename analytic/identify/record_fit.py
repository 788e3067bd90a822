"""Tree properties from a whole pendulum-test record: the exact 1-DOF model fitted to it.

The paper's procedure (eqs 39-48, :mod:`analytic.identify.procedure`) reads three numbers off
the record after the bodies move together. Here the exact model of eqs 12-35 (M_T, C_T, K_T,
e, the pendulum of eq 13 at u_1 of eq 48) is fitted to every sample of x(t) by nonlinear
least squares (``scipy.optimize.least_squares``), with the time of the first contact and a
sensor offset as nuisance parameters, and to the pendulum's y(t) too when the record has it.
95 % intervals come from the Jacobian at the optimum (residuals independent, equal variance
per channel: cov = s^2 (J^T J)^-1, s^2 = RSS / (n - p)); the fit "explains" the record when
its residual RMS is within :data:`EXPLAINED_FRACTION` of the peak displacement. The record:
:mod:`analytic.identify.pendulum_record`; the model at p: :mod:`analytic.identify.fit_model`; what
a one-impact record fixes: :mod:`analytic.identify.one_impact`. docs/identification.md has the
method and the measured accuracy.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.model.parameters import check_range

from .fit_model import model_motion, model_x  # noqa: F401 - model_x: public here too
from .one_impact import RIDGE, on_ridge, restitution_range
from .pendulum_record import Record, read_record  # noqa: F401 - read_record: public here
from .procedure import PendulumTest

#: The fit explains a record when its residual RMS is at most this fraction of the peak
#: displacement: 1-2 % sensor noise passes, a flexible trunk's second mode does not.
EXPLAINED_FRACTION = 0.03
Z95 = 1.959963984540054  # two-sided 95 % normal quantile
#: Restitutions the fit starts from, the best end kept: e has a local minimum per number
#: of impacts before the bodies move together or part; 0.1 tends to reach the chattering
#: branch, 0.5 a few impacts, 0.9 the one-impact branch (docs/identification.md).
START_RESTITUTIONS = (0.1, 0.5, 0.9)
DIFF_STEP = 1e-6  # relative forward-difference step of the fit's Jacobian


@dataclass(frozen=True)
class FitResult:
    """The fitted model (SI) with 95 % intervals, and how well it explains the record."""

    values: dict  # M_T kg, K_T N/m, C_T N s/m, xi 1, e 1, E Pa, omega_1 rad/s, V_1 m/s,
    #               t0 s, x_offset m (and y_offset m with a pendulum record)
    intervals: dict  # name -> (low, high)
    residual_rms: float  # m
    peak: float  # m, largest |x - offset| of the record
    explained: bool
    model_x: np.ndarray  # m, the fitted x at the record's times
    determined: dict  # name -> False for a quantity the record does not fix (value NaN)
    point: np.ndarray  # the optimum p (fit_model.NAMES); one of many if not all fixed
    note: str = ""  # why some quantities are not determined, or ""
    residual_rms_y: float | None = None  # m, of the pendulum's record if it has one
    model_y: np.ndarray | None = None  # m, the fitted y at the record's times

    def to_json(self) -> dict:
        return {k: {"value": v, "low": self.intervals[k][0], "high": self.intervals[k][1],
                    "determined": self.determined[k]} for k, v in self.values.items()}


def _start(record: Record, test: PendulumTest, e: float = 0.1) -> np.ndarray:
    """A first guess: the contact time extrapolated back from where x first passes 10 % and
    40 % of its range above its resting level (far above 1-2 % noise), M_T from the slope
    there (momentum at e = 0: V = m u1 / (M_T + m)), K_T from the time to the peak as a
    quarter period of the joint motion; the pendulum sensor's offset (if y is recorded) from
    the samples before the contact, less the free swing."""
    t, x = record.t, record.x
    rest = float(np.median(x[: max(3, x.size // 50)]))
    span = float(np.max(x) - rest)
    i10 = int(np.argmax(x - rest > 0.1 * span))
    i40 = int(np.argmax(x - rest > 0.4 * span))
    if i40 > i10:
        V = float((x[i40] - x[i10]) / (t[i40] - t[i10]))
    else:
        V = span / max(float(t[i40] - t[0]), 1e-4)
    V = max(V, 1e-6)
    t0 = float(t[i10]) - (float(x[i10]) - rest) / V
    i_peak = int(np.argmax(x))
    m, u1 = test.impactor_mass, test.impact_speed
    M = m * max(u1 / max(V, 1e-3 * u1) - 1.0, 0.05)
    omega = 0.5 * math.pi / max(float(t[i_peak]) - t0, 1e-4)
    K = max(omega ** 2 * (M + m) - test.impactor_stiffness, 1.0)
    p = np.array([math.log(M), math.log(K), 0.3, e, t0, rest, 0.0])
    if record.y is not None:
        before = t < t0
        if before.any():
            swing = model_motion(p, test, t[before], pendulum=True)[2]
            p[6] = float(np.median(record.y[before] - swing))
        else:
            p[6] = float(record.y[0])
    return p


class _Problem:
    """Residuals of a record, (x_model - x) / scale[0] and, if it has y, (y_model - y) /
    scale[1], and their Jacobian in the free parameters (indices ``free`` of p, the others
    held at ``fixed``)."""

    def __init__(self, record: Record, test: PendulumTest, scale, upper, fixed, free):
        self.t, self.test, self.upper = record.t, test, upper
        self.pendulum = record.y is not None
        self.data = np.concatenate([record.x, record.y]) if self.pendulum else record.x
        n = record.t.size
        self.weight = np.repeat(1.0 / np.asarray(scale[: 2 if self.pendulum else 1]), n)
        self.fixed, self.free = np.asarray(fixed, float), list(free)
        self._last = {}  # the motion at the last point evaluated: the Jacobian is asked there

    def full(self, q) -> np.ndarray:
        p = self.fixed.copy()
        p[self.free] = q
        return p

    def _motion(self, p):
        return model_motion(p, self.test, self.t, pendulum=self.pendulum)

    def residual(self, q) -> np.ndarray:
        p = self.full(q)
        self._last.clear()
        try:
            self._last[p.tobytes()] = m = self._motion(p)
        except ParameterError:  # a model the solver refuses: far from the record
            return np.full(self.data.shape, 1e3)
        model = np.concatenate([m[0], m[2]]) if self.pendulum else m[0]
        return (model - self.data) * self.weight

    def jacobian(self, q) -> np.ndarray:
        """Forward differences in ln M_T, ln K_T, xi, e (relative step DIFF_STEP, turned
        back at an upper bound); exact columns for t0 (minus the velocities: the record
        shifts with the contact) and the offsets (1 on their channel): four model runs a
        Jacobian instead of six or seven."""
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
                jac[:, col] = -(np.concatenate([m[1], m[3]]) if self.pendulum else m[1])
            elif j in (5, 6):
                jac[(j - 5) * n:(j - 4) * n, col] = 1.0
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

    def covariance(self, p) -> np.ndarray:
        """Covariance of p (zero rows for fixed parameters), the free block
        (J^T W J)^-1 with J = d model / d p in metres and W = 1 / s_c^2 per channel,
        s_c^2 = RSS_c / n_c x n / (n - k) (one channel: s^2 (J^T J)^-1, s^2 = RSS / (n - k))."""
        q = p[self.free]
        r = self.residual(q) / self.weight  # metres
        J = self.jacobian(q) / self.weight[:, None]
        n, k = r.size, len(self.free)
        channels = r.reshape(2 if self.pendulum else 1, -1)
        s2 = np.mean(channels ** 2, axis=1) * n / max(n - k, 1)
        w = np.repeat(1.0 / s2, self.t.size)
        cov = np.zeros((p.size, p.size))
        try:
            cov[np.ix_(self.free, self.free)] = np.linalg.inv(J.T @ (J * w[:, None]))
        except np.linalg.LinAlgError:
            cov[np.ix_(self.free, self.free)] = np.nan
        return cov


def fit_record(record: Record, test: PendulumTest, *, start=None,
               restitution: float | None = None,
               free_fit: FitResult | None = None) -> FitResult:
    """The least-squares fit of the exact model to the whole record (module docstring), to
    the pendulum's record y too when it has one; ``restitution`` (known e, e.g. of the
    pendulum's pad) holds e fixed instead of fitting it, starting also from the free fit
    moved to that e (``free_fit``: that fit if already made on this record, else made here).
    A record of x alone that the pendulum leaves after one impact fixes omega_1, xi and V_1
    but not M_T and e apart: then M_T, K_T, C_T, E and e are given as ranges
    (:mod:`analytic.identify.one_impact`)."""
    from scipy.optimize import least_squares

    t, x, y = record.t, record.x, record.y
    if restitution is not None:
        check_range("restitution", restitution, low=0.0, high=1.0)
        if start is None:  # from the free fit moved to the given e (same V_1, omega_1)
            starts = [_start(record, test, restitution)]
            free_fit = fit_record(record, test) if free_fit is None else free_fit
            moved = on_ridge(free_fit.point, restitution, test)
            if np.all(np.isfinite(moved)):
                starts.append(moved)
        else:
            starts = [start]
    else:
        starts = ([_start(record, test, e) for e in START_RESTITUTIONS] if start is None
                  else [start])
    starts = [np.array(p0, float) for p0 in starts]
    if restitution is not None:
        for p0 in starts:
            p0[3] = restitution
    dt = float(np.median(np.diff(t)))
    lower = np.array([math.log(1e-2), math.log(1.0), 1e-3, 0.0, t[0] - 10 * dt, -np.inf,
                      -np.inf])
    upper = np.array([math.log(1e5), math.log(1e10), 5.0, 0.95, t[-1] - 10 * dt, np.inf,
                      np.inf])
    scale = [max(float(np.max(np.abs(x - starts[0][5]))), 1e-12)]
    if y is not None:
        scale.append(max(float(np.max(np.abs(y - starts[0][6]))), 1e-12))
    free = [j for j in range(7) if not (j == 3 and restitution is not None)
            and not (j == 6 and y is None)]
    x_scale = np.array([1, 1, 0.1, 0.1, dt, 1e-4, 1e-4])[free]

    best = None
    for p0 in starts:  # e is the parameter with local minima: the best end kept
        prob = _Problem(record, test, scale, upper, p0, free)
        q0 = np.clip(p0[free], lower[free] + 1e-9, upper[free] - 1e-9)
        res = least_squares(prob.residual, q0, jac=prob.jacobian,
                            bounds=(lower[free], upper[free]), x_scale=x_scale, max_nfev=400)
        if best is None or res.cost < best[0].cost:
            best = (res, prob)
    res, prob = best
    p = prob.full(res.x)
    motion = model_motion(p, test, t, pendulum=y is not None)
    fitted = motion[0]
    rms = math.sqrt(float(np.mean((fitted - x) ** 2)))
    peak = float(np.max(np.abs(x - p[5])))
    explained = rms <= EXPLAINED_FRACTION * peak
    rms_y = None
    if y is not None:
        rms_y = math.sqrt(float(np.mean((motion[2] - y) ** 2)))
        explained = explained and rms_y <= EXPLAINED_FRACTION * float(np.max(np.abs(y - p[6])))
    # the pendulum's record fixes e (its rebound), so only a record of x alone can be a ridge
    e_range = restitution_range(p, test, t) if restitution is None and y is None else None
    if e_range is None:
        values, intervals = _estimates(p, prob.covariance(p), test, pendulum=y is not None)
        determined = dict.fromkeys(values, True)
        note = ""
    else:  # the record determines omega_1, xi and V_1 only: the ends of the ridge
        fixed_e = [j for j in free if j != 3]
        ends = []
        for e_end in e_range:
            pe = on_ridge(p, e_end, test)
            ends.append(_estimates(pe, _Problem(record, test, scale, upper, pe, fixed_e)
                                   .covariance(pe), test))
        values, intervals = _estimates(p, np.zeros((7, 7)), test)
        determined = {k: k not in RIDGE for k in values}
        for k in values:
            if k in RIDGE:
                values[k] = math.nan
            intervals[k] = (min(ends[0][1][k][0], ends[1][1][k][0]),
                            max(ends[0][1][k][1], ends[1][1][k][1]))
        intervals["e"] = e_range
        note = (f"the pendulum leaves after one impact and does not return within the "
                f"record: it fixes omega_1, xi and the trunk's velocity after the impact "
                f"V_1 = m (1 + e) u_1 / (M_T + m) (eqs 21, 54), not M_T and e apart; M_T, "
                f"K_T, C_T and E are ranges over e in [{e_range[0]:.3g}, 1] (a smaller e would "
                f"bring the pendulum back); a known e (--restitution) or a record of the "
                f"pendulum (column y) fixes them")
    return FitResult(values=values, intervals=intervals, residual_rms=rms, peak=peak,
                     explained=explained, model_x=fitted, determined=determined, point=p,
                     note=note, residual_rms_y=rms_y,
                     model_y=motion[2] if y is not None else None)


def _estimates(p, cov, test: PendulumTest, *, pendulum: bool = False) -> tuple[dict, dict]:
    """Values (SI) and 95 % intervals of every reported quantity at p with covariance cov
    (intervals of logarithms for the positive ones, by the delta method); the pendulum
    sensor's offset too if ``pendulum``."""
    M, K, xi, e = math.exp(p[0]), math.exp(p[1]), float(p[2]), float(p[3])
    m, u1 = test.impactor_mass, test.impact_speed
    C = 2.0 * xi * math.sqrt(K * M)
    I = math.pi * test.diameter ** 4 / 64.0
    e_mod = K * test.clamp_height ** 3 / (3.0 * I)  # eq 47
    omega = math.sqrt(K / M)  # eq 14: omega_1^2 = K_T / M_T
    v1 = m * (1.0 + e) * u1 / (M + m)  # eq 21 at the first impact, trunk at rest

    def sd(g):  # standard deviation of g . p
        g = np.concatenate([g, np.zeros(cov.shape[0] - len(g))])
        return math.sqrt(max(float(g @ cov @ g), 0.0))

    z = Z95
    values = {"M_T": M, "K_T": K, "C_T": C, "xi": xi, "e": e, "E": e_mod, "omega_1": omega,
              "V_1": v1, "t0": float(p[4]), "x_offset": float(p[5])}
    intervals = {
        "M_T": log_interval(M, z * sd([1, 0, 0, 0, 0, 0])),
        "K_T": log_interval(K, z * sd([0, 1, 0, 0, 0, 0])),
        "C_T": log_interval(C, z * sd([0.5, 0.5, 1.0 / xi, 0, 0, 0])),
        "xi": (xi - z * sd([0, 0, 1, 0, 0, 0]), xi + z * sd([0, 0, 1, 0, 0, 0])),
        "e": (e - z * sd([0, 0, 0, 1, 0, 0]), e + z * sd([0, 0, 0, 1, 0, 0])),
        "E": log_interval(e_mod, z * sd([0, 1, 0, 0, 0, 0])),
        "omega_1": log_interval(omega, z * sd([-0.5, 0.5, 0, 0, 0, 0])),
        "V_1": log_interval(v1, z * sd([-M / (M + m), 0, 0, 1.0 / (1.0 + e), 0, 0])),
        "t0": (p[4] - z * sd([0, 0, 0, 0, 1, 0]), p[4] + z * sd([0, 0, 0, 0, 1, 0])),
        "x_offset": (p[5] - z * sd([0, 0, 0, 0, 0, 1]), p[5] + z * sd([0, 0, 0, 0, 0, 1])),
    }
    if pendulum:
        values["y_offset"] = float(p[6])
        w = z * sd([0, 0, 0, 0, 0, 0, 1])
        intervals["y_offset"] = (p[6] - w, p[6] + w)
    return values, {k: (float(lo), float(hi)) for k, (lo, hi) in intervals.items()}


def log_interval(value: float, half_width: float) -> tuple[float, float]:
    """(value e^-w, value e^w) for a parameter fitted in logarithm with half-width w: a w
    beyond float range (a direction the record does not determine) gives (0, inf) as
    such, not an overflow; NaN stays NaN."""
    w = float(half_width)
    if not w < 700.0:  # e^700 ~ 1e304; NaN fails the test too and stays NaN below
        return (0.0, math.inf) if w == w else (math.nan, math.nan)
    return value * math.exp(-w), value * math.exp(w)
