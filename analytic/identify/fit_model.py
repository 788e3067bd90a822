"""The model the record fit adjusts: the exact two-body model (eqs 12-35) at a parameter
vector p (:class:`fit_parameters.Slot` order), its motion sampled at a record's times."""

from __future__ import annotations

import math

import numpy as np

from treeimpact.analytic.impact.oscillator import Oscillator
from treeimpact.analytic.impact.solver import solve_impacts
from treeimpact.analytic.model.two_body import TwoBodyModel

from .fit_parameters import Slot, padded
from .procedure import PendulumTest

#: Events one model run may take (impacts, flights, moving together): a tree's record takes
#: tens; a model far from any tree (a 0.01 kg trunk bouncing off the pendulum all record
#: long) is refused (SimulationDiverged) instead of taking seconds.
MAX_EVENTS = 20_000


def two_body_at(p, test: PendulumTest) -> TwoBodyModel:
    """The two-body model (SI) at p with the pendulum of ``test``: M_T = e^ln_m_t, K_T =
    e^ln_k_t, C_T = 2 zeta sqrt(K_T M_T) with zeta the trunk's damping ratio."""
    M, K = (math.exp(float(p[Slot.LN_DYNAMIC_MASS])),
            math.exp(float(p[Slot.LN_EQUIVALENT_STIFFNESS])))
    ratio, e = float(p[Slot.TRUNK_DAMPING_RATIO]), float(p[Slot.RESTITUTION])
    return TwoBodyModel(dynamic_mass=M, equivalent_damping=2.0 * ratio * math.sqrt(K * M),
                        equivalent_stiffness=K,
                        impactor_mass=test.impactor_mass,
                        impactor_stiffness=test.impactor_stiffness,
                        impact_speed=test.impact_speed, restitution=e)


def drift_at(p, s):
    """The sensor's drift (m) s seconds after the contact: x_drift s + x_drift2 s^2 of the
    parameters ``p`` (:class:`fit_parameters.Slot` order)."""
    q = padded(p)
    return (float(q[Slot.X_DRIFT]) + float(q[Slot.X_DRIFT2]) * s) * s


def model_x(p, test: PendulumTest, t: np.ndarray) -> np.ndarray:
    """x(t) (m) of the exact model with parameters p (:class:`fit_parameters.Slot` order)
    and the pendulum of ``test``."""
    return model_motion(p, test, t)[0]


def model_x_of_trunk(p, test: PendulumTest, t: np.ndarray, *, dynamic_mass: float,
                     equivalent_stiffness: float, trunk_damping_ratio: float) -> np.ndarray:
    """x(t) (m) at the times ``t`` (s) of the exact model at parameters ``p``
    (:class:`fit_parameters.Slot` order: the contact, e and sensor terms) with the pendulum
    of ``test`` and its trunk replaced by another's: M_T ``dynamic_mass`` (kg), K_T
    ``equivalent_stiffness`` (N/m) and ``trunk_damping_ratio`` C_T / (2 sqrt(K_T M_T)) (1),
    e.g. the paper's procedure's reading of a record."""
    q = np.array(p, float)
    q[Slot.LN_DYNAMIC_MASS] = math.log(dynamic_mass)
    q[Slot.LN_EQUIVALENT_STIFFNESS] = math.log(equivalent_stiffness)
    q[Slot.TRUNK_DAMPING_RATIO] = trunk_damping_ratio
    return model_x(q, test, t)


def model_motion(p, test: PendulumTest, t: np.ndarray, *, pendulum: bool = False) -> tuple:
    """(x, v) (m, m/s) of the exact model with parameters ``p`` (:class:`fit_parameters.Slot`
    order) and the pendulum of ``test`` at the sorted times t (s): :func:`model_x` and the
    trunk's velocity (without the drift's: -dx/dt0 is v and the drift's rate, the fit's
    exact Jacobian column for t0); with ``pendulum`` also the pendulum's (y, v_y) in the
    same frame (y = x at contact, y = 0 at the first one): before it, the free swing at u_1
    (eq 13) run back from the contact."""
    t0 = float(p[Slot.T0])
    s = t - t0
    x, v = float(p[Slot.X_OFFSET]) + drift_at(p, s), np.zeros(t.shape)
    first = int(np.searchsorted(t, t0, side="right"))  # the first sample after the contact
    sol = None
    if first < t.size:
        t_rel = t[first:] - t0
        sol = solve_impacts(two_body_at(p, test), float(t_rel[-1]), max_events=MAX_EVENTS)
        rows = sol.sorted_state(np.minimum(t_rel, sol.t_end), pendulum=pendulum)
        x[first:] += rows[0]
        v[first:] = rows[1]
    if not pendulum:
        return x, v
    y, vy = np.full(t.shape, float(p[Slot.Y_OFFSET])), np.empty(t.shape)
    swing = Oscillator.from_mck(test.impactor_mass, 0.0, test.impactor_stiffness)
    dy, vy[:first] = swing.advance(t[:first] - t0, 0.0, test.impact_speed, np)
    y[:first] += dy
    if sol is not None:
        y[first:] += rows[2]
        vy[first:] = rows[3]
    return x, v, y, vy
