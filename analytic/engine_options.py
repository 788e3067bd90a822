"""Validation of the options every engine backend shares (MuJoCo and PyBullet).

One-line :class:`~analytic.parameters.ParameterError` messages name the CLI flag and its
allowed values, the same in both engines.
"""

from __future__ import annotations

import math

from .model import TwoBodyModel, two_body_model
from .parameters import Contact, ParameterError, Pendulum, Scenario


def check_choice(name: str, value, allowed):
    """``value`` if it is one of ``allowed``, else a one-line error naming ``--name``."""
    if value not in allowed:
        raise ParameterError(f"--{name} = {value!r}: allowed {', '.join(allowed)}")
    return value


def engine_model(scenario: Scenario, *, pendulum: str, restitution, t_end
                 ) -> tuple[TwoBodyModel, float]:
    """The scenario's two-body model (eqs 7-13, 48) and the end time (s) of an engine run.

    ``restitution`` overrides the scenario's e (validated as ``contact.restitution``);
    ``pendulum = "full"`` needs a pendulum impactor; ``t_end`` (default the scenario's)
    must be a finite positive number.
    """
    if restitution is not None:
        Contact(restitution=restitution)
    if pendulum == "full" and not isinstance(scenario.impactor, Pendulum):
        raise ParameterError("--pendulum = 'full': the scenario's impactor is a billet")
    model = two_body_model(scenario, restitution)
    t_end = scenario.t_end if t_end is None else t_end
    if isinstance(t_end, bool) or not isinstance(t_end, (int, float)) or not (
            math.isfinite(t_end) and t_end > 0):
        raise ParameterError(f"--t-end = {t_end!r} s is out of range: allowed (0, inf) s")
    return model, float(t_end)
