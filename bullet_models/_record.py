"""A PyBullet run's record (t = 0 at the first contact), its energy ledger following
Bullet's semi-implicit step, and the SimulationResult. SI units; the ledger's rules:
docs/engines.md (``bullet_models/_runner.py``)."""

from __future__ import annotations

import numpy as np

from treeimpact.analytic.contact.law import pad_fields
from treeimpact.analytic.engine.interface import check_energy, engine_result, with_crown
from treeimpact.analytic.errors import SimulationDiverged
from treeimpact.analytic.results import ImpactRecord, SimulationResult

from ._world import JOINT_VELOCITY_LIMIT, RESTITUTION_THRESHOLD_FRACTION


def _pendulum(setup, rec: dict, inertia) -> tuple:
    """(y m, vy m/s, kinetic J, potential J) of the pendulum's contact point from its joint
    record: the full pendulum's angle (``inertia`` about the pivot, kg m^2) or the linear
    pendulum's slide on its spring m g / l_e (eq 13)."""
    model = setup.model
    m = model.impactor_mass
    if setup.pendulum == "full":
        imp = setup.scenario.impactor
        le, g = imp.equivalent_length, imp.gravity
        th, om = rec["q"], rec["qd"]
        y, vy = le * np.sin(th), le * np.cos(th) * om
        return y, vy, 0.5 * inertia * om * om, m * g * le * (1.0 - np.cos(th))
    y, vy = rec["q"], rec["qd"]
    return y, vy, 0.5 * m * vy * vy, 0.5 * model.impactor_stiffness * y * y


def _record(setup, rec: dict, t_shift: float, e0: float, inertia) -> ImpactRecord:
    """The :class:`ImpactRecord` of the loop's record ``rec``, t shifted by ``t_shift`` (s)
    to the first contact; the works follow Bullet's step (the work of an impulse over a step
    is P (v_n + v_{n+1}) / 2). Raises SimulationDiverged at Bullet's joint-speed clamp or
    when the mechanical energy exceeds the input ``e0`` (J)."""
    model = setup.model
    dt = setup.dt
    n = rec["x"].size
    h = rec.get("h")  # each step's size (s) of a run stepped by phase; None: every one dt
    t = (np.arange(n) * dt if h is None else np.concatenate([[0.0], np.cumsum(h)])) - t_shift
    x, vx = rec["x"], rec["vx"]
    y, vy, pend_kin, pend_pot = _pendulum(setup, rec, inertia)
    if setup.trunk == "chain":
        trunk_kin, trunk_pot = rec["trunk_kinetic"], rec["trunk_potential"]
        d_power = rec["damping_power"]
    else:
        trunk_kin = 0.5 * model.dynamic_mass * vx * vx
        trunk_pot = 0.5 * model.equivalent_stiffness * x * x
        d_power = model.equivalent_damping * vx[:-1] * 0.5 * (vx[:-1] + vx[1:])
    force = rec["force"]
    rel = vy - vx
    c_power = force[:-1] * 0.5 * (rel[:-1] + rel[1:])
    if h is None:
        damping_work = np.concatenate([[0.0], np.cumsum(d_power) * dt])
        contact_work = np.concatenate([[0.0], np.cumsum(c_power) * dt])
    else:
        damping_work = np.concatenate([[0.0], np.cumsum(d_power * h)])
        contact_work = np.concatenate([[0.0], np.cumsum(c_power * h)])
    if setup.contact == "soft":
        overlap = np.where(force > 0.0, np.maximum(y - x, 0.0), 0.0)
        c_pot = 0.5 * setup.bullet.stiffness * overlap ** 2  # Bullet's spring k_b
    else:
        c_pot = np.zeros(n)
    if not rec["joint_speed"] < 0.5 * JOINT_VELOCITY_LIMIT:  # NaN included
        raise SimulationDiverged(
            f"bullet: a joint speed reached {rec['joint_speed']:.4g} (rad/s or m/s), near "
            f"Bullet's clamp {JOINT_VELOCITY_LIMIT:g} (dt = {dt:.3g} s)")
    kinetic = trunk_kin + pend_kin
    potential = trunk_pot + pend_pot
    check_energy("bullet", kinetic + potential, e0, dt)
    # the force of step n acts from sample n to n + 1; the last sample repeats it
    force_rec = force.copy()
    force_rec[-1] = force[-2]
    record = ImpactRecord(t=t, x=x, vx=vx, y=y, vy=vy, force=force_rec, kinetic=kinetic,
                          potential=potential, damping_work=damping_work,
                          contact_work=contact_work, contact_potential=c_pot,
                          pendulum_energy=pend_kin + pend_pot)
    if setup.trunk == "chain":  # the chain's top
        record = with_crown(record, rec["crown"], rec["crown_velocity"])
    return record


def _result(setup, rec: dict, t_shift: float, e0: float, inertia,
            stepping: dict | None = None) -> SimulationResult:
    """The run's SimulationResult: :func:`_record`'s record, its metrics and the model as
    Bullet ran it (its contact's stiffness, damping, ERP and CFM); ``stepping``: what the
    stepping cost (:func:`._runner.stepping_record`), kept in ``extra``."""
    model = setup.model
    record = _record(setup, rec, t_shift, e0, inertia)
    b = setup.bullet
    return engine_result(
        "bullet", record, scenario=setup.scenario, model=model, t_end=setup.t_end,
        collision_duration=setup.collision_duration,
        detection_duration=setup.collision_duration, initial_energy=e0, model_fields={
            "segments": setup.segments, "dt": setup.dt,
            "contact_stiffness": setup.contact_stiffness,
            "contact_damping": setup.contact_damping,
            "engine_contact_stiffness": b.stiffness if b else None,
            "engine_contact_damping": b.damping if b else None,
            "trunk": setup.trunk, "pendulum": setup.pendulum,
            "trunk_damping_model": setup.damping,
            "calibration": setup.calibration,
            **pad_fields(setup.contact_stiffness, setup.contact_damping,
                         b.reduced_mass if b else None),
            "touch_duration": setup.collision_duration,
            "integrator": "semi-implicit Euler",  # Bullet's only one (docs/engines.md)
            "omega_max": setup.omega_max,
            "contact": setup.contact, "apparent_mass": setup.apparent_mass,
            "contact_erp": b.erp if b else 0.0, "contact_cfm": b.cfm if b else 0.0,
            "restitution_velocity_threshold": (
                RESTITUTION_THRESHOLD_FRACTION * model.impact_speed
                if setup.contact == "newton" else 0.0)},
        extra={"stepping": stepping} if stepping else None)
