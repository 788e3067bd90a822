"""Soft-contact variant of the paper's model: the same two bodies, a spring-dashpot contact.

Design notes and measured figures: docs/contact-law.md.
"""

from __future__ import annotations

import enum
import math

import numpy as np

from treeimpact.analytic.budget import Knob, StepCost, check_work
from treeimpact.analytic.errors import SimulationDiverged
from treeimpact.analytic.model.options import (
    CONTACT_DURATION,
    CONTACT_STIFFNESS,
    RESTITUTION,
    T_END,
    Option,
)
from treeimpact.analytic.model.parameters import DEFAULT_CONTACT_DURATION, Scenario
from treeimpact.analytic.model.registry import BY_PATH
from treeimpact.analytic.model.reduction import crown_factor
from treeimpact.analytic.model.two_body import TwoBodyModel, two_body_model
from treeimpact.analytic.records import model_metrics, with_static_shape_crown
from treeimpact.analytic.results import ImpactRecord, SimulationResult, Trajectory

from .exact_solve import deferred_record, solve
from .law import collision_duration, contact_law, pad_fields
from .linear_model import LinearImpactModel
from .phases import ContactPhase, Signal


class SoftMethod(enum.StrEnum):
    """How :func:`simulate_soft` solves the two-body model (the same solution)."""

    #: by the exact linear solver between contact switches (:mod:`.exact_solve`, the trunk
    #: a 1 x 1 mesh; the record's energies when first read)
    EXACT = "exact"
    #: by DOP853 with event location (the original implementation, the tests' reference:
    #: the same metrics to 1e-8)
    ODE = "ode"


#: The words ``method`` takes (:class:`SoftMethod`).
METHODS = tuple(m.value for m in SoftMethod)
#: One sample of the exact solution: wall time and the bytes of the samples and the metrics'
#: work arrays, measured (benchmarks/bench_cost.py; docs/budgets.md).
SAMPLE_COST = StepCost(0.45e-6, 190.0, "samples of the exact two-body solution")
#: The options of :func:`simulate_soft` (the ``soft`` backend).
OPTIONS = {"restitution": RESTITUTION, "contact_stiffness": CONTACT_STIFFNESS,
           "contact_duration": CONTACT_DURATION, "t_end": T_END,
           "samples_per_collision": Option(int, "record samples per free collision", low=2,
                                           cli=False),
           "method": Option(METHODS, "how the two-body model is solved (the same solution)",
                            cli=False)}


def sdof_impact_model(model: TwoBodyModel, trunk, k_c: float, c_c: float
                      ) -> LinearImpactModel:
    """The two-body model of Fig 3 with the pad (``k_c`` N/m, ``c_c`` N s/m) as a
    :class:`LinearImpactModel`: the trunk a 1 x 1 mesh (M_T, C_T, K_T, eq 11) whose crown
    moves with the static shape of ``trunk``, phi(l) x."""
    return LinearImpactModel(
        M=np.array([[model.dynamic_mass]]), D=np.array([[model.equivalent_damping]]),
        K=np.array([[model.equivalent_stiffness]]), clamp=0, crown=0,
        crown_gain=crown_factor(trunk),
        impactor_mass=model.impactor_mass, impactor_stiffness=model.impactor_stiffness,
        impact_speed=model.impact_speed, contact_stiffness=k_c, contact_damping=c_c)


def duration_knob(model: TwoBodyModel, contact, samples: int, damping=None) -> Knob | None:
    """The pad's duration as the budget's :class:`~analytic.budget.Knob` (the record's step
    is the collision's time over ``samples``): the ``contact``'s ``contact.duration`` (or
    its default; a run option that set it is named by its flag where the run refuses,
    analytic.model.options.as_typed); None for a pad set by its stiffness. ``model``: the
    1-DOF pair the pad law is solved on; ``damping``: k_c (N/m) -> c_c (N s/m) where the
    run recalibrates c_c (the beam's effective convention), else the law's own c_c."""
    if contact.stiffness is not None:
        return None
    value = contact.duration if contact.duration is not None else DEFAULT_CONTACT_DURATION

    def dt_of(tau: float) -> float:
        k_c, c_c = contact_law(model, duration=tau)
        return collision_duration(model, k_c, c_c if damping is None else damping(k_c)) / samples

    return Knob("contact.duration", value, "s", dt_of, BY_PATH["contact.duration"].high)


