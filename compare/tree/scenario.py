"""A scenario for a user's own tree (the ``scenario`` command and
:func:`compare.interface.api.tree_scenario` both build it here), one of two ways:

* measured: M_T, K_T and b (or the regression a1, a2, x_max, tau of Figs 4-5) of a pendulum
  test with the chosen l, rho, E, m_c become a trunk by
  :func:`analytic.model.calibration.calibrate_trunk`;
* from its geometry: l, a, d, m_c and a crown mass estimate m_f (no pendulum test), the root
  spring, the damping and (when not given) E and rho assumed as the registry declares them
  (:func:`analytic.model.assumed.geometry_trunk`); M_T, K_T, C_T follow (eqs 7, 8, 10).

The scenario's notes record which values were given, chosen, calibrated or assumed (each
assumption's value, range and reason), as the shipped files do, and its t_end is one its
analytic run can report. Errors name the command's flags (the API names them as its
keywords). SI units.
"""

from __future__ import annotations

import dataclasses
import math
import numbers
from dataclasses import dataclass

from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.model.assumed import geometry_trunk
from treeimpact.analytic.model.calibration import (
    MeasuredTree,
    calibrate_trunk,
    calibration_notes,
    damping_rate_from_regression,
    stiffness_from_regression,
)
from treeimpact.analytic.model.parameters import (
    LIMITS,
    Contact,
    Pendulum,
    Scenario,
    Trunk,
    check_range,
)
from treeimpact.analytic.model.plausible import implausible, warn_implausible
from treeimpact.analytic.model.reduction import reduce_trunk
from treeimpact.analytic.model.registry import BY_NAME, default_of

from ..runs.backends import get_backend
from ..runs.names import NAMING, show

#: Removed spellings of the inputs -> their names now (compare.runs.names.did_you_mean): the
#: ``scenario`` command's flags and :func:`treeimpact.tree_scenario`'s keywords both refuse
#: them with the new name.
RENAMED = {"stiffness": "equivalent_stiffness", "release_angle": "release_angle_deg",
           "mass": "impactor_mass"}
#: Chosen values when not given: the registry's defaults, each with its source (the density
#: the registry's assumed green apple wood; analytic.model.registry).
DEFAULTS = {name: default_of(name) for name in
            ("length", "density", "clamp_mass", "restitution", "contact_duration", "t_end")}
#: The inputs of a pendulum test's measured tree; a tree from its geometry gives none of
#: them (it gives the crown mass, :data:`GEOMETRY`).
MEASURED = ("dynamic_mass", "equivalent_stiffness", "damping_rate", "a1", "a2", "x_max", "tau")
#: The inputs only a tree from its geometry gives.
GEOMETRY = ("crown_mass",)
#: The inputs every tree gives (the test and the tree's geometry at the clamp).
REQUIRED = ("clamp_height", "diameter", "impactor_mass", "equivalent_length",
            "release_angle_deg")


@dataclass(frozen=True)
class TreeInputs:
    """What a user's tree scenario is built from (registry names, SI units): the test
    (given), the tree either measured (M_T, and K_T or x_max and tau, and b or a1 and a2,
    the regression of Figs 4-5; E required) or from its geometry (the crown mass m_f; E
    and rho assumed when not given), and the choices (None: :data:`DEFAULTS`)."""

    name: str
    clamp_height: float  # a, m
    diameter: float  # d, m
    impactor_mass: float  # m, kg
    equivalent_length: float  # l_e, m
    release_angle_deg: float  # theta_r, deg
    dynamic_mass: float | None = None  # M_T, kg
    youngs_modulus: float | None = None  # E, Pa
    crown_mass: float | None = None  # m_f, kg: a tree from its geometry
    equivalent_stiffness: float | None = None  # K_T, N/m
    damping_rate: float | None = None  # b, 1/s
    a1: float | None = None  # regression a1 = V, m/s (eq 40)
    a2: float | None = None  # regression a2, m/s^2 (eq 40)
    x_max: float | None = None  # largest displacement, m (eq 38)
    tau: float | None = None  # time of x_max from the extrapolated origin, s
    length: float | None = None  # l, m
    density: float | None = None  # rho, kg/m^3
    clamp_mass: float | None = None  # m_c, kg
    restitution: float | None = None  # e, 1
    contact_duration: float | None = None  # tau_c, s
    t_end: float | None = None  # s


