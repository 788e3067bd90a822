"""Session cache of backend runs, keyed by (scenario, backend, options).

Every run of ``pytest compare`` and of the report goes through one :class:`RunCache`, so a
scenario is simulated once per (backend, options) and shared by every test, the ladder and
the report. A run that cannot produce numbers keeps the reason instead:

* ``skipped``: the backend refused the run with a one-line :class:`ParameterError` (the
  engine package is not available here, or the engine cannot express the requested rung,
  e.g. an option it does not have);
* ``diverged``: the simulation raised :class:`SimulationDiverged` (a solver or an engine
  that diverged);
* ``outside validity``: a sound run whose result the model cannot represent
  (:class:`OutsideValidity`: x_max beyond the clamp height), worded "outside the model's
  validity", never as diverged;
* ``failed``: any other exception (a bug: the tests fail on it, the report shows it).

Nothing is ever dropped silently: the report lists every run with its status and reason.
"""

from __future__ import annotations

import hashlib
import json
import time
from dataclasses import dataclass, field
from enum import StrEnum

from treeimpact.analytic.errors import (
    OutsideValidity,
    ParameterError,
    SimulationDiverged,
    one_line,
)
from treeimpact.analytic.model.parameters import Scenario
from treeimpact.analytic.model.scenario import load_scenario, shipped_scenarios
from treeimpact.analytic.results import SimulationResult

from .backends import BACKENDS, get_backend
from .pool import process_map
from .progress import Progress


class Status(StrEnum):
    """What became of a run (a row of a sweep): the strings the tables and reports show."""

    OK = "ok"  # numbers
    SKIPPED = "skipped"  # refused with a one-line ParameterError (an option, an engine)
    DIVERGED = "diverged"  # SimulationDiverged: never numbers
    OUTSIDE = "outside validity"  # OutsideValidity: the model's validity, not a solver
    FAILED = "failed"  # any other exception: a bug
    INVALID = "invalid"  # a sweep point whose parameters the scenario refuses


OK, SKIPPED, DIVERGED, OUTSIDE, FAILED, INVALID = Status


@dataclass
class Run:
    """One backend run, the one record of it that the cache, the ladder, the sweeps and the
    report share: what ran, its :class:`Status`, the result (OK only) or the reason it has
    none, and its wall time (s). ``identification``: the paper's procedure on its record
    (:func:`compare.tree.identification.rung_identification`), computed once when asked for."""

    scenario: str
    backend: str
    options: dict
    status: Status
    result: SimulationResult | None = None
    reason: str | None = None
    wall_s: float = 0.0
    identification: object = None

    @property
    def ok(self) -> bool:
        """Whether the run finished (status OK)."""
        return self.status == OK

    @property
    def stepping(self) -> dict | None:
        """What an engine run's stepping cost (its result's ``extra["stepping"]``: steps,
        dt s, what set dt, wall s and us per step, the full pendulum's swing s); None for a
        run without a result or a backend that does not step (docs/engines.md)."""
        if self.result is None:
            return None
        return self.result.extra.get("stepping")

    def describe(self) -> str:
        """``scenario backend(name=value, ...)``, one line."""
        opts = ", ".join(f"{k}={v}" for k, v in sorted(self.options.items()))
        return f"{self.scenario} {self.backend}({opts})"

    def to_json(self) -> dict:
        """scenario, backend, options, status, reason, wall time (s) and an engine run's
        :attr:`stepping` (absent otherwise); not the result."""
        out = {"scenario": self.scenario, "backend": self.backend,
               "options": dict(self.options), "status": self.status,
               "reason": self.reason, "wall_s": self.wall_s}
        if self.stepping is not None:
            out["stepping"] = dict(self.stepping)
        return out


def failure(exc: Exception, invalid: str) -> tuple[str, str]:
    """(status, one-line reason) of a run or an analysis that raised ``exc``: ``invalid``
    (the caller's status for inputs that make no valid run) for a ParameterError, OUTSIDE,
    DIVERGED, else FAILED with the exception's type."""
    if isinstance(exc, ParameterError):
        return invalid, one_line(exc)
    if isinstance(exc, OutsideValidity):  # before SimulationDiverged, its base
        return OUTSIDE, f"outside the model's validity: {one_line(exc)}"
    if isinstance(exc, SimulationDiverged):
        return DIVERGED, f"diverged: {one_line(exc)}"
    return FAILED, f"{type(exc).__name__}: {one_line(exc)}"


