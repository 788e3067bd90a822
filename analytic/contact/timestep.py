"""The time-step rule of the engine runners (MuJoCo and PyBullet share it).

Design notes and measured figures: docs/time-step.md.
"""

from __future__ import annotations

import math

from treeimpact.analytic.errors import ParameterError


def _positive(name: str, value) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not (
            math.isfinite(value) and value > 0):
        raise ParameterError(f"{name} = {value!r} is out of range: allowed (0, inf)")
    return float(value)


def stability_limit(collision_duration: float, highest_frequency: float | None = None) -> float:
    """Largest stable step (s): 2 / omega for the contact (omega = pi /
    ``collision_duration``, s) and the ``highest_frequency`` of the trunk (rad/s, None: no
    trunk mode)."""
    t_c = _positive("collision_duration", collision_duration)
    limit = 2.0 * t_c / math.pi
    if highest_frequency is not None:
        limit = min(limit, 2.0 / _positive("highest_frequency", highest_frequency))
    return limit


def choose_time_step(collision_duration: float, highest_frequency: float | None = None, *,
                     steps_per_collision: int = 50, steps_per_period: int = 20) -> float:
    """The documented default step (s), see the module docstring: ``collision_duration``
    (s) / ``steps_per_collision``, and at most 2 pi / ``highest_frequency`` (rad/s, None:
    no trunk mode) / ``steps_per_period``."""
    t_c = _positive("collision_duration", collision_duration)
    dt = t_c / steps_per_collision
    if highest_frequency is not None:
        w = _positive("highest_frequency", highest_frequency)
        dt = min(dt, 2.0 * math.pi / w / steps_per_period)
    return dt


def check_time_step(dt, collision_duration: float, highest_frequency: float | None = None
                    ) -> float:
    """Return ``dt`` (s) if it can be stable for the ``collision_duration`` (s) and the
    ``highest_frequency`` (rad/s, None: no trunk mode), else raise a one-line
    ParameterError (:func:`stability_limit`)."""
    dt = _positive("dt", dt)
    limit = stability_limit(collision_duration, highest_frequency)
    if dt >= limit:
        what = f"contact duration {collision_duration:.3g} s"
        if highest_frequency is not None:
            what += f", highest trunk mode {highest_frequency:.4g} rad/s"
        raise ParameterError(f"--dt = {dt:.3g} s is too large for stability: allowed "
                             f"(0, {limit:.3g}) s ({what})")
    return dt


def sdof_rate(model) -> float:
    """Fastest rate (1/s) of the engines' SDOF trunk and linear pendulum of ``model`` (a
    :class:`analytic.model.two_body.TwoBodyModel`): the natural
    frequencies sqrt(K_T / M_T) and sqrt(k / m) and the damping rate C_T / M_T (the engines
    step the trunk's damper explicitly, stable for dt < 2 M_T / C_T, as for a frequency)."""
    return max(math.sqrt(model.equivalent_stiffness / model.dynamic_mass),
               model.equivalent_damping / model.dynamic_mass,
               math.sqrt(model.impactor_stiffness / model.impactor_mass))
