"""The two-body impact model of Fig 3: SDOF trunk (eq 11) struck by a linearised pendulum.

Tree: M_T x'' + C_T x' + K_T x = F (eq 11); pendulum (or billet): m y'' + k y = -F with
k = m g / l_e (eq 13; a billet: its own spring, k = 0 when free). Both start at rest
position 0, the pendulum moving at u_1 (eq 48) and touching the trunk at t = 0. Contact
means x = y; the pendulum may not pass the trunk (gap x - y >= 0).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

from .parameters import LIMITS, Billet, Pendulum, Scenario, check_range
from .reduction import reduce_trunk


@dataclass(frozen=True)
class TwoBodyModel:
    """Parameters of eqs 13-35, SI units."""

    dynamic_mass: float  # M_T, kg
    equivalent_damping: float  # C_T, N s/m
    equivalent_stiffness: float  # K_T, N/m
    impactor_mass: float  # m, kg
    impactor_stiffness: float  # k = m g / l_e, N/m (a billet: its own, 0 when free)
    impact_speed: float  # u_1, m/s
    restitution: float  # e

    def __post_init__(self):
        check_range("model.dynamic_mass", self.dynamic_mass, low=0, low_open=True, unit="kg")
        check_range("model.equivalent_damping", self.equivalent_damping, low=0, unit="N s/m")
        check_range("model.equivalent_stiffness", self.equivalent_stiffness, low=0,
                    low_open=True, unit="N/m")
        check_range("model.impactor_mass", self.impactor_mass, low=0, low_open=True, unit="kg")
        check_range("model.impactor_stiffness", self.impactor_stiffness, low=0, unit="N/m")
        check_range("model.impact_speed", self.impact_speed, low=0, low_open=True, unit="m/s")
        low, high, _ = LIMITS["contact.restitution"]  # the registry's range of e
        check_range("model.restitution", self.restitution, low=low, high=high)

    @property
    def reduced_mass(self) -> float:
        """mu = M_T m / (M_T + m), kg (eq 55)."""
        return self.dynamic_mass * self.impactor_mass / (self.dynamic_mass + self.impactor_mass)

    @property
    def initial_energy(self) -> float:
        """1/2 m u_1^2 = m g l_e (1 - cos theta_r) for the pendulum, J."""
        return 0.5 * self.impactor_mass * self.impact_speed ** 2

    @property
    def together_frequency(self) -> float:
        """omega_n = sqrt((K_T + k) / (M_T + m)), rad/s (eq 34, eq 46)."""
        return math.sqrt((self.equivalent_stiffness + self.impactor_stiffness)
                         / (self.dynamic_mass + self.impactor_mass))

    @property
    def together_decay(self) -> float:
        """b = C_T / (2 (M_T + m)), 1/s (eq 35-36)."""
        return self.equivalent_damping / (2.0 * (self.dynamic_mass + self.impactor_mass))

    def kinetic_energy(self, vx, vy):
        """1/2 M_T x'^2 + 1/2 m y'^2, J, at the velocities ``vx`` = x' and ``vy`` = y' (m/s;
        floats or arrays)."""
        return 0.5 * self.dynamic_mass * vx ** 2 + 0.5 * self.impactor_mass * vy ** 2

    def potential_energy(self, x, y):
        """1/2 K_T x^2 + 1/2 k y^2, J: the trunk's and the pendulum's springs (eqs 11, 13)."""
        return 0.5 * self.equivalent_stiffness * x ** 2 + 0.5 * self.impactor_stiffness * y ** 2

    def pendulum_energy(self, y, vy):
        """The pendulum's own energy 1/2 m y'^2 + 1/2 k y^2, J (linearised, eq 13), at y (m)
        and ``vy`` = y' (m/s)."""
        return 0.5 * self.impactor_mass * vy ** 2 + 0.5 * self.impactor_stiffness * y ** 2

    def with_restitution(self, e: float) -> "TwoBodyModel":
        """This model with the restitution ``e`` (1, eq 21)."""

        return replace(self, restitution=e)

    def as_dict(self) -> dict:
        """M_T (kg), C_T (N s/m), K_T (N/m), m (kg), k (N/m), restitution (1) and u1 (m/s):
        the ``model`` keys every backend reports."""
        return {"M_T": self.dynamic_mass, "C_T": self.equivalent_damping,
                "K_T": self.equivalent_stiffness,
                "m": self.impactor_mass, "k": self.impactor_stiffness,
                "restitution": self.restitution, "u1": self.impact_speed}


def two_body_model(scenario: Scenario) -> TwoBodyModel:
    """Reduce a scenario to the model of Fig 3 (eqs 7-11, 13, 48), with its e."""
    tree = reduce_trunk(scenario.trunk)
    imp = scenario.impactor
    e = scenario.contact.restitution
    if isinstance(imp, Pendulum):
        k = imp.stiffness
    elif isinstance(imp, Billet):
        k = imp.stiffness
    else:  # pragma: no cover - Scenario validates the type
        raise TypeError(imp)
    return TwoBodyModel(dynamic_mass=tree.dynamic_mass, equivalent_damping=tree.equivalent_damping,
                        equivalent_stiffness=tree.equivalent_stiffness, impactor_mass=imp.mass,
                        impactor_stiffness=k, impact_speed=imp.impact_speed, restitution=e)
