"""The design map: where the paper's 1-DOF trunk and its small-e consequences hold over the
choices a harvester designer makes (clamp height, impactor mass, pad, e) for one tree.

A cell is one point of those choices applied to the tree (compare.studies.sweep.apply: the ratios
``a_over_l`` and ``mass_ratio``, the pad's ``contact_duration`` and ``restitution``); its
numbers are the continuum trunk's gaps to the 1-DOF model (the answer table's: x_max, energy
delivered, crown acceleration) and the small-e errors (eq 57, the identified M_T and K_T) of
compare.studies.small_e. The maps run on the sweep machinery (one sweep per pair of inputs,
the analysis :func:`design_cell`), so a map resumes and runs on Dask. Reading a map
(crossings, words): compare.studies.design_words. Design notes: docs/design-map.md. SI.
"""

from __future__ import annotations

import enum
import math
import numbers
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from treeimpact.analytic.contact.soft import simulate_soft
from treeimpact.analytic.continuum.beam_impact import simulate_beam
from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.impact.simulate import simulate
from treeimpact.analytic.model.registry import BY_NAME
from treeimpact.analytic.model.two_body import two_body_model

from .small_e import at_restitution, errors_of_run


class Scale(enum.Enum):
    """How an input's values are spaced on a map and read between cells."""

    LINEAR = "linear"
    LOG = "log"


@dataclass(frozen=True)
class Input:
    """One designer's choice: its sweep name, unit, the map's default range (``low``,
    ``high``) and why, the range the study admits (``allowed``), its label, the factor
    to its display unit (``show``, ``shown_unit``) and its spacing."""

    name: str
    unit: str
    low: float
    high: float
    allowed: tuple
    label: str
    why: str
    scale: Scale = Scale.LINEAR
    show: float = 1.0
    shown_unit: str = ""

    def values(self, count: int, low: float | None = None, high: float | None = None) -> tuple:
        """``count`` values from ``low`` to ``high`` (default the map's range), both ends
        included, evenly spaced on the input's scale, rounded to 4 significant digits."""
        lo, hi = self.low if low is None else low, self.high if high is None else high
        v = np.geomspace(lo, hi, count) if self.scale is Scale.LOG else np.linspace(lo, hi, count)
        return tuple(float(f"{x:.4g}") for x in v)

    def span(self, own: float) -> tuple:
        """The map's range (low, high) for a tree whose own value is ``own``: the
        registry's rule (analytic.model.registry.DesignRange.span; the default range when
        the tree lies in it, else one relative to the tree, inside :attr:`allowed`)."""
        return BY_NAME[self.name].design.span(own)

    def coordinate(self, v):
        """``v`` on the axis a map is read on (log10 for a log input)."""
        return np.log10(v) if self.scale is Scale.LOG else np.asarray(v, dtype=float)

    def check(self, low: float, high: float, flag: str) -> None:
        """A ParameterError, one line naming ``flag`` as typed and the allowed range, if
        [low, high] is not inside :attr:`allowed` or low >= high."""
        a, b = self.allowed
        ok = all(math.isfinite(x) for x in (low, high)) and a <= low < high <= b
        if not ok:
            raise ParameterError(f"{flag}: {self.name} from {low:g} to {high:g} {self.unit}; "
                                 f"allowed {a:g} <= low < high <= {b:g} {self.unit}")


#: Each design input's label in the study's titles and text.
_LABELS = {"a_over_l": "clamp height a/l", "mass_ratio": "mass ratio m/M_T",
           "contact_duration": "contact duration", "restitution": "restitution e"}


def _input(name: str) -> Input:
    """The design input ``name`` as the registry declares it (its unit, map range, allowed
    range, reasons, scale and display unit; analytic.model.registry)."""
    p = BY_NAME[name]
    d = p.design
    return Input(name, p.unit, d.low, d.high, d.allowed, _LABELS[name], d.why,
                 Scale.LOG if d.log else Scale.LINEAR, p.shown[0], p.shown[1])


#: The designer's choices, the sweep's names (compare.studies.sweep.grid), from the registry.
INPUTS = {name: _input(name) for name in _LABELS}
#: What the map does not vary: the tree as its scenario file gives it.
HELD = ("the trunk's length, diameter, wood (E, density), damping, root spring, clamp mass "
        "and crown mass; the release (impact speed u1 from the pendulum's l_e and angle); "
        "the pad's law (k_c from the contact duration on the 1-DOF pair, c_c from e)")
#: The pairs drawn, each at the tree's own value of the other inputs.
PAIRS = (("a_over_l", "mass_ratio"), ("a_over_l", "contact_duration"),
         ("mass_ratio", "restitution"))
