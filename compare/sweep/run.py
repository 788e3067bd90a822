"""Run a sweep: every grid point on every target, results appended as they finish.

Design notes and measured figures: docs/sweeps.md.
"""

from __future__ import annotations

import csv
import dataclasses
import json
import math
import os
import socket
import time
from collections import OrderedDict
from dataclasses import dataclass, field
from pathlib import Path

from treeimpact.analytic.errors import ParameterError, one_line
from treeimpact.analytic.model.parameters import Scenario
from treeimpact.analytic.results import METRIC_KEYS
from treeimpact.compare.backends import get_backend
from treeimpact.compare.pool import (
    check_stop,
    check_workers,
    connect,
    dask_workers,
    run_chunks,
)
from treeimpact.compare.provenance import provenance
from treeimpact.compare.rungs import RungKind, analytic_samples
from treeimpact.compare.runs import DIVERGED, FAILED, INVALID, OK, attempt

from .apply import apply_point
from .grid import INPUT, RECORD, Grid, parse_grid, point_key

JOURNAL = "results.csv"
TABLE = "results.parquet"
SPEC = "sweep.json"

REFERENCE_BACKENDS = ("analytic", "soft", "beam")
MODEL_KEYS = ("M_T", "C_T", "K_T", "m", "k", "restitution", "u1", "segments", "dt",
              "contact_stiffness", "contact_damping", "contact_reduced_mass",
              "pad_damping_ratio")
IDENT_KEYS = ("M_T", "K_T", "xi", "E")
BASE_COLUMNS = ("scenario", "point", "target", "backend", "kind", "previous", "status", "error",
                "wall_s", "t_end", "task", "worker", "finished")


def columns_for(grid: Grid, analysis: str | None = None) -> list[str]:
    """The table's columns: the run's, the grid's axes, then the metrics, model and the
    identification (the standard analysis) or the columns ``analysis`` declares."""
    if analysis is not None:
        return list(BASE_COLUMNS) + list(grid.names) + list(load_analysis(analysis).columns)
    return (list(BASE_COLUMNS) + list(grid.names) + list(METRIC_KEYS)
            + [f"model.{k}" for k in MODEL_KEYS] + [f"id.{k}" for k in IDENT_KEYS]
            + [f"truth.{k}" for k in IDENT_KEYS] + ["id_error"])


def load_analysis(ref: str):
    """The analysis function of a ``module:function`` reference: ``fn(result, scenario,
    record) -> {column: value}`` with its ``columns`` (a tuple) as an attribute."""
    import importlib

    module, name = ref.split(":")
    return getattr(importlib.import_module(module), name)


# --------------------------------------------------------------------------- targets


@dataclass(frozen=True)
class Target:
    """What one row runs: ``backend`` with fixed ``options``, compared with ``previous``."""

    id: str
    backend: str
    options: tuple = ()  # sorted (name, value) pairs
    previous: str | None = None
    kind: RungKind = RungKind.MODEL  # the ladder's kind; MODEL for an engine run as
    # configured, compared with soft (numerics and trunk/pendulum together)
    drop: tuple = ()  # swept options this target ignores (segments for an SDOF trunk)

    @property
    def reference(self) -> bool:
        return self.backend in REFERENCE_BACKENDS


def _check_backends(backends) -> list[str]:

    if isinstance(backends, str):
        backends = [b.strip() for b in backends.split(",") if b.strip()]
    out = []
    for b in backends:
        try:
            get_backend(b)
        except ParameterError:
            from treeimpact.compare.backends import BACKENDS

            raise ParameterError(f"--backend {b!r}: allowed {', '.join(BACKENDS)} "
                                 f"(comma-separated)") from None
        if b not in out:
            out.append(b)
    return out


