"""``treeimpact modes SCENARIO``: the static stiffness at the impact height (N/m) and the
natural frequencies (rad/s) of a backend's trunk beside the continuous beam's."""

from __future__ import annotations


from treeimpact.analytic.model.scenario import load_scenario
from treeimpact.analytic.results import json_text
from treeimpact.compare.runs.backends import BACKENDS
from treeimpact.compare.runs.provenance import provenance

from ...runs.exits import ExitCode
from ._common import add_option_flags, fmt, options_of, relative_text

NAME = "modes"

#: The options of ``treeimpact modes`` (the backends' modes() take these of their OPTIONS).
MODES_OPTIONS = ("segments", "elements", "beam_theory", "trunk")


def add_arguments(sp) -> None:
    """The command's flags, added to its subparser ``sp``: the backend and the trunk
    options its modes() take."""
    sp.add_argument("scenario", help="shipped scenario name or TOML path")
    sp.add_argument("--backend", default="analytic", choices=tuple(BACKENDS),
                    help="analytic (the SDOF trunk), beam (its mesh), mujoco or bullet (their "
                         "hinged trunks)")
    add_option_flags(sp, MODES_OPTIONS)
    sp.add_argument("--json", action="store_true", help="machine-readable output")


def run(args) -> int:
    """Print the backend's modes beside the beam's for the parsed command line ``args``
    (text or ``--json``); exit code 0."""
    # lazy: +250 ms at import otherwise (the API's modules, numpy), which --help does not need
    from treeimpact.compare.interface.api import modes

    scenario = load_scenario(args.scenario)
    opts = options_of(args, MODES_OPTIONS)
    res = modes(scenario, args.backend, **opts).to_json()
    if args.json:
        res = res | {"provenance": provenance(scenario, backend=args.backend, options=opts)}
        print(json_text(res, indent=2))
        return ExitCode.OK
    model, beam = res["model"], res["beam"]
    theory = "Timoshenko" if getattr(args, "beam_theory", None) == "timoshenko" \
        else "Euler-Bernoulli"
    print(f"{scenario.name} ({args.backend} trunk against the continuous {theory} beam)")
    print(f"  {'quantity':<26}{'model':>14}{'beam':>14}{'difference':>12}  unit")
    rows = [("static stiffness at a", model["static_stiffness"], beam["static_stiffness"],
             "N/m")]
    rows += [(f"natural frequency {i + 1}", w, wb, "rad/s")
             for i, (w, wb) in enumerate(zip(model["omegas"], beam["omegas"]))]
    for name, v, vb, unit in rows:
        print(f"  {name:<26}{fmt(v):>14}{fmt(vb):>14}{relative_text(v, vb):>12}  {unit}")
    return ExitCode.OK
