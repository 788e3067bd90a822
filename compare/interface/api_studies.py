"""The public API's sweeps, studies and the report (re-exported by :mod:`treeimpact`;
docs/api.md, "Ladders, sweeps, the report"): resumable runs into a directory, each as its
command runs it (``treeimpact sweep`` calls sweep, sweep_pages and study; ``treeimpact
report`` calls report), the defaults the command line's; each input checked once, here,
where it enters."""

from __future__ import annotations

import json
import sys
from pathlib import Path

from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.model.parameters import Scenario

from ..runs.backends import BACKENDS
from ..runs.cache import resolve_scenario
from ..runs.names import NAMING, show
from ..studies.sweep.grid import Grid, parse_grid
from ..studies.sweep.journal import SPEC
from ..studies.sweep.plan import check_backends, check_options
from ..studies.sweep.run import SweepResult, run_sweep
from .api_call import api_function

#: The backends a sweep runs when none are given: all of them (the command line's too).
SWEEP_BACKENDS = tuple(BACKENDS)
#: The scenario a sweep runs when none is given (the command line's default too).
SWEEP_SCENARIO = "central-leader"
#: The report's directory when none is given (the command line's default too).
REPORT_DIR = "reports"


def _named(keyword: str, flag: str | None = None) -> str:
    """``keyword`` as the caller typed it: its flag (``flag``; by default the keyword as a
    flag, :func:`~compare.runs.names.show`) while a command runs, else the keyword."""
    return (flag or show(keyword)) if NAMING.get() == "flag" else keyword


def _backends(backends) -> list[str]:
    """The backend names of ``backends`` (names or one comma-separated string), checked
    where they enter: a one-line ParameterError naming ``backends`` (``--backend`` while the
    command runs) for an unknown one."""
    return check_backends(backends, flag=_named("backends", "--backend"))


def _grid_specs(grid) -> list:
    """The ``--grid`` specs of ``grid`` (one spec or a list of them), checked where they
    enter (:func:`~compare.studies.sweep.grid.parse_grid`: its refusal names ``grid``, the
    flag while the command runs), before anything is written."""
    specs = [grid] if isinstance(grid, str) else list(grid or ())
    if specs:
        parse_grid(specs)
    return specs


@api_function
def sweep(grid, out, *, scenario=SWEEP_SCENARIO, backends=SWEEP_BACKENDS,
          ladder: bool = False, options: dict | None = None, workers: int | None = None,
          scheduler=None, identify: bool = True, retry_failed: bool = False,
          progress: bool | None = False):
    """A resumable parameter sweep into a directory (docs/sweeps.md), as ``treeimpact sweep``
    runs it (its pages: :func:`sweep_pages`).

    Args:
        grid: the swept parameters, e.g. ``["restitution=0.05:0.5:10"]`` (the ``--grid``
            specs: NAME=START:STOP:COUNT or NAME=V1,V2,...; values in SI units: a contact
            duration in s).
        out: the output directory (rerunning with the same one resumes).
        scenario: the scenario (Scenario, shipped name or TOML path; default central-leader,
            as the command's).
        backends: the backends run at each point, names or one comma-separated string
            (default all five, as the command's; analytic always runs as the reference).
        ladder: run each engine as the ladder's rungs.
        options: backend options held fixed, ``{backend: {name: value}}`` or the
            command's ``--option`` specs ``[BACKEND.]NAME=VALUE`` (no BACKEND: every engine
            swept), each checked against its backend's options (values in SI units: ``dt``
            in s).
        workers: local worker processes (default one per CPU; 0 runs here).
        scheduler: a Dask scheduler address (``tcp://host:8786``) or Client to run on
            instead of local workers.
        identify: run the paper's identification on each run's record (the ``id.*`` and
            ``truth.*`` columns); False skips it (the command's ``--no-identify``).
        retry_failed: on resume, rerun the rows whose status is not ok.
        progress: True draws a progress bar on stderr, False nothing, None a bar only on a
            terminal (the command's).

    Returns:
        ``treeimpact.compare.studies.sweep.SweepResult``: its ``table`` a pandas DataFrame,
        one row per grid point and backend, its ``out`` the directory (:func:`sweep_pages`
        writes its pages there).

    Raises:
        ParameterError: a malformed grid spec, an unknown backend, scenario or scheduler,
            an option a backend does not have or a value out of its range, a workers count
            out of range, an output directory that cannot be created.
    """
    names = _backends(backends)
    parsed = grid if isinstance(grid, Grid) else parse_grid(grid)  # the one check
    fixed = check_options(options, names, label=_named("options", "--option"),
                          backends_label=_named("backends", "--backend"))
    return run_sweep(scenario, parsed, out, backends=tuple(names), ladder=ladder,
                     options=fixed, workers=workers, scheduler=scheduler,
                     identify=identify, retry_failed=retry_failed, progress=progress)