def make_targets(backends=("analytic",), *, ladder: bool = False,
                 options: dict | None = None) -> list[Target]:
    """The targets of a sweep (see the module docstring). ``options`` maps a backend name
    to fixed options for it (``{"mujoco": {"trunk": "sdof"}}``)."""
    names = _check_backends(backends)
    options = options or {}
    for b in options:
        _check_backends([b])

    def opts(backend, extra=()):
        return tuple(sorted({**dict(extra), **options.get(backend, {})}.items()))

    from treeimpact.compare.rungs import rung_table

    if ladder:  # the ladder's own rung table, chain segments left to the grid
        engines = [b for b in names if b not in REFERENCE_BACKENDS]
        return [Target(r.id, r.backend, opts(r.backend, r.options), r.previous, r.kind, r.drop)
                for r in rung_table(engines)]
    # the reference rungs of the same table that were asked for, each compared with the one
    # below it; the engines' default trunk is the hinged chain: the beam is its reference
    table = {r.id: r for r in rung_table(())}
    targets, below = [], None
    for rid in ("analytic", "soft", "beam"):
        if rid == "analytic" or rid in names:
            r = table[rid]
            targets.append(Target(r.id, r.backend, opts(r.backend, r.options), below, r.kind))
            below = rid
    for eng in (b for b in names if b not in REFERENCE_BACKENDS):  # engines (or any other)
        targets.append(Target(eng, eng, opts(eng), below, RungKind.MODEL))
    return targets


# --------------------------------------------------------------------------- one run


@dataclass
class Task:
    """One backend call, shared by every (point, target) row whose inputs are identical;
    ``analysis`` (``module:function``) runs on its result once per distinct record
    parameters of the rows (grid axes ``record.*``) instead of the standard columns."""

    key: str
    scenario: Scenario
    backend: object  # compare.backends.Backend (pickled whole, so a worker needs no registry)
    options: dict
    identify: bool
    analysis: str | None = None
    part: int = 0  # the sweep of run_sweeps it belongs to
    rows: list = field(default_factory=list)  # (point, point key, target, record parameters)


def _identify(result, scenario: Scenario) -> dict:
    """The paper's procedure on the run's record (compare.identification.identify_rung) as the
    sweep's id.* and truth.* columns, or id_error."""
    from treeimpact.compare.identification import identify_rung

    ident = identify_rung(result, scenario)
    out = {f"truth.{k}": v for k, v in ident.truth.items()}
    if not ident.ok:
        out["id_error"] = ident.reason
        return out
    out.update({f"id.{k}": float(v) for k, v in ident.values.items()})
    return out


def execute(task: Task) -> list[dict]:
    """Run one task: the outcome of each of its rows; never raises for a failing run (the
    error is the outcome)."""
    done = attempt(task.backend, task.scenario, task.options)
    out = {"status": str(done.status), "error": done.reason, "t_end": task.scenario.t_end,
           "worker": f"{socket.gethostname()}:{os.getpid()}", "wall_s": done.wall_s}
    result = done.result
    if done.status == OK:
        infinite = [k for k in METRIC_KEYS if math.isinf(_num(result.metrics.get(k)))]
        if infinite:  # a run that returned instead of raising: a divergence, not numbers
            out.update(status=DIVERGED, error=f"diverged: infinite {', '.join(infinite)}")
    if out["status"] != OK:
        return [out] * len(task.rows)
    if task.analysis is None:
        out.update({k: _num(result.metrics.get(k)) for k in METRIC_KEYS})
        model = result.model or {}
        out.update({f"model.{k}": _num(model.get(k)) for k in MODEL_KEYS})
        if task.identify:
            out.update(_identify(result, task.scenario))
        return [out] * len(task.rows)
    analyse = load_analysis(task.analysis)
    made: dict = {}
    outcomes = []
    for *_, record in task.rows:  # one analysis per distinct record parameters
        key = json.dumps(record, sort_keys=True)
        if key not in made:
            made[key] = out | analyse(result, task.scenario, record)
        outcomes.append(made[key])
    return outcomes


def run_chunk(tasks: list) -> list:
    """Worker entry point: each task's row outcomes, in order."""
    return [execute(t) for t in tasks]


def _num(v):
    if v is None:
        return math.nan
    try:
        return float(v)
    except (TypeError, ValueError):
        return math.nan


# --------------------------------------------------------------------------- the table


