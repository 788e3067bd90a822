"""Scenario files (TOML) and the shipped paper-tree scenarios.

Layout of a scenario file (SI units; angles in degrees where the key says ``_deg``)::

    name = "open-center"
    t_end = 0.1                      # s
    [trunk]       length, clamp_height, diameter, density, youngs_modulus,
                  clamp_mass, crown_mass, damping, base_stiffness (inf: a rigid clamp),
                  shear_modulus?, shear_coefficient? (Timoshenko theory; default E / 13, 0.894)
    [impactor]    type = "pendulum": mass, equivalent_length, release_angle_deg, gravity?
                  type = "billet":   mass, impact_speed, stiffness? (N/m; 0: free)
    [contact]     restitution, stiffness? | duration?
    [calibration] free text: which values are calibrated and from what; and
                  measured = ["trunk.clamp_mass", ...]: the fields of :data:`MEASURABLE`
                  that were measured on this tree (a sensitivity study holds them);
                  assumed = ["trunk.base_stiffness", ...]: the fields of a tree built
                  from its geometry that nobody measured (analytic.model.assumed.ASSUMABLE;
                  never measured too), each with its ``assumed_<field>`` note

Any error is a :class:`~analytic.errors.ParameterError` whose one-line message names
the field and the allowed range.
"""

from __future__ import annotations

import copy
import functools
import tomllib
from dataclasses import replace
from importlib import resources
from pathlib import Path

from treeimpact.analytic.errors import ParameterError

from .assumed import ASSUMABLE
from .parameters import Billet, Contact, Pendulum, Scenario, Trunk, check_limit
from .plausible import implausible, warn_implausible

_TRUNK_KEYS = {"length", "clamp_height", "diameter", "density", "youngs_modulus", "clamp_mass",
               "crown_mass", "damping", "base_stiffness", "shear_modulus", "shear_coefficient"}
_TRUNK_REQUIRED = {"length", "clamp_height", "diameter", "density", "youngs_modulus"}
#: Required too (a missing mass or damping is not silently 0), but reported after the
#: values that are given have been checked: what is wrong comes before what is missing.
_TRUNK_REQUIRED_LATER = ("clamp_mass", "crown_mass", "damping", "base_stiffness")
_PENDULUM_KEYS = {"type", "mass", "equivalent_length", "release_angle_deg", "gravity"}
_BILLET_KEYS = {"type", "mass", "impact_speed", "stiffness"}
_CONTACT_KEYS = {"restitution", "stiffness", "duration"}
_TOP_KEYS = {"name", "description", "t_end", "trunk", "impactor", "contact", "calibration"}

#: The fields a sensitivity study varies over their plausible ranges unless the file's
#: ``[calibration] measured`` list says they were measured on the tree
#: (compare/studies/sensitivity.py holds those at the file's values).
MEASURABLE = ("trunk.clamp_mass", "trunk.density", "trunk.shear_modulus",
              "trunk.base_stiffness", "contact.duration", "contact.stiffness",
              "contact.restitution")


#: The largest scenario file read (bytes): the shipped ones are about 2 kB.
MAX_FILE_BYTES = 1_000_000


def shipped_scenarios() -> list[str]:
    """The shipped scenarios (the paper's two trees and one with a realistic crown).

    Returns:
        list[str]: their names, sorted (what :func:`load_scenario` takes).

    Raises:
        Nothing.
    """
    folder = resources.files(__package__) / "scenarios"
    return sorted(p.name[:-5] for p in folder.iterdir() if p.name.endswith(".toml"))


def _table(data: dict, key: str) -> dict:
    if key not in data:
        raise ParameterError(f"{key}: missing table [{key}]")
    if not isinstance(data[key], dict):
        raise ParameterError(f"{key}: expected a table [{key}]")
    return data[key]


def _keys(table: dict, prefix: str, allowed: set, required: set) -> None:
    unknown = sorted(set(table) - allowed)
    if unknown:
        raise ParameterError(f"{prefix}.{unknown[0]}: unknown key (allowed: {', '.join(sorted(allowed))})")
    missing = sorted(required - set(table))
    if missing:
        raise ParameterError(f"{prefix}.{missing[0]}: missing required value")


