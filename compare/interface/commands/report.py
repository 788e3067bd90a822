"""``treeimpact report``: the discrepancy report (report.html, .md, .json) of the shipped or
given scenarios, with finished studies and optionally a study run beside it."""

from __future__ import annotations

import json

from treeimpact.analytic.errors import NotAchieved

from ...runs.exits import ExitCode
from ._common import add_budget_flag, writable_dir

NAME = "report"


def add_arguments(sp) -> None:
    """The command's flags, added to its subparser ``sp``."""
    sp.add_argument("--out", default="reports", help="output directory (default: reports)")
    sp.add_argument("--scenario", action="append", dest="scenarios",
                    help="shipped scenario name or TOML path (repeatable; default: all shipped)")
    sp.add_argument("--study", action="append", dest="studies", default=[],
                    help="directory of a finished study to include (repeatable)")
    sp.add_argument("--with-study", dest="with_study", metavar="PRESET", action="append",
                    default=[],
                    help="also run the study PRESET (treeimpact sweep --preset PRESET) into "
                         "OUT/study (the design preset: OUT/design) beside the report's own "
                         "runs, and include it (resumes a study already there; repeatable); "
                         "with --scenario, its maps are of the first tree given and its "
                         "sensitivity of every one")
    add_budget_flag(sp)


def run(args) -> int:
    """Write the report for the parsed command line ``args`` (the public API's
    :func:`~treeimpact.compare.interface.api_studies.report`, its studies beside it) and print the
    written paths; exit code 0, or NotAchieved (exit 4, after the paths) when a scenario's
    ladder gives no 1-DOF answer (its paper's-model or continuum rung failed: the pages say
    why)."""
    # lazy: +250 ms at import otherwise (the API's modules, numpy), which --help does not need
    from treeimpact.compare.interface.api_studies import report

    writable_dir("--out", args.out)
    paths = report(args.out, args.scenarios, studies=tuple(args.studies),
                   with_study=tuple(args.with_study), progress=True)
    for kind, path in paths.items():
        print(f"{kind}: {path}")
    unanswered = [a for a in json.loads(paths["json"].read_text())["answer"]["one_dof"]
                  if not a["available"]]
    if unanswered:  # the pages say why; the exit code and stderr say that it is so
        raise NotAchieved("the report is written, without a 1-DOF answer for " + "; ".join(
            f"{a['scenario']} ({a['why']})" for a in unanswered))
    return ExitCode.OK
