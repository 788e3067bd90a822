"""Run a sweep: every grid point on every target, results appended as they finish.

Targets (:func:`make_targets`): by default one per backend, each compared with the one
below it (``soft`` with ``analytic``; an engine with ``soft`` when it is swept, else with
``analytic``); ``analytic``, the paper's exact solution, is always run as the reference.
With ``ladder=True`` the targets are the rungs of :mod:`compare.ladder` (analytic, soft,
and per engine: SDOF trunk, hinged chain, hinged chain with the full pendulum), so a map
can say which assumption dominates the discrepancy.

Execution (:func:`run_sweep`):

* ``workers=0``: in this process, one run after the other (debugging, tests);
* ``workers=N`` (default: the CPU count): a local ``concurrent.futures.ProcessPoolExecutor``;
* ``scheduler=ADDRESS`` (or a ``dask.distributed.Client``): an existing Dask cluster.

Runs with identical inputs (a grid point whose swept options a backend does not take:
``segments`` for ``analytic``) are run once and their row written for every point.

The table (:data:`JOURNAL`, CSV) gets one row per (grid point, target) the moment its run
finishes, flushed at once, so an interrupted sweep loses nothing it finished; a rerun with
the same ``out`` skips the rows already there (``retry_failed`` reruns rows whose status is
not ``ok``; the last row of a key wins). A grid point outside a parameter's range
(``invalid``), a backend that refuses or is not installed (``skipped``), a diverged run
(``diverged``) or any other exception (``failed``) is recorded with its one-line error and
the sweep goes on. When the sweep ends (or is interrupted) the table is also written
deduplicated as :data:`TABLE` (Parquet).

Columns: ``scenario, point, target, backend, kind, previous, status, error, wall_s`` (s of
the backend call), ``t_end`` (simulated s), ``task``, ``worker``, ``finished`` (unix s); the
swept parameters under their grid names; the metrics of :data:`analytic.results.METRIC_KEYS`;
``model.*`` (M_T, C_T, K_T, m, k, e, u1 and the engine's segments, dt, contact stiffness);
``id.*`` the parameters the identification procedure (eqs 39-48) recovers from the run's
record, ``truth.*`` their true values, ``id_error`` why it failed.
"""

from __future__ import annotations

import csv
import dataclasses
import json
import math
import os
import socket
import sys
import time
from collections import OrderedDict
from dataclasses import dataclass, field
from pathlib import Path

from analytic.parameters import ParameterError, Pendulum, Scenario
from analytic.results import METRIC_KEYS, SimulationDiverged

from .apply import apply_point
from .grid import Grid, parse_grid, point_key

JOURNAL = "results.csv"
TABLE = "results.parquet"
SPEC = "sweep.json"

OK, SKIPPED, DIVERGED, FAILED, INVALID = "ok", "skipped", "diverged", "failed", "invalid"

REFERENCE_BACKENDS = ("analytic", "soft")
ENGINES = ("mujoco", "bullet")
MODEL_KEYS = ("M_T", "C_T", "K_T", "m", "k", "e", "u1", "segments", "dt", "contact_stiffness",
              "contact_damping")
IDENT_KEYS = ("M_T", "K_T", "xi", "E")
BASE_COLUMNS = ("scenario", "point", "target", "backend", "kind", "previous", "status", "error",
                "wall_s", "t_end", "task", "worker", "finished")
#: Spacing (s) of the analytic trajectory handed to the identification: 20 us, the record
#: spacing at which analytic.identification's tests recover b and omega_n.
ANALYTIC_SAMPLE_STEP = 2e-5


def columns_for(grid: Grid) -> list[str]:
    return (list(BASE_COLUMNS) + list(grid.names) + list(METRIC_KEYS)
            + [f"model.{k}" for k in MODEL_KEYS] + [f"id.{k}" for k in IDENT_KEYS]
            + [f"truth.{k}" for k in IDENT_KEYS] + ["id_error"])


# --------------------------------------------------------------------------- targets


@dataclass(frozen=True)
class Target:
    """What one row runs: ``backend`` with fixed ``options``, compared with ``previous``."""

    id: str
    backend: str
    options: tuple = ()  # sorted (name, value) pairs
    previous: str | None = None
    kind: str = "model"  # ladder kind: newton, contact, engine, trunk, pendulum; "model" for
    # an engine run as configured, compared with soft (numerics and trunk/pendulum together)
    drop: tuple = ()  # swept options this target ignores (segments for an SDOF trunk)

    @property
    def reference(self) -> bool:
        return self.backend in REFERENCE_BACKENDS


