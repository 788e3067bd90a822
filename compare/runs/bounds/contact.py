"""Bounds on the pad's steps: the soft SDOF against the Newton model ([step.contact]) and
the engines' SDOF against the soft one and against each other ([step.engine],
[engines.engine]), from the tree's own collision duration, damping, energies and step.

Soft against Newton: the same 1-DOF pair, a pad of duration t_c instead of an impulse. The
trunk's damper acts during t_c (an impulse of order C_T x(t_c) against the exchange's M_T V,
a change of order b t_c, b = C_T / (2 (M_T + m))); the motion after the impact starts
about t_c / 2 later (the pad's impulse is centred there). Each bound scales that change by
what its metric is relative to.

Engine against soft: the same model and pad, the engine's first-order integrator. Its error
at dt is read from the engine's own run at dt / 2 (Richardson): e(dt) = r / (r - 1)
(v(dt) - v(dt / 2)) with r = e(dt) / e(dt / 2) >= 1.6 (2 for a pure first-order error, the
O(dt^2) remainder allowed as in test_engine_sdof_error_is_first_order_in_dt), so at most
8/3 of the half-step change; plus the reading's own resolution where it has one.

Design notes: docs/ladder.md ("Tolerances per tree", "The pad and the engines' SDOF").
"""

from __future__ import annotations

import math

from treeimpact.analytic.errors import ParameterError

from ..cache import RunCache
from .base import Bound, Pair, half_step_run, register

#: e(dt) <= RICHARDSON |v(dt) - v(dt/2)| for a first-order error with e(dt)/e(dt/2) >= 1.6.
RICHARDSON = 1.6 / (1.6 - 1.0)
#: The soft contact's T0 is where |vy - vx| < this fraction of u1 (analytic.records), so V
#: (vx at T0) is defined to this fraction of u1 on either record.
COMMON_VELOCITY_TOLERANCE = 1e-3


# --------------------------------------------------------------------------- soft vs Newton


def pad_numbers(result) -> tuple[float, float, float]:
    """b = C_T / (2 (M_T + m)) (1/s), t_c (s) and E0 = m u1^2 / 2 (J) of a soft-pad run's
    ``result`` (a SimulationResult: its model dict and collision duration)."""
    md = result.model
    b = md["C_T"] / (2.0 * (md["M_T"] + md["m"]))
    return b, float(result.collision_duration), 0.5 * md["m"] * md["u1"] ** 2


def _pad_words(b: float, t_c: float) -> str:
    return f"b = {b:.3g} 1/s, t_c = {1e3 * t_c:.3g} ms: b t_c = {b * t_c:.2g}"


def _meaningless(rel: float) -> str:
    return (" (the error bound exceeds the value itself: no relative comparison means "
            "anything for this quantity on this tree)" if rel >= 1.0 else "")


@register("pad-damping")
def pad_damping(pair: Pair) -> Bound:
    """The moving-together motion's amplitudes and momenta: rel = b t_c of the tree's soft
    run (``pair.rung``, the soft SDOF; ``pair.reference`` the Newton model)."""
    b, t_c, _ = pad_numbers(pair.rung.result)
    return Bound(b * t_c, _pad_words(b, t_c))


@register("pad-energy")
def pad_energy(pair: Pair) -> Bound:
    """An energy of the event: its error is of order b t_c of the energy in play, the
    impactor's E0 = m u1^2 / 2, so rel = b t_c E0 / |E| with E the Newton model's value
    (``pair.reference_value``, J)."""
    b, t_c, e0 = pad_numbers(pair.rung.result)
    ref = abs(pair.reference_value)
    rel = b * t_c * e0 / ref if ref > 0 else math.inf
    return Bound(min(rel, 1e6), f"{_pad_words(b, t_c)} of E0 = {e0:.3g} J, over "
                 f"{pair.metric} = {ref:.3g} J: {rel:.2g}{_meaningless(rel)}")


@register("pad-rebound")
def pad_rebound(pair: Pair) -> Bound:
    """The impactor's rebound energy E_r: its velocity v_r = sqrt(2 E_r / m) changes by
    order b t_c u1 (b t_c of the momentum exchanged), so rel = 2 b t_c u1 / v_r =
    2 b t_c sqrt(E0 / E_r), E_r the Newton model's (``pair.reference_value``, J)."""
    b, t_c, e0 = pad_numbers(pair.rung.result)
    e_r = abs(pair.reference_value)
    rel = 2.0 * b * t_c * math.sqrt(e0 / e_r) if e_r > 0 else math.inf
    return Bound(min(rel, 1e6), f"{_pad_words(b, t_c)}, E0 = {e0:.3g} J, E_r = {e_r:.3g} "
                 f"J: 2 b t_c sqrt(E0 / E_r) = {rel:.2g}{_meaningless(rel)}")


