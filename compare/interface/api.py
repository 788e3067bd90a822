"""The public API re-exported by :mod:`treeimpact` (docs/api.md): one function per job, in SI
units (angles in degrees, named ``_deg``), each a thin call into the module that does the
work, returning the typed results of :mod:`treeimpact.compare.interface.api_results`. Its defaults
are the command line's. Each runs with one BLAS thread (the library's matrices are small:
analytic.threads), the caller's own setting put back when it returns.

Bad input raises :class:`treeimpact.ParameterError` in one line naming the keyword argument
as typed (``t_end``, not the command line's ``--t-end``) and its allowed range; a run with
no numbers to report raises :class:`treeimpact.SimulationDiverged`.
"""

from __future__ import annotations

import dataclasses
import functools
import re
import sys
from pathlib import Path

from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.identify.pendulum_record import Record
from treeimpact.analytic.identify.pendulum_record import read_record as read
from treeimpact.analytic.identify.procedure import PendulumTest
from treeimpact.analytic.model.parameters import LIMITS, Pendulum, Scenario, check_range
from treeimpact.analytic.model.plausible import implausible_values, warn_implausible
from treeimpact.analytic.model.scenario import shipped_scenarios
from treeimpact.analytic.threads import enter_limit, exit_limit

from ..runs.backends import BACKENDS, ENGINES, get_backend
from ..runs.cache import resolve_scenario
from ..runs.names import NAMING, did_you_mean, show
from ..runs.recording import check_sampling, sample
from ..studies.sweep.run import run_sweep
from ..tree.ladder import build_ladder
from ..tree.scenario import RENAMED as TREE_RENAMED
from ..tree.scenario import TreeInputs, check_keywords
from ..tree.scenario import tree_scenario as build_tree_scenario
from .api_results import (
    Identification,
    Modes,
    Simulation,
    identification_of,
    modes_of,
    simulation_of,
)

#: The backends a sweep runs when none are given: all of them (the command line's too).
SWEEP_BACKENDS = tuple(BACKENDS)
#: The scenario a sweep runs when none is given (the command line's default too).
SWEEP_SCENARIO = "central-leader"
#: The report's directory when none is given (the command line's default too).
REPORT_DIR = "reports"

_FLAG = re.compile(r"(?<![\w-])--([a-z][a-z0-9-]*)")


def _keywords(text: str) -> str:
    """A message of the package's with its command-line flags named as this API's keyword
    arguments (``--t-end`` -> ``t_end``); the run budget's flag named by its variable."""
    text = text.replace("--max-seconds, ", "").replace("--max-seconds", "TREEIMPACT_MAX_SECONDS")
    return _FLAG.sub(lambda m: m.group(1).replace("-", "_"), text)


def _api(func):
    """An API function whose ParameterError names keyword arguments, not flags, run with
    the library's BLAS thread limit (analytic.threads: the caller's setting is back when it
    returns)."""
    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        enter_limit()
        try:
            return func(*args, **kwargs)
        except ParameterError as exc:
            if NAMING.get() == "flag":  # a command's call: its refusal names the flags
                raise
            raise ParameterError(_keywords(str(exc))) from None
        finally:
            exit_limit()
    return wrapper


@_api
def simulate(scenario, backend: str = "analytic", **options) -> Simulation:
    """Run one scenario on one backend.

    Args:
        scenario: a :class:`Scenario`, a shipped scenario's name (``shipped_scenarios()``)
            or the path of a scenario file (TOML).
        backend: ``analytic`` (the paper's exact model, eqs 12-35; default), ``soft`` (the
            1-DOF trunk with the spring-dashpot pad), ``beam`` (the continuum trunk),
            ``mujoco`` or ``bullet`` (:func:`backends`).
        **options: the backend's own options, as the ``simulate`` command's flags with
            underscores (docs/cli.md): e.g. ``restitution`` (1), ``t_end`` (s),
            ``contact_stiffness`` (N/m), ``contact_duration`` (s), ``trunk="chain"``,
            ``segments``, ``elements``, ``dt`` (s), ``trunk_damping_model``.

    Returns:
        :class:`Simulation`: its ``metrics`` (:class:`Metrics`, SI), ``model``
        (:class:`Model`), ``scenario`` as run and ``trajectory``.

    Raises:
        ParameterError: an unknown backend or option (with what it may have meant), a value
            out of its range, or a run beyond the budget (TREEIMPACT_MAX_STEPS, ...).
        SimulationDiverged: the run has no physical numbers to report.
    """
    scen = _resolve_name(scenario) if isinstance(scenario, str) else resolve_scenario(scenario)
    as_run, result = get_backend(backend).run(scen, **options)
    return simulation_of(result, as_run)


