"""One local least-squares fit of the exact model to a record: the residuals and their
Jacobian in the free parameters (:class:`Problem`), the fit from a start (:class:`Fitter`),
and the covariance at its optimum. docs/identification.md, "The full-record fit"."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from treeimpact.analytic.errors import ParameterError, SimulationDiverged

from .fit_model import model_motion
from .fit_parameters import (
    DRIFT_POWER,
    OFFSET_CHANNEL,
    SENSOR_TERMS,
    FitVariables,
    Slot,
    record_parameters,
)
from .procedure import PendulumTest
from .record_features import features

DIFF_STEP = 1e-6  # relative forward-difference step of the fit's Jacobian
REFINE_NFEV = 100  # evaluations of the fit with e free
REFINE_SAMPLES = 20_000  # ... on every k-th sample, at most this many
POLISH_NFEV = 4  # then evaluations on all the samples (a Gauss-Newton step or two)


class Problem:
    """Residuals of a record (times ``t`` s, trunk channel ``x`` m, pendulum channel ``y``
    m or None) of the pendulum ``test``, (x_model - x) / scale[0] and, if it has y,
    (y_model - y) / scale[1], and their Jacobian in the free parameters of ``params`` (the
    frozen ones held at their values in ``p0``)."""

    def __init__(self, t, x, y, test: PendulumTest, scale, params: FitVariables, p0):
        self.t, self.test = t, test
        self.pendulum = y is not None
        self.data = np.concatenate([x, y]) if self.pendulum else np.asarray(x)
        n = t.size
        self.weight = np.repeat(1.0 / np.asarray(scale[: 2 if self.pendulum else 1]), n)
        self.params = params
        self.free = params.free
        self.upper = np.array([p.high for p in params.parameters])
        self.fixed = np.array(p0, float)
        self._last = {}  # the motion at the last point evaluated: the Jacobian is asked there
        self.runs = 0

    def full(self, q) -> np.ndarray:
        """The full parameter vector p (slot order): the free values ``q``, the rest held."""
        p = self.fixed.copy()
        p[list(self.free)] = q
        return p

    def _motion(self, p):
        self.runs += 1
        return model_motion(p, self.test, self.t, pendulum=self.pendulum)

    def _channels(self, m) -> np.ndarray:
        return np.concatenate([m[0], m[2]]) if self.pendulum else m[0]

    def residual(self, q) -> np.ndarray:
        """The scaled residuals (1) at the free values ``q``; 1e3 each where the solver
        refuses the model (far off)."""
        p = self.full(q)
        self._last.clear()
        try:
            self._last[p.tobytes()] = m = self._motion(p)
        except (ParameterError, SimulationDiverged, ValueError, ArithmeticError):
            # (SimulationDiverged: also a model over the solver's event budget)
            return np.full(self.data.shape, 1e3)  # a model the solver refuses: far off
        return (self._channels(m) - self.data) * self.weight

    def jacobian(self, q) -> np.ndarray:
        """d residual / d q at the free values ``q``.

        Forward differences in the tree's parameters (relative step DIFF_STEP, turned back
        at an upper bound); exact columns for t0 (minus the velocities and the drift: the
        record shifts with the contact), the offsets (1 on their channel) and the drift
        terms ((t - t0)^power on x)."""
        p = self.full(q)
        if p.tobytes() not in self._last:
            self.residual(q)
        m = self._last.get(p.tobytes())
        jac = np.zeros((self.data.size, len(self.free)))
        if m is None:  # p itself refused: no motion to differentiate
            return jac
        r0 = (self._channels(m) - self.data) * self.weight
        for col, slot in enumerate(self.free):
            if slot in OFFSET_CHANNEL or slot in DRIFT_POWER or slot == Slot.T0:
                jac[:, col] = self._exact_column(slot, p, m) * self.weight
            else:
                jac[:, col] = self._difference_column(q, col, p[slot], r0)
        self._last.clear()
        self._last[p.tobytes()] = m
        return jac

    def _exact_column(self, slot: Slot, p, m) -> np.ndarray:
        n = self.t.size
        column = np.zeros(self.data.size)
        if slot == Slot.T0:
            vx = m[1] + p[Slot.X_DRIFT] + 2.0 * p[Slot.X_DRIFT2] * (self.t - p[Slot.T0])
            column[:] = -(np.concatenate([vx, m[3]]) if self.pendulum else vx)
        elif slot in OFFSET_CHANNEL:
            channel = OFFSET_CHANNEL[slot]
            column[channel * n:(channel + 1) * n] = 1.0
        else:
            column[:n] = (self.t - p[Slot.T0]) ** DRIFT_POWER[slot]
        return column

    def _difference_column(self, q, col: int, value: float, r0) -> np.ndarray:
        h = DIFF_STEP * max(1.0, abs(value)) * (1.0 if value >= 0 else -1.0)
        if value + h > self.upper[self.free[col]]:
            h = -h
        step = q.copy()
        step[col] += h
        return (self.residual(step) - r0) / (step[col] - q[col])

    def covariance(self, p, floor: float = 0.0, *, given_e: bool = False) -> np.ndarray:
        """Covariance of p (zero rows for frozen parameters), the free block
        (J^T W J)^-1 with J = d model / d p in metres and W = 1 / s_c^2 per channel,
        s_c^2 = max(RSS_c / n_c x n / (n - k), floor^2) (one channel: s^2 (J^T J)^-1);
        with ``given_e`` the covariance of the others at this e (e's row and column of
        J^T W J left out: the profile's point of view)."""
        return self.covariances(p, floor)[1 if given_e else 0]

    def covariances(self, p, floor: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        """(the covariance of the parameters ``p``, the same given e) from one Jacobian, in
        slot order (0 for held ones), each channel's residual variance at least ``floor``
        (m) squared."""
        key = (p.tobytes(), floor)
        if getattr(self, "_cov_key", None) == key:
            return self._cov
        q = p[list(self.free)]
        r = self.residual(q) / self.weight  # metres
        J = self.jacobian(q) / self.weight[:, None]
        n, k = r.size, len(self.free)
        channels = r.reshape(2 if self.pendulum else 1, -1)
        s2 = np.maximum(np.mean(channels ** 2, axis=1) * n / max(n - k, 1), floor ** 2)
        w = np.repeat(1.0 / s2, self.t.size)
        info = J.T @ (J * w[:, None])
        out = []
        for given_e in (False, True):
            use = [i for i, s in enumerate(self.free)
                   if not (given_e and s == Slot.RESTITUTION)]
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
class Fit:
    """One local fit: the parameters ``p`` (slot order), its cost, least_squares' ``status``
    and the :class:`Problem` it solved."""

    p: np.ndarray
    cost: float  # the least-squares cost, 1/2 sum of the scaled residuals squared
    status: int
    problem: Problem


class Fitter:
    """One record's fits: its parameters (bounds, scales, what is held) and channel scales,
    and a local fit from a start. The record: times ``t`` (s), the trunk channel ``x`` (m),
    the pendulum's ``y`` (m, or None), of the pendulum ``test``; ``restitution_given``: e
    held; ``separable``: the sensor's offset and drift fitted (:func:`record_parameters`)."""

    def __init__(self, t, x, y, test, restitution_given: bool, separable: bool = True):
        self.t, self.x, self.y, self.test = t, x, y, test
        self.dt = float(np.median(np.diff(t)))
        self.runs = 0
        self.fits = 0
        # one scale per channel for every fit of the record: their costs compare
        rest = features(t, x).rest
        self.scale = [max(float(np.max(np.abs(x - rest))), 1e-300)]
        if y is not None:
            self.scale.append(max(float(np.max(np.abs(y - np.median(y)))), 1e-300))
        self.params = record_parameters(t, self.dt, self.scale,
                                        restitution_given=restitution_given,
                                        pendulum=y is not None, separable=separable)
        #: the sensor terms held at zero (a record that cannot tell them from the motion)
        self.held_at_zero = [s for s in SENSOR_TERMS if self.params[s].frozen
                             and s != Slot.X_DRIFT2]

    def refine(self, p0, keep, params: FitVariables | None = None) -> Fit:
        """The fit with all free from p0 on the samples ``keep`` selects: on every k-th of
        them (at most REFINE_SAMPLES), then a few steps on all of them if that left some
        out; ``params`` as in :meth:`fit`."""
        stride = max(1, int(math.ceil(np.count_nonzero(keep) / REFINE_SAMPLES)))
        f = self.fit(p0, keep=keep, stride=stride, params=params)
        return f if stride == 1 else self.fit(f.p, keep=keep, max_nfev=POLISH_NFEV,
                                              params=params)

    def fit(self, p0, *, keep=None, stride: int = 1, params: FitVariables | None = None,
            loss="linear", f_scale=1.0, max_nfev=REFINE_NFEV) -> Fit:
        """A local least-squares fit from p0 of ``params``' free parameters (default the
        record's) on the samples ``keep`` selects (None: all), every ``stride``-th, with
        least_squares' ``loss``, ``f_scale`` and ``max_nfev``."""
        # lazy: +356 ms at import otherwise (scipy.optimize)
        from scipy.optimize import least_squares

        params = self.params if params is None else params
        p0 = np.array(p0, float)
        p0[self.held_at_zero] = 0.0
        idx = np.arange(self.t.size)
        if keep is not None:
            idx = idx[keep]
        if stride > 1:
            idx = idx[::stride]
        prob = Problem(self.t[idx], self.x[idx], None if self.y is None else self.y[idx],
                       self.test, self.scale, params, p0)
        lo, hi = params.bounds()
        q0 = np.clip(np.asarray(p0, float)[list(params.free)], lo + 1e-9, hi - 1e-9)
        res = least_squares(prob.residual, q0, jac=prob.jacobian, bounds=(lo, hi),
                            x_scale=params.scales(), max_nfev=max_nfev, loss=loss,
                            f_scale=f_scale)
        self.runs += prob.runs
        self.fits += 1
        p = prob.full(res.x)
        r = prob.residual(res.x)
        return Fit(p, 0.5 * float(r @ r), int(res.status), prob)
