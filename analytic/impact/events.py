"""What the exact solver records of the impact process (eqs 12-35): each Newton impact
(eqs 20-21, loss eq 55), each chattering sequence closed at its accumulation point, each
stretch of closed-form motion (free, eq 13, or together, eq 34) and each separation."""

from __future__ import annotations

import enum
from dataclasses import dataclass


class Motion(enum.Enum):
    """What the bodies do from an instant on: a Newton impact there (eqs 20-21), a free
    flight (eq 13) or moving together (eq 34); a :class:`Phase` is one of the last two."""

    IMPACT = "impact"
    FREE = "free"
    TOGETHER = "together"


@dataclass(frozen=True)
class Impact:
    """One Newton impact (eqs 20-21); velocities in m/s, loss in J (eq 55)."""

    index: int
    t: float  # tau_i, s
    x: float  # contact position, m
    U: float  # tree approach velocity
    u: float  # pendulum approach velocity
    V: float  # tree separation velocity
    v: float  # pendulum separation velocity
    loss: float  # delta_i, J


@dataclass(frozen=True)
class TailClosure:
    """A chattering sequence closed at its accumulation point."""

    after_impact: int  # index of the last resolved impact
    t_start: float  # s, time of that impact
    t_accumulation: float  # s, accumulation point: the bodies move together from here
    gamma: float  # m/s, relative separation velocity left after the last resolved impact
    relative_acceleration: float  # m/s^2, a_rel < 0 (the trunk presses back)
    loss: float  # J, mu gamma^2 / 2
    method: str = "geometric tail: t_inf = t_i + 2 gamma / (|a_rel| (1 - e)), loss = mu gamma^2 / 2"


@dataclass(frozen=True)
class Phase:
    """A stretch of closed-form motion: free (eq 13) or together (eq 34)."""

    kind: Motion
    t0: float
    t1: float
    x0: float
    vx0: float
    y0: float
    vy0: float


@dataclass(frozen=True)
class Separation:
    """The bodies part after moving together (eq 34's contact force reaches zero)."""

    t: float  # s
    x: float  # m, the common displacement there
    v: float  # m/s, the common velocity there