@api_function
def sweep_pages(result, *, tolerance=None) -> dict:
    """The pages of a finished sweep, written beside its table, as ``treeimpact sweep``
    writes them after the sweep: its validity and identification maps (PNG), study.md,
    study.html and study.json.

    Args:
        result: the ``SweepResult`` :func:`sweep` returned (its ``out`` receives the pages).
        tolerance: the maps' criterion, a relative discrepancy (0.05 = 5 %, the default
            when None) or ``{metric: tolerance}``.

    Returns:
        dict: kind ("md", "html", "json", "table", "figures") -> the written path (a list of
        paths for "figures").

    Raises:
        TypeError: a ``result`` that is not a SweepResult.
        ParameterError: its directory cannot be written.
    """
    # lazy: +118 ms at import otherwise (jinja2, numpy),
    # which this module's other callers do not need
    from ..report.validity.study import write_study

    if not isinstance(result, SweepResult):
        raise TypeError(f"result: expected the SweepResult sweep() returns, got "
                        f"{type(result).__name__}")
    return write_study(result.out, {"sweep": result.out}, tolerance=tolerance,
                       title=f"Sweep of {_scenario_of(result)}",
                       meta={"wall_s": result.wall_s})


def _scenario_of(result) -> str:
    """The name of the scenario ``result`` swept (from its table, else its sweep.json)."""
    if len(result.table):
        return result.table["scenario"].iloc[0]
    return json.loads((result.out / SPEC).read_text())["scenario"]["name"]


@api_function
def study(out, preset: str = "default", *, scenario=SWEEP_SCENARIO, backends=None,
          workers: int | None = None, scheduler=None, tolerance=None, grid=None,
          retry_failed: bool = False, sensitivity_scenarios=None,
          progress: bool | None = False) -> dict:
    """A whole study of a preset (docs/sweeps.md), as ``treeimpact sweep --preset``: its
    sweeps, maps and page (study.md, study.html, study.json), resumable in ``out``.

    Args:
        out: the output directory (rerunning with the same one resumes).
        preset: ``default``, ``full`` (validity studies) or ``design`` (the design map, its
            count and ranges the defaults; :func:`design_map` takes them).
        scenario: the tree (Scenario, shipped name or TOML path; default central-leader, as
            the command's).
        backends: the backends, names or one comma-separated string, whose engines replace
            the preset's (None: the preset's own); not with ``design``.
        workers: local worker processes (default one per CPU; 0 runs here).
        scheduler: a Dask scheduler address (``tcp://host:8786``) or Client to run on
            instead of local workers.
        tolerance: the maps' criterion, a relative discrepancy (0.05 = 5 %, the default
            when None); not with ``design``.
        grid: ``--grid`` specs replacing the preset's validity grid (values in SI units;
            ``design``: one more sweep over its inputs).
        retry_failed: on resume, rerun the rows whose status is not ok.
        sensitivity_scenarios: the trees of its sensitivity study (shipped names or TOML
            paths; None: every shipped tree); not with ``design``.
        progress: True draws a progress bar on stderr, False nothing, None a bar only on a
            terminal (the command's).

    Returns:
        dict: kind ("md", "html", "json", "table", "figures", "warnings") -> the written
        path (a list for "figures"; "warnings": a line per sensitivity design with a failed
        point), as the study's kind writes them.

    Raises:
        ParameterError: an unknown preset, backend or scenario, a malformed grid spec, a
            keyword the preset fixes, a workers count out of range.
        NotAchieved: no point of its sensitivity study (or no cell of the design map) ran;
            the pages are written.
    """
    # lazy: +118 ms at import otherwise (jinja2, numpy),
    # which this module's other callers do not need
    from ..report.validity.study import get_preset, run_study

    p = get_preset(preset)
    names = None if backends is None else _backends(backends)
    specs = _grid_specs(grid)
    if p.run is not None:  # a study of another kind: it fixes what it runs and judges
        _refuse_fixed(p.name, backends=names, tolerance=tolerance,
                      sensitivity_scenarios=sensitivity_scenarios)
    return run_study(out, p.name, scenario=scenario, backends=names, workers=workers,
                     scheduler=scheduler, progress=progress, tolerance=tolerance,
                     grid=specs or None, retry_failed=retry_failed,
                     sensitivity_scenarios=sensitivity_scenarios)


