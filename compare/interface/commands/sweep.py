"""``treeimpact sweep``: a parameter sweep or a whole model-validity study (its presets, maps
and page: :mod:`treeimpact.compare.report.validity`).

    treeimpact sweep --grid restitution=0:0.9:10 --grid crown_ratio=0:4:9 [--scenario NAME]
        [--backend analytic,soft,mujoco,bullet] [--ladder] [--option [BACKEND.]NAME=VALUE]
        [--workers N] [--scheduler ADDRESS] [--tolerance REL] [--retry-failed]
        [--no-identify] --out DIR
    treeimpact sweep --preset default|full|design --out DIR      (a whole study)

Writes the sweep table (results.csv, results.parquet), the validity and identification maps
and study.md / study.html into DIR. Rerunning with the same DIR resumes; Ctrl-C keeps every
finished row and exits 130 with one line. Bad input: one line naming the flag and the
allowed form or range (exit 2). The command parses its flags, calls the public API
(:mod:`treeimpact.compare.interface.api_studies`: ``sweep`` then ``sweep_pages``, or
``study`` with ``--preset``) and prints what it returns.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

from treeimpact.analytic.errors import ParameterError
from treeimpact.compare.report.validity.presets import PRESETS
from treeimpact.compare.runs.backends import BACKENDS
from treeimpact.compare.runs.pool import STOP

from ...runs.exits import ExitCode
from ...studies.sweep.grid import GRID_FORM
from ...studies.sweep.plan import OPTION_FORM
from .. import api_studies  # the public API the command calls (sweep, sweep_pages, study)
from ._common import add_budget_flag

NAME = "sweep"

#: ``--backend``'s default: every backend (a plain sweep's; a preset's own when not typed).
BACKEND_DEFAULT = ",".join(BACKENDS)



def _workers(text: str) -> int:
    try:
        n = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer >= 0, got {text!r}") from None
    if n < 0:
        raise argparse.ArgumentTypeError(f"expected an integer >= 0, got {text!r}")
    return n


def _tolerance(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        v = math.nan
    if not (math.isfinite(v) and v > 0):
        raise argparse.ArgumentTypeError(f"expected a relative tolerance > 0 (0.05 = 5 %), "
                                         f"got {text!r}")
    return v


def add_sweep_arguments(parser) -> None:
    """Add the arguments of ``treeimpact sweep`` to ``parser``."""
    parser.add_argument("--grid", action="append", default=[], metavar="SPEC",
                        help=f"swept parameter, repeatable: {GRID_FORM}; NAME is a dotted "
                             "scenario field (trunk.crown_mass), restitution, "
                             "contact_stiffness, contact_duration, a ratio (mass_ratio, "
                             "a_over_l, crown_ratio) or a backend option (segments, dt, "
                             "integrator, ...)")
    parser.add_argument("--scenario", default="central-leader",
                        help="shipped scenario name or TOML path (default: central-leader)")

    parser.add_argument("--backend", default=BACKEND_DEFAULT,
                        help="comma-separated backends (analytic is always run as the "
                             f"reference; default: all, {','.join(BACKENDS)})")
    parser.add_argument("--ladder", action="store_true",
                        help="run each engine as the ladder's rungs (SDOF, chain, chain + full "
                             "pendulum) so maps show which assumption dominates")
    parser.add_argument("--option", action="append", default=[], metavar="OPT",
                        help=f"fixed backend option, repeatable: {OPTION_FORM}")
    parser.add_argument("--workers", type=_workers, default=None,
                        help="local worker processes (default: CPU count; 0: this process)")
    parser.add_argument("--scheduler", default=None, metavar="ADDRESS",
                        help="Dask scheduler address (tcp://host:8786): run on that cluster")

    parser.add_argument("--preset", default=None, choices=tuple(PRESETS),
                        help="run a whole study: "
                             + "; ".join(p.help for p in PRESETS.values())
                             + "; --grid replaces the preset's validity grid (design: one "
                             "more sweep over the design inputs)")
    parser.add_argument("--sensitivity-scenario", action="append", default=None,
                        dest="sensitivity_scenarios", metavar="SCENARIO",
                        help="with --preset: a tree of its sensitivity study, shipped name or "
                             "TOML path (repeatable; default: every shipped tree); a file's "
                             "[calibration] measured fields are held at its values")
    parser.add_argument("--tolerance", type=_tolerance, default=None,
                        help="validity tolerance, relative (default 0.05)")
    parser.add_argument("--retry-failed", action="store_true", dest="retry_failed",
                        help="on resume, rerun rows whose status is not ok")
    parser.add_argument("--no-identify", action="store_false", dest="identify",
                        help="skip the identification procedure on each record")
    parser.add_argument("--out", required=True, help="output directory (resumable)")


def add_arguments(sp) -> None:
    """The sweep's flags (:func:`add_sweep_arguments`) and the run budget, added to its
    subparser ``sp``."""
    add_sweep_arguments(sp)
    add_budget_flag(sp)


def run(args) -> int:
    """Run ``treeimpact sweep`` with the parsed command line ``args``; returns the exit
    code (ExitCode.OK; ExitCode.INTERRUPTED when interrupted by Ctrl-C or SIGTERM, with one
    line saying how to resume; bad input raises ParameterError)."""
    try:
        code = _run(args)
        if not STOP.is_set():  # else the request came after the last look: still a stop
            return code
    except KeyboardInterrupt:
        pass
    print(f"treeimpact: sweep interrupted; the finished rows are kept in {args.out}: "
          f"rerun the same command to resume", file=sys.stderr)
    return ExitCode.INTERRUPTED


def _refuse_fixed_by_preset(args) -> None:
    """ParameterError naming ``--ladder`` or ``--no-identify`` given with ``--preset``: a
    preset fixes its rungs and its identification (its study, and the resume of it from the
    same --out, runs what the preset says), so neither flag could change what runs."""
    for flag, given in (("--ladder", args.ladder), ("--no-identify", not args.identify)):
        if given:
            raise ParameterError(f"{flag}: not used with --preset {args.preset} (the preset "
                                 "fixes its rungs and its identification, and resuming it "
                                 "runs the same study); run a plain sweep (--grid) instead")


def _run(args) -> int:
    t_start = time.perf_counter()
    backends = _backend_names(args.backend)  # checked where they enter: by the API
    if args.sensitivity_scenarios and not args.preset:
        raise ParameterError("--sensitivity-scenario: used with --preset (a study's "
                             "sensitivity part)")
    if args.preset:
        if args.option:
            raise ParameterError("--option: not used with --preset (the preset fixes the "
                                 "engines' options); run a plain sweep instead")
        _refuse_fixed_by_preset(args)
        typed = args.backend != BACKEND_DEFAULT  # not typed: the preset's own
        paths = api_studies.study(args.out, args.preset, scenario=args.scenario,
                                  backends=backends if typed else None, workers=args.workers,
                                  scheduler=args.scheduler, tolerance=args.tolerance,
                                  grid=args.grid or None, retry_failed=args.retry_failed,
                                  sensitivity_scenarios=args.sensitivity_scenarios,
                                  progress=None)
    else:
        if not args.grid:
            raise ParameterError(f"--grid: give at least one ({GRID_FORM}) or --preset")
        res = api_studies.sweep(args.grid, args.out, scenario=args.scenario,
                                backends=backends, ladder=args.ladder, options=args.option,
                                workers=args.workers, scheduler=args.scheduler,
                                identify=args.identify, retry_failed=args.retry_failed,
                                progress=None)
        _print_sweep(res)
        paths = api_studies.sweep_pages(res, tolerance=args.tolerance)
    _print_paths(paths)
    print(f"wall time: {time.perf_counter() - t_start:.1f} s (the whole command: its runs and "
          "sweeps, then its maps and pages)")
    return ExitCode.OK


def _backend_names(text: str) -> list[str]:
    """The names ``--backend`` lists (comma-separated), each once, in order (the API checks
    them)."""
    return list(dict.fromkeys(b.strip() for b in text.split(",") if b.strip()))


def _print_sweep(res) -> None:
    """The sweep's line: its rows by status, what this run wrote, its wall time."""
    status = res.table["status"].value_counts().to_dict()
    print(f"sweep: {len(res.table)} rows ("
          + ", ".join(f"{k} {v}" for k, v in sorted(status.items()))
          + f"); {res.rows_written} written now, {res.rows_done_before} done before; "
          f"runs {res.wall_s:.1f} s")


def _print_paths(paths: dict) -> None:
    """What the study or the sweep's pages wrote (its ``paths``), and its warnings on
    stderr."""
    for kind in ("table", "md", "html", "json"):  # what the study wrote, of these
        if kind in paths:
            print(f"{kind}: {paths[kind]}")
    if paths.get("figures"):
        print(f"figures: {len(paths['figures'])} in {Path(paths['figures'][0]).parent}")
    for line in paths.get("warnings", []):  # the study ran, some of its points did not
        print(f"treeimpact: warning: {line}", file=sys.stderr)
