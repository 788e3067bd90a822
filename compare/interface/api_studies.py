"""The public API's sweeps, studies and the report (re-exported by :mod:`treeimpact`;
docs/api.md, "Ladders, sweeps, the report"): resumable runs into a directory, each as its
command runs it, the defaults the command line's."""

from __future__ import annotations

import sys
from pathlib import Path

from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.model.parameters import Scenario

from ..runs.backends import BACKENDS
from ..runs.cache import resolve_scenario
from ..runs.names import NAMING, show
from ..studies.sweep.run import run_sweep
from .api_call import api_function

#: The backends a sweep runs when none are given: all of them (the command line's too).
SWEEP_BACKENDS = tuple(BACKENDS)
#: The scenario a sweep runs when none is given (the command line's default too).
SWEEP_SCENARIO = "central-leader"
#: The report's directory when none is given (the command line's default too).
REPORT_DIR = "reports"

@api_function
def sweep(grid, out, *, scenario=SWEEP_SCENARIO, backends=SWEEP_BACKENDS,
          ladder: bool = False, options: dict | None = None, workers: int | None = None):
    """A resumable parameter sweep into a directory (docs/sweeps.md), as ``treeimpact sweep``.

    Args:
        grid: the swept parameters, e.g. ``["restitution=0.05:0.5:10"]`` (the ``--grid``
            specs: NAME=START:STOP:COUNT or NAME=V1,V2,...).
        out: the output directory (rerunning with the same one resumes).
        scenario: the scenario (default central-leader, as the command's).
        backends: the backends run at each point (default all five, as the command's;
            analytic always runs as the reference).
        ladder: run each engine as the ladder's rungs.
        options: backend options held fixed, ``{backend: {name: value}}``.
        workers: local worker processes (default one per CPU; 0 runs here).

    Returns:
        ``treeimpact.compare.studies.sweep.SweepResult``: its ``table`` a pandas DataFrame, one row
        per grid point and backend.

    Raises:
        ParameterError: a malformed grid spec, an unknown backend or option.
    """
    return run_sweep(scenario, grid, out, backends=tuple(backends),
                     ladder=ladder, options=options, workers=workers, progress=False)


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
        raise ParameterError(f"{show('with_study', NAMING.get())}: the scenarios by shipped "
                             "name or TOML path (a study's child process reads them)")
    scens = None if scenarios is None else [resolve_scenario(s) for s in scenarios]
    for study in studies:  # checked before the runs, not after
        if not Path(study).is_dir():
            flag = "--study" if NAMING.get() == "flag" else "studies"
            raise ParameterError(f"{flag} {str(study)!r}: not a directory (a finished "
                                 "study's output directory)")
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

    flag, folders = show("with_study", NAMING.get()), {}
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


__all__ = ["design_map", "report", "sweep"]
