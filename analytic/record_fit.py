"""Tree properties from a whole pendulum-test record: the exact 1-DOF model fitted to it.

The paper's procedure (eqs 39-48, :mod:`analytic.identification`) reads three numbers off
the record after the bodies move together. Here the exact model of eqs 12-35 (M_T, C_T, K_T,
e, the pendulum of eq 13 at u_1 of eq 48) is fitted to every sample of x(t) by nonlinear
least squares (``scipy.optimize.least_squares``), with the time of the first contact and a
sensor offset as nuisance parameters. 95 % intervals come from the Jacobian at the optimum
(residuals independent, equal variance: cov = s^2 (J^T J)^-1, s^2 = RSS / (n - p)); the fit
"explains" the record when its residual RMS is within :data:`EXPLAINED_FRACTION` of the peak
displacement. docs/identification.md has the method and the measured accuracy.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .identification import PendulumTest
from .model import TwoBodyModel
from .parameters import ParameterError

#: The fit explains a record when its residual RMS is at most this fraction of the peak
#: displacement: 1-2 % sensor noise passes, a flexible trunk's second mode does not.
EXPLAINED_FRACTION = 0.03
MIN_SAMPLES = 20
Z95 = 1.959963984540054  # two-sided 95 % normal quantile
NAMES = ("M_T", "K_T", "xi", "e", "t0", "x_offset")  # fitted: ln M_T, ln K_T, xi, e, s, m


@dataclass(frozen=True)
class Record:
    """A displacement record (SI): time t (s), trunk displacement at the clamp x (m), and the
    pendulum's displacement y (m) if measured."""

    t: np.ndarray
    x: np.ndarray
    y: np.ndarray | None = None

    def __post_init__(self):
        t, x = np.asarray(self.t, float), np.asarray(self.x, float)
        if t.ndim != 1 or t.shape != x.shape:
            raise ParameterError("record: t and x must be columns of the same length")
        if t.size < MIN_SAMPLES:
            raise ParameterError(f"record: {t.size} samples; at least {MIN_SAMPLES} needed")
        for name, v in (("t", t), ("x", x)) + ((("y", np.asarray(self.y, float)),)
                                               if self.y is not None else ()):
            bad = np.flatnonzero(~np.isfinite(v))
            if bad.size:
                raise ParameterError(f"record: {name} is not a finite number at row {bad[0] + 2}")
        steps = np.diff(t)
        if np.any(steps <= 0):
            row = int(np.flatnonzero(steps <= 0)[0]) + 3
            raise ParameterError(f"record: time t does not increase at row {row} (sorted, "
                                 "without repeats, is required)")
        if not np.max(x) - np.min(x) > 0:
            raise ParameterError("record: x never changes: the record holds no impact")


def read_record(path) -> Record:
    """A :class:`Record` from a CSV file with the header ``t,x`` or ``t,x,y`` (SI units)."""
    path = Path(path)
    try:
        with path.open(newline="", encoding="utf-8") as f:
            rows = list(csv.reader(f))
    except (OSError, UnicodeDecodeError) as exc:
        raise ParameterError(f"record {str(path)!r}: cannot be read ({exc})") from None
    if not rows:
        raise ParameterError(f"record {str(path)!r}: empty file")
    header = [h.strip() for h in rows[0]]
    if header not in (["t", "x"], ["t", "x", "y"]):
        raise ParameterError(f"record {str(path)!r}: header {','.join(header)!r}; allowed "
                             "'t,x' or 't,x,y' (s, m, m)")
    try:
        data = np.array([[float(v) for v in r] for r in rows[1:] if r], dtype=float)
    except ValueError as exc:
        raise ParameterError(f"record {str(path)!r}: not a number ({exc})") from None
    if data.ndim != 2 or data.shape[1] != len(header):
        raise ParameterError(f"record {str(path)!r}: every row needs {len(header)} values")
    return Record(data[:, 0], data[:, 1], data[:, 2] if len(header) == 3 else None)


@dataclass(frozen=True)
class FitResult:
    """The fitted model (SI) with 95 % intervals, and how well it explains the record."""

    values: dict  # M_T kg, K_T N/m, C_T N s/m, xi 1, e 1, E Pa, t0 s, x_offset m
    intervals: dict  # name -> (low, high)
    residual_rms: float  # m
    peak: float  # m, largest |x - offset| of the record
    explained: bool
    model_x: np.ndarray  # m, the fitted x at the record's times

    def to_json(self) -> dict:
        out = {k: {"value": v, "low": self.intervals[k][0], "high": self.intervals[k][1]}
               for k, v in self.values.items()}
        return out


