"""Run a sweep: every grid point on every target, results appended as they finish.

Design notes and measured figures: docs/sweeps.md.
"""

from __future__ import annotations

import dataclasses
import hashlib
import os
import time
from dataclasses import dataclass, field
from pathlib import Path

from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.model.parameters import Scenario
from treeimpact.analytic.results import json_text
from treeimpact.compare.runs.cache import resolve_scenario
from treeimpact.compare.runs.pool import (
    check_stop,
    check_workers,
    connect,
    dask_workers,
    run_chunks,
)
from treeimpact.compare.runs.provenance import provenance

from ...runs.progress import Progress
from .cost import chunks
from .execute import Task, died, execute, run_chunk
from .grid import INPUT, RECORD, Grid, parse_grid
from .journal import (
    JOURNAL,
    SPEC,
    Journal,
    check_spec,
    columns_for,
    finished,
    make_out,
    read_table,
    spec_of,
    write_parquet,
)
from .plan import check_grid, make_targets, plan, row_base


@dataclass
class SweepResult:
    """A finished (or resumed) sweep (docs/sweeps.md).

    Attributes:
        out: its directory.
        table: one row per grid point and backend (a pandas DataFrame).
        tasks_run: the backend calls this invocation made, a count.
        rows_written: the rows it appended, a count.
        rows_done_before: the rows found finished and skipped (resumed), a count.
        wall_s: its wall time, s.
    """

    out: Path
    table: object  # pandas DataFrame, deduplicated
    tasks_run: int  # backend calls made by this invocation
    rows_written: int  # rows appended by this invocation
    rows_done_before: int  # rows found finished and skipped (resume)
    wall_s: float

    @property
    def journal(self) -> Path:
        """The path of its journal (``results.csv`` in ``out``)."""
        return self.out / JOURNAL


@dataclass(frozen=True)
class SweepSpec:
    """One sweep of :func:`run_sweeps`: ``scenario`` (a Scenario, shipped name or TOML path)
    over ``grid`` (a :class:`Grid` or ``--grid`` specs) on ``backends`` into the directory
    ``out``; ``analysis``: ``module:function`` run on each result instead of the standard
    metrics (:func:`load_analysis`), its record parameters from ``record.*`` axes;
    ``label``: what a refusal of its grid names instead of the ``--grid`` spec (a grid a
    study made, which nobody typed)."""

    scenario: object
    grid: object
    out: object
    backends: tuple = ("analytic",)
    ladder: bool = False
    options: dict | None = None
    identify: bool = True
    analysis: str | None = None
    label: str | None = None


def run_sweep(scenario, grid, out, *, backends=("analytic",), ladder: bool = False,
              options: dict | None = None, workers: int | None = None, scheduler=None,
              identify: bool = True, retry_failed: bool = False, progress=None,
              on_rows=None, analysis: str | None = None) -> SweepResult:
    """Run (or resume) a sweep into the directory ``out``; see the module docstring. Returns
    its :class:`SweepResult`.

    ``scenario``: a Scenario, shipped name or TOML path; ``grid``: a :class:`Grid` or
    ``--grid`` specs; ``backends``, ``ladder`` and ``options``: the targets, as
    compare.studies.sweep.plan.make_targets takes them; ``identify``: the paper's identification on
    each run's record (the ``id.*`` and ``truth.*`` columns); ``analysis``:
    ``module:function`` run on each result instead of the standard columns. ``workers``,
    ``scheduler``, ``retry_failed``, ``progress`` and ``on_rows`` as :func:`run_sweeps`
    takes them.
    """
    spec = SweepSpec(scenario, grid, out, tuple(backends) if not isinstance(backends, str)
                     else backends, ladder, options, identify, analysis)
    return run_sweeps([spec], workers=workers, scheduler=scheduler,
                      retry_failed=retry_failed, progress=progress, on_rows=on_rows)[0]


@dataclass
class _Part:
    """A sweep being run: its spec resolved, its tasks and its journal."""

    scenario: Scenario
    grid: Grid
    targets: list
    out: Path
    identify: bool
    analysis: str | None
    applied: list
    done: set = field(default_factory=set)
    tasks: list = field(default_factory=list)
    immediate: list = field(default_factory=list)
    journal: Journal | None = None
    written: int = 0