def _range_of(key: str) -> tuple:
    """(low, high or None, unit) of the input ``key``: the registry's declared range (a
    regression input's, :data:`REGRESSION_RANGES`)."""
    if key in REGRESSION_RANGES:
        return REGRESSION_RANGES[key]
    p = BY_NAME[key]
    return p.low, None if math.isinf(p.high) else p.high, p.unit


def check_keywords(name, measured: dict) -> None:
    """The keywords ``measured`` ({keyword: value}) of :func:`treeimpact.tree_scenario`
    checked where they enter, one line naming the keyword as typed: ``name`` a text (TypeError otherwise), every required input
    given (ParameterError naming the first missing and every required one), every input
    given a real number (TypeError: a bool, a text or a list is not one) within the
    registry's declared range (ParameterError; analytic.model.registry). None means left
    out. Unknown keywords are the caller's to refuse (with what they may have meant). Named
    as flags (``--clamp-height``) while a command of the command line calls it (NAMING)."""
    style = NAMING.get()
    if not isinstance(name, str) or not name.strip():
        raise TypeError(f"name: expected the scenario's name, a non-empty str, got {name!r}")
    required = list(REQUIRED)
    missing = [k for k in required if measured.get(k) is None]
    if missing:
        unit = _range_of(missing[0])[2]
        what = "a number" if unit == "1" else f"a number in {unit}"
        raise ParameterError(f"{show(missing[0], style)}: missing ({what}); required: "
                             f"{', '.join(show(k, style) for k in required)}")
    for key, value in measured.items():
        if value is None:
            continue
        low, high, unit = _range_of(key)
        if isinstance(value, bool) or not isinstance(value, numbers.Real):
            what = "a number" if unit == "1" else f"a number in {unit}"
            raise TypeError(f"{show(key, style)}: expected {what}, got {value!r} "
                            f"({type(value).__name__})")
        check_range(show(key, style), float(value), low=low, high=high,
                    unit="" if unit == "1" else unit, low_open=_low_open(key))


def tree_scenario(inputs: TreeInputs) -> Scenario:
    """The calibrated :class:`Scenario` of ``inputs`` with a t_end its run can report
    (:func:`fit_t_end`). ParameterError naming the flag (``--damping-rate``) of a missing,
    contradictory or out-of-range input; OutsideValidity for a tree whose analytic x_max
    lies beyond the clamp height. An input outside what trees and harvesters show warns
    (ImplausibleInput, one line each)."""
    try:
        scenario = fit_t_end(build_scenario(inputs), given=inputs.t_end is not None)
    except ParameterError as exc:
        raise _as_flags(exc) from None
    warn_implausible(implausible(scenario))
    return scenario


#: Allowed ranges of the regression's inputs (Figs 4-5), SI: a1 = V up to 100 m/s (a pendulum
#: of the allowed l_e and theta_r is far slower), a2 down to -1e6 m/s^2, x_max up to the
#: clamp height a (the small-deflection trunk of eq 1 cannot move further), tau up to the
#: longest run, 10 s; beyond them e^(b tau) and b leave double precision.
REGRESSION_RANGES = {"a1": (0.0, 100.0, "m/s"), "a2": (-1e6, 0.0, "m/s^2"),
                     "x_max": (0.0, None, "m"), "tau": (0.0, 10.0, "s")}