def _check_backends(backends) -> list[str]:
    from compare.backends import get_backend

    if isinstance(backends, str):
        backends = [b.strip() for b in backends.split(",") if b.strip()]
    out = []
    for b in backends:
        try:
            get_backend(b)
        except ParameterError:
            from compare.backends import BACKENDS

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

    targets = [Target("analytic", "analytic", opts("analytic"), None, "newton")]
    has_soft = "soft" in names or ladder
    if has_soft:
        targets.append(Target("soft", "soft", opts("soft"), "analytic", "contact"))
    engines = [b for b in names if b not in REFERENCE_BACKENDS]  # engines (or any other)
    below = "soft" if has_soft else "analytic"
    for eng in engines:
        if not ladder:
            targets.append(Target(eng, eng, opts(eng), below, "model"))
            continue
        sdof, chain = f"{eng}-sdof", f"{eng}-chain"
        targets += [
            Target(sdof, eng, opts(eng, {"trunk": "sdof", "pendulum": "linear"}), "soft",
                   "engine", drop=("segments",)),
            Target(chain, eng, opts(eng, {"trunk": "chain", "pendulum": "linear"}), sdof,
                   "trunk"),
            Target(f"{chain}-full", eng, opts(eng, {"trunk": "chain", "pendulum": "full"}),
                   chain, "pendulum"),
        ]
    return targets


# --------------------------------------------------------------------------- one run


@dataclass
class Task:
    """One backend call, shared by every (point, target) row whose inputs are identical."""

    key: str
    scenario: Scenario
    backend: object  # compare.backends.Backend (pickled whole, so a worker needs no registry)
    options: dict
    identify: bool
    rows: list = field(default_factory=list)  # (point key, target id)


def _one_line(exc: BaseException) -> str:
    text = " ".join(str(exc).split())
    return text or type(exc).__name__


def _identify(result, scenario: Scenario) -> dict:
    """The paper's procedure (eqs 39-48, "paper" reading) on the run's displacement record."""
    from analytic.identification import identify_from_record, pendulum_test_of, truth_of

    out = {}
    if not isinstance(scenario.impactor, Pendulum):
        out["id_error"] = "the identification procedure needs a pendulum"
        return out
    truth = truth_of(scenario)
    out.update({f"truth.{k}": truth[k] for k in IDENT_KEYS})
    rec = result.extra.get("record") if result.extra else None
    src = rec if rec is not None else result.trajectory
    if src is None:
        out["id_error"] = "the run has no displacement record"
        return out
    try:
        ident, _ = identify_from_record(src.t, src.x, pendulum_test_of(scenario), y=src.y,
                                        reading="paper")
    except (ParameterError, ValueError, FloatingPointError) as exc:
        out["id_error"] = f"identification failed: {_one_line(exc)}"
        return out
    out.update({f"id.{k}": float(getattr(ident, k)) for k in IDENT_KEYS})
    return out


def execute(task: Task) -> dict:
    """Run one task; never raises for a failing run (the error is the outcome)."""
    out = {"status": OK, "error": None, "t_end": task.scenario.t_end,
           "worker": f"{socket.gethostname()}:{os.getpid()}"}
    t0 = time.perf_counter()
    try:
        result = task.backend.simulate(task.scenario, **task.options)
    except ParameterError as exc:
        out.update(status=SKIPPED, error=_one_line(exc))
    except SimulationDiverged as exc:
        out.update(status=DIVERGED, error=f"diverged: {_one_line(exc)}")
    except Exception as exc:  # noqa: BLE001 - recorded per row; the sweep goes on
        out.update(status=FAILED, error=f"{type(exc).__name__}: {_one_line(exc)}")
    out["wall_s"] = time.perf_counter() - t0
    if out["status"] != OK:
        return out
    out.update({k: _num(result.metrics.get(k)) for k in METRIC_KEYS})
    model = result.model or {}
    out.update({f"model.{k}": _num(model.get(k)) for k in MODEL_KEYS})
    if task.identify:
        out.update(_identify(result, task.scenario))
    return out


def run_chunk(tasks: list) -> list:
    """Worker entry point: the outcomes of a list of tasks, in order."""
    return [execute(t) for t in tasks]


def _num(v):
    if v is None:
        return math.nan
    try:
        return float(v)
    except (TypeError, ValueError):
        return math.nan


# --------------------------------------------------------------------------- the table