@functools.lru_cache(maxsize=32)
def _shipped(name: str) -> Scenario:
    """The shipped scenario ``name`` (:func:`resolve_scenario`), kept for the next call:
    package data, read and validated once a process (~0.15 ms a run otherwise, a tenth of
    the soft SDOF's, benchmarks/bench_exact.py). Scenarios are frozen, so sharing is safe."""
    return resolve_scenario(name)


def _resolve_name(name: str) -> Scenario:
    """The scenario named ``name``: a shipped one from :func:`_shipped`, else read."""
    return _shipped(name) if name in _shipped_names() else resolve_scenario(name)


@functools.lru_cache(maxsize=1)
def _shipped_names() -> frozenset:
    """The shipped scenarios' names (package data: listed once a process)."""
    return frozenset(shipped_scenarios())


@_api
def modes(scenario, backend: str = "analytic", **options) -> Modes:
    """The static stiffness and natural frequencies of a backend's trunk beside the
    continuous beam's.

    Args:
        scenario: a :class:`Scenario`, a shipped scenario's name or a TOML path.
        backend: ``analytic`` (the 1-DOF trunk; default), ``soft``, ``beam`` (its mesh),
            ``mujoco`` or ``bullet`` (their hinged chains).
        **options: the trunk options of the ``modes`` command: ``segments``, ``elements``,
            ``beam_theory``, ``trunk``.

    Returns:
        :class:`Modes`: ``model`` and ``beam``, each a :class:`TrunkModes` (static stiffness
        at the clamp height in N/m, natural frequencies in rad/s).

    Raises:
        ParameterError: an unknown backend or option, or a value out of its range.
    """
    return modes_of(get_backend(backend).modes(resolve_scenario(scenario), **options))


def backends() -> dict[str, str]:
    """The backends by name.

    Returns:
        dict: backend name -> one line saying what it is (their options: docs/cli.md).

    Raises:
        Nothing.
    """
    return {name: b.description for name, b in BACKENDS.items()}


@_api
def ladder(scenario, *, engines=None, segments: int | None = None):
    """The scenario run as the discrepancy ladder, one assumption per rung, each step judged
    against ``compare/runs/tolerances.toml`` (docs/ladder.md).

    Args:
        scenario: a :class:`Scenario`, a shipped scenario's name or a TOML path.
        engines: the engines whose rungs run (default: MuJoCo and Bullet; ``()``: the
            analytic rungs only).
        segments: the engines' chain segments (default: the fewest within 0.5 % of the
            beam).

    Returns:
        ``treeimpact.compare.tree.ladder.Ladder``: ``checks()`` the verdicts with their reasons,
        ``table()`` every rung's values and steps.

    Raises:
        ParameterError: an unknown engine or a bad segment count.
    """
    return build_ladder(resolve_scenario(scenario),
                        engines=ENGINES if engines is None else tuple(engines),
                        segments=segments)


@_api
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


@_api
def read_record(path, *, time_unit: str | None = None, length_unit: str | None = None):
    """A pendulum-test record read from a CSV file (docs/identification.md, "The record").

    Args:
        path: the file: a header naming the columns t, x and optionally y (the pendulum's),
            any order, units in the header ('t [ms]', 'x (mm)').
        time_unit: the unit of a time column whose header names none: s (default), ms, us.
        length_unit: that of x and y: m (default), cm, mm, um.

    Returns:
        :class:`Record`: times (s, from the first sample) and displacements (m).

    Raises:
        ParameterError: an unreadable file, a malformed header or row (named by its line).
    """
    return read(path, time_unit=time_unit, length_unit=length_unit)


