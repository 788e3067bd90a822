"""``treeimpact scenario``: a scenario file for a user's own tree from measured quantities.

The measured M_T, K_T and b (or the regression a1, a2, x_max, tau of Figs 4-5) and the
chosen l, rho, E, m_c become a trunk by :func:`analytic.model.calibration.calibrate_trunk`; the
file records which values were given, chosen and calibrated, as the shipped files do.
"""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

from treeimpact.analytic.errors import ParameterError
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
from treeimpact.analytic.model.registry import BY_NAME
from treeimpact.analytic.model.scenario_toml import scenario_toml
from treeimpact.compare.backends import get_backend

from ..exits import ExitCode
from ..names import show
from ._common import add_parameter_flag, number

NAME = "scenario"
HELP = "write a scenario file for your own tree from measured M_T, K_T, b"
#: Removed spellings -> their names now (compare.names).
RENAMED = {"stiffness": "equivalent_stiffness", "release_angle": "release_angle_deg",
           "mass": "impactor_mass"}

#: Chosen values when not given: the shipped trees' choices (analytic/model/scenarios/*.toml).
DEFAULTS = {"length": 1.0, "density": 950.0, "clamp_mass": 4.0, "restitution": 0.1,
            "contact_duration": 5e-4, "t_end": 0.1}


def add_arguments(sp: argparse.ArgumentParser) -> None:
    """The command's flags, added to its subparser ``sp``: the test (given), the tree
    (measured), the choices."""
    sp.add_argument("name", help="the scenario's name (also the file name with --out DIR)")
    g = sp.add_argument_group("the test (given)")
    for name in ("clamp_height", "diameter", "impactor_mass", "equivalent_length",
                 "release_angle_deg"):
        add_parameter_flag(g, name, required=True)
    m = sp.add_argument_group("the tree (measured)")
    add_parameter_flag(m, "dynamic_mass", required=True)
    add_parameter_flag(m, "equivalent_stiffness", note="or --x-max and --tau")
    add_parameter_flag(m, "damping_rate", note="or --a1 and --a2")
    m.add_argument("--a1", type=number, help="regression a1 = V, m/s (eq 40)")
    m.add_argument("--a2", type=number, help="regression a2, m/s^2 (eq 40)")
    m.add_argument("--x-max", type=number, help="largest displacement, m (eq 38)")
    m.add_argument("--tau", type=number, help="time of x_max from the extrapolated origin, s")
    c = sp.add_argument_group("chosen (defaults: the shipped trees' choices)")
    add_parameter_flag(c, "youngs_modulus", required=True,
                       note="Table 1 gives 8.9e9 and 12.6e9 for its two trees")
    for name, value in DEFAULTS.items():
        add_parameter_flag(c, name, note=f"default {value:g}")
    sp.add_argument("--out", help="write the file here (a directory: NAME.toml in it); "
                                  "default: print it")


#: Allowed ranges of the regression's inputs (Figs 4-5), SI: a1 = V up to 100 m/s (a pendulum
#: of the allowed l_e and theta_r is far slower), a2 down to -1e6 m/s^2, x_max up to the
#: clamp height a (the small-deflection trunk of eq 1 cannot move further), tau up to the
#: longest run, 10 s; beyond them e^(b tau) and b leave double precision.
REGRESSION_RANGES = {"a1": (0.0, 100.0, "m/s"), "a2": (-1e6, 0.0, "m/s^2"),
                     "x_max": (0.0, None, "m"), "tau": (0.0, 10.0, "s")}


def check_regression(args) -> None:
    """--a1, --a2, --x-max and --tau of the parsed ``args`` (those given) in
    :data:`REGRESSION_RANGES` (x_max at most --clamp-height), one line naming the flag."""
    for key, (low, high, unit) in REGRESSION_RANGES.items():
        value = getattr(args, key)
        if value is None:
            continue
        if key == "x_max":
            high = check_range("--clamp-height", args.clamp_height, low=0.0, low_open=True,
                               unit="m")
        check_range(f"--{key.replace('_', '-')}", value, low=low, high=high, unit=unit,
                    low_open=key != "a2")


def _stiffness(args, pendulum) -> float:
    """K_T (N/m) from --a1, --a2, --x-max, --tau (eqs 43, 46); an e^(b tau) beyond double
    precision is the overdamped motion it means (omega_n = 0 <= b), one line."""
    try:
        return stiffness_from_regression(
            a1=args.a1, a2=args.a2, x_max=args.x_max, tau=args.tau,
            dynamic_mass=args.dynamic_mass, impactor_mass=args.impactor_mass,
            impactor_stiffness=pendulum.stiffness)
    except OverflowError:
        b = -args.a2 / args.a1
        raise ParameterError(f"--a1 = {args.a1:g} m/s, --a2 = {args.a2:g} m/s^2, --tau = "
                             f"{args.tau:g} s: b tau = {b * args.tau:.4g}, so omega_n = a1 / "
                             "(x_max e^(b tau)) is 0 <= b: an overdamped motion with no "
                             "maximum of that kind (eqs 37, 43)") from None