def check_regression(inputs: TreeInputs) -> None:
    """--a1, --a2, --x-max and --tau of ``inputs`` (those given) in
    :data:`REGRESSION_RANGES` (x_max at most --clamp-height), one line naming the flag."""
    for key, (low, high, unit) in REGRESSION_RANGES.items():
        value = getattr(inputs, key)
        if value is None:
            continue
        if key == "x_max":
            high = check_range("--clamp-height", inputs.clamp_height, low=0.0, low_open=True,
                               unit="m")
        check_range(f"--{key.replace('_', '-')}", value, low=low, high=high, unit=unit,
                    low_open=_low_open(key))


def _low_open(key: str) -> bool:
    """Whether a regression input's range excludes its low end: a1 = V, x_max and tau are
    positive (0 has no maximum of eq 38 to read), a2 may be 0 (no damping)."""
    return key in REGRESSION_RANGES and key != "a2"


def _stiffness(inputs: TreeInputs, pendulum) -> float:
    """K_T (N/m) from --a1, --a2, --x-max, --tau (eqs 43, 46); an e^(b tau) beyond double
    precision is the overdamped motion it means (omega_n = 0 <= b), one line."""
    try:
        return stiffness_from_regression(
            a1=inputs.a1, a2=inputs.a2, x_max=inputs.x_max, tau=inputs.tau,
            dynamic_mass=inputs.dynamic_mass, impactor_mass=inputs.impactor_mass,
            impactor_stiffness=pendulum.stiffness)
    except OverflowError:
        b = -inputs.a2 / inputs.a1
        raise ParameterError(f"--a1 = {inputs.a1:g} m/s, --a2 = {inputs.a2:g} m/s^2, --tau = "
                             f"{inputs.tau:g} s: b tau = {b * inputs.tau:.4g}, so omega_n = a1 / "
                             "(x_max e^(b tau)) is 0 <= b: an overdamped motion with no "
                             "maximum of that kind (eqs 37, 43)") from None


def _pick(inputs: TreeInputs, key: str):
    v = getattr(inputs, key)
    return DEFAULTS[key] if v is None else v


def _as_typed(exc: ParameterError, inputs: TreeInputs) -> ParameterError:
    """``exc`` (calibrate_trunk's, naming b or K_T) led by the flags typed when the
    quantity came from the regression (b from --a1 and --a2, K_T from --x-max and --tau)."""
    text = str(exc)
    if text.startswith("damping_rate") and inputs.damping_rate is None:
        return ParameterError(f"--a1 = {inputs.a1:g} m/s, --a2 = {inputs.a2:g} m/s^2 give "
                              f"b = -a2/a1 (eq 42): {text}")
    if text.startswith("equivalent_stiffness") and inputs.equivalent_stiffness is None:
        return ParameterError(f"--x-max = {inputs.x_max:g} m, --tau = {inputs.tau:g} s give "
                              f"K_T (eqs 43, 46): {text}")
    return exc


def check_way(inputs: TreeInputs) -> bool:
    """Whether ``inputs`` build a tree from its geometry (--crown-mass) rather than a
    measured one (--dynamic-mass and the rest of :data:`MEASURED`); ParameterError in one
    line naming the flags typed when both ways are mixed, or the two ways when neither is
    given."""
    measured = [show(k) for k in MEASURED if getattr(inputs, k) is not None]
    geometry = [show(k) for k in GEOMETRY if getattr(inputs, k) is not None]
    if measured and geometry:
        raise ParameterError(
            f"{geometry[0]}: a tree from its geometry (--crown-mass) or a measured tree "
            f"(--dynamic-mass, ...), not both; given {', '.join(geometry + measured)}")
    if not measured and not geometry:
        raise ParameterError(
            "--dynamic-mass: missing (a measured tree: M_T in kg with K_T and b, or a tree "
            "from its geometry: --crown-mass in kg)")
    return bool(geometry)