def _refuse_fixed(preset: str, **given) -> None:
    """A one-line ParameterError naming the first keyword of ``given`` (``--backend``,
    ``--tolerance``, ``--sensitivity-scenario`` while the command runs) that is not None: a
    study of another kind (``preset``) fixes what it runs and judges."""
    flags = {"backends": "--backend", "sensitivity_scenarios": "--sensitivity-scenario"}
    for keyword, value in given.items():
        if value is not None:
            raise ParameterError(f"{_named(keyword, flags.get(keyword))}: not used with "
                                 f"--preset {preset} (its study fixes what it runs and "
                                 "judges)")


#: The ``treeimpact`` program as a child process runs it: a study run beside the report
#: (``with_study``) is its ``sweep --preset`` (compare.report.validity.study_job.StudyJob).
PROGRAM = (sys.executable, "-m", "treeimpact.compare.interface.cli")


@api_function
def report(out=REPORT_DIR, scenarios=None, *, studies=(), with_study=(),
           progress: bool = False) -> dict:
    """The discrepancy report (report.html, report.md, report.json), as ``treeimpact report``.

    Args:
        out: the output directory (default ``reports``, as the command's).
        scenarios: the scenarios (Scenario, shipped name or TOML path each; default: the
            shipped ones).
        studies: directories of finished studies (sweeps) to include.
        with_study: study presets (``treeimpact sweep --preset``'s names: ``default``,
            ``design``, ...) also run into ``out`` beside the report's own runs, in child
            processes, and included (a study already there resumes); with ``scenarios``
            (names or TOML paths only: a child process reads them), its maps are of the
            first and its sensitivity of every one.
        progress: draw progress bars on stderr (the command's).

    Returns:
        dict: kind ("html", "md", "json") -> the written file's path.

    Raises:
        ParameterError: an unknown scenario or preset, a study that is not a directory, two
            presets writing one folder, a Scenario object with ``with_study``.
    """
    # lazy: +120 ms at import otherwise (jinja2), which this module's other callers do not need
    from ..report import write_report

    folders = _study_folders(with_study)
    if folders and any(isinstance(s, Scenario) for s in scenarios or ()):
        raise ParameterError(f"{_named('with_study')}: the scenarios by shipped "
                             "name or TOML path (a study's child process reads them)")
    scens = None if scenarios is None else [resolve_scenario(s) for s in scenarios]
    for study in studies:  # checked before the runs, not after
        if not Path(study).is_dir():
            raise ParameterError(f"{_named('studies', '--study')} {str(study)!r}: not a "
                                 "directory (a finished study's output directory)")
    jobs = _study_jobs(folders, out, scenarios)
    try:
        for job in jobs:
            job.start()
        return write_report(out, scenarios=scens, study_dirs=tuple(studies),
                            progress=progress, study_jobs=jobs)
    finally:
        for job in jobs:
            job.stop()


