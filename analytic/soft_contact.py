"""Soft-contact variant of the paper's model: the same two bodies, a spring-dashpot contact.

Design notes and measured figures: docs/contact-law.md.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from .model import TwoBodyModel, two_body_model
from .parameters import DEFAULT_CONTACT_DURATION, Contact, ParameterError, Scenario


def release_time(zeta: float) -> float:
    """Release time of one collision, in units of 1/omega (see module docstring)."""
    if zeta < 0 or not math.isfinite(zeta):
        raise ParameterError(f"zeta = {zeta!r}: allowed [0, inf)")
    if abs(zeta - 1.0) < 1e-9:
        return 2.0
    if zeta < 1.0:
        s = math.sqrt(1.0 - zeta * zeta)
        return (math.pi - math.atan2(2.0 * zeta * s, 1.0 - 2.0 * zeta * zeta)) / s
    sd = math.sqrt(zeta * zeta - 1.0)
    r1, r2 = -1.0 / (zeta + sd), -zeta - sd  # r1 r2 = 1: no cancellation in r1
    return 2.0 * math.log(r2 / r1) / (r1 - r2)


def restitution_for_damping_ratio(zeta: float) -> float:
    """e of one collision under F = max(0, k delta + c delta') with damping ratio zeta."""
    t = release_time(zeta)
    if abs(zeta - 1.0) < 1e-9:
        return math.exp(-t) * (t - 1.0)
    if zeta < 1.0:
        s = math.sqrt(1.0 - zeta * zeta)
        ex = math.exp(-zeta * t)
        return -ex * (math.cos(s * t) - zeta / s * math.sin(s * t))
    sd = math.sqrt(zeta * zeta - 1.0)
    r1, r2 = -1.0 / (zeta + sd), -zeta - sd
    return -(r1 * math.exp(r1 * t) - r2 * math.exp(r2 * t)) / (r1 - r2)


#: The smallest restitution a spring-dashpot contact is asked for (damping ratio ~50).
MIN_SOFT_RESTITUTION = 1e-4


def damping_ratio_for_restitution(e: float) -> float:
    """Inverse of :func:`restitution_for_damping_ratio` for 0 < e <= 1."""
    if isinstance(e, bool) or not isinstance(e, (int, float)) or not (
            MIN_SOFT_RESTITUTION <= e <= 1.0):
        raise ParameterError(
            f"contact.restitution = {e!r} is out of range for a soft contact: allowed "
            f"[{MIN_SOFT_RESTITUTION:g}, 1] (e = 0 needs infinite damping; e ~ 1 / (4 zeta^2) "
            "when overdamped, so 1e-4 already needs a damping ratio of 50)")
    if e == 1.0:
        return 0.0
    hi = 1.0
    while restitution_for_damping_ratio(hi) > e:
        hi *= 2.0
    return brentq(lambda z: restitution_for_damping_ratio(z) - e, 0.0, hi, xtol=1e-15,
                  rtol=1e-14)


def contact_law(model: TwoBodyModel, contact: Contact | None = None, *,
                stiffness: float | None = None, duration: float | None = None
                ) -> tuple[float, float]:
    """(k_c in N/m, c_c in N s/m) giving the model's restitution e in one collision.

    The stiffness comes from ``stiffness`` or ``duration`` (keyword first, then the
    contact's), duration meaning the undamped collision time pi sqrt(mu / k); the default
    duration is :data:`analytic.parameters.DEFAULT_CONTACT_DURATION`.
    """
    mu = model.reduced_mass
    if stiffness is None and duration is None and contact is not None:
        stiffness, duration = contact.stiffness, contact.duration
    if stiffness is not None and duration is not None:
        raise ParameterError("contact: give either stiffness (N/m) or duration (s), not both")
    if stiffness is None:
        duration = DEFAULT_CONTACT_DURATION if duration is None else duration
        Contact(restitution=model.restitution, duration=duration)  # validates
        stiffness = mu * (math.pi / duration) ** 2
    else:
        Contact(restitution=model.restitution, stiffness=stiffness)
    zeta = damping_ratio_for_restitution(model.restitution)
    return stiffness, 2.0 * zeta * math.sqrt(stiffness * mu)


#: How a trunk other than the SDOF gets its contact damping: "pad" keeps the SDOF rung's
#: (k_c, c_c), one physical pad for every trunk; "effective" recalibrates c_c so that one
#: free collision with the trunk's instantaneous effective mass at the clamp rebounds at e
#: (the restitution convention; docs/contact-law.md).
CALIBRATIONS = ("pad", "effective")


def pad_restitution(stiffness: float, damping: float, reduced_mass: float) -> float:
    """e of one free collision of reduced mass mu (kg) under the pad (k N/m, c N s/m).

    The pad's own e on a light trunk is smaller than on M_T (the same c is more damping
    there); below :data:`MIN_SOFT_RESTITUTION` it is refused with a one-line error.
    """
    e = restitution_for_damping_ratio(damping / (2.0 * math.sqrt(stiffness * reduced_mass)))
    if e < MIN_SOFT_RESTITUTION:
        raise ParameterError(
            f"contact.restitution: the pad rebounds at e = {e:.3g} on the trunk's effective "
            f"mass, below {MIN_SOFT_RESTITUTION:g}: a larger e or --calibration effective")
    return e


def effective_damping(stiffness: float, restitution: float, reduced_mass: float) -> float:
    """c_c (N s/m) giving e in one free collision of reduced mass mu (kg) at stiffness k."""
    zeta = damping_ratio_for_restitution(restitution)
    return 2.0 * zeta * math.sqrt(stiffness * reduced_mass)


def collision_duration(model: TwoBodyModel, stiffness: float, damping: float) -> float:
    """Duration (s) of one free two-body collision under the law, first touch to release."""
    mu = model.reduced_mass
    omega = math.sqrt(stiffness / mu)
    return release_time(damping / (2.0 * math.sqrt(stiffness * mu))) / omega


def simulate_soft(scenario: Scenario, *, restitution: float | None = None,
                  contact_stiffness: float | None = None, duration: float | None = None,
                  t_end: float | None = None, samples_per_collision: int = 100):
    """The scenario's two-body model with the soft contact, integrated to ``t_end`` (s).

    ``contact_stiffness`` (N/m, the engines' and the CLI's name) or ``duration`` (s) replace
    the scenario's contact stiffness (:func:`contact_law`).

    Piecewise-smooth integration (DOP853, rtol 1e-11) with events at touch (delta = 0,
    rising) and release (k delta + c delta' = 0, falling). Returns a SimulationResult
    (backend "analytic-soft") whose metrics come from :func:`analytic.records.metrics_from_record`,
    the same rule the engines use.
    """
    from .records import model_metrics
    from .results import SimulationResult

    model = two_body_model(scenario, restitution)
    t_end = scenario.t_end if t_end is None else t_end
    k_c, c_c = contact_law(model, scenario.contact, stiffness=contact_stiffness,
                           duration=duration)
    t_col = collision_duration(model, k_c, c_c)
    rec = soft_record(model, k_c, c_c, t_end, dt_sample=t_col / samples_per_collision)
    from .records import with_static_shape_crown

    rec = with_static_shape_crown(rec, scenario.trunk)
    metrics = model_metrics(rec, model, scenario.impactor, collision_duration=t_col)
    model_dict = {**model.as_dict(), "contact_stiffness": k_c, "contact_damping": c_c}
    scen = scenario.to_dict()
    scen["contact"]["restitution"] = model.restitution
    return SimulationResult(
        backend="analytic-soft", metrics=metrics, model=model_dict, scenario=scen,
        trajectory=rec.trajectory(),
        record=rec, collision_duration=t_col)


def soft_record(model: TwoBodyModel, k_c: float, c_c: float, t_end: float, dt_sample: float):
    """Integrate the soft-contact two-body model; return an ``ImpactRecord`` sampled every dt."""
    from .records import ImpactRecord

    M, C, K = model.dynamic_mass, model.damping, model.stiffness
    m, kp = model.impactor_mass, model.impactor_stiffness

    def rhs(_t, s, in_contact):
        x, vx, y, vy = s[0], s[1], s[2], s[3]
        f = k_c * (y - x) + c_c * (vy - vx) if in_contact else 0.0
        # last two states: work dissipated by the trunk damping, work absorbed by the contact
        return [vx, (-K * x - C * vx + f) / M, vy, (-kp * y - f) / m, C * vx * vx,
                f * (vy - vx)]

    # Three phases, each integrated smoothly up to its terminal event:
    #   "contact":  F = k delta + c delta' > 0; ends when F falls through 0 (release);
    #   "overlap":  released but still overlapping (delta > 0, F = 0); contact resumes when
    #               k delta + c delta' rises through 0, free flight starts when delta falls
    #               through 0; steps limited to the collision time scale so that a short
    #               excursion of the law is never stepped over;
    #   "free":     delta < 0; contact starts when delta rises through 0 (F = c delta' > 0).
    def law(_t, s, _c):
        return k_c * (s[2] - s[0]) + c_c * (s[3] - s[1])

    def overlap(_t, s, _c):
        return s[2] - s[0]

    def law_rises(_t, s, c):
        return law(_t, s, c)

    law.terminal, law.direction = True, -1.0
    law_rises.terminal, law_rises.direction = True, 1.0
    overlap.terminal, overlap.direction = True, -1.0

    def overlap_rises(_t, s, c):
        return overlap(_t, s, c)

    overlap_rises.terminal, overlap_rises.direction = True, 1.0
    n = int(math.ceil(t_end / dt_sample))
    t_grid = np.linspace(0.0, t_end, n + 1)
    out = np.empty((6, t_grid.size))
    state = np.array([0.0, 0.0, 0.0, model.impact_speed, 0.0, 0.0])
    t, phase = 0.0, "contact"
    scale = max(model.impact_speed, 1e-12)
    short_step = math.pi * math.sqrt(model.reduced_mass / k_c) / 20.0
    contact_flag = np.zeros(t_grid.size, dtype=bool)
    stalls = 0
    while t < t_end:
        events = {"contact": [law], "overlap": [law_rises, overlap],
                  "free": [overlap_rises]}[phase]
        sol = solve_ivp(rhs, (t, t_end), state, method="DOP853", args=(phase == "contact",),
                        events=events, dense_output=True, rtol=1e-11,
                        atol=[1e-14 * scale, 1e-11 * scale, 1e-14 * scale, 1e-11 * scale,
                              1e-12, 1e-12], max_step=np.inf if phase == "free" else short_step)
        if sol.status == -1 or not np.all(np.isfinite(sol.y[:, -1])):
            from .results import SimulationDiverged

            raise SimulationDiverged(f"soft-contact integration failed: {sol.message}")
        hits = [(te[0], k) for k, te in enumerate(sol.t_events) if te.size]
        if hits:
            t_stop, which = min(hits)
            state = sol.y_events[which][0]
        else:
            t_stop, which = t_end, None
            state = sol.y[:, -1]
        sel = (t_grid >= t) & (t_grid <= t_stop)
        if np.any(sel):
            out[:, sel] = sol.sol(t_grid[sel])
            contact_flag[sel] = phase == "contact"
        stalls = stalls + 1 if t_stop <= t else 0
        if stalls > 10:
            from .results import SimulationDiverged

            raise SimulationDiverged(f"soft-contact integration stalled at t = {t:.6g} s")
        t = t_stop
        if which is not None:
            phase = {"contact": "overlap", "free": "contact"}.get(
                phase, "contact" if which == 0 else "free")
            if phase == "free" and state[2] >= state[0]:
                # The overlap event leaves delta = +-1e-19 of round-off. Free flight must start
                # with delta < 0: from delta >= 0 a step that jumps the brief negative
                # excursion sees no rising crossing and the pendulum passes through the trunk.
                state[2] = np.nextafter(state[0], -np.inf)
    x, vx, y, vy, w_damp, w_contact = out
    force = np.where(contact_flag, np.maximum(0.0, k_c * (y - x) + c_c * (vy - vx)), 0.0)
    overlap = np.where(contact_flag, np.maximum(y - x, 0.0), 0.0)
    return ImpactRecord(
        t=t_grid, x=x, vx=vx, y=y, vy=vy, force=force, kinetic=model.kinetic_energy(vx, vy),
        potential=model.potential_energy(x, y), damping_work=w_damp, contact_work=w_contact,
        contact_potential=0.5 * k_c * overlap ** 2, pendulum_energy=model.pendulum_energy(y, vy))