def _pick(args, key):
    v = getattr(args, key)
    return DEFAULTS[key] if v is None else v


def build_scenario(args):
    """The calibrated :class:`Scenario` of the command's parsed arguments ``args``."""
    pendulum = Pendulum(mass=args.impactor_mass, equivalent_length=args.equivalent_length,
                        release_angle_deg=args.release_angle_deg)
    check_regression(args)
    given = ["a", "d", "theta_r", "m", "l_e", "M_T"]
    if args.damping_rate is not None:
        if args.a1 is not None or args.a2 is not None:
            raise ParameterError("--damping-rate: give it or --a1 and --a2, not both")
        b = args.damping_rate
        given.append("b")
    elif args.a1 is not None and args.a2 is not None:
        b = damping_rate_from_regression(args.a1, args.a2)
        given.append(f"b = -a2/a1 (eq 42) from a1 = {args.a1:g} m/s, a2 = {args.a2:g} m/s^2")
    else:
        raise ParameterError("--damping-rate: missing (give b in 1/s, or --a1 and --a2)")
    if args.equivalent_stiffness is not None:
        if args.x_max is not None or args.tau is not None:
            raise ParameterError("--equivalent-stiffness: give it or --x-max and --tau, not "
                                 "both")
        equivalent_stiffness = args.equivalent_stiffness
        given.append("K_T")
    elif None not in (args.x_max, args.tau, args.a1, args.a2):
        equivalent_stiffness = _stiffness(args, pendulum)
        given.append(f"K_T from x_max = {args.x_max:g} m, tau = {args.tau:g} s (eqs 43, 46)")
    else:
        raise ParameterError("--equivalent-stiffness: missing (give K_T in N/m, or --x-max, "
                             "--tau, --a1 and --a2)")
    measured = MeasuredTree(dynamic_mass=args.dynamic_mass,
                            equivalent_stiffness=equivalent_stiffness, damping_rate=b)
    chosen = Trunk(length=_pick(args, "length"), clamp_height=args.clamp_height,
                   diameter=args.diameter, density=_pick(args, "density"),
                   youngs_modulus=args.youngs_modulus, clamp_mass=_pick(args, "clamp_mass"))
    trunk = calibrate_trunk(chosen, measured, impactor_mass=args.impactor_mass)
    chosen_names = [f"{sym} = {_pick(args, k):g} {unit}" for sym, k, unit in (
        ("l", "length", "m"), ("rho", "density", "kg/m^3"), ("m_c", "clamp_mass", "kg"))]
    notes = calibration_notes(measured, given=", ".join(given),
                              chosen=", ".join([f"E = {args.youngs_modulus:g} Pa",
                                                *chosen_names]))
    notes["restitution"] = f"e = {_pick(args, 'restitution'):g} chosen"
    contact = Contact(restitution=_pick(args, "restitution"),
                      duration=_pick(args, "contact_duration"))
    return Scenario(name=args.name, trunk=trunk, impactor=pendulum, contact=contact,
                    t_end=_pick(args, "t_end"),
                    description=f"{args.name}: calibrated by treeimpact scenario", notes=notes)


#: The model fields the command's flags set -> the flag (an error names what was typed).
FLAGS = {**{BY_NAME[n].path or n: show(n) for n in (
    "impactor_mass", "equivalent_length", "release_angle_deg", "clamp_height", "diameter",
    "length", "density", "youngs_modulus", "clamp_mass", "restitution", "contact_duration",
    "t_end", "dynamic_mass", "equivalent_stiffness", "damping_rate")},
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


def run(args) -> int:
    """Write (or print) the scenario file of the parsed command line ``args``, one that
    runs (:func:`fit_t_end`); exit code 0. Bad input is a ParameterError naming the flag
    (exit 2); a tree whose analytic x_max lies beyond the clamp height is OutsideValidity
    (exit 4, nothing written)."""
    try:
        scenario = fit_t_end(build_scenario(args), given=args.t_end is not None)
    except ParameterError as exc:
        raise _as_flags(exc) from None
    text = scenario_toml(scenario)
    if args.out is None:
        print(text, end="")
        return ExitCode.OK
    out = Path(args.out)
    path = out / f"{args.name}.toml" if out.is_dir() else out
    if not path.parent.is_dir():
        raise ParameterError(f"--out {args.out!r}: no such directory {str(path.parent)!r}")
    path.write_text(text, encoding="utf-8")
    print(f"wrote {path}")
    return ExitCode.OK
