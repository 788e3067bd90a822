"""What a record says about itself, apart from the tree: its resting level and the rise after
the contact (read on a median-of-3 copy, so one wild sample does not move them), and numbers
that look like another unit than declared. The sensor's noise: :mod:`.noise`.
docs/identification.md, "Diagnoses"."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .pendulum_record import LENGTH_UNITS as RECORD_LENGTH_UNITS
from .pendulum_record import TIME_UNITS as RECORD_TIME_UNITS

MAD_SIGMA = 1.482602218505602  # sigma / MAD of a normal distribution


def median3(x: np.ndarray) -> np.ndarray:
    """x with each interior sample replaced by the median of it and its two neighbours: an
    isolated wild sample is gone, a smooth record barely changes."""
    if x.size < 3:
        return np.array(x, float)
    out = np.array(x, float)
    out[1:-1] = np.median(np.stack([x[:-2], x[1:-1], x[2:]]), axis=0)
    return out


def robust_sigma(r: np.ndarray) -> float:
    """The standard deviation of normal samples r from their median absolute deviation."""
    r = np.asarray(r, float)
    return MAD_SIGMA * float(np.median(np.abs(r - np.median(r)))) if r.size else math.nan


#: How far above the rest's noise (its sigma) the rise's 10 % level must stand for the rise,
#: and so the trunk's speed, to count as measured: a record cut one sample into the impact
#: has 0.1-0.4 sigma there, a whole one at 1 % noise 7-12 (the validation set's tree D).
RESOLVED_SIGMAS = 3.0


@dataclass(frozen=True)
class Features:
    """A record's shape, read off its median-of-3 copy (SI)."""

    rest: float  # m, the resting level before the contact
    span: float  # m, the largest rise above it
    t_contact: float  # s, the contact extrapolated back from the 10 % and 40 % crossings
    velocity: float  # m/s, the slope between those crossings
    t_peak: float  # s, the time of the largest rise
    dt: float  # s, the median sample interval
    #: the 10 % level stands above the rest's noise (3 sigma) and the 40 % crossing comes
    #: after the 10 % one, so ``velocity`` is the rise's slope; else (a record ending at the
    #: contact: its span a sample or two of noise; a rise within one sample) it is no
    #: measure of the trunk's speed
    velocity_resolved: bool = True