@register("pad-time")
def pad_time(pair: Pair) -> Bound:
    """A time of the motion after the impact: the pad's impulse is centred up to t_c / 2
    after Newton's, so rel = b t_c + t_c / (2 t) with t the Newton model's value (s), of
    ``pair`` (the soft SDOF's rung against the Newton model's)."""
    b, t_c, _ = pad_numbers(pair.rung.result)
    t = abs(pair.reference_value)
    shift = 0.5 * t_c / t if t > 0 else math.inf
    return Bound(min(b * t_c + shift, 1e6), f"{_pad_words(b, t_c)}, plus t_c / (2 "
                 f"{pair.metric}) = {1e3 * 0.5 * t_c:.3g} ms / {1e3 * t:.3g} ms = {shift:.2g}")


# --------------------------------------------------------------------------- engine vs soft


def half_step_value(scenario, rung_result, metric: str) -> tuple[float, float]:
    """The step dt (s) of an engine rung's run (``rung_result``, a compare.tree.ladder.RungResult
    of ``scenario``) and its value of ``metric`` (SI) rerun at dt / 2 (NaN when that run
    did not finish); each rerun once a process."""
    dt = float(rung_result.result.model["dt"])
    run = half_step_run(scenario, rung_result)
    value = run.result.metrics.get(metric) if run.ok else None
    return dt, (math.nan if value is None else float(value))


def first_order_error(scenario, rung_result, metric: str) -> tuple[float, float, float]:
    """dt (s), the half-step change v(dt) - v(dt / 2) of ``metric`` on the engine rung
    ``rung_result`` of ``scenario`` and its first-order error at dt, RICHARDSON times that
    change (SI)."""
    dt, half = half_step_value(scenario, rung_result, metric)
    change = rung_result.values.get(metric, math.nan) - half
    return dt, change, RICHARDSON * abs(change)


def _resolution(pair: Pair, dt: float) -> tuple[float, str]:
    """The reading's own resolution at step ``dt`` (s), relative to the soft reference: T0
    is a crossing on records sampled at dt (dt / T0), x0 moves with it (|V| dt / |x0|);
    other metrics none."""
    ref = pair.reference.values
    if pair.metric == "T0":
        rel = dt / abs(ref["T0"])
        return rel, f" + one step dt / T0 = {rel:.2g}"
    if pair.metric == "x0":
        rel = abs(ref["V"]) * dt / abs(ref["x0"])
        return rel, f" + one step |V| dt / x0 = {rel:.2g}"
    return 0.0, ""


@register("engine-first-order", step=True)
def engine_first_order(pair: Pair) -> Bound:
    """An engine SDOF (``pair.rung``) against the soft SDOF (``pair.reference``): the
    engine's first-order error at its dt from its rerun at dt / 2, relative to the soft
    value, plus the reading's resolution (:func:`_resolution`)."""
    dt, change, err = first_order_error(pair.scenario, pair.rung, pair.metric)
    ref = abs(pair.reference_value)
    if not (math.isfinite(err) and ref > 0):
        return Bound(0.0, f"dt = {1e6 * dt:.3g} us: no value at dt / 2 to bound the error by")
    floor, floor_words = _resolution(pair, dt)
    rel = err / ref + floor
    return Bound(rel, f"dt = {1e6 * dt:.3g} us, {pair.metric} moves by {change:+.3g} from dt "
                 f"to dt / 2, so its first-order error at dt is <= 8/3 of that = "
                 f"{err / ref:.2g} of {ref:.4g}{floor_words}: {rel:.2g}")


@register("engines-first-order", step=True)
def engines_first_order(pair: Pair) -> Bound:
    """Bullet's SDOF (``pair.rung``) against MuJoCo's (``pair.reference``), the same model
    and pad: each engine's first-order error from its rerun at dt / 2; they differ by at
    most the sum, relative to MuJoCo's value."""
    errs, words = [], []
    for rr in (pair.reference, pair.rung):
        dt, change, err = first_order_error(pair.scenario, rr, pair.metric)
        errs.append(err)
        words.append(f"{rr.rung.id} {change:+.3g} from dt to dt / 2")
    ref = abs(pair.reference_value)
    if not (all(math.isfinite(e) for e in errs) and ref > 0):
        return Bound(0.0, "no value at dt / 2 to bound the engines' errors by")
    floor = 2.0 * _resolution(pair, dt)[0]
    rel = sum(errs) / ref + floor
    return Bound(rel, f"dt = {1e6 * dt:.3g} us, {', '.join(words)}: the sum of 8/3 of each "
                 f"is {sum(errs) / ref:.2g} of {ref:.4g}"
                 + (f" + two steps' resolution {floor:.2g}" if floor else "") + f": {rel:.2g}")


