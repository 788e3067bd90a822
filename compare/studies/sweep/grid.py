"""Grid specifications of a sweep: ``NAME=START:STOP:COUNT`` or ``NAME=V1,V2,...``.

Design notes and measured figures: docs/sweeps.md.
"""

from __future__ import annotations

import dataclasses
import itertools
import json
import math
import re
from dataclasses import dataclass, replace
from enum import StrEnum

import numpy as np

from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.model.parameters import (
    Billet,
    Contact,
    Pendulum,
    Scenario,
    Trunk,
    check_range,
)
from treeimpact.analytic.model.ratios import RATIOS, ratio_of
from treeimpact.analytic.model.registry import BY_NAME, PARAMETERS
from treeimpact.compare.runs.backends import BACKENDS

#: Bounds of a grid: values per axis and points in all (the --preset full study has 540).
MAX_AXIS_VALUES = 1000
MAX_POINTS = 100_000
GRID_FORM = "NAME=START:STOP:COUNT (COUNT values, both ends included) or NAME=V1,V2,..."


class TargetKind(StrEnum):
    """What a grid NAME sets (:class:`GridTarget`)."""

    SCENARIO = "scenario"  # a scenario field (dotted path)
    OPTION = "option"  # a backend option
    DERIVED = "derived"  # a ratio of DERIVED_RATIOS, solved against the final values
    RECORD = "record"  # how the run's record is sampled (read by an analysis)
    INPUT = "input"  # an input of an analysis (the sensitivity study's)


SCENARIO, OPTION, DERIVED, RECORD, INPUT = TargetKind

#: How a run's record is sampled before an analysis reads it (``record.NAME`` axes; a sweep
#: with such axes needs an analysis that takes them): (type, low, low included, unit).
RECORD_FIELDS = {"rate": (float, 0.0, False, "Hz"), "noise": (float, 0.0, True, "1"),
                 "seed": (int, 0, True, "")}

#: Short names of scenario fields: the spelling every table, CLI flag and JSON key uses
#: (an axis given by its dotted field is stored under its short name); the registry's sweep
#: names (analytic.model.registry).
ALIASES = {p.sweep: p.path for p in PARAMETERS if p.path is not None and p.sweep != p.path}
SHORT_NAMES = {target: name for name, target in ALIASES.items()}

#: Derived ratios: (underlying dotted parameter, meaning), the registry's; applied in this
#: order (analytic.model.ratios.RATIOS).
DERIVED_RATIOS = {name: (BY_NAME[name].sets, f"{BY_NAME[name].symbol}: {BY_NAME[name].meaning}")
                  for name in RATIOS}


def backend_option(name: str):
    """The :class:`~treeimpact.analytic.model.options.Option` that a backend's OPTIONS give
    ``name`` (the first backend that has it; they share one definition), or None: an option
    axis takes its type, range and words from there."""
    for backend in BACKENDS.values():
        try:
            option = backend.options().get(name)
        except ParameterError:  # a backend not installed here
            continue
        if option is not None:
            return option
    return None


_SECTIONS = {"trunk": (Trunk,), "impactor": (Pendulum, Billet), "contact": (Contact,)}
_EXTRA_FIELDS = {"impactor": {"release_angle_deg"}}
_TOP_FIELDS = {"t_end"}
_NAME_RE = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*(\.[A-Za-z_][A-Za-z0-9_]*)?$")


@dataclass(frozen=True)
class GridTarget:
    """What a grid NAME sets: ``kind`` scenario/option/derived and its ``target``
    (dotted scenario path, option name, or ratio name)."""

    name: str
    kind: TargetKind
    target: str
    given: str = ""  # the name as typed (messages name it), when it differs

    @property
    def option(self):
        """The backend Option of an option axis (None for scenario fields and ratios)."""
        return backend_option(self.target) if self.kind == OPTION else None


def _fields(cls) -> set[str]:
    return {f.name for f in dataclasses.fields(cls)}