def features(t: np.ndarray, x: np.ndarray) -> Features:
    """The :class:`Features` of the record ``x`` (m) at times ``t`` (s), read off its
    median-of-3 copy: the rest (median of the first 2 % of samples, at least 3), the span
    above it, the contact extrapolated back from the 10 % and 40 % crossings at their
    slope, the peak's time and the median sample interval."""
    xs = median3(x)
    dt = float(np.median(np.diff(t)))
    rest = float(np.median(xs[: max(3, xs.size // 50)]))
    # the rest's noise from its sample-to-sample steps (a slow drift does not count)
    noise = robust_sigma(np.diff(np.asarray(x, float)[: max(5, xs.size // 50)])) / math.sqrt(2)
    span = float(np.max(xs) - rest)
    i10 = int(np.argmax(xs - rest > 0.1 * span))
    i40 = int(np.argmax(xs - rest > 0.4 * span))
    if i40 > i10:
        v = float((xs[i40] - xs[i10]) / (t[i40] - t[i10]))
    else:
        v = span / max(float(t[i40] - t[0]), dt)
    v = max(v, 1e-12 * max(span, 1e-300) / dt)
    t_contact = float(t[i10]) - (float(xs[i10]) - rest) / v
    t_contact = min(max(t_contact, float(t[0])), float(t[i10]))
    return Features(rest=rest, span=span, t_contact=t_contact, velocity=v,
                    t_peak=float(t[int(np.argmax(xs))]), dt=dt,
                    velocity_resolved=i40 > i10 and 0.1 * span > RESOLVED_SIGMAS * noise)


#: What a pendulum test can record, a generous window around orchards' numbers: a peak
#: displacement at the clamp (m), the contact-to-peak time (s), the sample interval (s) and
#: the trunk's velocity after the contact over the pendulum's u_1 (at most 2 by eq 21, the
#: slope read off the record a little more with noise).
PLAUSIBLE = {"peak": (1e-5, 0.5), "rise": (5e-5, 2.0), "dt": (1e-7, 0.05), "speed": (1e-4, 2.5)}
#: Typical values, to choose between units that would all be plausible (a 5 mm peak, 20 ms
#: to it, half the pendulum's speed).
TYPICAL = {"peak": 5e-3, "rise": 0.02, "speed": 0.5}
#: The record reader's units (pendulum_record: their powers of ten) as factors to SI.
LENGTH_UNITS = {u: 10.0 ** p for u, p in RECORD_LENGTH_UNITS.items()}
TIME_UNITS = {u: 10.0 ** p for u, p in RECORD_TIME_UNITS.items()}


#: The largest dynamic mass a pendulum test meets at the clamp, kg (10 t: a whole large
#: tree): after the first impact the trunk moves at V_1 / u_1 = m (1 + e) / (M_T + m) (eq 21)
#: >= m / (M_PLAUSIBLE + m), so a slower trunk is read in a wrong unit.
M_PLAUSIBLE = 1e4


def _plausible(peak: float, rise: float, dt: float, speed: float | None,
               speed_low: float = PLAUSIBLE["speed"][0]) -> dict:
    """Which of the record's numbers lie in :data:`PLAUSIBLE` (``speed`` None: not measured,
    not judged)."""
    values = {"peak": peak, "rise": rise, "dt": dt, "speed": speed}
    ok = {k: v is None or PLAUSIBLE[k][0] <= v <= PLAUSIBLE[k][1] for k, v in values.items()}
    ok["speed"] = ok["speed"] and (speed is None or speed >= speed_low)
    return ok


def _distance(**values) -> float:
    return sum(abs(math.log(v / TYPICAL[k])) for k, v in values.items() if v is not None)


def unit_suspicions(feat: Features, u1: float, time_unit: str = "s",
                    length_unit: str = "m", impactor_mass: float | None = None) -> list[str]:
    """One line per record whose numbers look like another unit than declared (its
    features ``feat``, against the pendulum's impact speed ``u1``, m/s): the peak
    displacement, the time from the contact to the peak, the sample interval or the trunk's
    velocity after the contact (against the pendulum's u_1) implausible (:data:`PLAUSIBLE`),
    and plausible once a column, or both, is read in another unit (a factor 1e2-1e6 each;
    one column rather than two, the likeliest when several would do). ``time_unit`` and
    ``length_unit``: what the record was declared in (its numbers already converted to
    SI). With the pendulum's ``impactor_mass`` m (kg), a trunk slower after the contact than
    a tree of :data:`M_PLAUSIBLE` would move is implausible too. A record whose rise is not
    resolved (``feat.velocity_resolved`` False: it ends at the contact, or rises within one
    sample) has no measured speed, and is not judged on it."""
    peak, rise = feat.span, max(feat.t_peak - feat.t_contact, feat.dt)
    speed = feat.velocity / u1 if feat.velocity_resolved else None  # None: not measured
    low = PLAUSIBLE["speed"][0] if impactor_mass is None else max(
        PLAUSIBLE["speed"][0], impactor_mass / (M_PLAUSIBLE + impactor_mass))
    ok = _plausible(peak, rise, feat.dt, speed, low)
    if all(ok.values()):
        return []
    options = []
    for length, f in LENGTH_UNITS.items():
        for time, h in TIME_UNITS.items():
            g = f / LENGTH_UNITS[length_unit]  # lengths x g, times x k: read in these
            k = h / TIME_UNITS[time_unit]
            changed = [c for c, u, d in (("t", time, time_unit), ("x", length, length_unit))
                       if u != d]
            moved = None if speed is None else speed * g / k
            if changed and all(_plausible(peak * g, rise * k, feat.dt * k, moved,
                                          low).values()):
                options.append((len(changed), _distance(peak=peak * g, rise=rise * k,
                                                        speed=moved),
                                {"t": time, "x": length}, changed))
    facts = (f"a peak of {peak:.3g} m, {rise:.3g} s from the contact to it, samples "
             f"{feat.dt:.3g} s apart and a trunk velocity of {feat.velocity:.3g} m/s after a "
             f"pendulum at u_1 = {u1:.3g} m/s")
    if not options:
        bad = ", ".join(k for k, v in ok.items() if not v)
        return [f"the record is implausible for a pendulum test in any unit ({bad}: {facts}); "
                "check the pendulum's flags and the columns' units"]
    _, _, units, changed = min(options, key=lambda o: o[:2])
    return [_unit_line(changed, units, {"t": time_unit, "x": length_unit}, facts)]


def _unit_line(changed: list, units: dict, declared: dict, facts: str) -> str:
    """``x looks like mm, not m: ...`` (or ``t looks like ms and x like mm, not s and m``)
    with how to declare it."""
    flag = {"t": "--time-unit", "x": "--length-unit"}
    looks = " and ".join(f"{c} {'looks ' if i == 0 else ''}like {units[c]}"
                         for i, c in enumerate(changed))
    not_ = " and ".join(declared[c] for c in changed)
    read = " and ".join(units[c] for c in changed)
    headers = ", ".join(f"'{c} ({units[c]})'" for c in changed)
    flags = " ".join(f"{flag[c]} {units[c]}" for c in changed)
    noun = "it: a header" if len(changed) == 1 else "them: headers"
    return (f"{looks}, not {not_}: {facts} are implausible, in {read} they are not "
            f"(declare {noun} {headers} or {flags})")


def pendulum_unit_suspicion(x: np.ndarray, y: np.ndarray | None, chord: float,
                            length_unit: str = "m", approach: float = 0.0) -> list[str]:
    """One line when the pendulum's column ``y`` (m as declared, the trunk's ``x`` m beside
    it) looks like another unit than ``length_unit``, else []: the pendulum swings within
    its release chord ``chord`` = 2 l_e sin(theta_0 / 2) (m) of the contact, the trunk by
    its own span in the trunk's frame, so y spans at most 2 chord + x's span; it spans at
    least its ``approach`` (m) before the contact (u_1 sin(w_2 s) / w_2 over the rest
    recorded, eq 13: at least u_1 T_rest / pi, a half of it for noise, from the caller) and
    1e-3 of x's span (in contact y = x, eq 12; a factor of 1000: a unit's). The unit named
    is the one that brings y within both (the likeliest: nearest x's span)."""
    if y is None:
        return []
    span_x, span_y = float(np.ptp(median3(x))), float(np.ptp(median3(y)))
    high, low = 2.0 * chord + span_x, max(1e-3 * span_x, approach)
    if low <= span_y <= high:
        return []
    declared = LENGTH_UNITS[length_unit]
    fits = [(abs(math.log(span_y * f / declared / max(span_x, 1e-300))), u)
            for u, f in LENGTH_UNITS.items()
            if u != length_unit and low <= span_y * f / declared <= high]
    facts = (f"y spans {span_y:.3g} m where the trunk's x spans {span_x:.3g} m and the "
             f"pendulum swings within {chord:.3g} m of the contact")
    if not fits:
        return [f"the pendulum's column y is implausible in any unit ({facts}); check its "
                "unit and that it is the pendulum's displacement"]
    unit = min(fits)[1]
    return [f"y looks like {unit}, not {length_unit}: {facts}, implausible; in {unit} it is "
            f"not (declare it: a header 'y ({unit})')"]


#: Consecutive sample steps whose median is compared with the block's before: a column whose
#: unit changes part-way has its steps change by the units' factor (1e3 from s to ms) over
#: every block after that row; a gap (a few lost samples) moves a block's median not at all.
STEP_BLOCK = 12
#: A block's median step this many times the block's before (or below its inverse) is
#: another unit, not a logger's jitter (a few per cent) or a rate changed by a factor < 10.
STEP_FACTOR = 10.0


def mixed_time_unit(t: np.ndarray) -> int | None:
    """The first sample (its index) in the other unit where a block of STEP_BLOCK steps of
    the times ``t`` (s) has a median step STEP_FACTOR or more off the previous block's (a
    time column in two units: s, then ms), or None."""
    steps = np.diff(np.asarray(t, float))
    blocks = [float(np.median(steps[i:i + STEP_BLOCK]))
              for i in range(0, steps.size - STEP_BLOCK + 1, STEP_BLOCK)]
    for k in range(1, len(blocks)):
        ref = blocks[k - 1]
        if not ref / STEP_FACTOR < blocks[k] < ref * STEP_FACTOR:
            span = steps[(k - 1) * STEP_BLOCK:(k + 1) * STEP_BLOCK]
            off = np.flatnonzero(~((span > ref / STEP_FACTOR) & (span < ref * STEP_FACTOR)))
            return (k - 1) * STEP_BLOCK + int(off[0]) + 1
    return None


#: A step this many times every step of the block on its smaller side (in the unit of the
#: smaller values) is a discontinuity no motion makes: a struck trunk's steps are V dt and
#: change smoothly; a spike moves two adjacent steps and not the level.
JUMP_FACTOR = 20.0
#: The factors between the length units the reader knows (cm/m, mm/cm, mm/m, um/mm, ...).
UNIT_FACTORS = tuple(sorted({a / b for a in LENGTH_UNITS.values() for b in LENGTH_UNITS.values()
                             if a > b}))
#: The largest steps of a column tried as the switch (a switch near a zero crossing of the
#: motion is a small jump; the steps in the larger unit's noise can exceed it).
SWITCH_CANDIDATES = 8


def mixed_length_unit(x: np.ndarray) -> tuple[int, float] | None:
    """(the first sample in the other unit, the factor after / before) where a length column
    ``x`` switches unit part-way (m, then mm: every value after one row a unit factor
    larger), else None. At one of the SWITCH_CANDIDATES largest steps, two facts at once:
    the median |value| of the STEP_BLOCK samples after it is a unit factor (within 2 x) of
    the block's before (a spike leaves the level), and the step is JUMP_FACTOR times every
    step of the block on the smaller side (a discontinuity, not the motion). A switch where
    the values lie within the noise of zero changes nothing the record shows: not found."""
    x = np.asarray(x, float)
    steps = np.abs(np.diff(x))
    for i in np.argsort(steps)[::-1][:SWITCH_CANDIDATES]:
        i = int(i)
        if not (i + 1 >= STEP_BLOCK and i + 1 + STEP_BLOCK <= x.size):
            continue
        before, after = x[i + 1 - STEP_BLOCK:i + 1], x[i + 1:i + 1 + STEP_BLOCK]
        low, high = float(np.median(np.abs(before))), float(np.median(np.abs(after)))
        if low <= 0.0 or high <= 0.0:
            continue
        small = before if low < high else after
        ratio = max(high / low, low / high)
        if (any(f / 2.0 <= ratio <= 2.0 * f for f in UNIT_FACTORS)
                and steps[i] > JUMP_FACTOR * float(np.max(np.abs(np.diff(small))))):
            return i + 1, high / low
    return None
