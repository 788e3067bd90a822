"""Result types shared by every backend (analytic, soft contact, MuJoCo, PyBullet).

All backends return a :class:`SimulationResult` whose ``metrics`` dict has exactly the keys
of :data:`METRIC_KEYS` (SI units, see :data:`METRIC_UNITS`), so ``compare`` never branches
on the backend.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

#: Metric keys, their units and meaning (paper's symbols).
METRIC_UNITS = {
    "n_impacts": ("1", "impacts resolved before the bodies move together (eqs 20-21)"),
    "T0": ("s", "duration of the impact process: first impact to moving together (Table 1)"),
    "x0": ("m", "trunk displacement when the bodies begin to move together (Table 1)"),
    "V": ("m/s", "common velocity when the bodies begin to move together (eq 34)"),
    "x_max": ("m", "largest displacement of the impact point (eq 37-38)"),
    "t_xmax": ("s", "time of x_max after the first impact"),
    "t_sep": ("s", "time at which the bodies separate after moving together"),
    "A_x": ("m s", "area under x(t) over the impact process (eq 44)"),
    "A_y": ("m s", "area under y(t) over the impact process (eq 44)"),
    "impact_loss": ("J", "mechanical energy lost in the impacts, eq 56"),
    "impact_loss_inelastic": ("J", "e = 0 approximation of the impact loss, eq 57"),
    "energy_transferred": ("J", "energy transferred to the tree, eq 58 with the loss of eq 56"),
    "theta_b": ("rad", "rebound angle of the pendulum (eq 58); NaN for a billet"),
    "ledger_residual": ("1", "largest |energy ledger error| / initial energy over all events"),
}
METRIC_KEYS = tuple(METRIC_UNITS)


class SimulationDiverged(RuntimeError):
    """A simulation went non-finite or gained energy: it has no numbers to report."""


@dataclass(frozen=True)
class Trajectory:
    """Sampled motion; t = 0 at the first contact. x: trunk impact point, y: pendulum."""

    t: np.ndarray  # s
    x: np.ndarray  # m
    vx: np.ndarray  # m/s
    y: np.ndarray  # m
    vy: np.ndarray  # m/s
    force: np.ndarray | None = None  # N, contact force on the trunk (>= 0)


@dataclass(frozen=True)
class SimulationResult:
    """What every backend returns."""

    backend: str
    metrics: dict
    model: dict
    scenario: dict
    trajectory: Trajectory | None = None
    extra: dict = field(default_factory=dict)

    def to_json(self) -> dict:
        return {"backend": self.backend, "model": _clean(self.model),
                "metrics": _clean(self.metrics), "scenario": _clean(self.scenario)}


def _clean(obj):
    """JSON-safe copy: NaN and inf become None (JSON has neither)."""
    if isinstance(obj, dict):
        return {k: _clean(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_clean(v) for v in obj]
    if isinstance(obj, (np.floating, float)):
        f = float(obj)
        return f if math.isfinite(f) else None
    if isinstance(obj, np.integer):
        return int(obj)
    return obj
