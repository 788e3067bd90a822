"""``simulate(scenario)``: the paper's model solved exactly, with the metrics of every backend."""

from __future__ import annotations

import math
from functools import lru_cache, partial

import numpy as np

from treeimpact.analytic.metrics import METRIC_KEYS
from treeimpact.analytic.model.options import RESTITUTION, T_END, Option
from treeimpact.analytic.model.parameters import Pendulum, Scenario
from treeimpact.analytic.model.reduction import crown_factor
from treeimpact.analytic.model.two_body import TwoBodyModel, two_body_model
from treeimpact.analytic.records import with_static_shape_crown
from treeimpact.analytic.results import ImpactRecord, SimulationResult, Trajectory

from .events import Motion
from .solution import ImpactSolution
from .solver import solve_impacts
from .together import force_coefficients


def impact_metrics(sol: ImpactSolution, scenario: Scenario | None = None) -> dict:
    """The metrics of :data:`analytic.metrics.METRIC_KEYS` from an exact solution ``sol``
    (theta_b needs the ``scenario``'s pendulum; NaN without it).

    T0, x0, V: start of the first moving-together phase (the accumulation point when the
    chattering tail was closed analytically). If the bodies never move together they are NaN.
    theta_b: from the pendulum's energy after the last separation (it swings freely then);
    energy_transferred: eq 58 with the exact loss of eq 56.
    """
    model = sol.model
    nan = math.nan
    ts = sol.together_start
    if ts is not None:
        t0 = ts[0]
        tail = next((c for c in sol.tails if c.t_start == t0), None)
        T0 = tail.t_accumulation if tail is not None else t0
        T0 = min(T0, sol.t_end)
        x_, vx_, _, _ = sol._scalar_state(T0)
        x0, V = x_, vx_
        A_x = sol._integral("x", T0)
        A_y = sol._integral("y", T0)
        loss_process = sum(i.loss for i in sol.impacts if i.t <= t0) + sum(
            c.loss for c in sol.tails if c.t_start <= t0)
    else:
        T0 = x0 = V = A_x = A_y = nan
        loss_process = sum(i.loss for i in sol.impacts) + sum(c.loss for c in sol.tails)
    t_sep = sol.separations[0].t if sol.separations else nan
    x_max, t_xmax = sol.x_max
    theta_b = nan
    e_transferred = nan
    if sol.separations:
        t_last = sol.separations[-1].t
        _, _, y, vy = sol._scalar_state(t_last)
        e_pend = model.pendulum_energy(y, vy)
        e_transferred = model.initial_energy - e_pend - loss_process
        if scenario is not None and isinstance(scenario.impactor, Pendulum):
            p = scenario.impactor
            c = 1.0 - e_pend / (p.mass * p.gravity * p.equivalent_length)
            theta_b = math.acos(max(-1.0, min(1.0, c)))
    metrics = {
        "n_impacts": sol.n_impacts,
        "T0": T0, "x0": x0, "V": V,
        "x_max": x_max, "t_xmax": t_xmax, "t_sep": t_sep,
        "A_x": A_x, "A_y": A_y,
        "impact_loss": loss_process,
        "impact_loss_inelastic": sol.inelastic_loss(),
        "energy_transferred": e_transferred,
        "theta_b": theta_b,
        "ledger_residual": sol.ledger_residual(),
        **_whole_event(sol, scenario),
    }
    assert tuple(metrics) == METRIC_KEYS
    return metrics


def _whole_event(sol: ImpactSolution, scenario: Scenario | None) -> dict:
    """Whole-event metrics of the exact solution (analytic.metrics.METRIC_UNITS): every
    impact, tail and moving-together phase. The energies and the impulse need the bodies to
    have parted for good within t_end (else NaN); the impulse is the pendulum's momentum
    balance m u1 - m y'(t) - k int_0^t y dt; force and crown acceleration are impulsive."""
    model = sol.model
    nan = math.nan
    out = {"energy_delivered": nan, "contact_dissipation": nan, "rebound_energy": nan,
           "impulse": nan, "peak_force": nan,
           "contact_episodes": len(sol.impacts) + len(sol.together_starts),
           "first_contact_duration": nan, "crown_peak": nan, "crown_peak_acceleration": nan}
    last = sol.phases[-1] if sol.phases else None
    if last is not None and last.kind is Motion.FREE:
        t = last.t0  # the final free flight starts at the last separation or impact
        vy = last.vy0
        rebound = model.pendulum_energy(last.y0, vy)
        dissipated = sum(i.loss for i in sol.impacts) + sum(c.loss for c in sol.tails)
        out.update(energy_delivered=model.initial_energy - rebound - dissipated,
                   contact_dissipation=dissipated, rebound_energy=rebound,
                   impulse=model.impactor_mass * (model.impact_speed - vy)
                   - model.impactor_stiffness * sol._integral("y", t))
    if scenario is not None:
        out["crown_peak"] = _crown_factor(scenario.trunk) * sol.x_max[0]
    return out