class Journal:
    """The CSV table, appended one flushed line per row."""

    def __init__(self, path: Path, columns: list[str]):
        self.path = Path(path)
        self.columns = columns
        fresh = not self.path.exists() or self.path.stat().st_size == 0
        if not fresh:
            _drop_partial_line(self.path)
            with open(self.path, newline="") as fh:
                header = next(csv.reader(fh), None)
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


def read_table(out, *, dedupe: bool = True):
    """The sweep's rows as a pandas DataFrame (last row per (point, target) when ``dedupe``)."""
    import pandas as pd

    out = Path(out)
    journal = out / JOURNAL
    if journal.exists():
        _drop_partial_line(journal)
        df = pd.read_csv(journal, keep_default_na=True)
    elif (out / TABLE).exists():
        df = pd.read_parquet(out / TABLE)
    else:
        raise ParameterError(f"--out {out}: no sweep table ({JOURNAL} or {TABLE}) there")
    if dedupe and len(df):
        df = df.drop_duplicates(subset=["point", "target"], keep="last").reset_index(drop=True)
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
    out: Path
    table: object  # pandas DataFrame, deduplicated
    tasks_run: int  # backend calls made by this invocation
    rows_written: int  # rows appended by this invocation
    rows_done_before: int  # rows found finished and skipped (resume)
    wall_s: float

    @property
    def journal(self) -> Path:
        return self.out / JOURNAL


def _spec(scenario: Scenario, grid: Grid, identify: bool) -> dict:
    return {"version": 1, "scenario": scenario.to_dict(), "grid": grid.specs(),
            "axes": list(grid.names), "identify": identify}


def _check_spec(out: Path, spec: dict) -> None:
    path = out / SPEC
    if not path.exists():
        return
    old = json.loads(path.read_text())
    for key in ("scenario", "axes", "identify"):
        if json.dumps(old.get(key), sort_keys=True) != json.dumps(spec[key], sort_keys=True):
            raise ParameterError(f"--out {out}: holds a sweep with another {key} "
                                 f"({SPEC}); use a new --out to start a different sweep")


def plan(scenario: Scenario, grid: Grid, targets: list[Target], *, identify: bool = True,
         done: set | None = None):
    """(tasks to run, rows already decided without running: invalid points)."""
    from compare.backends import get_backend
    from compare.runs import options_key, scenario_key

    done = done or set()
    tasks: OrderedDict[str, Task] = OrderedDict()
    immediate = []
    accepted = {}
    for t in targets:
        if t.reference:
            accepted[t.id] = get_backend(t.backend).options()
    for point in grid.points():
        pk = point_key(point)
        todo = [t for t in targets if (pk, t.id) not in done]
        if not todo:
            continue
        try:
            scen, popts = apply_point(scenario, point)
        except ParameterError as exc:
            for t in todo:
                immediate.append(_row_base(scenario, point, pk, t) | {
                    "status": INVALID, "error": _one_line(exc), "t_end": scenario.t_end})
            continue
        for t in todo:
            opts = dict(t.options)
            for name, value in popts.items():
                if name in t.drop or (t.reference and name not in accepted[t.id]):
                    continue  # the option does not change this target's model
                opts[name] = value
            if t.backend == "analytic" and identify and "samples" in accepted[t.id] \
                    and "samples" not in opts:
                opts["samples"] = int(round(scen.t_end / ANALYTIC_SAMPLE_STEP)) + 1
            key = json.dumps([scenario_key(scen), t.backend, options_key(opts)], default=str)
            task = tasks.get(key)
            if task is None:
                task = tasks[key] = Task(key, scen, get_backend(t.backend), opts, identify)
            task.rows.append((point, pk, t))
    return list(tasks.values()), immediate


def _row_base(scenario, point, pk, target: Target) -> dict:
    return {"scenario": scenario.name, "point": pk, "target": target.id,
            "backend": target.backend, "kind": target.kind, "previous": target.previous,
            **point}


def _rows_of(task: Task, outcome: dict, scenario: Scenario) -> list[dict]:
    import hashlib

    tid = hashlib.sha1(task.key.encode()).hexdigest()[:12]
    now = time.time()
    return [_row_base(scenario, point, pk, t) | outcome | {"task": tid, "finished": now}
            for point, pk, t in task.rows]


