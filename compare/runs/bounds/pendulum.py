"""Bounds on the pendulum's step (the compound pendulum against the linear one) and on the
two engines against each other, from the tree's own runs.

* ``first_order_in_dt``: both engines step the contact and the trunk with a first-order
  (semi-implicit Euler) step, so a compared difference Delta(dt) = Delta* + a dt carries a
  first-order part a dt that is no physics of either model. Each compared run is run again
  at half its own step (fixed, every step dt / 2: a finer step than the run's, phased or
  not); Richardson's estimate of the first-order part is 2 |Delta(dt) - Delta(dt / 2)|. The
  tolerance is the entry's ``floor`` (what stays at any step: its reason) plus that part,
  plus for the pendulum's step the compound pendulum's own terms: its linearisation,
  theta^2 / 2 at the largest angle theta = y / l_e it turns over the contacts (cos theta in
  the contact point's speed; sin theta's theta^2 / 6 and 1 - cos theta's theta^2 / 12 are
  smaller), and for the moving-together quantities the touch's phase within a step (the
  linear pendulum starts at the touch, the compound one reaches it anywhere within a step,
  so the event shifts by up to one step: dt over T0 or t_sep, vx(T0) dt over x0, the trunk's
  deceleration times dt over V).
* ``contact_sequence``: the contact count of two runs of the same chain and pad. The
  smallest contacts that together carry less than :data:`GRAZING_SHARE` of the total
  impulse are grazing touches that a sub-step change of the motion makes or removes (the
  impulse check cannot tell them from none); the two sequences are the same up to those, so
  their counts differ by at most the larger number of grazing contacts of either run.

Design notes and measured figures: docs/ladder.md ("Tolerances per tree: the pendulum and
the two engines").
"""

from __future__ import annotations

import math

import numpy as np

from treeimpact.analytic.records import contact_intervals

from .base import Bound, Pair, half_step_run, register, relative_step

#: Share of the total impulse that the grazing contacts carry together at most: the impulse
#: check of the same two runs ([step.pendulum] impulse, floor 0.005) resolves no less, so
#: contacts carrying less momentum together cannot be told from none by the compared metrics.
GRAZING_SHARE = 0.005
#: The quantities defined at the moving-together point T0, shifted by the touch's phase.
AT_T0 = ("T0", "x0", "V", "t_sep")


def half_step_result(scenario, rung_result):
    """The SimulationResult of ``rung_result``'s rung (a ``compare.tree.ladder.RungResult``) on
    ``scenario`` run again at half its step (:func:`compare.runs.bounds.base.half_step_run`);
    None when that run does not finish (its reason is then the bound's words)."""
    run = half_step_run(scenario, rung_result)
    return run.result if run.ok else None


def _floor(pair: Pair) -> float:
    """The evaluated entry's ``floor`` (1), what stays at any step; 0 where it gives none."""
    return float((pair.entry or {}).get("floor", 0.0))


def contact_angle(result, equivalent_length: float) -> float:
    """The largest angle (rad) the pendulum turns from the touch over the contacts of
    ``result`` (a SimulationResult): max |y| / l_e up to the last contact's end, with
    ``equivalent_length`` l_e (m)."""
    tr = result.trajectory
    t, y, force = (np.asarray(a, dtype=float) for a in (tr.t, tr.y, tr.force))
    on = np.flatnonzero(force > 0.0)
    if on.size == 0:
        return 0.0
    return float(np.abs(y[:on[-1] + 1]).max() / equivalent_length)


def touch_phase(result, metric: str) -> float:
    """The relative shift (1) of ``metric`` (one of :data:`AT_T0`) of ``result`` when its
    contact starts up to one step dt later: dt / T0, dt / t_sep, |vx(T0)| dt / |x0| or
    |dvx/dt (T0)| dt / |V| (the trunk's deceleration read from the record at T0)."""
    m, dt = result.metrics, float(result.model["dt"])
    value = float(m.get(metric, math.nan))
    if not (math.isfinite(value) and value != 0):
        return 0.0
    if metric in ("T0", "t_sep"):
        return dt / abs(value)
    tr = result.trajectory
    t, vx = np.asarray(tr.t, dtype=float), np.asarray(tr.vx, dtype=float)
    t0 = float(m["T0"])
    if metric == "x0":
        return abs(float(np.interp(t0, t, vx))) * dt / abs(value)
    i = int(np.clip(np.searchsorted(t, t0), 1, t.size - 2))
    accel = (vx[i + 1] - vx[i - 1]) / (t[i + 1] - t[i - 1])
    return abs(float(accel)) * dt / abs(value)


