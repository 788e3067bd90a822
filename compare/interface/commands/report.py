"""``treeimpact report``: the discrepancy report (report.html, .md, .json) of the shipped or
given scenarios, with finished studies and optionally a study run beside it."""

from __future__ import annotations

import json
import sys
from pathlib import Path

from treeimpact.analytic.errors import NotAchieved, ParameterError
from treeimpact.analytic.model.scenario import load_scenario

from ...runs.exits import ExitCode
from ._common import add_budget_flag, writable_dir

NAME = "report"
#: The ``treeimpact`` program as a child process runs it: ``--with-study``'s study is its
#: ``sweep --preset`` (compare.report.validity.study_job.StudyJob), beside the report.
PROGRAM = (sys.executable, "-m", "treeimpact.compare.interface.cli")


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
    """Write the report for the parsed command line ``args`` and print the written paths;
    exit code 0, or NotAchieved (exit 4, after the paths) when a scenario's ladder gives no
    1-DOF answer (its paper's-model or continuum rung failed: the pages say why)."""
    # lazy: +94 ms at import otherwise (jinja2, numpy),
    # which this module's other callers do not need
    from treeimpact.compare.report import write_report

    folders = _study_folders(args.with_study)
    scenarios = [load_scenario(n) for n in args.scenarios] if args.scenarios else None
    for study in args.studies:  # checked before an hour of runs, not after
        if not Path(study).is_dir():
            raise ParameterError(f"--study {study!r}: not a directory (a finished study, "
                                 "treeimpact sweep --out DIR)")
    writable_dir("--out", args.out)
    jobs = []
    if args.with_study:
        # lazy: +73 ms at import otherwise (the study runner), which only --with-study needs
        from treeimpact.compare.report.validity.study_job import StudyJob

        jobs += [StudyJob(preset, Path(args.out) / folder, PROGRAM, scenarios=args.scenarios)
                 for preset, folder in folders.items()]
    try:
        for job in jobs:
            job.start()
        paths = write_report(args.out, scenarios=scenarios, study_dirs=tuple(args.studies),
                             progress=True, study_jobs=tuple(jobs))
    finally:
        for job in jobs:
            job.stop()
    for kind, path in paths.items():
        print(f"{kind}: {path}")
    unanswered = [a for a in json.loads(paths["json"].read_text())["answer"]["one_dof"]
                  if not a["available"]]
    if unanswered:  # the pages say why; the exit code and stderr say that it is so
        raise NotAchieved("the report is written, without a 1-DOF answer for " + "; ".join(
            f"{a['scenario']} ({a['why']})" for a in unanswered))
    return ExitCode.OK


def _study_folders(presets: list) -> dict:
    """``--with-study``'s presets -> their folders in OUT; a one-line ParameterError for an
    unknown preset or two writing one folder."""
    # lazy: +118 ms at import otherwise (jinja2, numpy),
    # which this module's other callers do not need
    from treeimpact.compare.report.validity.study import PRESETS

    folders: dict = {}
    for preset in presets:
        if preset not in PRESETS:
            raise ParameterError(f"--with-study {preset!r}: allowed {', '.join(PRESETS)}")
        folder = PRESETS[preset].folder
        other = next((p for p, f in folders.items() if f == folder), None)
        if other is not None:
            raise ParameterError(f"--with-study {preset}: {other} writes OUT/{folder} too; "
                                 "give one of them")
        folders[preset] = folder
    return folders