def simulate_soft(scenario: Scenario, *, samples_per_collision: int = 100,
                  method: str = "exact"):
    """The scenario's two-body model with the soft contact (its pad: contact.stiffness or
    contact.duration, :func:`contact_law`), solved to its t_end (s).

    The record is sampled ``samples_per_collision`` times per free collision; ``method``
    (:data:`METHODS`) changes the cost, not the solution. Returns a SimulationResult
    (backend "analytic-soft") whose metrics come from
    :func:`analytic.records.metrics_from_record`, the same rule the engines use.
    """
    method = SoftMethod(OPTIONS["method"].check("method", method))
    model = two_body_model(scenario)
    t_end = scenario.t_end
    k_c, c_c = contact_law(model, scenario.contact)
    t_col = collision_duration(model, k_c, c_c)
    dt = t_col / samples_per_collision
    check_work(t_end, dt, SAMPLE_COST,
               duration_knob(model, scenario.contact, samples_per_collision))
    if method is SoftMethod.ODE:
        rec = with_static_shape_crown(soft_record(model, k_c, c_c, t_end, dt_sample=dt),
                                      scenario.trunk)
        samples, trajectory = rec, rec.trajectory()
    else:
        linear = sdof_impact_model(model, scenario.trunk, k_c, c_c)
        samples, _ = solve(linear, t_end, dt)
        rec = deferred_record(linear, t_end, dt)
        trajectory = Trajectory(t=samples.t, x=samples.x, vx=samples.vx, y=samples.y,
                                vy=samples.vy, force=samples.force)
    metrics = model_metrics(samples, model, scenario.impactor, collision_duration=t_col)
    model_dict = {**model.as_dict(), "contact_stiffness": k_c, "contact_damping": c_c,
                  **pad_fields(k_c, c_c, model.reduced_mass)}
    return SimulationResult(
        backend="analytic-soft", metrics=metrics, model=model_dict,
        scenario=scenario.to_dict(), trajectory=trajectory, record=rec, collision_duration=t_col)


def soft_record(model: TwoBodyModel, k_c: float, c_c: float, t_end: float, dt_sample: float):
    """Integrate the soft-contact two-body ``model`` with the pad (``k_c`` N/m, ``c_c``
    N s/m) by DOP853 to ``t_end`` (s), each phase of :mod:`.phases` smoothly up to its
    terminal event; return an ``ImpactRecord`` sampled every ``dt_sample`` (s). Raises
    SimulationDiverged when the integration fails or stalls."""
    # lazy: +525 ms at import otherwise (scipy.integrate)
    from scipy.integrate import solve_ivp

    rhs, events = _soft_rhs(model, k_c, c_c), _pad_events(k_c, c_c)
    n = int(math.ceil(t_end / dt_sample))
    t_grid = np.linspace(0.0, t_end, n + 1)
    out = np.empty((6, t_grid.size))
    state = np.array([0.0, 0.0, 0.0, model.impact_speed, 0.0, 0.0])
    t, phase = 0.0, ContactPhase.CONTACT
    scale = max(model.impact_speed, 1e-12)
    atol = [1e-14 * scale, 1e-11 * scale, 1e-14 * scale, 1e-11 * scale, 1e-12, 1e-12]
    # released but overlapping, steps are limited to the collision time scale so that a
    # short excursion of the law is never stepped over
    short_step = math.pi * math.sqrt(model.reduced_mass / k_c) / 20.0
    contact_flag = np.zeros(t_grid.size, dtype=bool)
    stalls = 0
    while t < t_end:
        ends = events[phase]
        sol = solve_ivp(rhs, (t, t_end), state, method="DOP853", args=(phase.touching,),
                        events=[e for e, _ in ends], dense_output=True, rtol=1e-11, atol=atol,
                        max_step=np.inf if phase is ContactPhase.FREE else short_step)
        if sol.status == -1 or not np.all(np.isfinite(sol.y[:, -1])):
            raise SimulationDiverged(f"soft-contact integration failed: {sol.message}")
        hits = [(te[0], k) for k, te in enumerate(sol.t_events) if te.size]
        t_stop, which = min(hits) if hits else (t_end, None)
        state = sol.y_events[which][0] if hits else sol.y[:, -1]
        sel = (t_grid >= t) & (t_grid <= t_stop)
        if np.any(sel):
            out[:, sel] = sol.sol(t_grid[sel])
            contact_flag[sel] = phase.touching
        stalls = stalls + 1 if t_stop <= t else 0
        if stalls > 10:
            raise SimulationDiverged(f"soft-contact integration stalled at t = {t:.6g} s")
        t = t_stop
        if which is not None:
            phase = phase.after(ends[which][1], state[2] - state[0])
            if phase is ContactPhase.FREE and state[2] >= state[0]:
                # The overlap event leaves delta = +-1e-19 of round-off. Free flight must start
                # with delta < 0: from delta >= 0 a step that jumps the brief negative
                # excursion sees no rising crossing and the pendulum passes through the trunk.
                state[2] = np.nextafter(state[0], -np.inf)
    return _soft_impact_record(model, k_c, c_c, t_grid, out, contact_flag)