@_api
def record_from_simulation(simulation: Simulation, *, rate_hz: float = 5000.0,
                           noise: float = 0.0, seed: int = 0):
    """A run as a field test records it (what ``treeimpact simulate --record`` writes).

    Args:
        simulation: a :func:`simulate` result.
        rate_hz: the sampling rate, Hz, in [50, 1e6] (default 5000, as the command's).
        noise: Gaussian noise as a fraction of the peak, in [0, 0.5] (default 0).
        seed: the noise's seed, an integer >= 0 (default 0).

    Returns:
        :class:`Record`: the trunk's displacement x (m) from 20 ms before the impact, times
        t (s) from the first sample.

    Raises:
        ParameterError: a rate, noise or seed out of range, or a backend without a
            trajectory.
    """
    check_sampling(rate_hz, noise, seed, names=("rate_hz", "noise", "seed"))
    t, x = sample(simulation.result, rate_hz, noise, seed)
    return Record(t=t, x=x, source=f"{simulation.scenario.name} ({simulation.backend})")


@_api
def tree_scenario(name: str, **measured) -> Scenario:
    """A scenario for your own tree from what you measured (the ``scenario`` command's):
    a pendulum test's M_T, K_T and b, or the tree's geometry and a crown mass estimate.

    Args:
        name: the scenario's name.
        **measured: the test (``clamp_height`` a, m; ``diameter`` d, m; ``impactor_mass``
            m, kg; ``equivalent_length`` l_e, m; ``release_angle_deg`` theta_r, deg), then
            one of two ways: the tree measured (``dynamic_mass`` M_T, kg;
            ``equivalent_stiffness`` K_T, N/m, or ``x_max`` m and ``tau`` s with ``a1``
            m/s and ``a2`` m/s^2, the regression of Figs 4-5; ``damping_rate`` b, 1/s, or
            ``a1`` and ``a2``; ``youngs_modulus`` E, Pa, required) or from its geometry
            (``crown_mass`` m_f, kg; the root spring, the damping and, when left out, E and
            ``density`` assumed as analytic.model.registry declares them), and the choices
            (``length``, ``density``, ``clamp_mass``, ``restitution``,
            ``contact_duration``, ``t_end``: the shipped trees' when left out), as
            :class:`compare.tree.scenario.TreeInputs` names them.

    Returns:
        :class:`Scenario`: measured, the trunk calibrated to M_T, K_T and b (eqs 7, 8, 42);
        from its geometry, M_T, K_T and C_T of eqs 7, 8, 10 with the assumptions; its notes
        saying what was given, chosen, calibrated or assumed (each assumption's value,
        range and reason), its t_end one the analytic model's x_max and separation fit in.

    Raises:
        ParameterError: an unknown, missing, contradictory or out-of-range input, named;
            the two ways mixed (naming the keywords given).
        TypeError: an input that is not a number (a bool, a text), or a name not a text.
        OutsideValidity: a tree whose analytic x_max lies beyond the clamp height.
    """
    known = {f.name for f in dataclasses.fields(TreeInputs)} - {"name"}
    unknown = sorted(set(measured) - known)
    if unknown:
        raise ParameterError(f"{unknown[0]}: not an input of tree_scenario"
                             f"{did_you_mean(unknown[0], known, TREE_RENAMED, style='keyword')}")
    check_keywords(name, measured)
    return build_tree_scenario(TreeInputs(name=name, **{k: float(v) for k, v in
                                                        measured.items() if v is not None}))