def _header(path: Path):
    with open(path, newline="", encoding="utf-8") as fh:
        return next(csv.reader(fh), None)


def read_file(path: Path, reader, what: str):
    """``reader(path)`` of a file a sweep wrote and reads back (its journal, table, spec), or
    a one-line ParameterError naming it when it is not what the sweep wrote: corrupt,
    another encoding, nested beyond reason, a field longer than a CSV reader takes."""
    import csv as csv_module

    import pandas as pd

    try:
        return reader(path)
    except (ValueError, UnicodeDecodeError, RecursionError, csv_module.Error,
            pd.errors.ParserError, pd.errors.EmptyDataError, OSError) as exc:
        detail = str(exc).strip().splitlines()[0][:120] if str(exc).strip() else \
            type(exc).__name__
        raise ParameterError(f"--out {str(path.parent)!r}: {path.name} is not the {what} a "
                             f"sweep writes ({type(exc).__name__}: {detail}); move it away "
                             "or use a new --out") from None


class Journal:
    """The CSV table, appended one flushed line per row."""

    def __init__(self, path: Path, columns: list[str]):
        self.path = Path(path)
        self.columns = columns
        fresh = not self.path.exists() or self.path.stat().st_size == 0
        if not fresh:
            _drop_partial_line(self.path)
            header = read_file(self.path, _header, "table")
            if header != columns:
                raise ParameterError(f"--out {self.path.parent}: {self.path.name} has other "
                                     f"columns (another grid); use a new --out")
        self.fh = open(self.path, "a", newline="")
        self.writer = csv.writer(self.fh)
        if fresh:
            self.writer.writerow(columns)
            self.fh.flush()

    def append(self, rows: list[dict]) -> None:
        for r in rows:
            self.writer.writerow([_cell(r.get(c)) for c in self.columns])
        self.fh.flush()

    def close(self) -> None:
        self.fh.close()


def _cell(v):
    if v is None:
        return ""
    if isinstance(v, float):
        return "" if math.isnan(v) else repr(v)
    if isinstance(v, str):
        return " ".join(v.split())  # one line per row, always
    return v


def _drop_partial_line(path: Path) -> None:
    """Cut a last line left unfinished by a killed sweep (it was never a finished row)."""
    with open(path, "rb+") as fh:
        data = fh.read()
        if data.endswith(b"\n"):
            return
        fh.truncate(data.rfind(b"\n") + 1)


def read_table(out, *, dedupe: bool = True, grid: Grid | None = None):
    """The sweep's rows as a pandas DataFrame (last row per (point, target) when ``dedupe``;
    only the points of ``grid`` when given: a directory resumed with other values keeps the
    earlier rows in its journal)."""
    import pandas as pd

    out = Path(out)
    journal = out / JOURNAL
    if journal.exists():
        _drop_partial_line(journal)
        df = read_file(journal, lambda p: pd.read_csv(p, keep_default_na=True), "table")
    elif (out / TABLE).exists():
        df = read_file(out / TABLE, pd.read_parquet, "table")
    else:
        raise ParameterError(f"--out {out}: no sweep table ({JOURNAL} or {TABLE}) there")
    if dedupe and len(df):
        df = df.drop_duplicates(subset=["point", "target"], keep="last").reset_index(drop=True)
    if grid is not None and len(df):
        df = df[df["point"].isin({point_key(p) for p in grid.points()})].reset_index(drop=True)
    return df


def write_parquet(out) -> Path:
    out = Path(out)
    df = read_table(out)
    for c in df.columns:  # Parquet needs one type per column: text columns stay text
        if df[c].dtype == object:
            df[c] = df[c].astype("string")
    path = out / TABLE
    df.to_parquet(path, index=False)
    return path


# --------------------------------------------------------------------------- the sweep


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
        return self.out / JOURNAL


def make_out(out) -> Path:
    """The output directory, created; a one-line ``--out`` error when it cannot be."""
    out = Path(out)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ParameterError(f"--out {str(out)!r}: cannot create the directory "
                             f"({exc.strerror or type(exc).__name__}); allowed: a new or "
                             f"existing writable directory") from None
    return out