def _study_folders(presets) -> dict:
    """``with_study``'s presets -> their folders in the report's directory; a one-line
    ParameterError for an unknown preset or two writing one folder."""
    if not presets:
        return {}
    # lazy: +118 ms at import otherwise (jinja2, numpy),
    # which this module's other callers do not need
    from ..report.validity.study import PRESETS

    flag, folders = _named("with_study"), {}
    for preset in presets:
        if preset not in PRESETS:
            raise ParameterError(f"{flag} {preset!r}: allowed {', '.join(PRESETS)}")
        folder = PRESETS[preset].folder
        other = next((p for p, f in folders.items() if f == folder), None)
        if other is not None:
            raise ParameterError(f"{flag} {preset}: {other} writes OUT/{folder} too; "
                                 "give one of them")
        folders[preset] = folder
    return folders


def _study_jobs(folders: dict, out, scenarios) -> tuple:
    """The StudyJob of each preset -> folder of ``folders``, into ``out``/folder, of the
    ``scenarios`` as given (names or paths; None: the study's own)."""
    if not folders:
        return ()
    # lazy: +73 ms at import otherwise (the study runner), which only with_study needs
    from ..report.validity.study_job import StudyJob

    given = None if scenarios is None else [str(s) for s in scenarios]
    return tuple(StudyJob(preset, Path(out) / folder, PROGRAM, scenarios=given)
                 for preset, folder in folders.items())


@api_function
def design_map(out, scenario=SWEEP_SCENARIO, *, count: int = 30, ranges: dict | None = None,
               workers: int | None = None, scheduler=None, engines: bool = False) -> dict:
    """The design study (docs/design-map.md), as ``treeimpact sweep --preset design``: where
    the 1-DOF trunk and the small-e consequences hold for one tree over the clamp height,
    the mass ratio, the pad and e; resumable in ``out``.

    Args:
        out: the output directory (rerunning with the same one resumes).
        scenario: the tree (Scenario, shipped name or TOML path; default central-leader).
        count: values per input of each pair's map (30: 30 x 30 cells a pair).
        ranges: ``{input: (low, high)}`` replacing an input's default range; inputs
            ``a_over_l`` (1), ``mass_ratio`` (1), ``contact_duration`` (s), ``restitution``.
        workers: local worker processes (default one per CPU; 0 runs here).
        scheduler: a Dask scheduler address or Client to run on instead.
        engines: also run MuJoCo's and Bullet's chains and MuJoCo's flex rod at the corners
            of the a/l x contact duration map and at the cells nearest its 5 % line, each
            compared with the continuum against its stated tolerance (about a minute).

    Returns:
        dict: kind ("json", "md", "html", "figures") -> the written paths; design.json holds
        every map's numbers and the sentences read off them.

    Raises:
        ParameterError: a range outside an input's allowed one or not (low, high), an
            unknown input, a count below 2, a tree whose own a/l, m/M_T, pad or e lies
            outside the study's allowed range.
        TypeError: an ``out``, ``scenario`` or ``engines`` of the wrong type.
        NotAchieved: no cell of the maps has numbers (nothing is written but the rows).
    """
    # lazy: +80 ms at import otherwise (treeimpact.compare.report.validity.design_study),
    # which this module's other callers do not need
    from ..report.validity.design_study import run_design_study

    if not isinstance(count, int) or isinstance(count, bool) or not 2 <= count <= 200:
        raise ParameterError(f"count = {count!r}: allowed an integer from 2 to 200")
    return run_design_study(out, scenario, count=count, ranges=ranges, workers=workers,
                            scheduler=scheduler, progress=False, engines=engines)


__all__ = ["design_map", "report", "study", "sweep", "sweep_pages"]
