"""A :class:`~analytic.model.parameters.Scenario` written as a scenario file (the layout that
:func:`analytic.model.scenario.load_scenario` reads; SI units, release angle in degrees)."""

from __future__ import annotations

import json
import math

from .parameters import STANDARD_GRAVITY, Scenario
from .registry import BY_PATH

def _unit(path: str) -> str | None:
    """The registry's unit of the scenario field at ``path`` (``trunk.length``), None for a
    field that is no physical input (a name, a type)."""
    p = BY_PATH.get(path)
    return p.unit if p is not None else None


def _value(v) -> str:
    if isinstance(v, str):
        return json.dumps(v)  # a JSON string is a valid TOML basic string
    v = float(v)
    return repr(v) if math.isfinite(v) else ("inf" if v > 0 else "-inf")  # round-trip exact


def _line(key, v, path: str | None = None) -> str:
    if isinstance(v, (list, tuple)):  # [calibration] measured: a list of field names
        return f"{key} = [{', '.join(_value(str(x)) for x in v)}]"
    unit = _unit(path) if path else None
    return f"{key} = {_value(v)}" + (f"  # {unit}" if unit else "")


def scenario_toml(scenario: Scenario) -> str:
    """A scenario as a scenario file's text (SI units, each value's unit in a comment).

    Args:
        scenario: the :class:`Scenario` to write.

    Returns:
        str: the TOML text; loading it gives back an equal scenario (notes included).

    Raises:
        Nothing.
    """
    d = scenario.to_dict()
    lines = [_line("name", d["name"])]
    if scenario.description:
        lines.append(_line("description", scenario.description))
    lines.append(_line("t_end", d["t_end"], "t_end"))
    for table in ("trunk", "impactor", "contact"):
        lines += ["", f"[{table}]"]
        for key, v in d[table].items():
            if table == "trunk" and key == "base_stiffness" and v is None:
                v = math.inf  # the paper's rigid clamp, written out
            if v is None or (key == "gravity" and v == STANDARD_GRAVITY):
                continue  # an optional value left at its default
            lines.append(f'type = "{v}"' if key == "type" else _line(key, v, f"{table}.{key}"))
    if scenario.notes:
        lines += ["", "[calibration]"]
        lines += [_line(k, v if isinstance(v, (list, tuple)) else str(v))
                  for k, v in scenario.notes.items()]
    return "\n".join(lines) + "\n"