def _spec(scenario: Scenario, grid: Grid, identify: bool, analysis: str | None) -> dict:
    return {"version": 1, "scenario": scenario.to_dict(), "grid": grid.specs(),
            "axes": list(grid.names), "identify": identify, "analysis": analysis}


def _check_spec(out: Path, spec: dict) -> None:
    path = out / SPEC
    if not path.exists():
        return
    old = read_file(path, lambda p: json.loads(p.read_text(encoding="utf-8")), "spec")
    if not isinstance(old, dict):
        raise ParameterError(f"--out {str(out)!r}: {SPEC} is not the spec a sweep writes; "
                             "move it away or use a new --out")
    for key in ("scenario", "axes", "identify", "analysis"):
        if json.dumps(old.get(key), sort_keys=True) != json.dumps(spec[key], sort_keys=True):
            raise ParameterError(f"--out {out}: holds a sweep with another {key} "
                                 f"({SPEC}); use a new --out to start a different sweep")


def apply_points(scenario: Scenario, grid: Grid) -> list[tuple]:
    """Every grid point with what :func:`~compare.sweep.apply.apply_point` makes of it:
    ``(point, (scenario, options))``, or ``(point, ParameterError)`` for an invalid point.
    Computed once per sweep (:func:`check_grid` and :func:`plan` both read it)."""
    out = []
    for point in grid.points():
        try:
            out.append((point, apply_point(scenario, point)))
        except ParameterError as exc:
            out.append((point, exc))
    return out


def plan(scenario: Scenario, grid: Grid, targets: list[Target], *, identify: bool = True,
         done: set | None = None, applied: list | None = None, analysis: str | None = None,
         part: int = 0):
    """(tasks to run, rows already decided without running: invalid points).
    ``applied``: :func:`apply_points` of this scenario and grid, when already computed."""
    from treeimpact.compare.runs import options_key, scenario_key

    done = done or set()
    tasks: OrderedDict[str, Task] = OrderedDict()
    immediate = []
    accepted = {t.id: _accepted(t.backend) for t in targets}
    for point, outcome in (applied if applied is not None else apply_points(scenario, grid)):
        pk = point_key(point)
        record = {a.parameter.target: point[a.name] for a in grid.axes
                  if a.parameter.kind in (RECORD, INPUT)}  # the analysis's, not the run's
        todo = [t for t in targets if (pk, t.id) not in done]
        if not todo:
            continue
        if isinstance(outcome, ParameterError):
            for t in todo:
                immediate.append(_row_base(scenario, point, pk, t) | {
                    "status": INVALID, "error": one_line(outcome), "t_end": scenario.t_end})
            continue
        scen, popts = outcome
        for t in todo:
            opts = dict(t.options)
            for name, value in popts.items():
                if name in t.drop or (t.reference and name not in accepted[t.id]):
                    continue  # the option does not change this target's model
                opts[name] = value
            if not t.reference:
                opts = _trunk_options(opts, accepted[t.id])
            if t.backend == "analytic" and identify and "samples" in accepted[t.id] \
                    and "samples" not in opts:
                opts["samples"] = analytic_samples(scen.t_end)
            key = [scenario_key(scen), t.backend, options_key(opts)]
            if analysis is not None and record and \
                    get_backend(t.backend).cost(opts) < ANALYSIS_COST:
                # a run cheaper than its analysis is repeated per record: the records'
                # analyses spread over the workers instead of queueing on one
                key.append(record)
            key = json.dumps(key, default=str, sort_keys=True)
            task = tasks.get(key)
            if task is None:
                task = tasks[key] = Task(key, scen, get_backend(t.backend), opts, identify,
                                         analysis, part)
            task.rows.append((point, pk, t, record))
    return list(tasks.values()), immediate


def _accepted(backend: str) -> set:
    """The options ``backend``'s simulate() takes (empty when it is not installed: its rows
    are then skipped with the backend's own reason)."""

    try:
        return set(get_backend(backend).options())
    except ParameterError:
        return set()