def step_energy_error(result) -> tuple[float, float, float]:
    """dt (s), omega_c dt = pi dt / t_c (1) and the energy error (omega_c dt)^2 / 2 of E0 (J)
    of an engine SDOF run's ``result`` (its model dict's dt, m, u1, collision duration)."""
    dt = float(result.model["dt"])
    w_dt = math.pi * dt / float(result.collision_duration)
    return dt, w_dt, 0.5 * w_dt ** 2 * 0.5 * result.model["m"] * result.model["u1"] ** 2


def _energy_bound(pair: Pair, runs: tuple) -> Bound:
    """The summed step energy errors of ``runs`` (engine SDOF results) over the reference's
    rebound energy E_r (J)."""
    errs = [step_energy_error(r) for r in runs]
    e_r = abs(pair.reference_value)
    total = sum(e[2] for e in errs)
    rel = total / e_r if e_r > 0 else math.inf
    dt, w_dt, _ = errs[0]
    return Bound(min(rel, 1e6), f"dt = {1e6 * dt:.3g} us, omega_c dt = {w_dt:.3g}: "
                 f"{total:.3g} J of E0 = {errs[0][2] / (0.5 * w_dt ** 2):.3g} J"
                 + (" (both engines)" if len(runs) > 1 else "")
                 + f", over E_r = {e_r:.3g} J: {rel:.2g}{_meaningless(rel)}")


@register("engine-energy", step=True)
def engine_energy(pair: Pair) -> Bound:
    """The engine SDOF's (``pair.rung``) rebound energy against the soft SDOF's
    (``pair.reference``): the step's energy error (omega_c dt)^2 / 2 of E0 over E_r."""
    return _energy_bound(pair, (pair.rung.result,))


@register("engines-energy", step=True)
def engines_energy(pair: Pair) -> Bound:
    """Bullet's SDOF (``pair.rung``) against MuJoCo's (``pair.reference``) on the rebound
    energy: the sum of the two steps' energy errors over MuJoCo's E_r."""
    return _energy_bound(pair, (pair.reference.result, pair.rung.result))


# --------------------------------------------------------------------------- T0, x0, V


def crossing_rate(result, t0: float) -> float:
    """|d(vy - vx)/dt| (m/s^2) where the relative velocity of ``result``'s trajectory crosses
    the common-velocity threshold at ``t0`` (s): the slope of a line fitted over t_c / 2
    centred on it (the contact's oscillation averaged over a quarter period each side)."""
    import numpy as np  # lazy: numpy only where a trajectory is read, not at registry import

    tr, half = result.trajectory, 0.25 * float(result.collision_duration)
    sel = (tr.t >= t0 - half) & (tr.t <= t0 + half)
    if np.count_nonzero(sel) < 3:
        return math.nan
    slope = np.polyfit(tr.t[sel], (tr.vy - tr.vx)[sel], 1)[0]
    return abs(float(slope))


def t0_shift(engine_result, reference) -> tuple[float, str]:
    """The bound on the T0 shift (s) of an engine run's ``engine_result`` (a SimulationResult:
    its dt, e, u1 and t_c) and its words: the engine's restitution is off
    by O(omega_c dt) (the touch force a step late), so the relative velocity after the first
    collision, at most e u1, is off by delta_w = omega_c dt e u1; T0, where |vy - vx| falls
    below the threshold at the rate of ``reference`` (a RungResult with a trajectory), moves
    by delta_w / rate, plus one step of reading."""
    md = engine_result.model
    dt = float(md["dt"])
    w_dt = math.pi * dt / float(engine_result.collision_duration)
    delta_w = w_dt * md["restitution"] * md["u1"]
    rate = crossing_rate(reference.result, reference.values["T0"])
    shift = delta_w / rate + dt if rate > 0 else math.inf
    return shift, (f"omega_c dt = {w_dt:.3g}, e u1 = {md['restitution'] * md['u1']:.3g} m/s: "
                   f"delta_w = {1e3 * delta_w:.3g} mm/s at |d(vy - vx)/dt| = {rate:.3g} m/s^2, "
                   f"dT0 <= {1e6 * shift:.3g} us (with one step dt = {1e6 * dt:.3g} us)")