#: The trunk diameters of the family of trees, as factors of the tree's own.
DIAMETER_FACTORS = (0.6, 0.8, 1.0, 1.25, 1.5)
#: e below this is read here (the pad law and the continuum need e > 0; small_e.E_FLOOR).
E_FLOOR = 1e-3


class Kind(enum.Enum):
    """What a map's number is: the continuum's gap to the 1-DOF model, or a small-e
    approximation's error against the exact model."""

    ONE_DOF = "1-DOF gap"
    SMALL_E = "small-e error"


@dataclass(frozen=True)
class Quantity:
    """A number of a cell: its label and kind (relative, 1)."""

    label: str
    kind: Kind


QUANTITIES = {
    "x_max": Quantity("x_max", Kind.ONE_DOF),
    "energy_delivered": Quantity("energy delivered", Kind.ONE_DOF),
    "crown_peak_acceleration": Quantity("crown acceleration", Kind.ONE_DOF),
    "eq57_energy_loss": Quantity("eq 57 energy loss", Kind.SMALL_E),
    "identification_M_T": Quantity("identified M_T", Kind.SMALL_E),
    "identification_K_T": Quantity("identified K_T", Kind.SMALL_E),
}
COLUMNS = tuple(f"design.{q}" for q in QUANTITIES)
#: The tolerances whose lines the maps draw (relative).
LEVELS = (0.05, 0.20)


def _rel(value: float, reference: float) -> float:
    ok = math.isfinite(value) and math.isfinite(reference) and reference != 0.0
    return (value - reference) / abs(reference) if ok else math.nan


def one_dof_gaps(scenario) -> dict:
    """The continuum trunk's gaps to the 1-DOF model at ``scenario`` (its e read at
    :data:`E_FLOOR` below it), the answer table's rule: (continuum - 1-DOF) / |1-DOF| with the
    paper's Newton model, or the soft 1-DOF with the same pad where Newton has no value
    (the crown's acceleration). Relative, by quantity name."""
    s = at_restitution(scenario, max(scenario.contact.restitution, E_FLOOR))
    newton = simulate(s, samples=2).metrics
    beam = simulate_beam(s).metrics
    out = {}
    soft = None
    for name, q in QUANTITIES.items():
        if q.kind is not Kind.ONE_DOF:
            continue
        ref = newton.get(name, math.nan)
        if not math.isfinite(ref):
            soft = soft or simulate_soft(s).metrics
            ref = soft[name]
        out[name] = _rel(beam[name], ref)
    return out


def design_cell(result, scenario, record=None) -> dict:
    """The sweep analysis: a cell's numbers (``design.NAME``, relative) at the exact 1-DOF
    run ``result`` of ``scenario`` (the point applied): :func:`one_dof_gaps` and the small-e
    errors of compare.studies.small_e.errors_of_run; ``record`` is not read."""
    errors = errors_of_run(result, scenario, continuum=False)
    out = {f"design.{k}": v for k, v in one_dof_gaps(scenario).items()}
    for name, q in QUANTITIES.items():
        if q.kind is Kind.SMALL_E:
            out[f"design.{name}"] = errors[f"small_e.{name}"]
    return out


design_cell.columns = COLUMNS


def operating_point(scenario) -> dict:
    """The tree ``scenario``'s own value of every input (:data:`INPUTS` units): a/l, m/M_T (M_T of eq 7),
    the pad's contact duration (s; from its stiffness on the 1-DOF pair if the file gives
    that) and e."""
    # lazy: +62 ms at import otherwise (treeimpact.compare.studies.sweep.grid),
    # which this module's other callers do not need
    from .sweep.grid import derived_ratios

    c = scenario.contact
    duration = c.duration
    if duration is None:
        duration = math.pi / math.sqrt(c.stiffness / two_body_model(scenario).reduced_mass)
    r = derived_ratios(scenario)
    return {"a_over_l": r["a_over_l"], "mass_ratio": r["mass_ratio"],
            "contact_duration": float(duration), "restitution": float(c.restitution)}


def map_ranges(scenario, ranges: dict | None = None) -> dict:
    """{input: (low, high)}: the range each input's map spans for the tree ``scenario``,
    ``ranges``' where given, else :meth:`Input.span` of the tree's own value (its map
    spans the tree's operating point)."""
    ranges = ranges or {}
    here = operating_point(scenario)
    return {name: tuple(float(v) for v in ranges[name]) if name in ranges
            else inp.span(here[name]) for name, inp in INPUTS.items()}


def pair_grid(scenario, pair, count: int, ranges: dict | None = None) -> list[str]:
    """The ``--grid`` specs of the map over ``pair`` (two :data:`INPUTS` names), ``count``
    values each over ``ranges`` ({name: (low, high)}, default :func:`map_ranges`' for the
    tree), the other inputs at the operating point of the tree ``scenario``."""
    spans = map_ranges(scenario, ranges)
    here = operating_point(scenario)
    specs = []
    for name in INPUTS:
        if name in pair:
            vals = INPUTS[name].values(count, *spans[name])
        else:
            vals = (float(f"{here[name]:.6g}"),)
        specs.append(f"{name}=" + ",".join(repr(v) for v in vals))
    return specs


