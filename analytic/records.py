"""Metrics from a sampled contact record: the one rule every soft-contact backend shares.

Design notes and measured figures: docs/ladder.md.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from treeimpact.analytic.model.parameters import pendulum_stiffness
from treeimpact.analytic.model.reduction import crown_factor

from .errors import ParameterError
from .results import ImpactRecord
from .metrics import METRIC_KEYS


def static_shape_crown(record: "ImpactRecord", tip: float):
    """(crown, crown_velocity) of an SDOF trunk record: the static shape of eq 5 moves the
    crown by phi(l) x (``tip`` = phi(l), :func:`analytic.model.reduction.crown_factor`). SI
    units."""
    return tip * record.x, tip * record.vx


def with_static_shape_crown(record: "ImpactRecord", trunk) -> "ImpactRecord":
    """``record`` of an SDOF trunk with its crown motion (:func:`static_shape_crown`)."""
    crown, velocity = static_shape_crown(record, crown_factor(trunk))
    return replace(record, crown=crown, crown_velocity=velocity)


def window_means(t: np.ndarray, cumulative: np.ndarray, window: float, plan=None
                 ) -> np.ndarray:
    """(C(t + window) - C(t)) / window at every sample with t + window inside the record (C
    the ``cumulative`` array at the increasing times t, s): the
    mean over ``window`` (s) of the quantity whose running integral is C (a velocity gives
    the mean acceleration, the force's running impulse the mean force). Empty if the record
    is shorter than the window. ``plan``: :func:`shift_plan` of (t, window) if known (what
    depends on the grid alone, shared by the means of one record)."""
    t, c = np.asarray(t, dtype=float), np.asarray(cumulative, dtype=float)
    if not (window > 0 and t[-1] - t[0] > window):
        return np.array([])
    plan = shift_plan(t, window) if plan is None else plan
    ahead = _interp_shifted(t, c, plan)
    ahead -= c[:plan.n]
    ahead /= window
    return ahead


@dataclass(frozen=True)
class ShiftPlan:
    """What np.interp(t[:n] + shift, t, c) needs of the grid t alone (:func:`shift_plan`):
    n, the points x, the offset q of their intervals (None: not one offset for all, or out
    of the grid) and, with q, the intervals' widths and x's place in them (s)."""

    n: int
    x: np.ndarray
    q: int | None
    width: np.ndarray | None = None
    into: np.ndarray | None = None

    def head(self, k: int) -> "ShiftPlan":
        """The plan of the first ``k`` (<= n) shifted samples alone."""
        return replace(self, n=k, x=self.x[:k],
                                   width=None if self.width is None else self.width[:k],
                                   into=None if self.into is None else self.into[:k])


def shift_plan(t: np.ndarray, shift: float) -> ShiftPlan:
    """The :class:`ShiftPlan` of increasing times t (s) shifted by ``shift`` (s, > 0, less
    than the record): the samples with t + shift inside the record."""
    n = int(np.searchsorted(t, t[-1] - shift, side="right"))  # t <= t[-1] - shift
    x = t[:n] + shift
    q = int(np.searchsorted(t, x[0], side="right")) - 1
    if not 0 <= q < t.size - n:
        return ShiftPlan(n, x, None)
    t_lo, t_hi = t[q:q + n], t[q + 1:q + 1 + n]
    if not (np.all(t_lo < x) and np.all(x < t_hi)):
        return ShiftPlan(n, x, None)
    return ShiftPlan(n, x, q, np.subtract(t_hi, t_lo), np.subtract(x, t_lo))


def _interp_shifted(t: np.ndarray, c: np.ndarray, plan: ShiftPlan) -> np.ndarray:
    """np.interp(t[:n] + shift, t, c), bitwise, for increasing t (``plan``: the grid's
    :class:`ShiftPlan`): when every x_i = t_i + shift lies strictly inside the same interval
    (t_(i+q), t_(i+q+1)) (an even grid), numpy's own formula
    (c_(j+1) - c_j) / (t_(j+1) - t_j) (x - t_j) + c_j on slices, without its search; else
    (or on a non-finite value) np.interp itself."""
    n, q = plan.n, plan.q
    if q is None:
        return np.interp(plan.x, t, c)
    c_lo = c[q:q + n]
    slope = np.subtract(c[q + 1:q + 1 + n], c_lo)
    slope /= plan.width
    out = np.multiply(plan.into, slope, out=slope)  # (x - t_j) slope
    out += c_lo
    return out if np.all(np.isfinite(out)) else np.interp(plan.x, t, c)


def _running_integral(t: np.ndarray, f: np.ndarray) -> np.ndarray:
    """Trapezoidal running integral of f over t, 0 at t[0] (numpy only: the command line's
    start-up does not pay for scipy)."""
    t, f = np.asarray(t, dtype=float), np.asarray(f, dtype=float)
    step = f[1:] + f[:-1]
    step *= 0.5
    step *= np.diff(t)
    out = np.empty(t.size)
    out[0] = 0.0
    np.cumsum(step, out=out[1:])
    return out


def _peak(values: np.ndarray) -> float:
    """max |values| (NaN if empty or any is), without forming |values|."""
    return max(float(values.max()), -float(values.min())) if values.size else math.nan


def _force_peak(t: np.ndarray, force: np.ndarray, window: float, plan) -> float:
    """max |window means| of the ``force`` (N) over ``window`` (s) at the times t (s):
    :func:`window_means` of its running impulse (``plan``: their :func:`shift_plan`, or None
    when the record is shorter than the window: NaN), over the windows that start at or
    before the last nonzero force. A later window holds no force: its running impulse C is
    constant there (each step adds (0 + 0) h / 2), so its mean is exactly 0, which max |.|
    does not need beside any other value; with no nonzero force, every window's mean."""
    f = np.asarray(force, dtype=float)
    nonzero = f != 0.0  # a NaN counts: its windows stay
    last = f.size - 1 - int(nonzero[::-1].argmax())
    if plan is None or not nonzero[last]:
        return _peak(window_means(t, _running_integral(t, f), window, plan))
    e = min(f.size, last + 2)  # C[e:] = C[e - 1]: the steps from sample last + 1 on are 0
    c = np.empty(f.size)
    c[:e] = _running_integral(t[:e], f[:e])
    c[e:] = c[e - 1]
    k = min(plan.n, last + 1)  # the windows starting at or before the last force
    return _peak(window_means(t, c, window, plan.head(k)))


def whole_event_metrics(record: "ImpactRecord", intervals: list, initial_energy: float, *,
                        impactor_mass: float, impactor_stiffness: float,
                        impact_speed: float, collision_duration: float) -> dict:
    """The metrics over every contact of the record (robust to chattering: no moving-together
    point needed; ``intervals``: its contact intervals, sample index pairs, from
    :func:`contact_intervals`). They need the record to end after the last contact (else
    NaN): energy delivered = ``initial_energy`` (J) - pendulum energy after the last
    separation - contact work, the work
    delivered = initial - pendulum energy after the last separation - contact work, the work
    of the contact force on the trunk (the pendulum loses int F y', the contact absorbs
    int F (y' - x')); impulse from the pendulum's momentum, m (u1 - y') - k int y dt (eq 13),
    which a subsampled force record would miss (``impactor_mass`` m kg,
    ``impactor_stiffness`` k N/m, ``impact_speed`` u1 m/s). Peak force and crown
    acceleration are the
    largest means over one ``collision_duration`` (s, :func:`window_means`): the pad's
    dashpot makes the force jump at the touch, a step that the engines sample a step late
    and that excites every mode of a continuum alike, so pointwise peaks depend on the time
    step and the mesh; the means over t_c converge."""
    r = record
    nan = math.nan
    t = np.asarray(r.t, dtype=float)
    # the grid's part of the window means, shared by the force's and the crown's
    plan = (shift_plan(t, collision_duration)
            if collision_duration > 0 and t[-1] - t[0] > collision_duration else None)
    out = {"energy_delivered": nan, "contact_dissipation": nan, "rebound_energy": nan,
           "impulse": nan, "peak_force": _force_peak(t, r.force, collision_duration, plan),
           "contact_episodes": len(intervals), "first_contact_duration": nan,
           "crown_peak": nan,
           "crown_peak_acceleration": nan}
    if intervals and intervals[0][1] < r.t.size - 1:  # released within the record
        i0, i1 = intervals[0]
        out["first_contact_duration"] = _release_time(r.t, r.force, i0, i1) - float(r.t[i0])
    after = _released(r.force, intervals[-1][1] + 1) if intervals else None
    if after is not None:
        rebound = float(r.pendulum_energy[after])
        dissipated = r.contact_loss(float(r.t[after]))
        spring = impactor_stiffness * float(np.trapezoid(r.y[:after + 1], r.t[:after + 1]))
        out.update(energy_delivered=initial_energy - rebound - dissipated,
                   contact_dissipation=dissipated, rebound_energy=rebound,
                   impulse=impactor_mass * (impact_speed - float(r.vy[after])) - spring)
    if r.crown is not None:
        out["crown_peak"] = _peak(r.crown)
    if r.crown_velocity is not None:
        out["crown_peak_acceleration"] = _peak(window_means(t, r.crown_velocity,
                                                            collision_duration, plan))
    return out


def model_metrics(record: "ImpactRecord", model, impactor, *, collision_duration: float,
                  initial_energy: float | None = None) -> dict:
    """:func:`metrics_from_record` of ``record`` with the two-body ``model``'s u1, m, M_T
    and initial energy (J; ``initial_energy`` overrides it, e.g. an engine's own), the
    ``impactor``'s l_e, g and spring k (a billet has no l_e or g: theta_b is NaN) and the
    ``collision_duration`` (s) impacts are told apart by."""
    return metrics_from_record(
        record, impact_speed=model.impact_speed,
        initial_energy=model.initial_energy if initial_energy is None else initial_energy,
        collision_duration=collision_duration, impactor_mass=model.impactor_mass,
        dynamic_mass=model.dynamic_mass,
        equivalent_length=getattr(impactor, "equivalent_length", None),
        gravity=getattr(impactor, "gravity", 9.81), impactor_stiffness=impactor.stiffness)


def contact_intervals(force: np.ndarray, threshold: float) -> list[tuple[int, int]]:
    """Index pairs (first, last) of the maximal runs with force > threshold."""
    on = np.asarray(force) > threshold
    if not on.any():
        return []
    edges = np.diff(on.astype(np.int8))
    starts = list(np.flatnonzero(edges == 1) + 1)
    ends = list(np.flatnonzero(edges == -1))
    if on[0]:
        starts.insert(0, 0)
    if on[-1]:
        ends.append(on.size - 1)
    return list(zip(starts, ends))


def _released(force: np.ndarray, start: int) -> int | None:
    """The first sample from ``start`` on with no contact force: where the pad has let go
    (a contact interval ends below its threshold, where a damped pad may still push a
    little and hold a compression its dashpot balances: the elastic energy of that
    compression never returns to the bodies, so the loss is read after the release);
    None when the force never reaches 0 within the record."""
    free = np.asarray(force[start:]) <= 0.0
    k = int(free.argmax()) if free.size else 0  # the first True (0 if none)
    return start + k if free.size and free[k] and start + k < force.size - 1 else None


def _release_time(t: np.ndarray, force: np.ndarray, i0: int, i1: int) -> float:
    """Zero of the force extrapolated from samples i1 - 1, i1 (see t_sep in the docstring)."""
    if i1 == i0:
        return float(t[i1])
    f0, f1 = float(force[i1 - 1]), float(force[i1])
    slope = (f1 - f0) / (t[i1] - t[i1 - 1])
    if not slope < 0.0:
        return float(t[i1])
    return float(min(t[i1 + 1], t[i1] - f1 / slope))


def _interp(t: np.ndarray, f: np.ndarray, at: float) -> float:
    return float(np.interp(at, t, f))


def _integral_to(t: np.ndarray, f: np.ndarray, t_stop: float) -> float:
    k = int(np.searchsorted(t, t_stop, side="right"))
    tt = np.append(t[:k], t_stop)
    ff = np.append(f[:k], _interp(t, f, t_stop))
    return float(np.trapezoid(ff, tt))


def metrics_from_record(record: ImpactRecord, *, impact_speed: float, initial_energy: float,
                        collision_duration: float, impactor_mass: float, dynamic_mass: float,
                        equivalent_length: float | None = None, gravity: float = 9.81,
                        impactor_stiffness: float | None = None, force_threshold: float = 1e-6, persist_factor: float = 3.0,
                        common_velocity_tolerance: float = 1e-3) -> dict:
    """The metrics of :data:`METRIC_KEYS` from a record, by the rule of the module docstring.

    ``dynamic_mass`` (M_T, kg) only enters the e = 0 loss of eq 57,
    0.5 m u1^2 M_T / (M_T + m); ``equivalent_length`` (m) gives theta_b (NaN for a billet);
    ``impactor_stiffness`` k (N/m) the impulse's spring term (None: m g / l_e, or 0 without
    l_e). ``record`` is an :class:`ImpactRecord` or anything with its motion arrays (t, x, vx, y,
    vy, force, pendulum_energy, crown, crown_velocity) and its two energy reads,
    ``contact_loss(t)`` and ``ledger_residual(initial_energy)``: an exact solver gives those
    in closed form instead of from sampled energies (analytic.continuum.beam_impact).
    ``impact_speed`` u1 (m/s), ``initial_energy`` (J), ``impactor_mass`` m (kg) and
    ``gravity`` g (m/s^2) are the run's; contacts are where the force exceeds
    ``force_threshold`` times its peak; the bodies move together in the first contact
    longer than ``persist_factor`` x ``collision_duration`` (s), from where their relative
    velocity is within ``common_velocity_tolerance`` x u1.
    """
    r = record
    peak = float(np.max(r.force))
    if not (math.isfinite(peak) and peak > 0):
        raise ParameterError("--t-end: no contact in the record: the pendulum never touched "
                             "the trunk within t_end (peak force <= 0)")
    intervals = contact_intervals(r.force, force_threshold * peak)
    t = r.t
    together = next((iv for iv in intervals
                     if t[iv[1]] - t[iv[0]] > persist_factor * collision_duration), None)
    if together is not None:
        joint = _together_metrics(r, intervals, together,
                                  common_velocity_tolerance * impact_speed)
    else:
        joint = _NOT_TOGETHER | {"impact_loss": r.contact_loss(float(t[-1])),
                                 "n_impacts": len(intervals)}
    theta_b, e_transferred = _after_contact(r, intervals, together, initial_energy,
                                            joint["impact_loss"], impactor_mass, gravity,
                                            equivalent_length)
    x_max, t_xmax = _displacement_peak(t, r.x)
    m = impactor_mass
    metrics = {
        "n_impacts": int(joint["n_impacts"]),
        "T0": joint["T0"], "x0": joint["x0"], "V": joint["V"],
        "x_max": x_max, "t_xmax": t_xmax, "t_sep": joint["t_sep"],
        "A_x": joint["A_x"], "A_y": joint["A_y"],
        "impact_loss": float(joint["impact_loss"]),
        "impact_loss_inelastic": 0.5 * m * impact_speed ** 2 * dynamic_mass / (dynamic_mass + m),
        "energy_transferred": e_transferred,
        "theta_b": theta_b,
        "ledger_residual": r.ledger_residual(initial_energy),
        **whole_event_metrics(
            r, intervals, initial_energy, impactor_mass=m, impact_speed=impact_speed,
            collision_duration=collision_duration,
            impactor_stiffness=impactor_stiffness if impactor_stiffness is not None
            else 0.0 if equivalent_length is None
            else pendulum_stiffness(m, gravity, equivalent_length)),
    }
    assert tuple(metrics) == METRIC_KEYS
    return metrics


#: The moving-together metrics of a record whose bodies never move together.
_NOT_TOGETHER = {"T0": math.nan, "x0": math.nan, "V": math.nan, "A_x": math.nan,
                 "A_y": math.nan, "t_sep": math.nan}


def _together_metrics(r, intervals: list, together: tuple, tol: float) -> dict:
    """T0, x0, V, A_x, A_y (to T0), the impact loss to T0, the impacts before T0 and t_sep
    of a record ``r`` whose bodies move together in the contact interval ``together`` (of
    its contact ``intervals``): T0 where their relative velocity falls within ``tol``
    (m/s), :func:`_common_velocity_time`."""
    t = r.t
    i0, i1 = together
    T0 = _common_velocity_time(t, r.vy[i0:i1 + 1] - r.vx[i0:i1 + 1], i0, tol)
    return {"T0": T0, "x0": _interp(t, r.x, T0), "V": _interp(t, r.vx, T0),
            "A_x": _integral_to(t, r.x, T0), "A_y": _integral_to(t, r.y, T0),
            "impact_loss": r.contact_loss(T0),
            "n_impacts": sum(1 for j0, _ in intervals if t[j0] <= T0),
            "t_sep": _release_time(t, r.force, i0, i1) if i1 < t.size - 1 else math.nan}


def _common_velocity_time(t: np.ndarray, rel: np.ndarray, i0: int, tol: float) -> float:
    """T0 (s): the first time in a contact from sample ``i0`` on where the relative velocity
    ``rel`` (m/s, from that sample) changes sign or falls within ``tol``, interpolated
    linearly between the samples at times ``t``; the contact's start if it is within
    ``tol`` there or never. The samples are searched in growing chunks (256, then x 8: T0
    is most often within the first few), each pair of neighbours tested as over the whole."""
    if abs(rel[0]) - tol <= 0:
        return float(t[i0])
    start, size = 0, 256
    while start < rel.size - 1:
        seg = rel[start:start + size + 1]  # pairs (start + i, start + i + 1)
        g = np.abs(seg) - tol  # <= 0 once the velocities are common
        cross = np.flatnonzero(((g[:-1] > 0) & (g[1:] <= 0))
                               | (np.sign(seg[:-1]) * np.sign(seg[1:]) < 0))
        if cross.size:
            k = int(cross[0])
            # the sign change of rel, or the crossing of |rel| = tol, interpolated linearly
            a, b = (seg[k], seg[k + 1]) if np.sign(seg[k]) != np.sign(seg[k + 1]) else (
                g[k], g[k + 1])
            frac = a / (a - b) if a != b else 0.0
            j = i0 + start + k
            return float(t[j] + frac * (t[j + 1] - t[j]))
        start, size = start + size, 8 * size
    return float(t[i0])


def _displacement_peak(t: np.ndarray, x: np.ndarray) -> tuple[float, float]:
    """(x_max m, t_xmax s) of the samples ``x`` at times ``t``: the largest sample, refined
    by the parabola through it and its two neighbours."""
    k_max = int(np.argmax(x))
    x_max, t_xmax = float(x[k_max]), float(t[k_max])
    if 0 < k_max < t.size - 1:  # parabola through the three samples around the maximum
        y0, y1, y2 = x[k_max - 1:k_max + 2]
        den = y0 - 2.0 * y1 + y2
        if den < 0:
            s = 0.5 * (y0 - y2) / den
            h = 0.5 * (t[k_max + 1] - t[k_max - 1])
            x_max = float(y1 - 0.25 * (y0 - y2) * s)
            t_xmax = float(t[k_max] + s * h)
    return x_max, t_xmax


def _after_contact(r, intervals: list, together, initial_energy: float, loss: float,
                   impactor_mass: float, gravity: float,
                   equivalent_length: float | None) -> tuple[float, float]:
    """(theta_b rad, energy transferred J, eq 58) from the pendulum's energy after the last
    contact of record ``r``; NaN unless the bodies moved together and parted within it."""
    theta_b = e_transferred = math.nan
    if intervals and intervals[-1][1] < r.t.size - 1 and together is not None:
        e_pend = float(r.pendulum_energy[intervals[-1][1] + 1])
        e_transferred = initial_energy - e_pend - loss
        if equivalent_length is not None:
            c = 1.0 - e_pend / (impactor_mass * gravity * equivalent_length)
            theta_b = math.acos(max(-1.0, min(1.0, c)))
    return theta_b, e_transferred


#: A peak is ambiguous when x(t) has another local maximum this close to its largest.
PEAK_AMBIGUITY = 0.05


def peak_times(t, x, within: float = PEAK_AMBIGUITY) -> list[float]:
    """Times (s) of the local maxima of x(t) within ``within`` of its largest (prominence at
    least 2 % of the largest, so ripple on one peak is not a second one). More than one: the
    time of the maximum is not a robust quantity (which peak wins flips with small changes)."""
    # lazy: +706 ms at import otherwise (scipy.signal)
    from scipy.signal import find_peaks

    t, x = np.asarray(t, float), np.asarray(x, float)
    top = float(np.max(x))
    if not top > 0:
        return []
    peaks, _ = find_peaks(x, prominence=0.02 * top)
    return [float(t[i]) for i in peaks if x[i] >= (1.0 - within) * top]
