"""Stepping by phase (both engines): the contact's step while the pad can touch, the trunk's
own step during free vibration, and the rule that switches between them. SI units.

Design notes and measured convergence: docs/engines.md ("Stepping by phase").

The rule, true for any tree (nothing here reads a tree's numbers):

* The contact's step dt_c (:mod:`analytic.contact.timestep`: t_c / 50, or the trunk's
  highest mode if smaller) is the step of every sample at which the pad can carry force:
  the contact law is calibrated for it (the engines' step corrections) and the contact
  metrics are read at its resolution.
* The free step h_f = 2 pi / omega_max / STEPS_PER_PERIOD is the step rule's own term for
  the trunk's highest mode (10 steps a period, a third of the stability limit omega h < 2):
  what the fixed-step run takes wherever the contact does not set the step.
* A run takes n big steps from a state only when the pad cannot reach the trunk within
  them: with the bodies' gap g (m) and a bound V (m/s) on the closing speed, n = floor(g /
  (V h_f)) - 1 steps leave a gap of at least V h_f (one more step's travel) at their end.
  V bounds the relative speed of the two contact spheres' centres, the rate of their
  distance: |J_rel v|^2 <= lambda_max(J_rel M^-1 J_rel^T) v^T M v (Cauchy-Schwarz in the
  kinetic-energy metric) with v^T M v = 2 T <= 2 (1 + ENERGY_GROWTH_LIMIT) E_in, since the
  springs' and the pendulum's potential energies are >= 0 about the rest state and the run
  is refused when its mechanical energy exceeds that bound. Each step moves the bodies by
  h v_{n+1} (the engines' semi-implicit Euler), so the travel of one step is at most V h.
  lambda is evaluated at the check's configuration and doubled (:data:`SPEED_FACTOR`), and
  every big step's sample is checked after the chunk (no force, gap > 0): a chunk that
  failed is stepped again with the contact's step, so a re-touch inside a big step is
  never missed.
* Fewer than :data:`MIN_FREE_STEPS` big steps are not taken: near the touch and after each
  release the run keeps the contact's step until the gap allows that many, which is the
  margin before the touch (the last big step ends a step's bounded travel away from it)
  and after the release (the gap must open to MIN_FREE_STEPS + 1 steps' travel).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from treeimpact.analytic.errors import ParameterError

#: The closing-speed bound's factor on lambda_max's square root evaluated at the check:
#: the trunk's deflection changes J_rel and M over the chunk; 2 holds while lambda_max
#: changes by less than a factor 4 (the chunk is checked after stepping anyway).
SPEED_FACTOR = 2.0
#: Fewest big steps worth a switch: one big step saves less than the check costs.
MIN_FREE_STEPS = 2
#: Free steps must be at least this many contact steps for the run to be phased at all
#: (below, the two steps are nearly one and the fixed step is kept).
MIN_STEP_RATIO = 1.5


@dataclass(frozen=True)
class PhaseRule:
    """A run's two steps and its closing-speed bound's energy.

    Attributes:
        contact_step: dt_c, s (the step rule's, the contact law calibrated for it).
        free_step: h_f, s (2 pi / omega_max / STEPS_PER_PERIOD).
        energy_bound: (1 + ENERGY_GROWTH_LIMIT) x the run's input energy, J.
        chunk_steps: contact steps between two checks (2 t_c / dt_c: two free collisions).
    """

    contact_step: float
    free_step: float
    energy_bound: float
    chunk_steps: int

    def speed_bound(self, lam: float) -> float:
        """V = SPEED_FACTOR sqrt(2 E lambda), m/s, for ``lam`` = lambda_max(J_rel M^-1
        J_rel^T) (1/kg) at the check's configuration (module docstring)."""
        return SPEED_FACTOR * math.sqrt(2.0 * self.energy_bound * max(lam, 0.0))

    def free_steps(self, gap: float, lam: float, time_left: float) -> int:
        """Big steps safe from ``gap`` (m, > 0 apart) with ``lam`` (1/kg) and ``time_left``
        (s) before the run's end: floor(g / (V h_f)) - 1, at most the time left, 0 below
        :data:`MIN_FREE_STEPS` (then the contact's step)."""
        if not gap > 0.0:
            return 0
        v = self.speed_bound(lam)
        n = int(gap / (v * self.free_step)) - 1 if v > 0.0 else 10 ** 9
        n = min(n, int(time_left / self.free_step))
        return n if n >= MIN_FREE_STEPS else 0

    def contact_chunk(self, time_left: float) -> int:
        """Contact steps to take before the next check, with ``time_left`` (s) before the
        run's end: :attr:`chunk_steps`, fewer at the end, at least one."""
        return max(1, min(self.chunk_steps, int(round(time_left / self.contact_step))))


def input_energy(model, scenario, pendulum: str) -> float:
    """A run's input energy, J: the full pendulum's drop m g l_e (1 - cos theta_r), the
    linear one's 1/2 m u1^2 (eq 48); ``model`` a TwoBodyModel of ``scenario``."""
    imp = scenario.impactor
    if pendulum == "full":
        return model.impactor_mass * imp.gravity * imp.equivalent_length * (
            1.0 - math.cos(imp.release_angle_rad))
    return 0.5 * model.impactor_mass * model.impact_speed ** 2


def phase_rule(contact_step: float, omega_max: float | None, input_energy: float,
               collision_duration: float, steps_per_period: int, growth_limit: float
               ) -> PhaseRule | None:
    """The :class:`PhaseRule` of a run stepped at ``contact_step`` (s) with the trunk's
    highest mode ``omega_max`` (rad/s; None: an SDOF trunk, whose own step would sample
    x_max too coarsely, so not phased), the run's ``input_energy`` (J), the free
    collision's ``collision_duration`` t_c (s), the rule's ``steps_per_period`` and the
    engines' ``growth_limit``; None when the free step is not :data:`MIN_STEP_RATIO` times
    the contact's (the fixed step is kept)."""
    if omega_max is None:
        return None
    if not (input_energy > 0.0 and contact_step > 0.0):
        raise ParameterError(f"phase rule: input energy {input_energy!r} J and step "
                             f"{contact_step!r} s must be > 0")
    h_f = 2.0 * math.pi / omega_max / steps_per_period
    if h_f < MIN_STEP_RATIO * contact_step:
        return None
    chunk = max(1, round(2.0 * collision_duration / contact_step))
    return PhaseRule(float(contact_step), float(h_f),
                     (1.0 + growth_limit) * float(input_energy), chunk)
