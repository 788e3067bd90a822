"""Backend options as data: each option of a backend's ``simulate`` (its type or allowed
words, range, unit and meaning), so the command line, the sweeps' grids and the run checks
read one table, the backend's ``OPTIONS`` (option name -> :class:`Option`).

The options every backend shares override a scenario field for one run and take its
plausibility range, unit and meaning from the registry (:mod:`.registry`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from treeimpact.analytic.errors import ParameterError

from .parameters import check_range
from .registry import BY_PATH


@dataclass(frozen=True)
class Option:
    """One option: ``kind`` is ``float``, ``int`` or the tuple of allowed words; numbers
    lie in [low, high] (``low_open``: (low, high]); ``cli``: offered as a command-line flag
    (an internal sampling option is not)."""

    kind: type | tuple
    help: str
    unit: str = ""
    low: float | None = None
    high: float | None = None
    low_open: bool = False
    cli: bool = True

    @property
    def choices(self) -> tuple | None:
        """The allowed words of a word option, None for a number."""
        return self.kind if isinstance(self.kind, tuple) else None

    def check(self, name: str, value, *, label: str | None = None):
        """``value`` if allowed, else a one-line ParameterError naming ``label`` (default
        the flag ``--name``) and the allowed values or range."""
        label = label or "--" + name.replace("_", "-")
        if self.choices is not None:
            if value not in self.choices:
                raise ParameterError(f"{label} = {value!r}: allowed {', '.join(self.choices)}")
            return value
        if self.kind is int:
            if isinstance(value, bool) or not isinstance(value, (int, float)) \
                    or not float(value).is_integer():
                raise ParameterError(f"{label} = {value!r}: allowed integers "
                                     f"{_span(self)}")
            value = int(value)
        check_range(label, value, low=self.low, high=self.high, low_open=self.low_open,
                    unit="" if self.unit in ("", "1") else self.unit)
        return value


def _span(option: Option) -> str:
    low = "-inf" if option.low is None else f"{option.low:g}"
    high = "inf" if option.high is None else f"{option.high:g}"
    return f"{'(' if option.low_open else '['}{low}, {high}]"


def scenario_option(field: str) -> Option:
    """An option that overrides the scenario field ``field`` (dotted, a registry path) for
    one run, with the registry's range, unit and meaning (its help)."""
    p = BY_PATH[field]
    return Option(float, p.meaning, p.unit, p.low, None if math.isinf(p.high) else p.high)


#: The options that override the scenario for one run (every backend takes some of them).
RESTITUTION = scenario_option("contact.restitution")
T_END = scenario_option("t_end")
CONTACT_STIFFNESS = scenario_option("contact.stiffness")
CONTACT_DURATION = scenario_option("contact.duration")