def check_ranges(ranges, flag: str = "ranges") -> None:
    """ParameterError (one line naming ``flag``) for ``ranges`` that are not a mapping
    {name: (low, high)}, an unknown input, a range that is not two numbers, or one outside
    its allowed range."""
    if not isinstance(ranges, Mapping):
        raise ParameterError(f"{flag}: expected {{input: (low, high)}}, a dict, got a "
                             f"{type(ranges).__name__}; inputs {', '.join(INPUTS)}")
    for name, pair in ranges.items():
        if name not in INPUTS:
            raise ParameterError(f"{flag}: {name!r} is not a design input; allowed "
                                 f"{', '.join(INPUTS)}")
        a, b = INPUTS[name].allowed
        if isinstance(pair, (str, bytes)) or not isinstance(pair, Sequence) or len(pair) != 2 \
                or not all(isinstance(v, numbers.Real) and not isinstance(v, bool)
                           for v in pair):
            unit = "" if INPUTS[name].unit == "1" else f" {INPUTS[name].unit}"
            raise ParameterError(f"{flag}: {name} = {pair!r}; expected (low, high), two "
                                 f"numbers with {a:g} <= low < high <= {b:g}{unit}")
        INPUTS[name].check(float(pair[0]), float(pair[1]), flag)


def check_grid_specs(specs, flag: str = "--grid") -> None:
    """ParameterError (one line naming ``flag`` and the spec as typed) for one of the
    ``specs`` (``--grid`` specs) of a design input with values outside its allowed range,
    or an axis that is not a design input."""
    # lazy: +62 ms at import otherwise (treeimpact.compare.studies.sweep.grid),
    # which this module's other callers do not need
    from .sweep.grid import parse_axis

    for spec in specs:
        axis = parse_axis(spec, flag)
        if axis.name not in INPUTS:
            raise ParameterError(f"{flag} {spec!r}: not a design input; allowed "
                                 f"{', '.join(INPUTS)}")
        a, b = INPUTS[axis.name].allowed
        bad = [v for v in axis.values if not a <= float(v) <= b]
        if bad:
            raise ParameterError(f"{flag} {spec!r}: {axis.name} = {bad[0]:g} outside the "
                                 f"allowed {a:g}-{b:g} {INPUTS[axis.name].unit}")


def check_operating_point(scenario, label: str) -> None:
    """ParameterError (one line naming ``label``, what the user typed for the tree) when the
    tree ``scenario``'s own value of a design input (:func:`operating_point`) lies outside
    the range the study admits: its maps hold that input at the tree's value."""
    here = operating_point(scenario)
    for name, inp in INPUTS.items():
        a, b = inp.allowed
        if not (math.isfinite(here[name]) and a <= here[name] <= b):
            unit = f" {inp.unit}" if inp.unit != "1" else ""
            raise ParameterError(
                f"{label}: the tree's own {inp.label} = {here[name]:.4g}{unit} lies outside "
                f"the design study's allowed {a:g} to {b:g}{unit} (its maps hold it at the "
                "tree's value); a tree within it")


def design_spec(scenario, specs, out, label: str | None = None):
    """A sweep (compare.studies.sweep.run.SweepSpec) of :func:`design_cell` over the ``--grid``
    ``specs`` on ``scenario`` into ``out``; ``label``: what a refusal of the grid names (a
    map's grid the study made; None: the specs, as typed)."""
    # lazy: +59 ms at import otherwise (treeimpact.compare.studies.sweep.run),
    # which this module's other callers do not need
    from .sweep.run import SweepSpec

    return SweepSpec(scenario, list(specs), Path(out), ("analytic",), identify=True,
                     analysis="treeimpact.compare.studies.design:design_cell", label=label)


def map_of(table, pair, quantity: str):
    """The map of ``quantity`` over ``pair`` from a design sweep's ``table``: (x values,
    y values, Z with Z[j, i] at y[j], x[i]); NaN where a cell has no number."""
    rows = table[table["target"] == "analytic"] if "target" in table else table
    x = np.array(sorted({float(v) for v in rows[pair[0]]}))
    y = np.array(sorted({float(v) for v in rows[pair[1]]}))
    z = np.full((len(y), len(x)), np.nan)
    col = f"design.{quantity}"
    for xv, yv, zv, st in zip(rows[pair[0]], rows[pair[1]], rows.get(col, []), rows["status"]):
        if st == "ok":
            z[np.searchsorted(y, float(yv)), np.searchsorted(x, float(xv))] = float(zv)
    return x, y, z