def _trunk_options(opts: dict, accepted: set) -> dict:
    """An engine's options with ``segments`` read against its trunk: ``segments = 1`` is the
    one-degree-of-freedom trunk (``trunk = sdof``, eq 7; a hinged chain needs 2 or more), and
    an SDOF trunk has no segments (dropped: they do not change its model)."""
    if "trunk" not in accepted or "segments" not in opts:
        return opts
    if opts["segments"] == 1:
        return {k: v for k, v in opts.items() if k != "segments"} | {"trunk": "sdof"}
    if opts.get("trunk") == "sdof":
        return {k: v for k, v in opts.items() if k != "segments"}
    return opts


def check_grid(scenario: Scenario, grid: Grid, targets: list[Target]) -> list[tuple]:
    """Refuse, before anything runs, what no grid point could run (one-line ParameterError
    naming the ``--grid`` spec): an engine option that no backend of the sweep takes, and an
    axis value outside its parameter's range at every point (``restitution=2``). A point that is
    invalid only in combination with other axes (a clamp height above one of the swept
    lengths) is kept: it becomes an ``invalid`` row and the sweep goes on. Returns
    :func:`apply_points` of the grid, for :func:`plan`."""
    accepted = set().union(*(_accepted(t.backend) for t in targets))
    for ax in grid.axes:
        p = ax.parameter
        if p.kind == "option" and p.target not in accepted:
            raise ParameterError(
                f"--grid {ax.spec()!r}: no backend of this sweep "
                f"({', '.join(dict.fromkeys(t.backend for t in targets))}) takes the option "
                f"{p.target!r}; allowed: {', '.join(sorted(accepted))}")
    applied = apply_points(scenario, grid)
    errors = [one_line(o) if isinstance(o, ParameterError) else None for _, o in applied]
    if not any(errors):
        return applied
    for ax in grid.axes:
        for v in ax.values:
            errs = [e for (point, _), e in zip(applied, errors) if point[ax.name] == v]
            if all(errs):
                raise ParameterError(f"--grid {ax.spec()!r}: {errs[0]} (at every point of "
                                     f"the grid)")
    return applied


def _row_base(scenario, point, pk, target: Target) -> dict:
    return {"scenario": scenario.name, "point": pk, "target": target.id,
            "backend": target.backend, "kind": target.kind, "previous": target.previous,
            **point}


def _rows_of(task: Task, outcomes: list, scenario: Scenario) -> list[dict]:
    import hashlib

    tid = hashlib.sha1(task.key.encode()).hexdigest()[:12]
    now = time.time()
    return [_row_base(scenario, point, pk, t) | outcome | {"task": tid, "finished": now}
            for (point, pk, t, _), outcome in zip(task.rows, outcomes)]


#: Seconds one record's analysis takes (a full-record fit of compare.ident_study, median
#: 0.5 s, docs/identification.md): a run cheaper than this is repeated per record.
ANALYSIS_COST = 0.5

#: Seconds of estimated work per worker call. A call costs scheduling: measured on the 2-core
#: VM, 4 ms a call through a Dask LocalCluster (0.02 s calls ran at 89 % of two cores, 0.1 s
#: calls at 96 %) and well under 1 ms through the process pool; so short runs are grouped.
#: An interrupted sweep loses at most about this much finished work per worker (a run
#: longer than this is a call of its own).
CALL_BUDGET = 1.0


def _cost_class(task: Task) -> tuple:
    trunk = task.options.get("trunk")
    return (task.backend.name, trunk if trunk == "sdof" else None)


def _run_cost(cost_class: tuple) -> float:
    """Rough cost (s) of one run of a class: the registry's
    (:meth:`compare.backends.Backend.cost`); what decides how many runs go into one call."""
    backend, trunk = cost_class
    return get_backend(backend).cost({"trunk": trunk} if trunk else {})