def pendulum_test(test, clamp_height, diameter):
    """The identification's PendulumTest (analytic.identify.procedure) of ``test``: a
    Scenario (its pendulum, its trunk's clamp height and diameter), or a Pendulum with the
    ``clamp_height`` a and ``diameter`` d (m) it struck; each checked against its range
    (ParameterError naming it). Shared by :func:`identify` and ``treeimpact identify``."""
    if isinstance(test, Scenario):
        if clamp_height is not None or diameter is not None:
            raise ParameterError("clamp_height, diameter: the scenario's trunk gives them; "
                                 "pass them only with a Pendulum")
        pend, clamp_height, diameter = (test.impactor, test.trunk.clamp_height,
                                        test.trunk.diameter)
    else:
        pend = test
    if not isinstance(pend, Pendulum):
        raise ParameterError(f"test: expected a Scenario or a Pendulum, got "
                             f"{type(pend).__name__} (the identification needs a pendulum)")
    for name, value in (("clamp_height", clamp_height), ("diameter", diameter)):
        if value is None:
            raise ParameterError(f"{name}: required with a Pendulum (m)")
        low, high, unit = LIMITS[f"trunk.{name}"]
        check_range(name, value, low=low, high=high, unit=unit)
    if not isinstance(test, Scenario):  # a scenario warned where it was read
        warn_implausible(implausible_values({
            "impactor.mass": pend.mass, "impactor.equivalent_length": pend.equivalent_length,
            "impactor.release_angle_deg": pend.release_angle_deg, "impactor.gravity":
            pend.gravity, "trunk.clamp_height": clamp_height, "trunk.diameter": diameter}))
    return PendulumTest(impactor_mass=pend.mass, equivalent_length=pend.equivalent_length,
                        release_angle=pend.release_angle_rad, clamp_height=clamp_height,
                        diameter=diameter, gravity=pend.gravity)


@_api
def identify(record, test, *, clamp_height: float | None = None,
             diameter: float | None = None, restitution: float | None = None
             ) -> Identification:
    """Tree properties from a pendulum-test record: the exact 1-DOF model fitted to every
    sample (docs/identification.md), as ``treeimpact identify``.

    Args:
        record: a :class:`Record` (:func:`read_record`, :func:`record_from_simulation`) or
            the path of a record file (read in s and m unless its header says otherwise).
        test: the test's :class:`Scenario` (its pendulum, clamp height and diameter) or its
            :class:`Pendulum`.
        clamp_height: the impact height a, m (with a Pendulum only).
        diameter: the trunk's diameter d, m (with a Pendulum only).
        restitution: the pad's e in [0, 1] if known, held fixed (default: fitted).

    Returns:
        :class:`Identification`: M_T (kg), K_T (N/m), C_T (N s/m), the damping ratios, e,
        E (Pa), each an :class:`Estimate` with its 95 % interval, and the verdict.

    Raises:
        ParameterError: an unreadable record, a test that is not a pendulum's, a value out
            of its range.
    """
    # lazy: +643 ms at import otherwise (scipy, numpy),
    # which this module's other callers do not need
    from treeimpact.analytic.identify.record_fit import fit_record


    the_test = pendulum_test(test, clamp_height, diameter)
    if isinstance(record, (str, Path)):
        record = read_record(record)
    if not isinstance(record, Record):
        raise ParameterError(f"record: expected a Record or a path, got "
                             f"{type(record).__name__}")
    if restitution is not None:
        check_range("restitution", restitution, low=0.0, high=1.0)
    return identification_of(fit_record(record, the_test, restitution=restitution),
                             record)


#: The ``treeimpact`` program as a child process runs it: a study run beside the report
#: (``with_study``) is its ``sweep --preset`` (compare.report.validity.study_job.StudyJob).
PROGRAM = (sys.executable, "-m", "treeimpact.compare.interface.cli")


@_api
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
    for study in studies:
        if not Path(study).is_dir():
            raise ParameterError(f"studies: {str(study)!r} is not a directory (a finished "
                                 "study, treeimpact sweep --out DIR)")
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


@_api
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


__all__ = ["backends", "design_map", "identify", "ladder", "modes", "read_record",
           "record_from_simulation", "report", "simulate", "sweep"]
