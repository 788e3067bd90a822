"""The record fit's parameters by name: what each is (:class:`Slot`), its bounds, the
optimiser's scale for it and whether it is held fixed (:class:`FitVariable`, ``frozen``), and
the set of them for one record (:class:`FitVariables`). The optimiser works on the vector p
of their values in :class:`Slot` order; nothing outside this module counts positions in it.
docs/identification.md, "The full-record fit"."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from enum import IntEnum

import numpy as np


class Slot(IntEnum):
    """The record fit's parameters, each at its place in the parameter vector p (SI)."""

    LN_DYNAMIC_MASS = 0  # ln M_T, M_T in kg (eq 11)
    LN_EQUIVALENT_STIFFNESS = 1  # ln K_T, K_T in N/m (eq 11)
    TRUNK_DAMPING_RATIO = 2  # C_T / (2 sqrt(K_T M_T)), the trunk's own (eq 14)
    RESTITUTION = 3  # e (eq 21)
    T0 = 4  # s, the time of the first contact
    X_OFFSET = 5  # m, the trunk sensor's offset
    Y_OFFSET = 6  # m, the pendulum sensor's offset (a record with y)
    X_DRIFT = 7  # m/s, the trunk sensor's drift, x_drift s (s = t - t0)
    X_DRIFT2 = 8  # m/s^2, its bend, x_drift2 s^2

    @property
    def label(self) -> str:
        """The parameter's name as the fit's messages say it (``restitution``, ``t0``)."""
        return self.name.lower()


#: The tree's parameters: the model is differentiated numerically in these.
MODEL_SLOTS = (Slot.LN_DYNAMIC_MASS, Slot.LN_EQUIVALENT_STIFFNESS, Slot.TRUNK_DAMPING_RATIO,
               Slot.RESTITUTION)
#: The sensors' offsets and the channel (0: x, 1: y) each moves.
OFFSET_CHANNEL = {Slot.X_OFFSET: 0, Slot.Y_OFFSET: 1}
#: The drift terms and the power of s = t - t0 each multiplies.
DRIFT_POWER = {Slot.X_DRIFT: 1, Slot.X_DRIFT2: 2}
DRIFTS = tuple(DRIFT_POWER)

#: Allowed ranges of the fit (SI): a value at a bound is no tree's.
M_RANGE, K_RANGE, XI_RANGE, E_MAX = (1e-2, 1e5), (1.0, 1e10), (1e-3, 5.0), 0.95


@dataclass(frozen=True)
class FitVariable:
    """One parameter of the fit: its value, bounds, the optimiser's typical step
    (``scale``, least_squares' x_scale) and whether it is held at its value (``frozen``)."""

    slot: Slot
    value: float
    low: float = -math.inf
    high: float = math.inf
    scale: float = 1.0
    frozen: bool = False

    @property
    def name(self) -> str:
        """The parameter's name (its slot's label)."""
        return self.slot.label


@dataclass(frozen=True)
class FitVariables:
    """Every :class:`Slot`'s :class:`FitVariable`, in slot order."""

    parameters: tuple

    def __post_init__(self):
        if tuple(p.slot for p in self.parameters) != tuple(Slot):
            raise ValueError("FitVariables: one FitVariable per Slot, in Slot order")

    def __getitem__(self, slot: Slot) -> FitVariable:
        return self.parameters[slot]

    @property
    def free(self) -> tuple:
        """The slots the optimiser moves (not frozen), in slot order."""
        return tuple(p.slot for p in self.parameters if not p.frozen)

    def vector(self) -> np.ndarray:
        """Every parameter's value (p)."""
        return np.array([p.value for p in self.parameters], float)

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """(low, high) of the free parameters."""
        free = [self.parameters[s] for s in self.free]
        return np.array([p.low for p in free]), np.array([p.high for p in free])

    def scales(self) -> np.ndarray:
        """The optimiser's typical steps of the free parameters (least_squares' x_scale)."""
        return np.array([self.parameters[s].scale for s in self.free])

    def freeze(self, *slots: Slot) -> FitVariables:
        """The set with the parameters of ``slots`` held at their values."""
        return self._with(slots, frozen=True)

    def thaw(self, *slots: Slot) -> FitVariables:
        """The set with the parameters of ``slots`` free."""
        return self._with(slots, frozen=False)

    def at(self, p) -> FitVariables:
        """The set with the values of the vector p (shorter: zeros after its end)."""
        values = padded(p)
        return FitVariables(tuple(replace(q, value=float(values[q.slot]))
                                  for q in self.parameters))

    def _with(self, slots, **changes) -> FitVariables:
        return FitVariables(tuple(replace(p, **changes) if p.slot in slots else p
                                  for p in self.parameters))


def padded(p) -> np.ndarray:
    """p (a vector of values in slot order, possibly shorter) with zeros to every slot."""
    out = np.zeros(len(Slot))
    out[: len(p)] = np.asarray(p, float)
    return out


#: The sensor terms a record that cannot tell them from the motion holds at zero.
SENSOR_TERMS = (Slot.X_OFFSET, *DRIFTS)


def record_parameters(t: np.ndarray, dt: float, scale: list, *, restitution_given: bool,
                      pendulum: bool, separable: bool = True) -> FitVariables:
    """The fit's parameters for a record at times t (s; median interval ``dt``) whose
    channels' peaks are ``scale`` (m: x, then y): the bounds (M_RANGE, K_RANGE, XI_RANGE,
    E_MAX; the contact within the record, up to 10 samples before it), the optimiser's
    scales and what is held: e when given (``restitution_given``), the pendulum's offset
    without a y (``pendulum`` False), the trunk
    sensor's offset and drift (at zero) unless ``separable`` (the record can tell them from
    the motion), the drift's bend until the record calls for it (fit_record). Values 0 (set
    from a start)."""
    span = float(t[-1] - t[0])
    x, y = scale[0], scale[-1]
    rows = (
        (Slot.LN_DYNAMIC_MASS, math.log(M_RANGE[0]), math.log(M_RANGE[1]), 1.0, False),
        (Slot.LN_EQUIVALENT_STIFFNESS, math.log(K_RANGE[0]), math.log(K_RANGE[1]), 1.0, False),
        (Slot.TRUNK_DAMPING_RATIO, XI_RANGE[0], XI_RANGE[1], 0.1, False),
        (Slot.RESTITUTION, 0.0, E_MAX, 0.1, restitution_given),
        (Slot.T0, t[0] - 10 * dt, t[-1] - 10 * dt, dt, False),
        (Slot.X_OFFSET, -math.inf, math.inf, 1e-2 * x, not separable),
        (Slot.Y_OFFSET, -math.inf, math.inf, 1e-2 * y, not pendulum),
        (Slot.X_DRIFT, -math.inf, math.inf, 1e-2 * x / span, not separable),
        (Slot.X_DRIFT2, -math.inf, math.inf, 1e-2 * x / span ** 2, True),
    )
    return FitVariables(tuple(FitVariable(slot, 0.0, float(lo), float(hi), float(sc), frozen)
                              for slot, lo, hi, sc, frozen in rows))