#: The options of :func:`simulate` (the ``analytic`` backend).
OPTIONS = {"restitution": RESTITUTION, "t_end": T_END,
           "samples": Option(int, "samples of the trajectory", low=2, cli=False)}


def simulate(scenario: Scenario, *, samples: int = 2001) -> SimulationResult:
    """Solve the scenario's two-body model exactly (eqs 12-35) up to its t_end (s), with its
    e (a run option that overrides one is applied to the scenario before:
    analytic.model.options.scenario_as_run).

    Returns a :class:`SimulationResult` (backend "analytic") with the metrics, the model
    (M_T, C_T, K_T, m, k, e, u1) and the trajectory sampled at ``samples`` times.
    """
    sol = solve_impacts(_model_of(scenario), scenario.t_end)
    return result_from_solution(sol, scenario, samples=samples)


def _model_of(scenario: Scenario) -> TwoBodyModel:
    """:func:`two_body_model` of ``scenario``, reduced once per scenario (a sweep or a fit
    runs one many times; the model is frozen): ~10 us of a 0.2 ms run."""
    try:
        return _cached_model(scenario)
    except TypeError:  # a scenario holding something unhashable: reduced every time
        return two_body_model(scenario)


@lru_cache(maxsize=256)
def _cached_model(scenario: Scenario) -> TwoBodyModel:
    return two_body_model(scenario)


@lru_cache(maxsize=256)
def _crown_factor(trunk) -> float:
    """:func:`~analytic.model.reduction.crown_factor` of a trunk, once per trunk."""
    return crown_factor(trunk)


def result_from_solution(sol: ImpactSolution, scenario: Scenario | None = None, *,
                         samples: int = 2001, backend: str = "analytic") -> SimulationResult:
    """The SimulationResult (named ``backend``) of the exact solution ``sol`` of
    ``scenario`` (or None: a bare model): its metrics (:func:`impact_metrics`), and its
    trajectory and record at ``samples`` times, computed when first read."""
    scen = scenario.to_dict() if scenario is not None else {}
    if scenario is not None:
        scen["contact"]["restitution"] = sol.model.restitution
        scen["t_end"] = sol.t_end
    return SimulationResult(
        backend=backend, metrics=impact_metrics(sol, scenario), model=sol.model.as_dict(),
        scenario=scen, trajectory=Trajectory.deferred(partial(sampled_trajectory, sol, samples)),
        solution=sol,
        record=ImpactRecord.deferred(partial(sampled_record, sol, samples, scenario)),
    )


def sampled_trajectory(sol: ImpactSolution, samples: int) -> Trajectory:
    """The exact motion of ``sol`` at ``samples`` equally spaced times from 0 to t_end (s,
    m, m/s)."""
    t = np.linspace(0.0, sol.t_end, samples)
    x, vx, y, vy = sol.state(t)
    return Trajectory(t=t, x=x, vx=vx, y=y, vy=vy)


def sampled_record(sol: ImpactSolution, samples: int, scenario: Scenario | None = None):
    """The exact solution ``sol`` as an :class:`analytic.results.ImpactRecord` at
    ``samples`` equally
    spaced times (SI). Its force is the contact force while the bodies move together (eq 34,
    the solver's N = cx x + cv v); the impacts are impulses, which no sampled force holds.
    The contact's work is the impact losses so far (eq 55, the closed tails included), its
    potential 0; the energies close on the input at every sample (tests). The crown moves
    with the static shape when the scenario is given."""
    m = sol.model
    t = np.linspace(0.0, sol.t_end, samples)
    x, vx, y, vy = sol.state(t)
    cx, cv = force_coefficients(m)
    together = np.zeros(t.size, dtype=bool)
    for ph in sol.phases:
        if ph.kind is Motion.TOGETHER:
            together |= (t >= ph.t0) & (t <= ph.t1)
    force = np.where(together, np.maximum(cx * x + cv * vx, 0.0), 0.0)
    events = sorted([(i.t, i.loss) for i in sol.impacts] + [(c.t_start, c.loss)
                                                             for c in sol.tails])
    ev_t = np.array([e[0] for e in events])
    ev_loss = np.concatenate(([0.0], np.cumsum([e[1] for e in events])))
    record = ImpactRecord(
        t=t, x=x, vx=vx, y=y, vy=vy, force=force, kinetic=m.kinetic_energy(vx, vy),
        potential=m.potential_energy(x, y),
        damping_work=np.array([sol._integral("damping", ti) for ti in t]),
        contact_work=ev_loss[np.searchsorted(ev_t, t, side="right")],
        contact_potential=np.zeros_like(t), pendulum_energy=m.pendulum_energy(y, vy))
    return record if scenario is None else with_static_shape_crown(record, scenario.trunk)


def simulate_model(model: TwoBodyModel, t_end: float, **kw) -> SimulationResult:
    """Like :func:`simulate` for a bare :class:`TwoBodyModel` ``model`` (no trunk geometry)
    to ``t_end`` (s); ``kw`` (``samples``, ``backend``) as :func:`result_from_solution`."""
    return result_from_solution(solve_impacts(model, t_end), None, **kw)
