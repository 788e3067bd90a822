"""Inputs inside their allowed range but outside what fruit trees, harvesters and pads show:
the run goes on, and each such input gets one line saying so, with the range and its source
and, where a common slip of unit brings the value into that range, the slip (radians for
degrees, centimetres for metres). The ranges are the registry's (:mod:`.registry`,
``Parameter.plausible``); docs/parameters.md lists them.
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from dataclasses import dataclass

from treeimpact.analytic.errors import ImplausibleInput

from .registry import BY_PATH, Plausible

#: unit -> (factor, what the value would be in): a value typed in the second unit reads as
#: ``value * factor`` in the first (a diameter of 12 typed in cm is 0.12 m).
_SLIPS = {
    "m": ((0.01, "centimetres"), (0.001, "millimetres")),
    "deg": ((180.0 / math.pi, "radians"),),
    "kg": ((0.001, "grams"),),
    "Pa": ((1e9, "GPa"), (1e6, "MPa")),
    "s": ((0.001, "milliseconds"),),
    "kg/m^3": ((1000.0, "g/cm^3"),),
}


#: What a warning adds to :attr:`Implausible.text`: the run goes on with the value typed.
RUN_AS_GIVEN = "; run as given"


@dataclass(frozen=True)
class Implausible:
    """One input outside its plausible range.

    Attributes:
        path: the field as a scenario file spells it (``impactor.release_angle_deg``).
        value: its value, in ``unit``.
        unit: the registry's unit.
        plausible: the range and its source.
        slip: "" or the unit slip that would bring the value into the range.
    """

    path: str
    value: float
    unit: str
    plausible: Plausible
    slip: str

    @property
    def text(self) -> str:
        """One line: the field, its value, the range with its source, the slip if any."""
        p, u = self.plausible, f" {self.unit}" if self.unit != "1" else ""
        slip = f"; {self.slip}" if self.slip else ""
        return (f"{self.path} = {self.value:g}{u} is outside what fruit trees and harvesters "
                f"show, {p.low:g}-{p.high:g}{u} ({p.source}){slip}")


def _slip(value: float, unit: str, plausible: Plausible) -> str:
    """The unit slip that brings ``value`` into ``plausible``, as words, or ""."""
    for factor, typed_in in _SLIPS.get(unit, ()):
        meant = value * factor
        if plausible.low <= meant <= plausible.high:
            return f"typed in {typed_in}? {value:g} {typed_in} is {meant:.4g} {unit}"
    return ""


def implausible_values(values: dict) -> tuple[Implausible, ...]:
    """The entries of ``values`` ({dotted path: number}) outside their registry parameter's
    plausible range, in the order given; paths without a plausible range, and None, pass."""
    out = []
    for path, value in values.items():
        param = BY_PATH.get(path)
        if param is None or param.plausible is None or value is None:
            continue
        v = float(value)
        if math.isfinite(v) and not param.plausible.low <= v <= param.plausible.high:
            out.append(Implausible(path, v, param.unit, param.plausible,
                                   _slip(v, param.unit, param.plausible)))
    return tuple(out)


def scenario_values(scenario) -> dict:
    """{dotted path: value} of every registry field ``scenario``'s parts declare (a billet
    has no release angle and a pendulum's impact speed is derived, not a field; a contact
    given by its stiffness has duration None)."""
    values = {}
    for path in BY_PATH:
        part, _, name = path.rpartition(".")
        holder = getattr(scenario, part) if part else scenario
        if name in {f.name for f in dataclasses.fields(holder)}:
            values[path] = getattr(holder, name)
    return values


def implausible(scenario) -> tuple[Implausible, ...]:
    """The inputs of ``scenario`` outside what fruit trees and harvesters show."""
    return implausible_values(scenario_values(scenario))


def warn_implausible(found) -> None:
    """One :class:`ImplausibleInput` warning per entry of ``found`` (a tuple of
    :class:`Implausible`): where an input enters (a scenario file read, a tree built from
    its measurements, a pendulum test typed)."""
    for item in found:
        warnings.warn(item.text + RUN_AS_GIVEN, ImplausibleInput, stacklevel=3)
