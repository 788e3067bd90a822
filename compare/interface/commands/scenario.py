"""``treeimpact scenario``: a scenario file for a user's own tree, from a pendulum test's
measured quantities or from its geometry and a crown mass estimate (the rest assumed).

The flags are :class:`compare.tree.scenario.TreeInputs`;
:func:`compare.tree.scenario.tree_scenario` (the API's too) builds the calibrated scenario,
and this command writes it as TOML, the file recording which values were given, chosen and
calibrated, as the shipped files do.
"""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.model.scenario_toml import scenario_toml

from ...runs.exits import ExitCode
from treeimpact.analytic.model.registry import ASSUMED

from ...tree.scenario import DEFAULTS, TreeInputs
from ...tree.scenario import RENAMED as TREE_RENAMED
from ._common import add_parameter_flag, number

NAME = "scenario"
#: Removed spellings -> their names now (compare.interface.cli reads a command's RENAMED):
#: the builder's.
RENAMED = TREE_RENAMED


def add_arguments(sp: argparse.ArgumentParser) -> None:
    """The command's flags, added to its subparser ``sp``: the test (given), the tree
    (measured, or from its geometry), the choices."""
    sp.add_argument("name", help="the scenario's name (also the file name with --out DIR)")
    g = sp.add_argument_group("the test (given)")
    for name in ("clamp_height", "diameter", "impactor_mass", "equivalent_length",
                 "release_angle_deg"):
        add_parameter_flag(g, name, required=True)
    m = sp.add_argument_group("the tree measured by a pendulum test (or from its geometry: "
                              "--crown-mass)")
    add_parameter_flag(m, "dynamic_mass", note="required for a measured tree")
    add_parameter_flag(m, "equivalent_stiffness", note="or --x-max and --tau")
    add_parameter_flag(m, "damping_rate", note="or --a1 and --a2")
    m.add_argument("--a1", type=number, help="regression a1 = V, m/s (eq 40)")
    m.add_argument("--a2", type=number, help="regression a2, m/s^2 (eq 40)")
    m.add_argument("--x-max", type=number, help="largest displacement, m (eq 38)")
    m.add_argument("--tau", type=number, help="time of x_max from the extrapolated origin, s")
    g = sp.add_argument_group("the tree from its geometry (no pendulum test; root spring and "
                              "damping assumed, see docs/parameters.md)")
    add_parameter_flag(g, "crown_mass", note="an estimate; not with the measured tree's "
                       "flags")
    c = sp.add_argument_group("chosen (defaults: the registry's, each with its source in docs/parameters.md)")
    e = ASSUMED["youngs_modulus"]
    add_parameter_flag(c, "youngs_modulus",
                       note=f"required for a measured tree (Table 1 prints 8.9e9 and 12.6e9); "
                       f"from its geometry assumed {e.value:g} if not given")
    for name, value in DEFAULTS.items():
        add_parameter_flag(c, name, note=f"default {value:g}")
    sp.add_argument("--out", help="write the file here (a directory: NAME.toml in it); "
                                  "default: print it")


def run(args) -> int:
    """Write (or print) the scenario file of the parsed command line ``args``, one that
    runs (:func:`compare.tree.scenario.tree_scenario`); exit code 0. Bad input is a
    ParameterError naming the flag (exit 2); a tree whose analytic x_max lies beyond the
    clamp height is OutsideValidity (exit 4, nothing written)."""
    # lazy: +250 ms at import otherwise (the API's modules, numpy), which --help does not need
    from treeimpact.compare.interface.api import tree_scenario

    fields = [f.name for f in dataclasses.fields(TreeInputs) if f.name != "name"]
    scenario = tree_scenario(args.name, **{n: getattr(args, n) for n in fields})
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