def build_scenario(inputs: TreeInputs) -> Scenario:
    """The :class:`Scenario` of ``inputs`` (measured and calibrated, or from its geometry:
    :func:`check_way`), its t_end as given or the default."""
    pendulum = Pendulum(mass=inputs.impactor_mass, equivalent_length=inputs.equivalent_length,
                        release_angle_deg=inputs.release_angle_deg)
    if check_way(inputs):
        trunk, notes = _geometry(inputs)
        return _scenario(inputs, trunk, pendulum, notes, "built from its geometry")
    for key, unit in (("dynamic_mass", "kg"), ("youngs_modulus", "Pa")):
        if getattr(inputs, key) is None:
            raise ParameterError(
                f"{show(key)}: missing (a number in {unit}); a measured tree requires "
                f"{', '.join(show(k) for k in (*REQUIRED, 'dynamic_mass', 'youngs_modulus'))}"
                " with K_T and b (a tree from its geometry: --crown-mass instead of M_T, "
                "K_T and b)")
    check_regression(inputs)
    given = ["a", "d", "theta_r", "m", "l_e", "M_T"]
    if inputs.damping_rate is not None:
        if inputs.a1 is not None or inputs.a2 is not None:
            raise ParameterError("--damping-rate: give it or --a1 and --a2, not both")
        b = inputs.damping_rate
        given.append("b")
    elif inputs.a1 is not None and inputs.a2 is not None:
        b = damping_rate_from_regression(inputs.a1, inputs.a2)
        given.append(f"b = -a2/a1 (eq 42) from a1 = {inputs.a1:g} m/s, a2 = {inputs.a2:g} m/s^2")
    else:
        raise ParameterError("--damping-rate: missing (give b in 1/s, or --a1 and --a2)")
    if inputs.equivalent_stiffness is not None:
        if inputs.x_max is not None or inputs.tau is not None:
            raise ParameterError("--equivalent-stiffness: give it or --x-max and --tau, not "
                                 "both")
        equivalent_stiffness = inputs.equivalent_stiffness
        given.append("K_T")
    elif None not in (inputs.x_max, inputs.tau, inputs.a1, inputs.a2):
        equivalent_stiffness = _stiffness(inputs, pendulum)
        given.append(f"K_T from x_max = {inputs.x_max:g} m, tau = {inputs.tau:g} s (eqs 43, 46)")
    else:
        raise ParameterError("--equivalent-stiffness: missing (give K_T in N/m, or --x-max, "
                             "--tau, --a1 and --a2)")
    measured = MeasuredTree(dynamic_mass=inputs.dynamic_mass,
                            equivalent_stiffness=equivalent_stiffness, damping_rate=b)
    chosen = Trunk(length=_pick(inputs, "length"), clamp_height=inputs.clamp_height,
                   diameter=inputs.diameter, density=_pick(inputs, "density"),
                   youngs_modulus=inputs.youngs_modulus, clamp_mass=_pick(inputs, "clamp_mass"))
    try:
        trunk = calibrate_trunk(chosen, measured, impactor_mass=inputs.impactor_mass)
    except ParameterError as exc:
        raise _as_typed(exc, inputs) from None
    chosen_names = [f"{sym} = {_pick(inputs, k):g} {unit}" for sym, k, unit in (
        ("l", "length", "m"), ("rho", "density", "kg/m^3"), ("m_c", "clamp_mass", "kg"))]
    notes = calibration_notes(measured, given=", ".join(given),
                              chosen=", ".join([f"E = {inputs.youngs_modulus:g} Pa",
                                                *chosen_names]))
    return _scenario(inputs, trunk, pendulum, notes, "calibrated")


def _scenario(inputs: TreeInputs, trunk, pendulum, notes: dict, how: str) -> Scenario:
    """The scenario of ``trunk`` and ``pendulum`` with the chosen pad and t_end, its notes
    ``notes`` and the restitution chosen; ``how`` it was built, for its description."""
    notes = {**notes, "restitution": f"e = {_pick(inputs, 'restitution'):g} chosen"}
    contact = Contact(restitution=_pick(inputs, "restitution"),
                      duration=_pick(inputs, "contact_duration"))
    return Scenario(name=inputs.name, trunk=trunk, impactor=pendulum, contact=contact,
                    t_end=_pick(inputs, "t_end"),
                    description=f"{inputs.name}: {how} by treeimpact scenario", notes=notes)