def _chunks(tasks: list, workers: int) -> list[list]:
    """Tasks grouped into worker calls: runs of one cost class (:func:`_run_cost`) up to
    :data:`CALL_BUDGET` seconds a call, and no fewer than about 8 calls per worker; order
    kept within a class. The calls come longest first (estimated), so the short ones (the
    analytic reference runs) fill the workers' last gaps instead of a long call running
    alone at the end."""
    classes = [_cost_class(t) for t in tasks]
    count = {c: classes.count(c) for c in set(classes)}
    size = {c: max(1, min(int(CALL_BUDGET / _run_cost(c)),
                          n // max(1, 8 * workers))) for c, n in count.items()}
    chunks, open_ = [], {}
    for t, c in zip(tasks, classes):
        group = open_.setdefault(c, [])
        group.append(t)
        if len(group) >= size[c]:
            chunks.append(group)
            open_[c] = []
    chunks += [g for g in open_.values() if g]
    chunks.sort(key=lambda c: -len(c) * _run_cost(_cost_class(c[0])))  # stable
    return chunks


def _progress(total: int, enabled):
    """Rows reported on stderr: ``enabled`` None, a bar on a terminal and a line every few
    seconds elsewhere; True, a bar; False, nothing."""
    if enabled is False or total == 0:
        return None
    from ..progress import Progress

    return Progress(total, "sweep", unit="row", bar=True if enabled else None)


@dataclass(frozen=True)
class SweepSpec:
    """One sweep of :func:`run_sweeps`: ``scenario`` (a Scenario, shipped name or TOML path)
    over ``grid`` (a :class:`Grid` or ``--grid`` specs) on ``backends`` into the directory
    ``out``; ``analysis``: ``module:function`` run on each result instead of the standard
    metrics (:func:`load_analysis`), its record parameters from ``record.*`` axes."""

    scenario: object
    grid: object
    out: object
    backends: tuple = ("analytic",)
    ladder: bool = False
    options: dict | None = None
    identify: bool = True
    analysis: str | None = None


def run_sweep(scenario, grid, out, *, backends=("analytic",), ladder: bool = False,
              options: dict | None = None, workers: int | None = None, scheduler=None,
              identify: bool = True, retry_failed: bool = False, progress=None,
              on_rows=None, analysis: str | None = None) -> SweepResult:
    """Run (or resume) a sweep into the directory ``out``; see the module docstring.

    ``scenario``: a Scenario, shipped name or TOML path; ``grid``: a :class:`Grid` or
    ``--grid`` specs; ``scheduler``: a Dask scheduler address or ``Client``; ``on_rows``:
    called with each batch of rows after it is written (tests interrupt a sweep there).
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
    """Run (or resume) several sweeps on one pool, with one progress report: every spec is
    checked before anything runs, each sweep writes its own directory (table, spec), and
    the runs of all of them are grouped into worker calls together. Returns one
    :class:`SweepResult` per spec, in order."""
    from treeimpact.compare.runs import resolve_scenario

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
                           check_grid(scen, grid, targets)))
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
    spec = _spec(part.scenario, part.grid, part.identify, part.analysis)
    _check_spec(part.out, spec)
    (part.out / SPEC).write_text(json.dumps(spec | {
        "targets": [dataclasses.asdict(t) for t in part.targets],
        "provenance": provenance(part.scenario)}, indent=2, default=str))
    journal_path = part.out / JOURNAL
    if journal_path.exists() and journal_path.stat().st_size:
        import pandas as pd

        _drop_partial_line(journal_path)
        prev = read_file(journal_path, lambda p: pd.read_csv(
            p, usecols=["point", "target", "status"]), "table")
        prev = prev.drop_duplicates(subset=["point", "target"], keep="last")
        if retry_failed:
            prev = prev[prev["status"] == OK]
        part.done = set(zip(prev["point"], prev["target"]))
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
                run_chunks(run_chunk, _chunks(tasks, n), workers=n, client=client,
                           on_result=emit_tasks, on_died=_died)
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


def _died(task: Task, exc: BaseException) -> list[dict]:
    return [{"status": FAILED, "t_end": task.scenario.t_end, "wall_s": math.nan,
             "error": f"worker process died running this point ({type(exc).__name__}: "
                      f"{one_line(exc)}); rerun with --retry-failed"}] * len(task.rows)