def _first_order(pair: Pair) -> tuple[float, str]:
    """(Richardson's first-order part 2 |Delta(dt) - Delta(dt / 2)| (1), its words) of the
    pair's difference, from both rungs run again at half their steps."""
    a = half_step_result(pair.scenario, pair.rung)
    b = half_step_result(pair.scenario, pair.reference)
    if a is None or b is None:
        return 0.0, "no first-order part: a run at half the step did not finish"
    d = relative_step(pair.value, pair.reference_value)
    dh = relative_step(a.metrics.get(pair.metric), b.metrics.get(pair.metric))
    if not (math.isfinite(d) and math.isfinite(dh)):
        return 0.0, "no first-order part: the difference is not defined at half the step"
    part = 2.0 * abs(d - dh)
    return part, (f"first-order part 2 |{100 * d:+.3f} % - ({100 * dh:+.3f} % at dt / 2)| "
                  f"= {100 * part:.3f} % (dt = {1e6 * float(pair.rung.result.model['dt']):.3g}"
                  f" / {1e6 * float(pair.reference.result.model['dt']):.3g} us)")


def _pendulum_terms(pair: Pair) -> tuple[float, list[str]]:
    """(the compound pendulum's own terms (1), their words): theta^2 / 2 at its largest
    angle over the contacts, and for :data:`AT_T0` the touch's phase within a step."""
    le = pair.scenario.impactor.equivalent_length
    theta = contact_angle(pair.rung.result, le)
    rel, words = 0.5 * theta * theta, [f"theta^2 / 2 = {0.5 * theta * theta:.2g} at theta = "
                                       f"{theta:.3g} rad (y / l_e over the contacts)"]
    if pair.metric in AT_T0:
        phase = touch_phase(pair.rung.result, pair.metric)
        rel += phase
        words.append(f"touch phase {100 * phase:.3f} % (one step)")
    return rel, words


@register("first_order_in_dt", step=True, floor=True)
def first_order_in_dt(pair: Pair) -> Bound:
    """The tolerance of ``pair`` (its two rungs' runs): the entry's floor plus the
    first-order part of the difference (module docstring), plus the compound pendulum's
    terms when the rung is the full pendulum against the linear one."""
    floor = _floor(pair)
    rel, words = floor, [f"floor {100 * floor:.2g} %"]
    if pair.rung.rung.kind != pair.reference.rung.kind:  # the pendulum's step
        extra, extra_words = _pendulum_terms(pair)
        rel += extra
        words += extra_words
    if _within(pair, rel):  # the first-order part (two runs at dt / 2) can only add to it
        return Bound(rel, " + ".join(words) + f" = {100 * rel:.3g} %, which the step is "
                     "within (the first-order part, runs at dt / 2, measured only beyond it)")
    part, part_words = _first_order(pair)
    rel += part
    words.insert(1, part_words)
    return Bound(rel, " + ".join(words) + f" = {100 * rel:.3g} %")


def _within(pair: Pair, rel: float) -> bool:
    """Whether ``pair``'s relative step, as the verdict computes it, is finite and within
    ``rel``."""
    return abs(relative_step(pair.value, pair.reference_value)) <= rel


def episodes(result) -> tuple[int, int]:
    """(contacts, grazing ones) of ``result``'s record (contacts: the runs of force > 0; the
    grazing ones: the smallest, as many as together carry less than :data:`GRAZING_SHARE`
    of the total impulse)."""
    tr = result.trajectory
    t, force = np.asarray(tr.t, dtype=float), np.asarray(tr.force, dtype=float)
    raw = contact_intervals(force, 0.0)
    carried = np.sort([float(np.trapezoid(force[i0:i1 + 2], t[i0:i1 + 2])) for i0, i1 in raw])
    grazing = int(np.count_nonzero(np.cumsum(carried) < GRAZING_SHARE * carried.sum()))
    return len(raw), grazing


@register("contact_sequence")
def contact_sequence(pair: Pair) -> Bound:
    """The same sequence of contacts up to its grazing touches (module docstring) on
    ``pair``'s two runs: the counts within the larger number of grazing contacts of
    either."""
    (na, ga), (nb, gb) = episodes(pair.rung.result), episodes(pair.reference.result)
    ref = pair.reference_value
    slack = max(ga, gb)
    rel = slack / ref if math.isfinite(ref) and ref > 0 else 0.0
    return Bound(rel, f"{na} and {nb} contacts, of which {ga} and {gb} grazing (together "
                      f"under {100 * GRAZING_SHARE:g} % of the impulse): counts within {slack}"
                      f" of {ref:g}")