def _geometry(inputs: TreeInputs) -> tuple:
    """(trunk, notes) of a tree from its geometry (:func:`analytic.model.assumed.
    geometry_trunk`): what was given, chosen and assumed, and the M_T, K_T, C_T that
    follow (eqs 7, 8, 10). A given density is measured (the study holds it)."""
    built = geometry_trunk(length=_pick(inputs, "length"), clamp_height=inputs.clamp_height,
                           diameter=inputs.diameter, clamp_mass=_pick(inputs, "clamp_mass"),
                           crown_mass=inputs.crown_mass, density=inputs.density,
                           youngs_modulus=inputs.youngs_modulus)
    given = ["a", "d", "theta_r", "m", "l_e", f"m_f = {inputs.crown_mass:g} kg (a crown mass "
             "estimate)"]
    given += [f"{sym} = {v:g} {unit}" for sym, v, unit in (
        ("E", inputs.youngs_modulus, "Pa"), ("rho", inputs.density, "kg/m^3")) if v is not None]
    chosen = [f"{sym} = {_pick(inputs, k):g} {unit}" for sym, k, unit in (
        ("l", "length", "m"), ("m_c", "clamp_mass", "kg"))]
    tree = reduce_trunk(built.trunk)
    notes = {"given": ", ".join(given), "chosen": ", ".join(chosen),
             "assumed": list(built.assumed), **built.notes,
             "derived": (f"M_T = {tree.dynamic_mass:.6g} kg (eq 7), K_T = "
                         f"{tree.equivalent_stiffness:.6g} N/m (eq 8), C_T = "
                         f"{tree.equivalent_damping:.6g} N s/m (eq 10) from the geometry, the "
                         "crown and the assumptions; no pendulum test")}
    if inputs.density is not None:
        notes["measured"] = ["trunk.density"]
    return built.trunk, notes


#: The model fields the command's flags set -> the flag (an error names what was typed).
#: (Read from :class:`TreeInputs`: each registry quantity by its scenario path, or its name
#: for a reading; the regression's inputs by their names.)
FLAGS = {**{BY_NAME[f.name].path or f.name: show(f.name)
            for f in dataclasses.fields(TreeInputs) if f.name in BY_NAME},
         **{n: show(n) for n in REGRESSION_RANGES}}


def _as_flags(exc: ParameterError) -> ParameterError:
    """``exc`` with the model field it starts with named as the flag that set it."""
    text = str(exc)
    for field, flag in sorted(FLAGS.items(), key=lambda kv: -len(kv[0])):
        if text.startswith(field) and text[len(field):len(field) + 1] in (" ", ":"):
            return ParameterError(flag + text[len(field):])
    return exc


def fit_t_end(scenario, given: bool):
    """``scenario`` with a t_end (s) its run can report: the analytic model's x_max and the
    separation inside it. A ``given`` t_end is kept or refused (naming --t-end); the default
    is doubled until the run fits, up to the limit of t_end (10 s), else refused."""
    analytic = get_backend("analytic")
    t_end = scenario.t_end
    while True:
        try:
            analytic.simulate(dataclasses.replace(scenario, t_end=t_end))
            if t_end == scenario.t_end:
                return scenario
            notes = {**scenario.notes, "t_end": (
                f"t_end = {t_end:g} s: {scenario.t_end:g} s doubled until the analytic "
                "model's x_max and separation lie inside the run")}
            return dataclasses.replace(scenario, t_end=t_end, notes=notes)
        except ParameterError as exc:
            if given or not str(exc).startswith("--t-end") or 2 * t_end > LIMITS["t_end"][1]:
                raise ParameterError(f"{exc} (the tree written would not run: the longest "
                                     f"allowed is {LIMITS['t_end'][1]:g} s)" if not given
                                     else str(exc)) from None
            t_end *= 2.0