def resolve_parameter(name: str, flag: str = "--grid") -> GridTarget:
    """The :class:`GridTarget` a grid NAME (``name``) refers to, named by its one spelling (a
    short name of :data:`ALIASES` where the field has one), or a one-line ParameterError
    naming ``flag``."""
    if not isinstance(name, str) or not _NAME_RE.match(name):
        raise ParameterError(f"{flag} {name!r}: not a NAME; allowed: a scenario field "
                             f"(trunk.crown_mass), a short name ({', '.join(sorted(ALIASES))}), "
                             f"a ratio ({', '.join(DERIVED_RATIOS)}) or a backend option")
    if name in DERIVED_RATIOS:
        return GridTarget(name, DERIVED, name)
    if name.startswith("input.") and _NAME_RE.match(name.split(".", 1)[1]):
        return GridTarget(name, INPUT, name.split(".", 1)[1])  # read by an analysis
    if name.startswith("record."):
        field = name.split(".", 1)[1]
        if field not in RECORD_FIELDS:
            raise ParameterError(f"{flag} {name!r}: the record has no parameter {field!r}; "
                                 f"allowed: {', '.join('record.' + f for f in RECORD_FIELDS)}")
        return GridTarget(name, RECORD, field)
    target = ALIASES.get(name, name)
    if target.startswith("option."):  # any option: check_grid refuses one no backend takes
        option = target.split(".", 1)[1]
        return GridTarget(option, OPTION, option, name)
    if "." not in target and target not in _TOP_FIELDS and backend_option(target) is not None:
        return GridTarget(target, OPTION, target, name)
    if "." not in target:
        if target in _TOP_FIELDS:
            return GridTarget(name, SCENARIO, target)
        raise ParameterError(
            f"{flag} {name!r}: unknown name; allowed: dotted scenario fields "
            f"(trunk.*, impactor.*, contact.*, t_end), short names {', '.join(sorted(ALIASES))}, "
            f"ratios {', '.join(DERIVED_RATIOS)}, or a backend option (segments, dt, ...)")
    section, field = target.split(".")
    if section not in _SECTIONS:
        raise ParameterError(f"{flag} {name!r}: unknown section {section!r}; allowed: "
                             f"{', '.join(_SECTIONS)}")
    allowed = set().union(*(_fields(c) for c in _SECTIONS[section])) | _EXTRA_FIELDS.get(
        section, set())
    if field not in allowed:
        raise ParameterError(f"{flag} {name!r}: {section} has no field {field!r}; allowed: "
                             f"{', '.join(sorted(allowed))}")
    return GridTarget(SHORT_NAMES.get(target, target), SCENARIO, target, name)


@dataclass(frozen=True)
class Axis:
    """One swept parameter and its values (floats; ints for integer options; words for
    engine options that take words)."""

    parameter: GridTarget
    values: tuple

    @property
    def name(self) -> str:
        """The swept parameter's name."""
        return self.parameter.name

    @property
    def numeric(self) -> bool:
        """Whether every value is a number (not a word)."""
        return all(isinstance(v, (int, float)) for v in self.values)

    def spec(self) -> str:
        """The axis as a ``--grid`` spec, in the name the user gave it."""
        return f"{self.parameter.given or self.name}=" + ",".join(_fmt(v) for v in self.values)


def _fmt(v) -> str:
    return repr(v) if isinstance(v, float) else str(v)