def _number(table: dict, prefix: str, key: str):
    v = table[key]
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        name = f"{prefix}.{key}" if prefix else key
        raise ParameterError(f"{name}: expected a number, got {v!r}")
    if isinstance(v, int) and not isinstance(v, bool):
        try:
            float(v)
        except OverflowError:  # an integer of hundreds of digits: beyond double precision
            name = f"{prefix}.{key}" if prefix else key
            raise ParameterError(f"{name}: a number of {len(str(abs(v)))} digits is beyond "
                                 "double precision (about 1.8e308)") from None
    return v


def scenario_from_dict(data: dict, default_name: str = "scenario") -> Scenario:
    """Build a validated :class:`Scenario` from ``data``, the parsed TOML layout (its name
    ``default_name`` when the data names none); ParameterError naming the first bad key."""
    if not isinstance(data, dict):
        raise ParameterError("scenario: expected a table")
    unknown = sorted(set(data) - _TOP_KEYS)
    if unknown:
        raise ParameterError(f"{unknown[0]}: unknown key (allowed: {', '.join(sorted(_TOP_KEYS))})")
    trunk_t = _table(data, "trunk")
    _keys(trunk_t, "trunk", _TRUNK_KEYS, _TRUNK_REQUIRED)
    trunk_kw = {k: _number(trunk_t, "trunk", k) for k in trunk_t}
    trunk = Trunk(**trunk_kw)

    imp_t = _table(data, "impactor")
    kind = imp_t.get("type", "pendulum")
    if kind == "pendulum":
        _keys(imp_t, "impactor", _PENDULUM_KEYS, {"mass", "equivalent_length", "release_angle_deg"})
        deg = check_limit("impactor.release_angle_deg", _number(imp_t, "impactor",
                                                           "release_angle_deg"))
        kw = dict(mass=_number(imp_t, "impactor", "mass"),
                  equivalent_length=_number(imp_t, "impactor", "equivalent_length"),
                  release_angle_deg=deg)
        if "gravity" in imp_t:
            kw["gravity"] = _number(imp_t, "impactor", "gravity")
        impactor = Pendulum(**kw)
    elif kind == "billet":
        _keys(imp_t, "impactor", _BILLET_KEYS, {"mass", "impact_speed"})
        impactor = Billet(mass=_number(imp_t, "impactor", "mass"),
                          impact_speed=_number(imp_t, "impactor", "impact_speed"),
                          stiffness=_number(imp_t, "impactor", "stiffness")
                          if "stiffness" in imp_t else 0.0)
    else:
        raise ParameterError(f"impactor.type = {kind!r}: allowed 'pendulum' or 'billet'")

    con_t = _table(data, "contact")
    _keys(con_t, "contact", _CONTACT_KEYS, {"restitution"})
    contact = Contact(**{k: _number(con_t, "contact", k) for k in con_t})

    later = [k for k in _TRUNK_REQUIRED_LATER if k not in trunk_t]
    if later:
        raise ParameterError(f"trunk.{later[0]}: missing required value"
                             + (" (base_stiffness = inf: a rigid clamp)"
                                if later[0] == "base_stiffness" else ""))
    notes = data.get("calibration", {})
    if not isinstance(notes, dict):
        raise ParameterError("calibration: expected a table [calibration] of notes")
    if "measured" in notes:
        _check_measured(notes["measured"], {"trunk": trunk_t, "contact": con_t})
    if "assumed" in notes:
        _check_assumed(notes["assumed"], trunk_t, notes.get("measured", ()))
    name = data.get("name", default_name)
    if not isinstance(name, str) or not name:
        raise ParameterError("name: expected a non-empty string")
    kw = {}
    if "t_end" in data:
        kw["t_end"] = _number(data, "", "t_end")
    return Scenario(name=name, trunk=trunk, impactor=impactor, contact=contact,
                    description=str(data.get("description", "")),
                    notes=dict(notes), **kw)


def _check_measured(measured, tables: dict) -> None:
    """``[calibration] measured``: a list of :data:`MEASURABLE` fields, each given in the
    file (a measured value is the file's value)."""
    allowed = f"a list of {', '.join(repr(m) for m in MEASURABLE)}"
    if not isinstance(measured, list) or not all(isinstance(m, str) for m in measured):
        raise ParameterError(f"calibration.measured = {measured!r}: allowed {allowed}")
    for m in measured:
        if m not in MEASURABLE:
            raise ParameterError(f"calibration.measured: {m!r} is not one of the inputs a "
                                 f"sensitivity study varies; allowed {allowed}")
        table, key = m.split(".")
        if key not in tables[table]:
            raise ParameterError(f"calibration.measured: {m!r} is measured but the file does "
                                 f"not give {table}.{key}")
    if len(set(measured)) != len(measured):
        raise ParameterError(f"calibration.measured = {measured!r}: a field listed twice")


