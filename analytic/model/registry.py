"""The parameter registry: one frozen :class:`Parameter` per physical input of a scenario
(its name, symbol, unit, allowed range, label, scenario path and how it is applied), so the
limits, sweeps, maps, studies and figures read one table (issue 42 item 1;
docs/parameters.md).

Units are SI in one vocabulary: "1" for a dimensionless number. The ranges of the scenario
fields are their plausibility limits (what an orchard tree, a harvester's pendulum and a
pad can be; :data:`~treeimpact.analytic.model.parameters.LIMITS` is a view of them). A
derived input (a ratio, a study's reading) has no path of its own: a ratio names the field
it solves (``sets``; :mod:`.ratios` applies it). ``design`` holds the design study's map range and reasons where the
parameter is one of its designer's choices.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Callable

from treeimpact.analytic.errors import ParameterError


@dataclass(frozen=True)
class DesignRange:
    """A design input's map range [low, high] (``log``: spaced on a log scale), the range
    the design study admits (``allowed``) and why (issue 43; compare.studies.design)."""

    low: float
    high: float
    allowed: tuple
    log: bool
    why: str
    relative: float | None = None

    def span(self, own: float) -> tuple:
        """The map's range for a tree whose own value is ``own`` (the input's unit): [low,
        high] when the tree lies in it (the shipped trees' maps), else the tree's own value
        over ``relative`` to it times ``relative`` ([own / f, own * f]; without a factor the
        range widened to ``own``), clipped to :attr:`allowed`: the map spans the tree's
        own operating point (issue 50 item 5)."""
        if not math.isfinite(own) or self.low <= own <= self.high:
            return self.low, self.high
        if self.relative is None:
            lo, hi = min(self.low, own), max(self.high, own)
        else:
            lo, hi = own / self.relative, own * self.relative
        return max(lo, self.allowed[0]), min(hi, self.allowed[1])


@dataclass(frozen=True)
class UnmeasuredRange:
    """An input nobody measured: the range the sensitivity study varies it over [low, high]
    (in the parameter's unit), why that range, and the measurement that would fix it
    (compare.studies.sensitivity; docs/sensitivity.md)."""

    low: float
    high: float
    why: str
    measure: str


@dataclass(frozen=True)
class Assumed:
    """What a tree built from its geometry assumes for an input nobody measured
    (compare.tree.scenario; issue 50 item 6): ``value`` and the range [low, high] it may
    lie in, both in the unit of the registry's parameter ``via`` (a dimensionless form that
    transfers from the paper's trees to another: the root's share of the flexibility, the
    damping ratio), and why (the physical reason and its source)."""

    via: str
    value: float
    low: float
    high: float
    why: str


@dataclass(frozen=True)
class Plausible:
    """What fruit trees, harvesters and pads show of an input, [low, high] in the
    parameter's unit, and where that range comes from: a value inside the allowed range
    but outside this one is run and warned about (:mod:`.plausible`)."""

    low: float
    high: float
    source: str


@dataclass(frozen=True)
class Default:
    """The value an input takes where a user gives none (a tree built by ``scenario``,
    the pad of a run without one), in the parameter's unit, and where that value comes
    from (``source``, one line)."""

    value: float
    source: str


@dataclass(frozen=True)
class Parameter:
    """One physical input.

    Attributes:
        name: its one spelling in code, JSON and flags (``contact_duration``).
        symbol: the paper's symbol (``tau_c``), as text.
        unit: SI unit, "1" for a dimensionless number.
        low, high: the allowed range, in ``unit`` (high may be inf).
        label: a figure's or table's words for it, without the unit.
        path: the dotted scenario field it sets (``contact.duration``), None if derived.
        sweep: the name a sweep axis (``--grid``) and a map go by.
        shown: (factor, unit) of its display unit (a duration read in ms).
        apply: (scenario, value) -> scenario with it set, a pure function; None for a
            ratio (:mod:`.ratios` applies it: it reads M_T, above this floor) and for a
            reading that no single field sets (K_T, M_T, C_T).
        sets: the dotted field a ratio solves (``a_over_l`` sets ``trunk.clamp_height``).
        text: what a map's axis and a study's text call it, if not its symbol.
        meaning: one line on what it is (a command-line option's help), or "".
        design: the design study's range and reasons, or None.
        unmeasured: the sensitivity study's range, reason and fixing measurement, or None.
        plausible: what trees, harvesters and pads show (a warning beyond it), or None.
        assumed: what a tree from its geometry assumes for it (value, range, reason), or
            None (:class:`Assumed`).
        default: the value it takes where none is given, with its source, or None
            (:class:`Default`; :func:`default_of`).
    """

    name: str
    symbol: str
    unit: str
    low: float
    high: float
    label: str
    path: str | None = None
    sweep: str | None = None
    shown: tuple = (1.0, "")
    apply: Callable | None = None
    design: DesignRange | None = None
    sets: str | None = None
    text: str = ""
    meaning: str = ""
    unmeasured: UnmeasuredRange | None = None
    plausible: Plausible | None = None
    assumed: Assumed | None = None
    default: Default | None = None

    @property
    def axis(self) -> str:
        """What a map's axis and a study's text call it: ``text``, else the symbol."""
        return self.text or self.symbol

    @property
    def shown_unit(self) -> str:
        """The unit a figure or text reads it in (its own unit unless ``shown`` says)."""
        return self.shown[1] or self.unit


def set_field(scenario, path: str, value):
    """``scenario`` with the dotted field ``path`` set to ``value`` (dataclasses.replace);
    a contact's stiffness and duration exclude each other (setting one clears the other).
    ParameterError if the scenario's part has no such field."""
    if "." not in path:
        return dataclasses.replace(scenario, **{path: value})
    section, field = path.split(".")
    part = getattr(scenario, section)
    changes = {field: value}
    if section == "impactor" and field == "release_angle_deg":
        if not hasattr(part, "release_angle_deg"):
            raise ParameterError(f"{path}: the scenario's impactor is a "
                                 f"{type(part).__name__.lower()}, which has no release angle")
    elif field not in {f.name for f in dataclasses.fields(part)}:
        raise ParameterError(f"{path}: the scenario's {section} is a "
                             f"{type(part).__name__.lower()}, which has no field {field!r}")
    if section == "contact" and field == "stiffness":
        changes["duration"] = None  # stiffness and duration are exclusive (analytic.Contact)
    elif section == "contact" and field == "duration":
        changes["stiffness"] = None
    return dataclasses.replace(scenario, **{section: dataclasses.replace(part, **changes)})


def _setter(path: str) -> Callable:
    return lambda scenario, value: set_field(scenario, path, value)


def _field(name, symbol, unit, low, high, label, path, sweep=None, shown=(1.0, ""),
           design=None, text="", meaning="") -> Parameter:
    """A parameter that one scenario field holds (swept by its path unless ``sweep``)."""
    return Parameter(name, symbol, unit, low, high, label, path, sweep or path, shown,
                     _setter(path), design, text=text, meaning=meaning,
                     unmeasured=_UNMEASURED.get(name), plausible=_PLAUSIBLE.get(name),
                     assumed=_ASSUMED.get(name), default=_DEFAULTS.get(name))


_INF = math.inf

#: Why the design study maps each designer's choice over its range (compare.studies.design).
_DESIGN = {
    "a_over_l": DesignRange(
        0.1, 0.6, (0.05, 1.0), False,
        "a shaker clamps between knee height and the first scaffold: 0.1-0.6 of the "
        "crown's height l on orchard trees (the shipped trees clamp at 0.315 m of 1 m)", 2.0),
    "mass_ratio": DesignRange(
        0.2, 5.0, (0.05, 20.0), True,
        "a light billet (a fifth of the tree's M_T) to a heavy pendulum (5 M_T); the "
        "paper's pendulum is 1.2 M_T on central-leader", 5.0),
    "contact_duration": DesignRange(
        2e-4, 5e-2, (1e-5, 0.1), True,
        "a hard impactor (0.2 ms, the shipped 0.5 ms) to a thick rubber pad (50 ms), the "
        "report's contact scan's range", 10.0),
    "restitution": DesignRange(
        0.0, 0.9, (0.0, 0.95), False,
        "a dead pad (0) to a bouncy one (0.9); the paper assumes e small, the shipped 0.1"),
}

#: The inputs nobody measured, as the sensitivity study varies them
#: (compare.studies.sensitivity).
_UNMEASURED = {
    "clamp_mass": UnmeasuredRange(
        1.0, 16.0, "the harvester's clamp: not weighed (the shipped 4 kg chosen)",
        "weigh the clamp and the trunk section it grips"),
    "e_over_g": UnmeasuredRange(
        0.0, 20.0, ("E / G of the trunk: 0 is the paper's Euler-Bernoulli beam; green "
                    "hardwood 10-20 (Wood Handbook)"),
        "a static push test at two heights, or the shear modulus of a core sample"),
    "log10_pad_duration": UnmeasuredRange(
        math.log10(2e-4), math.log10(2e-2),
        "the pad's stiffness as its 1-DOF collision time: a hard impactor (0.2 ms) to a "
        "padded one (20 ms)", "the contact force of one strike (a load cell at the pad)"),
    "restitution": UnmeasuredRange(
        0.05, 0.5, "the pad's e: not measured (the paper: small)",
        "the pendulum's rebound off a rigid stop (a drop test of the pad)"),
    "root_share": UnmeasuredRange(
        0.0, 0.9, ("the root's share of the static flexibility at the clamp: 0 reads Table "
                   "1's K_T by eq 47 (a rigid clamp, E 8.9e8 / 1.3e9 Pa), 0.9 the printed E "
                   "(8.9e9 / 12.6e9 Pa) with a compliant root"),
        "a static push test measuring the root's rotation"),
    "density": UnmeasuredRange(
        500.0, 1100.0, ("green wood: the trunk's share of M_T (the crown mass follows from "
                        "the measured M_T)"), "weigh a trunk section"),
    "damping_ratio": UnmeasuredRange(
        0.563, 0.601, ("the tree's own damping ratio C_T / (2 sqrt(K_T M_T)) (eq 14) of the "
                       "paper's two apple trees: C_T = 2 b (M_T + m) (eq 34) with b = -a2/a1 "
                       "of Figs 4-5 (eq 42), Table 1's M_T and K_T and the 132.4 kg pendulum: "
                       "0.601 open center, 0.563 central leader"),
        "a pendulum test: b = -a2/a1 of the moving-together motion (eq 42)"),
    "youngs_modulus": UnmeasuredRange(
        8.89e8, 1.263e9, ("E = K_T a^3 / (3 I) (eq 47) of Table 1's two trees with the paper's "
                          "rigid clamp: 8.89e8 open center, 1.263e9 Pa central leader (a tree from "
                          "its geometry that was not given E)"),
        "a static push test at the clamp (K_T) with the root held, or a core sample's E"),
}

#: What a tree from its geometry (``treeimpact scenario --crown-mass``) assumes for the
#: inputs its user did not measure: the paper's own assumptions or its two trees' measured
#: values in a form that transfers to another tree (compare.tree.scenario).
_ASSUMED = {
    "base_stiffness": Assumed(
        "root_share", 0.0, _UNMEASURED["root_share"].low, _UNMEASURED["root_share"].high,
        "the paper's own assumption: the trunk 'rigidly fixed to the ground' (eq 1), "
        "k_theta = inf; up to 0.9 of the static flexibility at the clamp is the root's when "
        "Table 1's printed E is to give its measured K_T (eq 8 with a root spring)"),
    "damping": Assumed(
        "damping_ratio", 0.582, _UNMEASURED["damping_ratio"].low,
        _UNMEASURED["damping_ratio"].high,
        "the paper gives no C (eq 9 assumes it proportional to velocity); its two trees' "
        "measured decay b (eq 42) as the tree's own damping ratio C_T / (2 sqrt(K_T M_T)) "
        "(eq 14), which does not depend on the pendulum: 0.563-0.601, their mean 0.582; "
        "C = C_T / J (eq 10 as derived)"),
    "youngs_modulus": Assumed(
        "youngs_modulus", 1.076e9, _UNMEASURED["youngs_modulus"].low,
        _UNMEASURED["youngs_modulus"].high,
        "E = K_T a^3 / (3 I) (eq 47) of Table 1's K_T, a and d: the E with which the paper's "
        "rigid clamp gives its two trees' measured K_T, 8.89e8 (open center) to 1.263e9 Pa "
        "(central leader), their mean 1.076e9; the printed 8.9e9 / 12.6e9 are ten times these "
        "(discrepancy 'eq 47')"),
    "density": Assumed(
        "density", 950.0, _UNMEASURED["density"].low, _UNMEASURED["density"].high,
        "green apple wood, the shipped trees' choice; the range green wood's (the sensitivity "
        "study's)"),
}

#: What orchard trees, harvesters and pads show of the scenario's fields (wider than the
#: shipped trees, narrower than the allowed range): beyond it a value is run and warned
#: about, since it is more often a slip of unit (radians for degrees, cm for m) than a tree.
_PLAUSIBLE = {
    "length": Plausible(0.3, 6.0, "a fruit tree's crown height; the paper's trees 0.75-1 m"),
    "clamp_height": Plausible(0.1, 2.0, "harvesters clamp between knee height and the first "
                              "scaffold; the paper's 0.315-0.354 m"),
    "diameter": Plausible(0.02, 0.5, "fruit-tree trunks at the clamp; the paper's "
                          "0.126-0.142 m"),
    "density": Plausible(300.0, 1300.0, "green wood, USDA Wood Handbook"),
    "youngs_modulus": Plausible(1e8, 3e10, "wood along the grain, green to dry, Wood "
                                "Handbook; the paper's eq 47 reading 8.9e8-1.3e9 Pa"),
    "impactor_mass": Plausible(1.0, 1000.0, "harvesters' pendulums and billets; the paper's "
                               "pendulum 132.4 kg"),
    "equivalent_length": Plausible(0.2, 5.0, "a harvester's pendulum arm; the paper's "
                                   "1.51 m"),
    "release_angle_deg": Plausible(2.0, 90.0, "a pendulum test's release; the paper's "
                                   "33.76-36.39 deg"),
    "gravity": Plausible(9.76, 9.84, "the Earth's surface, 9.78 at the equator to 9.83 at "
                         "the poles"),
    "impact_speed": Plausible(0.1, 10.0, "a pendulum or a billet at the clamp; the paper's "
                              "2.3-2.5 m/s"),
    "contact_duration": Plausible(1e-4, 0.05, "a hard impactor (0.1 ms) to a thick rubber "
                                  "pad (50 ms)"),
}

#: The values inputs take where a user gives none, each with its source: the only place
#: they are written (compare.tree.scenario, the pad law and the CLI read them here).
_DEFAULTS = {
    "length": Default(1.0, "the shipped trees' choice: about 1 m from the ground to the first "
                      "scaffold (the paper gives no l)"),
    "clamp_mass": Default(4.0, "the shipped trees' choice: a shaker clamp's jaws and pads on "
                          "the trunk"),
    "restitution": Default(0.1, "the paper gives no e ('very small'); 0.1 lies between the "
                           "estimates from Table 1's V, x0 and T0 (treeimpact paper)"),
    "contact_duration": Default(5e-4, "half a millisecond, well inside the paper's T0 of "
                                "4-6 ms: the impact stays short against the trunk's motion"),
    "t_end": Default(0.1, "past the shipped trees' x_max (9-30 ms) and their separation"),
}

#: Every physical input, scenario fields first (in LIMITS' order), then derived ones.
PARAMETERS = (
    _field("length", "l", "m", 0.1, 30.0, "trunk length", "trunk.length",
           meaning="the trunk's length, ground to crown"),
    _field("clamp_height", "a", "m", 0.01, 30.0, "clamp height", "trunk.clamp_height",
           meaning="the clamp's (impact) height above the ground"),
    _field("diameter", "d", "m", 0.005, 3.0, "trunk diameter", "trunk.diameter",
           meaning="the trunk's diameter"),
    _field("density", "rho", "kg/m^3", 100.0, 2000.0, "wood density", "trunk.density",
           meaning="the wood's density"),
    _field("youngs_modulus", "E", "Pa", 1e7, 1e11, "Young's modulus", "trunk.youngs_modulus",
           meaning="the wood's Young's modulus"),
    _field("clamp_mass", "m_c", "kg", 0.0, 1000.0, "clamp mass", "trunk.clamp_mass",
           meaning="the clamp's mass on the trunk"),
    _field("crown_mass", "m_f", "kg", 0.0, 1e4, "crown mass", "trunk.crown_mass",
           meaning="the crown's mass at l: fruit, leaves and scaffolds, lumped (eq 7)"),
    _field("damping", "C", "N s/m^2", 0.0, 1e6, "distributed damping", "trunk.damping"),
    _field("base_stiffness", "k_theta", "N m/rad", 10.0, _INF, "root stiffness",
           "trunk.base_stiffness"),
    _field("shear_modulus", "G", "Pa", 1e6, _INF, "shear modulus", "trunk.shear_modulus"),
    _field("shear_coefficient", "kappa", "1", 0.1, 1.0, "shear coefficient",
           "trunk.shear_coefficient"),
    _field("impactor_mass", "m", "kg", 0.1, 1e4, "impactor mass", "impactor.mass",
           meaning="the pendulum's (impactor's) mass"),
    _field("equivalent_length", "l_e", "m", 0.05, 30.0, "pendulum length",
           "impactor.equivalent_length", meaning="the pendulum's equivalent length"),
    _field("release_angle_deg", "theta_r", "deg", 0.01, 180.0, "release angle",
           "impactor.release_angle_deg", meaning="the pendulum's release angle"),
    _field("gravity", "g", "m/s^2", 1.0, 30.0, "gravity", "impactor.gravity"),
    _field("impact_speed", "u_1", "m/s", 0.01, 50.0, "impact speed", "impactor.impact_speed"),
    _field("impactor_stiffness", "k", "N/m", 0.0, 1e9, "impactor spring",
           "impactor.stiffness", meaning="the impactor's spring k: a billet's as given (0: "
           "a free billet), a pendulum's m g / l_e (eq 13)"),
    _field("restitution", "e", "1", 0.0, 1.0, "pad restitution", "contact.restitution",
           "restitution", design=_DESIGN["restitution"],
           meaning="restitution e of the contact (eq 21)"),
    _field("contact_stiffness", "k_c", "N/m", 1e2, 1e12, "pad stiffness", "contact.stiffness",
           "contact_stiffness", meaning="the pad's stiffness k_c"),
    _field("contact_duration", "tau_c", "s", 1e-6, 0.1, "contact duration",
           "contact.duration", "contact_duration", (1e3, "ms"), _DESIGN["contact_duration"],
           "contact duration", meaning="the pad, as the undamped collision time "
           "pi sqrt(mu / k_c) of the 1-DOF pair"),
    _field("t_end", "t_end", "s", 1e-4, 10.0, "simulated time", "t_end",
           meaning="simulated time"),
    Parameter("a_over_l", "a / l", "1", 0.0, _INF, "clamp height a / l", None, "a_over_l",
              design=_DESIGN["a_over_l"], sets="trunk.clamp_height",
              meaning="clamp (impact) height over trunk length"),
    Parameter("crown_ratio", "m_f / m_trunk", "1", 0.0, _INF, "crown mass / trunk mass",
              None, "crown_ratio", sets="trunk.crown_mass",
              meaning="crown mass over trunk mass rho A l"),
    Parameter("mass_ratio", "m / M_T", "1", 0.0, _INF, "mass ratio m / M_T", None,
              "mass_ratio", design=_DESIGN["mass_ratio"], sets="impactor.mass",
              meaning="impactor mass over the dynamic mass (eq 7)"),
    Parameter("dynamic_mass", "M_T", "kg", 0.0, _INF, "dynamic mass (eq 7)",
              meaning="the tree's dynamic mass at the clamp (eq 7)"),
    Parameter("equivalent_stiffness", "K_T", "N/m", 0.0, _INF, "equivalent stiffness (eq 8)",
              meaning="the tree's equivalent spring stiffness at the clamp (eq 8)"),
    Parameter("equivalent_damping", "C_T", "N s/m", 0.0, _INF, "equivalent damping (eq 10)"),
    Parameter("damping_rate", "b", "1/s", 0.0, _INF,
              "damping rate C_T / (2 (M_T + m)) (eq 42)",
              meaning="the moving-together motion's decay rate C_T / (2 (M_T + m)) (eq 42)"),
    Parameter("damping_ratio", "xi_T", "1", 0.0, 10.0,
              "tree's damping ratio",
              meaning="the tree's own damping ratio C_T / (2 sqrt(K_T M_T)) (eq 14)",
              unmeasured=_UNMEASURED["damping_ratio"]),
    Parameter("contact_damping", "c_c", "N s/m", 0.0, _INF, "pad damping",
              meaning="the pad's damping c_c (set by e on a scenario)"),
    Parameter("e_over_g", "E / G", "1", 0.0, 20.0, "E / G (shear)",
              unmeasured=_UNMEASURED["e_over_g"]),
    Parameter("log10_pad_duration", "log10 tau_c", "log10 s", math.log10(2e-4),
              math.log10(2e-2), "pad contact duration",
              unmeasured=_UNMEASURED["log10_pad_duration"]),
    Parameter("root_share", "root share", "1", 0.0, 0.9, "root compliance",
              unmeasured=_UNMEASURED["root_share"]),
)

#: name -> Parameter.
BY_NAME = {p.name: p for p in PARAMETERS}
#: dotted scenario path -> Parameter, for the parameters one field holds.
BY_PATH = {p.path: p for p in PARAMETERS if p.path is not None}
#: sweep axis name -> Parameter.
BY_SWEEP = {p.sweep: p for p in PARAMETERS if p.sweep is not None}
#: the paper's symbol -> Parameter (M_T, K_T, C_T, E, ...).
BY_SYMBOL = {p.symbol: p for p in PARAMETERS}


#: The inputs a tree from its geometry assumes -> the parameter's name (registry order).
ASSUMED = {p.name: p.assumed for p in PARAMETERS if p.assumed is not None}


def assumed_table() -> str:
    """What a tree from its geometry assumes, as a Markdown table (docs/parameters.md holds
    it): the input, the value assumed and its range in the dimensionless form stated, and
    why."""
    rows = ["| input | assumed, as | value | range | why |", "|---|---|---|---|---|"]
    for name, a in ASSUMED.items():
        via = BY_NAME[a.via]
        unit = "" if via.unit == "1" else f" {via.unit}"
        rows.append(f"| `{name}` | {via.symbol} (`{a.via}`) | {_cell(a.value)}{unit} | "
                    f"[{_cell(a.low)}, {_cell(a.high)}]{unit} | {a.why} |")
    return "\n".join(rows) + "\n"


def units_of(*keys: str) -> dict:
    """{key: the registry's unit} for keys that are a parameter's name, path, sweep name or
    symbol (``"K_T"`` -> ``"N/m"``): what a unit table takes from the registry. KeyError
    for a key that is none of these."""
    out = {}
    for key in keys:
        for table in (BY_NAME, BY_PATH, BY_SWEEP, BY_SYMBOL):
            if key in table:
                out[key] = table[key].unit
                break
        else:
            raise KeyError(f"{key!r}: not a parameter of the registry")
    return out


def default_of(name: str) -> float:
    """The value the input ``name`` takes where none is given (its unit): its
    :class:`Default`, else the value a tree from its geometry assumes for it in its own
    unit (the density). KeyError for an input that has neither."""
    p = BY_NAME[name]
    if p.default is not None:
        return p.default.value
    if p.assumed is not None and p.assumed.via == name:
        return p.assumed.value
    raise KeyError(f"{name!r}: no default in the registry")


def parameter(name: str) -> Parameter:
    """The :class:`Parameter` a name, a path or a sweep name means; ParameterError naming
    the allowed names otherwise."""
    for table in (BY_NAME, BY_PATH, BY_SWEEP):
        if name in table:
            return table[name]
    raise ParameterError(f"{name!r}: not a parameter; allowed: {', '.join(BY_NAME)}")


def _cell(x: float) -> str:
    return "inf" if math.isinf(x) else f"{x:g}"


def registry_table() -> str:
    """The registry as a Markdown table (docs/parameters.md holds it): name, symbol, unit,
    range, plausible range with its source, default with its source, label, scenario path
    (or the field a ratio sets) and sweep name."""
    rows = ["| name | symbol | unit | range | plausible (warned beyond) | default | label | "
            "sets | sweep |", "|---|---|---|---|---|---|---|---|---|"]
    for p in PARAMETERS:
        sets = f"`{p.path}`" if p.path else (f"`{p.sets}` (ratio)" if p.sets else "a reading")
        seen = (f"[{_cell(p.plausible.low)}, {_cell(p.plausible.high)}]: {p.plausible.source}"
                if p.plausible else "")
        default = f"{_cell(p.default.value)}: {p.default.source}" if p.default else ""
        rows.append(f"| `{p.name}` | {p.symbol} | {p.unit} | [{_cell(p.low)}, {_cell(p.high)}] "
                    f"| {seen} | {default} | {p.label} | {sets} | "
                    f"{f'`{p.sweep}`' if p.sweep else ''} |")
    return "\n".join(rows) + "\n"