def model_x(p, test: PendulumTest, t: np.ndarray) -> np.ndarray:
    """x(t) (m) of the exact model with parameters p = (ln M_T, ln K_T, xi, e, t0, offset)."""
    from .solver import solve_impacts

    ln_m, ln_k, xi, e, t0, off = (float(v) for v in p)
    M, K = math.exp(ln_m), math.exp(ln_k)
    model = TwoBodyModel(dynamic_mass=M, damping=2.0 * xi * math.sqrt(K * M), stiffness=K,
                         impactor_mass=test.impactor_mass,
                         impactor_stiffness=test.impactor_stiffness,
                         impact_speed=test.impact_speed, restitution=e)
    out = np.full(t.shape, off)
    after = t > t0
    if after.any():
        t_rel = t[after] - t0
        sol = solve_impacts(model, float(t_rel[-1]))
        out[after] += sol.state(np.minimum(t_rel, sol.t_end))[0]
    return out


def _start(record: Record, test: PendulumTest, e: float = 0.1) -> np.ndarray:
    """A first guess: the contact time extrapolated back from where x first passes 10 % and
    40 % of its range above its resting level (far above 1-2 % noise), M_T from the slope
    there (momentum at e = 0: V = m u1 / (M_T + m)), K_T from the time to the peak as a
    quarter period of the joint motion."""
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
    return np.array([math.log(M), math.log(K), 0.3, e, t0, rest])


def fit_record(record: Record, test: PendulumTest, *, start=None) -> FitResult:
    """The least-squares fit of the exact model to the whole record (module docstring)."""
    from scipy.optimize import least_squares

    t, x = record.t, record.x
    starts = ([_start(record, test, e) for e in (0.1, 0.5)] if start is None
              else [np.asarray(start, float)])
    dt = float(np.median(np.diff(t)))
    lower = [math.log(1e-2), math.log(1.0), 1e-3, 0.0, t[0] - 10 * dt, -np.inf]
    upper = [math.log(1e5), math.log(1e10), 5.0, 0.95, t[-1] - 10 * dt, np.inf]
    scale = max(float(np.max(np.abs(x - starts[0][5]))), 1e-12)

    def residual(p):
        try:
            return (model_x(p, test, t) - x) / scale
        except ParameterError:  # a model the solver refuses: far from the record
            return np.full(x.shape, 1e3)

    best = None
    for p0 in starts:  # e is the parameter with local minima: two starts, the better kept
        p0 = np.clip(p0, np.array(lower) + 1e-9, np.array(upper) - 1e-9)
        res = least_squares(residual, p0, bounds=(lower, upper),
                            x_scale=[1, 1, 0.1, 0.1, dt, 1e-4], diff_step=1e-6, max_nfev=400)
        if best is None or res.cost < best.cost:
            best = res
    res = best
    p = res.x
    fitted = model_x(p, test, t)
    rss = float(np.sum((fitted - x) ** 2))
    n, k = x.size, p.size
    s2 = rss / max(n - k, 1)
    J = res.jac * scale  # d model / d p, in metres
    try:
        cov = s2 * np.linalg.inv(J.T @ J)
    except np.linalg.LinAlgError:
        cov = np.full((k, k), np.nan)
    sd = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    M, K, xi = math.exp(p[0]), math.exp(p[1]), float(p[2])
    C = 2.0 * xi * math.sqrt(K * M)
    # ln C_T = ln 2 + ln xi + (ln K + ln M) / 2: its variance by the delta method
    g = np.array([0.5, 0.5, 1.0 / xi, 0.0, 0.0, 0.0])
    sd_ln_c = math.sqrt(max(float(g @ cov @ g), 0.0))
    I = math.pi * test.diameter ** 4 / 64.0
    e_mod = K * test.clamp_height ** 3 / (3.0 * I)  # eq 47
    values = {"M_T": M, "K_T": K, "C_T": C, "xi": xi, "e": float(p[3]), "E": e_mod,
              "t0": float(p[4]), "x_offset": float(p[5])}
    z = Z95
    intervals = {
        "M_T": log_interval(M, z * sd[0]),
        "K_T": log_interval(K, z * sd[1]),
        "C_T": log_interval(C, z * sd_ln_c),
        "xi": (xi - z * sd[2], xi + z * sd[2]),
        "e": (float(p[3]) - z * sd[3], float(p[3]) + z * sd[3]),
        "E": log_interval(e_mod, z * sd[1]),
        "t0": (float(p[4]) - z * sd[4], float(p[4]) + z * sd[4]),
        "x_offset": (float(p[5]) - z * sd[5], float(p[5]) + z * sd[5]),
    }
    rms = math.sqrt(rss / n)
    peak = float(np.max(np.abs(x - p[5])))
    return FitResult(values=values, intervals=intervals, residual_rms=rms, peak=peak,
                     explained=rms <= EXPLAINED_FRACTION * peak, model_x=fitted)


def log_interval(value: float, half_width: float) -> tuple[float, float]:
    """(value e^-w, value e^w) for a parameter fitted in logarithm with half-width w: a w
    beyond float range (a direction the record does not determine) gives (0, inf) as
    such, not an overflow; NaN stays NaN."""
    w = float(half_width)
    if not w < 700.0:  # e^700 ~ 1e304; NaN fails the test too and stays NaN below
        return (0.0, math.inf) if w == w else (math.nan, math.nan)
    return value * math.exp(-w), value * math.exp(w)