def _check_assumed(assumed, trunk_t: dict, measured) -> None:
    """``[calibration] assumed``: a list of distinct :data:`~.assumed.ASSUMABLE` fields, each
    given in the file and none also measured."""
    allowed = f"a list of {', '.join(repr(m) for m in ASSUMABLE)}"
    if not isinstance(assumed, list) or not all(isinstance(m, str) for m in assumed) \
            or len(set(assumed)) != len(assumed):
        raise ParameterError(f"calibration.assumed = {assumed!r}: allowed {allowed}, each once")
    for m in assumed:
        if m not in ASSUMABLE:
            raise ParameterError(f"calibration.assumed: {m!r}: allowed {allowed}")
        if m.split(".")[1] not in trunk_t:
            raise ParameterError(f"calibration.assumed: {m!r} is assumed but the file does "
                                 f"not give {m}")
        if m in measured:
            raise ParameterError(f"calibration.assumed: {m!r} is also listed measured; a "
                                 "field is one or the other")


def assumed_fields(scenario: Scenario) -> tuple[str, ...]:
    """The trunk fields the scenario's file says were assumed (a tree from its geometry:
    analytic.model.assumed); () for a measured tree."""
    return tuple(scenario.notes.get("assumed", ()))


def measured_fields(scenario: Scenario) -> tuple[str, ...]:
    """The fields of :data:`MEASURABLE` the scenario's file says were measured."""
    return tuple(scenario.notes.get("measured", ()))


def load_scenario(source: str | Path) -> Scenario:
    """A scenario from a shipped name or a scenario file (TOML, SI units, release angle in
    degrees; every key required but the Timoshenko theory's optional two).

    Args:
        source: a shipped scenario's name (``open-center``; :func:`shipped_scenarios`) or
            the path of a TOML file.

    Returns:
        Scenario: validated against :data:`LIMITS`; an input outside what trees and
        harvesters show warns (:class:`~analytic.errors.ImplausibleInput`, one line each).

    Raises:
        ParameterError: an unknown name, an unreadable or malformed file, a missing or
            unknown key, a value out of its range (each in one line naming the key).
    """
    text: str
    path = Path(source)
    if isinstance(source, str) and source in shipped_scenarios():
        raw = (resources.files(__package__) / "scenarios" / f"{source}.toml").read_bytes()
        default = source
    elif path.exists() and not path.is_file():
        raise ParameterError(f"scenario {str(source)!r}: not a regular file (a scenario is a "
                             "TOML file or a shipped name)")
    elif path.is_file():
        if path.stat().st_size > MAX_FILE_BYTES:
            raise ParameterError(f"scenario {str(source)!r}: {path.stat().st_size} bytes; a "
                                 f"scenario file is at most {MAX_FILE_BYTES} bytes")
        try:
            raw = path.read_bytes()
        except OSError as exc:
            raise ParameterError(f"scenario {str(source)!r}: cannot be read "
                                 f"({exc.strerror})") from None
        default = path.stem
    else:
        raise ParameterError(
            f"scenario {str(source)!r}: no such file or shipped scenario "
            f"(shipped: {', '.join(shipped_scenarios())})")
    scenario = _parsed(raw, default, str(source))
    warn_implausible(implausible(scenario))
    return replace(scenario, notes=copy.deepcopy(scenario.notes))  # a caller's own notes


@functools.lru_cache(maxsize=64)
def _parsed(raw: bytes, default: str, source: str) -> Scenario:
    """The scenario of a file's bytes ``raw`` (named ``default`` unless it names itself;
    ``source`` as typed, for the errors): parsed once per distinct content, since a sweep or
    a study loads the same file for every run (TOML parsing was 0.2 ms of a 3 ms soft run)."""
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ParameterError(f"scenario {source!r}: not UTF-8 text (byte "
                             f"0x{raw[exc.start]:02x} at offset {exc.start}); TOML files are "
                             "UTF-8") from None
    try:
        data = tomllib.loads(text)
    except RecursionError:
        raise ParameterError(f"scenario {source!r}: nested too deeply to be a scenario "
                             "file (tables trunk, impactor, contact of numbers)") from None
    except tomllib.TOMLDecodeError as exc:
        raise ParameterError(f"scenario {source!r}: malformed TOML: {exc}") from None
    return scenario_from_dict(data, default_name=default)