def _number(text: str, spec: str, flag: str, what: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise ParameterError(f"{flag} {spec!r}: {what} {text!r} is not a number; "
                             f"expected {GRID_FORM}") from None
    if not math.isfinite(v):
        raise ParameterError(f"{flag} {spec!r}: {what} {text!r} must be finite; "
                             f"expected {GRID_FORM}")
    return v


def _record_value(v, kind, low, closed, unit, label):
    if isinstance(v, str) or (kind is int and v != int(v)) or not (
            v >= low if closed else v > low):
        what = "integers" if kind is int else "numbers"
        raise ParameterError(f"{label} = {v!r}: allowed {what} {'>=' if closed else '>'} "
                             f"{low:g}{' ' + unit if unit and unit != '1' else ''}")
    return kind(v)


def _range_values(body: str, spec: str, flag: str) -> list:
    """The values of a ``START:STOP:COUNT`` range ``body`` of the spec ``spec``."""
    parts = body.split(":")
    if len(parts) != 3:
        raise ParameterError(f"{flag} {spec!r}: a range needs exactly START:STOP:COUNT; "
                             f"expected {GRID_FORM}")
    start = _number(parts[0], spec, flag, "START")
    stop = _number(parts[1], spec, flag, "STOP")
    try:
        count = int(parts[2])
    except ValueError:
        raise ParameterError(f"{flag} {spec!r}: COUNT {parts[2]!r} must be an integer >= 1; "
                             f"expected {GRID_FORM}") from None
    if count < 1 or count > MAX_AXIS_VALUES:
        raise ParameterError(f"{flag} {spec!r}: COUNT = {count}: allowed 1 to "
                             f"{MAX_AXIS_VALUES}; expected {GRID_FORM}")
    if start == stop:  # no interval: one value is a list of one (NAME=V)
        raise ParameterError(f"{flag} {spec!r}: START = STOP = {parts[0]}: an empty range; "
                             f"allowed START != STOP with COUNT >= 2, or one value as "
                             f"{spec.split('=')[0].strip()}={parts[0]}")
    if count == 1:
        raise ParameterError(f"{flag} {spec!r}: COUNT = 1: a range needs COUNT >= 2 (both "
                             f"ends); expected {GRID_FORM}")
    # 12 significant digits: 0.3, not 0.30000000000000004 (linspace's rounding)
    return [float(f"{v:.12g}") for v in np.linspace(start, stop, count)]


def _list_values(body: str, spec: str, flag: str, param) -> list:
    """The values of a comma list ``body``: finite numbers, or words for an engine option."""
    items = [s.strip() for s in body.split(",")]
    if any(not s for s in items):
        raise ParameterError(f"{flag} {spec!r}: empty value in the list; expected {GRID_FORM}")
    values = []
    for s in items:
        try:
            v = float(s)
        except ValueError:
            if param.kind != OPTION:
                raise ParameterError(f"{flag} {spec!r}: value {s!r} is not a number; "
                                     f"expected {GRID_FORM}") from None
            v = s  # a word, for engine options such as contact=soft,newton
        else:
            if not math.isfinite(v):
                raise ParameterError(f"{flag} {spec!r}: value {s!r} must be finite; "
                                     f"expected {GRID_FORM}")
        values.append(v)
    return values


def parse_axis(spec: str, flag: str = "--grid") -> Axis:
    """Parse one ``--grid`` spec into an :class:`Axis` (one-line ParameterError naming
    ``flag`` and the allowed form on any mistake)."""
    if not isinstance(spec, str) or spec.count("=") != 1:
        raise ParameterError(f"{flag} {spec!r}: expected {GRID_FORM}, e.g. "
                             f"restitution=0:0.9:10 or segments=1,2,4")
    name, body = (s.strip() for s in spec.split("="))
    try:
        param = resolve_parameter(name, flag)
    except ParameterError as exc:  # name the whole spec the user wrote
        raise ParameterError(str(exc).replace(f"{flag} {name!r}", f"{flag} {spec!r}", 1)) \
            from None
    if not body:
        raise ParameterError(f"{flag} {spec!r}: no values; expected {GRID_FORM}")
    values = _range_values(body, spec, flag) if ":" in body else \
        _list_values(body, spec, flag, param)
    option = param.option
    if option is not None:  # its words, integers and range, from the backends' OPTIONS
        label = f"{flag} {spec!r}: {param.name}"
        if param.name == "segments":  # a sweep's segments = 1 is the SDOF trunk (run.py)
            option = replace(option, low=1)
        values = [option.check(param.name, v, label=label) for v in values]
    if param.kind == RECORD:
        kind, low, closed, unit = RECORD_FIELDS[param.target]
        values = [_record_value(v, kind, low, closed, unit, f"{flag} {spec!r}: {name}")
                  for v in values]
    if len(set(values)) != len(values):
        raise ParameterError(f"{flag} {spec!r}: repeated values; expected {GRID_FORM}")
    return Axis(param, tuple(values))


@dataclass(frozen=True)
class Grid:
    """The axes of a sweep; points are their cartesian product (first axis slowest)."""

    axes: tuple

    def __post_init__(self):
        names = [a.parameter.given or a.name for a in self.axes]
        targets = [(a.parameter.kind, a.parameter.target) for a in self.axes]
        for i, t in enumerate(targets):
            if t in targets[:i]:
                first = names[targets.index(t)]
                what = "is given twice" if first == names[i] else \
                    f"sets the same parameter as {first!r}"
                raise ParameterError(f"--grid {names[i]!r}: {what}; give each parameter once")
        derived_targets = {DERIVED_RATIOS[a.name][0] for a in self.axes
                           if a.parameter.kind == DERIVED}
        for a in self.axes:
            if a.parameter.kind == SCENARIO and a.parameter.target in derived_targets:
                raise ParameterError(f"--grid {a.name!r}: also set by a swept ratio; "
                                     f"sweep either the parameter or its ratio")

    @property
    def names(self) -> tuple:
        """The axes' names, in order."""
        return tuple(a.name for a in self.axes)

    def __len__(self) -> int:
        n = 1
        for a in self.axes:
            n *= len(a.values)
        return n

    def points(self) -> list[dict]:
        """Every grid point as {axis name: value}, in a fixed order."""
        return [dict(zip(self.names, combo))
                for combo in itertools.product(*(a.values for a in self.axes))]

    def specs(self) -> list[str]:
        """Each axis as its ``--grid`` spec."""
        return [a.spec() for a in self.axes]

    def axis(self, name: str) -> Axis:
        """The axis of ``name`` (KeyError if none)."""
        for a in self.axes:
            if a.name == name:
                return a
        raise KeyError(name)


@dataclass(frozen=True)
class Design(Grid):
    """Explicit points instead of a cartesian product (a sampling design, e.g. Morris):
    ``design`` holds one tuple of values per point, in the axes' order."""

    design: tuple = ()

    @classmethod
    def of(cls, names, points) -> "Design":
        """A design over ``names`` (grid NAMEs) with ``points`` (tuples of numbers)."""
        params = [resolve_parameter(n) for n in names]
        points = tuple(tuple(float(v) for v in p) for p in points)
        if not points or any(len(p) != len(params) for p in points):
            raise ParameterError(f"design: {len(points)} points, each needs {len(params)} "
                                 f"values ({', '.join(names)})")
        axes = tuple(Axis(p, tuple(sorted({pt[i] for pt in points})))
                     for i, p in enumerate(params))
        return cls(axes, points)

    def __len__(self) -> int:
        return len(self.design)

    def points(self) -> list[dict]:
        """The design's points, each {name: value}."""
        return [dict(zip(self.names, p)) for p in self.design]

    def specs(self) -> list[str]:
        """One line describing the design (its size and names)."""
        return [f"design of {len(self.design)} points over {', '.join(self.names)}"]


def value_axis(name: str, values) -> Axis:
    """An :class:`Axis` of the scenario input ``name`` (a registry sweep name) over the
    numbers ``values``, given as numbers (no spec text to parse): what a study that varies
    an input passes. ParameterError for an unknown name, a non-finite or repeated value."""
    values = tuple(check_range(f"{name}", v) for v in values)
    if len(set(values)) != len(values):
        raise ParameterError(f"{name}: repeated values {values}")
    return Axis(resolve_parameter(name), values)


def parse_grid(specs, flag: str = "--grid") -> Grid:
    """A :class:`Grid` from ``--grid`` specs (a string or a list of them); one-line
    ParameterErrors name ``flag``."""
    if isinstance(specs, str):
        specs = [specs]
    specs = list(specs or [])
    if not specs:
        raise ParameterError(f"{flag}: give at least one, {GRID_FORM}")
    grid = Grid(tuple(parse_axis(s, flag) for s in specs))
    n = math.prod(len(a.values) for a in grid.axes)
    if n > MAX_POINTS:
        raise ParameterError(f"{flag}: {n} grid points (" + " x ".join(
            str(len(a.values)) for a in grid.axes) + f"): allowed up to {MAX_POINTS}")
    return grid


def point_key(point: dict) -> str:
    """A stable text key of a grid point (JSON; floats by repr, so exact)."""
    return json.dumps([[k, v] for k, v in point.items()], separators=(",", ":"))


def point_from_key(key: str) -> dict:
    """The grid point of a :func:`point_key` ``key``."""
    return {k: v for k, v in json.loads(key)}


def derived_ratios(scenario: Scenario) -> dict:
    """The derived ratios of a scenario: a_over_l, crown_ratio, mass_ratio (see module doc)."""
    return {name: ratio_of(scenario, name) for name in RATIOS}
