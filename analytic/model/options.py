"""Backend options as data: each option of a backend's ``simulate`` (its type or allowed
words, range, unit and meaning), so the command line, the sweeps' grids and the run checks
read one table, the backend's ``OPTIONS`` (option name -> :class:`Option`).

The options every backend shares override a scenario field for one run and take its
plausibility range, unit and meaning from the registry (:mod:`.registry`).
"""

from __future__ import annotations

import dataclasses
import math
import re
from dataclasses import dataclass

from treeimpact.analytic.errors import ParameterError

from .parameters import Scenario, check_range
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

#: The run options that override a scenario field for one run, option -> the field's dotted
#: path (:func:`scenario_as_run` applies them; every backend takes some of them).
OVERRIDES = {"restitution": "contact.restitution", "contact_stiffness": "contact.stiffness",
             "contact_duration": "contact.duration", "t_end": "t_end"}


def scenario_as_run(scenario: Scenario, options: dict) -> Scenario:
    """``scenario`` with the run options of :data:`OVERRIDES` in ``options`` applied (None:
    not given): ``restitution`` (1), ``contact_stiffness`` (N/m; the duration then unset),
    ``contact_duration`` (s; the stiffness then unset) and ``t_end`` (s). The one way a run
    option reaches the physics: each value is range-checked here, once, by the scenario's
    own dataclasses (a refusal names the field: :func:`as_typed` names it by its flag).
    Returns the scenario itself when nothing is overridden (frozen)."""
    given = {k: options[k] for k in OVERRIDES if options.get(k) is not None}
    if not given:
        return scenario
    contact = scenario.contact
    if "restitution" in given:
        contact = dataclasses.replace(contact, restitution=given["restitution"])
    if "contact_stiffness" in given:
        contact = dataclasses.replace(contact, stiffness=given["contact_stiffness"],
                                      duration=None)
    if "contact_duration" in given:
        contact = dataclasses.replace(contact, duration=given["contact_duration"],
                                      stiffness=None)
    return dataclasses.replace(scenario, contact=contact,
                               t_end=given.get("t_end", scenario.t_end))


def numerical_options(options: dict) -> dict:
    """``options`` without the run options of :data:`OVERRIDES`: what a backend's own
    function takes beside the scenario as run (:func:`scenario_as_run`)."""
    return {k: v for k, v in options.items() if k not in OVERRIDES}


def as_typed(message: str, options: dict) -> str:
    """``message`` with each scenario field that a run option in ``options`` set named by
    that option's flag instead (``contact.duration`` -> ``--contact-duration``): a refusal
    names what the user typed."""
    for option, path in OVERRIDES.items():
        if options.get(option) is not None:
            flag = "--" + option.replace("_", "-")
            message = re.sub(rf"(?<![\w.-]){re.escape(path)}\b", flag, message)
    return message