def _chunks(tasks: list, workers: int) -> list[list]:
    """Tasks grouped so that each worker gets about 8 chunks (fewer round trips for the
    4 ms analytic runs, still a fine-grained progress bar and little lost work)."""
    n = max(1, min(16, len(tasks) // max(1, 8 * workers)))
    return [tasks[i:i + n] for i in range(0, len(tasks), n)]


def _progress(total: int, enabled):
    if enabled is None:
        enabled = sys.stderr.isatty()
    if not enabled:
        return None
    from tqdm import tqdm

    return tqdm(total=total, unit="row", desc="sweep", file=sys.stderr)


def run_sweep(scenario, grid, out, *, backends=("analytic",), ladder: bool = False,
              options: dict | None = None, workers: int | None = None, scheduler=None,
              identify: bool = True, retry_failed: bool = False, progress=None,
              on_rows=None) -> SweepResult:
    """Run (or resume) a sweep into the directory ``out``; see the module docstring.

    ``scenario``: a Scenario, shipped name or TOML path; ``grid``: a :class:`Grid` or
    ``--grid`` specs; ``scheduler``: a Dask scheduler address or ``Client``; ``on_rows``:
    called with each batch of rows after it is written (tests interrupt a sweep there).
    """
    from compare.runs import resolve_scenario

    t_start = time.perf_counter()
    scen = resolve_scenario(scenario)
    grid = grid if isinstance(grid, Grid) else parse_grid(grid)
    targets = make_targets(backends, ladder=ladder, options=options)
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int)
                                or workers < 0):
        raise ParameterError(f"--workers = {workers!r}: allowed integers >= 0 "
                             f"(0 runs in this process)")
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    spec = _spec(scen, grid, identify)
    _check_spec(out, spec)
    (out / SPEC).write_text(json.dumps(spec | {"targets": [dataclasses.asdict(t)
                                                           for t in targets]}, indent=2))
    columns = columns_for(grid)
    done = set()
    journal_path = out / JOURNAL
    if journal_path.exists() and journal_path.stat().st_size:
        import pandas as pd

        _drop_partial_line(journal_path)
        prev = pd.read_csv(journal_path, usecols=["point", "target", "status"])
        prev = prev.drop_duplicates(subset=["point", "target"], keep="last")
        if retry_failed:
            prev = prev[prev["status"] == OK]
        done = set(zip(prev["point"], prev["target"]))
    tasks, immediate = plan(scen, grid, targets, identify=identify, done=done)
    journal = Journal(journal_path, columns)
    total = len(immediate) + sum(len(t.rows) for t in tasks)
    bar = _progress(total, progress)
    written = 0
    ran = 0

    def emit(rows):
        nonlocal written
        journal.append(rows)
        written += len(rows)
        if bar is not None:
            bar.update(len(rows))
        if on_rows is not None:
            on_rows(rows)

    try:
        if immediate:
            emit(immediate)
        if tasks:
            if scheduler is not None:
                ran = _run_dask(tasks, scheduler, scen, emit)
            elif workers == 0:
                for task in tasks:
                    emit(_rows_of(task, execute(task), scen))
                    ran += 1
            else:
                ran = _run_pool(tasks, workers or os.cpu_count() or 1, scen, emit)
    finally:
        journal.close()
        if bar is not None:
            bar.close()
        write_parquet(out)
    return SweepResult(out, read_table(out), ran, written, len(done),
                       time.perf_counter() - t_start)


def _run_pool(tasks, workers, scen, emit) -> int:
    from concurrent.futures import ProcessPoolExecutor, as_completed

    ran = 0
    chunks = _chunks(tasks, workers)
    pool = ProcessPoolExecutor(max_workers=workers)
    try:
        futures = {pool.submit(run_chunk, c): c for c in chunks}
        for fut in as_completed(futures):
            for task, outcome in zip(futures[fut], fut.result()):
                emit(_rows_of(task, outcome, scen))
                ran += 1
    finally:
        pool.shutdown(wait=True, cancel_futures=True)
    return ran


def _run_dask(tasks, scheduler, scen, emit) -> int:
    from distributed import Client, as_completed

    own = not isinstance(scheduler, Client)
    try:
        client = Client(scheduler) if own else scheduler
    except (OSError, ValueError, TypeError) as exc:
        raise ParameterError(f"--scheduler {scheduler!r}: cannot connect "
                             f"({_one_line(exc)})") from None
    ran = 0
    try:
        workers = max(1, sum(client.nthreads().values()))
        chunks = _chunks(tasks, workers)
        futures = client.map(run_chunk, chunks, pure=False)
        owner = {f.key: c for f, c in zip(futures, chunks)}
        try:
            for fut in as_completed(futures):
                for task, outcome in zip(owner[fut.key], fut.result()):
                    emit(_rows_of(task, outcome, scen))
                    ran += 1
        finally:
            client.cancel(futures)
    finally:
        if own:
            client.close()
    return ran
