"""The per-tree bounds of the pendulum's step and of the two engines (compare.runs.bounds.pendulum)
against independent checks: the linearisation term scales as the angle squared, the touch's
phase as the step, a grazing contact is counted as grazing, and the first-order part the
bound estimates from one halving of the step predicts a second halving (the difference is
first order in dt)."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np

from treeimpact.compare.runs.bounds import pendulum as P


def _result(t, y, force, vx=None, dt=1e-6, **metrics):
    tr = SimpleNamespace(t=np.asarray(t), y=np.asarray(y), force=np.asarray(force),
                         vx=np.zeros(len(t)) if vx is None else np.asarray(vx))
    return SimpleNamespace(trajectory=tr, model={"dt": dt}, metrics=metrics)


def test_the_linearisation_term_scales_with_the_angle_squared():
    t = np.linspace(0.0, 0.01, 1001)
    y = 0.002 * np.sin(200.0 * t)  # m: the contact point's travel
    force = np.where(t < 0.008, 1.0, 0.0)  # contact up to 8 ms, free after
    le = 1.5
    theta = P.contact_angle(_result(t, y, force), le)
    assert math.isclose(theta, np.abs(y[t < 0.008]).max() / le, rel_tol=1e-12)
    twice = P.contact_angle(_result(t, 2.0 * y, force), le)
    assert math.isclose((twice / theta) ** 2, 4.0, rel_tol=1e-12)  # theta^2 / 2: x4
    assert P.contact_angle(_result(t, y, np.zeros_like(t)), le) == 0.0  # no contact


def test_the_touch_phase_is_one_step_of_each_quantity_s_rate():
    t = np.linspace(0.0, 1e-3, 1001)
    vx = 2.0 - 1e3 * t  # m/s: the trunk decelerating at 1000 m/s^2
    r = _result(t, np.zeros_like(t), np.ones_like(t), vx=vx, dt=2e-6, T0=4e-4, x0=1e-3,
                V=1.6, t_sep=8e-4)
    assert math.isclose(P.touch_phase(r, "T0"), 2e-6 / 4e-4)
    assert math.isclose(P.touch_phase(r, "t_sep"), 2e-6 / 8e-4)
    assert math.isclose(P.touch_phase(r, "x0"), 1.6 * 2e-6 / 1e-3, rel_tol=1e-9)
    assert math.isclose(P.touch_phase(r, "V"), 1e3 * 2e-6 / 1.6, rel_tol=1e-6)
    halved = _result(t, r.trajectory.y, r.trajectory.force, vx=vx, dt=1e-6, **r.metrics)
    assert math.isclose(P.touch_phase(halved, "x0"), 0.5 * P.touch_phase(r, "x0"))


def test_contacts_that_together_carry_under_the_share_of_the_impulse_are_grazing():
    t = np.arange(0.0, 0.01, 1e-5)
    force = np.zeros_like(t)
    force[100:200] = 1000.0  # carries 1 N s
    force[300] = 400.0  # 2e-3 N s: 0.18 %, grazing
    force[400] = 400.0  # another 0.18 %: both together 0.36 %
    force[500:550] = 200.0  # 0.1 N s: 9 %
    assert P.episodes(_result(t, np.zeros_like(t), force)) == (4, 2)
    force[450] = 400.0  # a third: together 0.54 %, so one of them carries
    assert P.episodes(_result(t, np.zeros_like(t), force)) == (5, 2)
    force[450] = 0.0
    lin = SimpleNamespace(result=_result(t, np.zeros_like(t), force), values={
        "contact_episodes": 4.0})
    force2 = force.copy()
    force2[300] = 0.0  # a grazing touch missing
    full = SimpleNamespace(result=_result(t, np.zeros_like(t), force2), values={
        "contact_episodes": 3.0})
    b = P.contact_sequence(P.Pair(None, None, "contact_episodes", full, lin))
    assert math.isclose(b.rel, 2 / 4) and "counts within 2 of 4" in b.words
    assert abs(3.0 - 4.0) / 4.0 <= b.rel  # one grazing touch less: the same sequence
    force3 = force2.copy()
    force3[500:550] = 0.0  # and the carrying contacts missing
    force3[100:200] = 0.0
    none = SimpleNamespace(result=_result(t, np.zeros_like(t), force3), values={
        "contact_episodes": 1.0})
    b3 = P.contact_sequence(P.Pair(None, None, "contact_episodes", none, lin))
    assert abs(1.0 - 4.0) / 4.0 > b3.rel  # three contacts fewer: the check fails


def test_the_pendulum_step_s_difference_is_first_order_in_dt():
    """Bullet's compound against its linear pendulum on the light pendulum that bounces off
    (the family's bounce-off): the difference at dt, dt / 2 and dt / 4 (fixed steps). The
    first-order part that the bound reads from the first halving, 2 |D(dt) - D(dt / 2)|,
    predicts D(dt / 4) = D* + (D(dt / 2) - D*) / 2 to within a tenth of that part."""
    from treeimpact.analytic.continuum.chain import default_segments
    from treeimpact.compare.runs.backends import get_backend
    from treeimpact.compare.tree import family

    bounce_off = family.build(family.BY_NAME["bounce-off"])
    bullet = get_backend("bullet")
    # the stiffness-and-frequency rule's N (10), whose step leaves a difference to measure
    # (the ladder's N for this tree, 40, sets a step at which it is 1e-6)
    n = default_segments(bounce_off.trunk)
    dt = bullet.simulate(bounce_off, trunk="chain", pendulum="linear", segments=n).model["dt"]

    def diff(step):
        full, lin = (bullet.simulate(bounce_off, trunk="chain", pendulum=p, segments=n,
                                     dt=step).metrics["energy_delivered"]
                     for p in ("full", "linear"))
        return (full - lin) / abs(lin)

    d1, d2, d4 = diff(dt), diff(dt / 2), diff(dt / 4)
    part = 2.0 * abs(d1 - d2)
    limit = 2.0 * d2 - d1  # Richardson's D*
    assert part > 1e-3  # the family member's difference is the step's, not noise
    assert abs(d4 - (limit + 0.5 * (d2 - limit))) < 0.1 * part
    assert abs(limit) < 0.1 * part  # what stays at any step is under a tenth of it