def _moving_together_bound(pair: Pair, engines: tuple) -> Bound:
    """T0, x0 or V of the engine results ``engines`` against ``pair.reference``: T0 by the
    summed shifts, x0 by |V| dT0, V by |a(T0)| dT0 + delta_w (the trunk's deceleration a
    read on the reference's record); relative to the reference's value."""
    ref = pair.reference.values
    if not all(math.isfinite(ref.get(k, math.nan)) for k in ("T0", "x0", "V")):
        return Bound(0.0, "no moving-together phase on the reference: nothing to bound")
    shifts = [t0_shift(r, pair.reference) for r in engines]
    d_t0 = sum(s[0] for s in shifts)
    words = shifts[0][1] + (" each" if len(engines) > 1 else "")
    if pair.metric == "T0":
        err = d_t0
    elif pair.metric == "x0":
        err, words = abs(ref["V"]) * d_t0, words + f"; |V| dT0 = {1e6 * abs(ref['V']) * d_t0:.3g} um"
    else:
        tr = pair.reference.result.trajectory
        import numpy as np  # lazy: as crossing_rate

        acc = abs(float(np.interp(ref["T0"], tr.t, np.gradient(tr.vx, tr.t))))
        md = engines[0].model
        delta_w = len(engines) * math.pi * md["dt"] / engines[0].collision_duration * \
            md["restitution"] * md["u1"]
        err = acc * d_t0 + delta_w
        words += f"; |a| dT0 + delta_w = {1e3 * err:.3g} mm/s at |a| = {acc:.3g} m/s^2"
    rel = err / abs(pair.reference_value) if pair.reference_value else math.inf
    return Bound(min(rel, 1e6), f"{words}; over {pair.metric} = {abs(pair.reference_value):.4g}"
                 f": {rel:.2g}{_meaningless(rel)}")


@register("engine-moving-together", step=True)
def engine_moving_together(pair: Pair) -> Bound:
    """T0, x0, V of an engine SDOF (``pair.rung``) against the soft SDOF (``pair.reference``)."""
    return _moving_together_bound(pair, (pair.rung.result,))


@register("engines-moving-together", step=True)
def engines_moving_together(pair: Pair) -> Bound:
    """T0, x0, V of Bullet's SDOF (``pair.rung``) against MuJoCo's (``pair.reference``):
    each engine's shift from the same motion, summed."""
    return _moving_together_bound(pair, (pair.reference.result, pair.rung.result))


# --------------------------------------------------------------------------- identification

#: The procedure's regression window (s): analytic.identify.procedure.regress's default.
WINDOW = 0.010
#: The tree at e = 0, run on the Newton rung once a process: the procedure's own floor.
_FLOOR_RUNS = RunCache()


def procedure_floor(scenario, rung_result, metric: str) -> float:
    """The procedure's relative error (1) on ``metric`` (an IDENT_METRICS key) on the exact
    e = 0 record of ``scenario`` run as ``rung_result``'s rung (the Newton model): the bodies
    move together from t = 0 with x0 = 0, the procedure's own assumption, so all that is
    left is eq 39 truncated at t^2 over the window; NaN when it refuses that record."""
    import dataclasses  # lazy: only the identification's bound needs it

    # lazy: the procedure (numpy, scipy) only where an identification is judged
    from treeimpact.analytic.identify.procedure import (
        identify_from_record,
        pendulum_test_of,
        truth_of,
    )

    s0 = dataclasses.replace(scenario, contact=dataclasses.replace(scenario.contact,
                                                                   restitution=0.0))
    run = _FLOOR_RUNS.run(s0, rung_result.rung.backend, **dict(rung_result.rung.options))
    if not run.ok:
        return math.nan
    tr = run.result.trajectory
    try:
        ident, _ = identify_from_record(tr.t, tr.x, pendulum_test_of(s0), y=tr.y,
                                        reading="paper")
    except (ParameterError, ValueError, FloatingPointError):  # refused: no floor to read
        return math.nan
    return ident.as_dict()[metric] / truth_of(s0)[metric] - 1.0  # by its symbol (M_T, ...)


@register("procedure-floor")
def procedure_floor_bound(pair: Pair) -> Bound:
    """An identified value on the Newton record (``pair.rung``) against the truth: the
    floor of eq 39's truncation on this tree (:func:`procedure_floor`), scaled to the
    record's own window: the t^3 term biases the quadratic's t^2 coefficient by 3 times the
    window's midpoint from the origin, (s0 + W / 2) where the e = 0 record has W / 2 (an
    upper bound on the growth: the same term in a1 lowers it), so
    rel = |floor| (1 + 2 s0 / W), s0 = t_together - t_origin of the record's regression."""
    metric = pair.metric.removeprefix("id_")
    floor = procedure_floor(pair.scenario, pair.rung, metric)
    reg = (pair.rung.identification.regression or {}) if pair.rung.identification else {}
    s0 = reg.get("t_together", math.nan) - reg.get("t_origin", math.nan)
    if not (math.isfinite(floor) and math.isfinite(s0)):
        return Bound(0.0, "the procedure refuses this tree's e = 0 record or its own: no floor")
    rel = abs(floor) * (1.0 + 2.0 * max(s0, 0.0) / WINDOW)
    return Bound(rel, f"the procedure's error on this tree's e = 0 record is {floor:+.3g}; "
                 f"the window starts s0 = {1e3 * s0:.3g} ms after the origin, so "
                 f"|floor| (1 + 2 s0 / {1e3 * WINDOW:g} ms) = {rel:.3g}")