def run_sweeps(specs, *, workers: int | None = None, scheduler=None,
               retry_failed: bool = False, progress=None, on_rows=None) -> list[SweepResult]:
    """Run (or resume) several sweeps, the ``specs`` (:class:`SweepSpec`), on one pool, with
    one progress report: every spec is checked before anything runs, each sweep writes its
    own directory (table, spec), and the runs of all of them are grouped into worker calls
    together. Returns one :class:`SweepResult` per spec, in order.

    ``workers``: worker processes (None: one per core; 0: in this process); ``scheduler``:
    a Dask scheduler address or ``Client`` to run on instead (its workers counted);
    ``retry_failed``: rerun the rows whose last outcome was not ok (failed, diverged,
    invalid; else only unfinished rows run); ``progress``: None a bar on a terminal (nothing elsewhere),
    True a bar, False nothing; ``on_rows``: called with each batch of rows after it is
    written (tests interrupt a sweep there)."""
    t_start = time.perf_counter()
    check_workers(workers)
    parts = []
    for spec in specs:  # every check before anything runs or is written
        scen = resolve_scenario(spec.scenario)
        grid = spec.grid if isinstance(spec.grid, Grid) else parse_grid(spec.grid)
        targets = make_targets(spec.backends, ladder=spec.ladder, options=spec.options)
        records = [a.spec() for a in grid.axes if a.parameter.kind in (RECORD, INPUT)]
        if records and spec.analysis is None:
            raise ParameterError(f"--grid {records[0]!r}: record and input parameters are "
                                 "read by an analysis (the identification and sensitivity "
                                 "studies), not by a plain sweep")
        parts.append(_Part(scen, grid, targets, Path(spec.out), spec.identify, spec.analysis,
                           check_grid(scen, grid, targets, label=spec.label)))
    client, own_client = connect(scheduler) if scheduler is not None else (None, False)
    try:
        return _sweep(parts, workers=workers, client=client, retry_failed=retry_failed,
                      progress=progress, on_rows=on_rows, t_start=t_start)
    finally:
        if own_client:
            client.close()


def _open(part: _Part, index: int, retry_failed: bool) -> None:
    """Create the part's directory and spec, read what an earlier run finished, plan the
    rest and open its journal."""
    part.out = make_out(part.out)
    spec = spec_of(part.scenario, part.grid, part.identify, part.analysis)
    check_spec(part.out, spec)
    (part.out / SPEC).write_text(json_text(spec | {
        "targets": [dataclasses.asdict(t) for t in part.targets],
        "provenance": provenance(part.scenario)}, indent=2))
    journal_path = part.out / JOURNAL
    part.done = finished(journal_path, retry_failed)
    part.tasks, part.immediate = plan(part.scenario, part.grid, part.targets,
                                      identify=part.identify, done=part.done,
                                      applied=part.applied, analysis=part.analysis,
                                      part=index)
    part.journal = Journal(journal_path, columns_for(part.grid, part.analysis))


def _sweep(parts, *, workers, client, retry_failed, progress, on_rows,
           t_start) -> list[SweepResult]:
    try:
        for i, part in enumerate(parts):
            _open(part, i, retry_failed)
        tasks = [t for part in parts for t in part.tasks]
        total = sum(len(p.immediate) for p in parts) + sum(len(t.rows) for t in tasks)
        bar = _progress(total, progress)

        def emit(part, rows):
            part.journal.append(rows)
            part.written += len(rows)
            if bar is not None:
                bar.update(len(rows))
            if on_rows is not None:
                on_rows(rows)

        def emit_tasks(chunk, outcomes):  # one flushed write per sweep per call
            for part in parts:
                rows = [r for t, o in zip(chunk, outcomes) if t.part == parts.index(part)
                        for r in _rows_of(t, o, part.scenario)]
                if rows:
                    emit(part, rows)

        try:
            for part in parts:
                if part.immediate:
                    emit(part, part.immediate)
            if tasks and workers == 0 and client is None:  # in this process
                for task in tasks:
                    emit_tasks([task], [execute(task)])
                    check_stop()
            elif tasks:
                n = dask_workers(client) if client is not None else workers or os.cpu_count() \
                    or 1
                run_chunks(run_chunk, chunks(tasks, n), workers=n, client=client,
                           on_result=emit_tasks, on_died=died)
        finally:
            if bar is not None:
                bar.close()
    finally:
        for part in parts:
            if part.journal is not None:
                part.journal.close()
                write_parquet(part.out)
    wall = time.perf_counter() - t_start
    return [SweepResult(p.out, read_table(p.out, grid=p.grid), len(p.tasks), p.written,
                        len(p.done), wall) for p in parts]


def _rows_of(task: Task, outcomes: list, scenario: Scenario) -> list[dict]:
    tid = hashlib.sha1(task.key.encode()).hexdigest()[:12]
    now = time.time()
    return [row_base(scenario, point, pk, t) | outcome | {"task": tid, "finished": now}
            for (point, pk, t, _), outcome in zip(task.rows, outcomes)]


def _progress(total: int, enabled):
    """Rows reported on stderr: ``enabled`` None, a bar on a terminal and nothing elsewhere (a
    child job's records for its parent); True, a bar; False, nothing."""
    if enabled is False or total == 0:
        return None

    return Progress(total, "sweep", unit="row", bar=True if enabled else None)