def attempt(backend, scenario: Scenario, options: dict) -> Run:
    """The :class:`Run` of one backend run of ``scenario`` with ``options`` (``backend``: a
    :class:`compare.runs.backends.Backend`), timed; never raises for a failing run (SKIPPED,
    OUTSIDE, DIVERGED or FAILED with its reason)."""
    t0 = time.perf_counter()
    result, reason, status = None, None, OK
    try:
        result = backend.simulate(scenario, **options)
    except Exception as exc:  # noqa: BLE001 - recorded, shown, and failed on by the tests
        status, reason = failure(exc, SKIPPED)
    return Run(scenario.name, backend.name, dict(options), status, result, reason,
               time.perf_counter() - t0)


def resolve_scenario(scenario) -> Scenario:
    """A :class:`Scenario` from ``scenario``: a shipped name, a TOML path or a Scenario."""
    if isinstance(scenario, Scenario):
        return scenario

    return load_scenario(scenario)


def is_shipped(scenario: Scenario) -> bool:
    """Whether ``scenario`` is a shipped tree input for input (its name and every input
    equal to the packaged file's), not a user's tree that shares a name."""
    if scenario.name not in shipped_scenarios():
        return False
    return scenario_key(scenario) == scenario_key(load_scenario(scenario.name))


def scenario_key(scenario: Scenario) -> str:
    """The scenario's name plus a digest of all its inputs (two edits of one name differ)."""
    text = json.dumps(scenario.to_dict(), sort_keys=True, default=str)
    return f"{scenario.name}#{hashlib.sha1(text.encode()).hexdigest()[:10]}"


def options_key(options: dict) -> tuple:
    """``options`` as a hashable key: its (name, value) items, sorted."""
    return tuple(sorted(options.items()))


@dataclass
class RunCache:
    """Runs keyed by (scenario inputs, backend, options); see the module docstring."""

    runs: dict = field(default_factory=dict)

    def run(self, scenario, backend: str, **options) -> Run:
        """The :class:`Run` of ``scenario`` on ``backend`` with ``options``: cached, or
        attempted now and kept (never raises for a failing run)."""
        scen = resolve_scenario(scenario)
        key = (scenario_key(scen), backend, options_key(options))
        hit = self.runs.get(key)
        if hit is not None:
            return hit

        try:
            run = attempt(get_backend(backend), scen, options)
        except ParameterError as exc:  # not a backend of the registry
            run = Run(scen.name, backend, dict(options), SKIPPED, reason=one_line(exc))
        self.runs[key] = run
        return run

    def prefetch(self, requests, workers: int | None = None, progress: bool = False) -> None:
        """Run the (scenario, backend, options) requests not yet cached on a process pool.

        Each run is the same call :meth:`run` makes, in a worker process (``forkserver``: the
        engines' thread pools are never forked), so the cache ends up exactly as after
        serial :meth:`run` calls, only sooner. The slowest kinds (hinged-trunk engine runs)
        are sent first. ``workers``: default the CPU count; 1 runs serially. ``progress``:
        report finished runs on stderr (:class:`compare.runs.progress.Progress`).
        """
        todo, seen = [], set()
        for scenario, backend, options in requests:
            scen = resolve_scenario(scenario)
            key = (scenario_key(scen), backend, options_key(options))
            if key not in self.runs and key not in seen:
                seen.add(key)
                todo.append((key, scen, backend, dict(options)))

        # slowest first; a backend not in the registry is a run that records its own skip
        todo.sort(key=lambda t: -(BACKENDS[t[2]].cost(t[3]) if t[2] in BACKENDS else 0.0))
        bar = Progress(len(todo), "runs") if progress else None  # a stage even when cached
        runs = process_map(_run_uncached, [t[1:] for t in todo], workers=workers,
                           done=bar.update if bar is not None else None, died=_died)
        for (key, *_), run in zip(todo, runs):
            self.runs[key] = run
        if bar is not None:
            bar.close()

    def __iter__(self):
        return iter(self.runs.values())

    def __len__(self):
        return len(self.runs)

    def timings(self) -> dict:
        """Wall time (s) and number of runs per backend."""
        out: dict = {}
        for r in self.runs.values():
            t = out.setdefault(r.backend, {"runs": 0, "wall_s": 0.0})
            t["runs"] += 1
            t["wall_s"] += r.wall_s
        return out


def _died(request: tuple, exc: BaseException) -> Run:
    """The run whose worker process died (a crash inside an engine): failed, with why."""
    scenario, backend, options = request
    return Run(scenario.name, backend, dict(options), FAILED,
               reason=f"worker process died running this ({type(exc).__name__})")


def _run_uncached(request: tuple) -> Run:
    """One (scenario, backend, options) run in a worker process (:meth:`RunCache.prefetch`)."""
    scenario, backend, options = request
    return RunCache().run(scenario, backend, **options)