def _soft_rhs(model: TwoBodyModel, k_c: float, c_c: float):
    """The two bodies' equations (eqs 11 and 13) with the pad acting while ``in_contact``;
    the last two states integrate the trunk's damping work and the pad's work (J)."""
    M, C, K = model.dynamic_mass, model.equivalent_damping, model.equivalent_stiffness
    m, kp = model.impactor_mass, model.impactor_stiffness

    def rhs(_t, s, in_contact):
        x, vx, y, vy = s[0], s[1], s[2], s[3]
        f = k_c * (y - x) + c_c * (vy - vx) if in_contact else 0.0
        return [vx, (-K * x - C * vx + f) / M, vy, (-kp * y - f) / m, C * vx * vx,
                f * (vy - vx)]

    return rhs


def _pad_events(k_c: float, c_c: float) -> dict:
    """Each phase's ending events as solve_ivp's terminal events, with the signal each
    crosses: ``{ContactPhase: ((event, Signal), ...)}`` (the rule of :mod:`.phases`)."""

    def crossing(signal: Signal, direction: float):
        def event(_t, s, _c):
            delta = s[2] - s[0]
            return delta if signal is Signal.DELTA else k_c * delta + c_c * (s[3] - s[1])

        event.terminal, event.direction = True, direction
        return event, signal

    return {ContactPhase.CONTACT: (crossing(Signal.LAW, -1.0),),
            ContactPhase.OVERLAP: (crossing(Signal.LAW, 1.0), crossing(Signal.DELTA, -1.0)),
            ContactPhase.FREE: (crossing(Signal.DELTA, 1.0),)}


def _soft_impact_record(model: TwoBodyModel, k_c: float, c_c: float, t_grid: np.ndarray,
                        out: np.ndarray, contact_flag: np.ndarray) -> ImpactRecord:
    """The :class:`ImpactRecord` of the integrated states on the sample grid."""
    x, vx, y, vy, w_damp, w_contact = out
    force = np.where(contact_flag, np.maximum(0.0, k_c * (y - x) + c_c * (vy - vx)), 0.0)
    overlap = np.where(contact_flag, np.maximum(y - x, 0.0), 0.0)
    return ImpactRecord(
        t=t_grid, x=x, vx=vx, y=y, vy=vy, force=force, kinetic=model.kinetic_energy(vx, vy),
        potential=model.potential_energy(x, y), damping_work=w_damp, contact_work=w_contact,
        contact_potential=0.5 * k_c * overlap ** 2, pendulum_energy=model.pendulum_energy(y, vy))
