"""The one pool every part of ``compare`` runs independent work on: local worker processes
or a Dask scheduler. ``run_chunks`` hands each chunk's outcomes back as it finishes (sweeps
journal them); ``process_map`` keeps the items' order (the report's and ``pytest compare``'s
runs, the identification study). A stop request (SIGTERM in the CLI: :func:`request_stop`)
ends a loop at its next look at STOP. Design notes: docs/sweeps.md.
"""

from __future__ import annotations

import importlib.util
import multiprocessing
import os
import signal
import threading
import time
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from functools import partial

from treeimpact.analytic.budget import VARIABLES
from treeimpact.analytic.errors import ParameterError, one_line
from treeimpact.analytic.threads import blas_limit, limit_process

#: Seconds to wait for a Dask scheduler (and its first worker) before it is refused.
SCHEDULER_TIMEOUT_S = 10

class _StopFlag:
    """A flag set from a signal handler, so without a lock: a threading.Event's set() holds
    one, and a second signal landing in it (``timeout`` signals the command and then its
    process group) deadlocked the command in its own handler."""

    def __init__(self):
        self._set = False

    def set(self) -> None:
        self._set = True

    def clear(self) -> None:
        self._set = False

    def is_set(self) -> bool:
        return self._set


#: Set by a stop request (:func:`request_stop`): the loops raise KeyboardInterrupt at their
#: next look, at each result and, waiting for local workers, every POLL_S s (Dask: at each
#: result).
STOP = _StopFlag()
#: Seconds between looks at STOP while waiting for local workers.
POLL_S = 0.2


def max_workers() -> int:
    """The most local worker processes a pool starts: twice the cores (more only thrash)."""
    return 2 * (os.cpu_count() or 1)


def check_workers(workers) -> int | None:
    """``workers`` (None: one per core) if it is an integer in [0, :func:`max_workers`],
    else a one-line ParameterError naming --workers."""
    if workers is None:
        return None
    if isinstance(workers, bool) or not isinstance(workers, int) or not (
            0 <= workers <= max_workers()):
        raise ParameterError(f"--workers = {workers!r}: allowed integers 0 to {max_workers()} "
                             f"(0 runs in this process; twice this machine's "
                             f"{os.cpu_count() or 1} cores at most)")
    return workers


#: Set while a pool's loop runs (it looks at STOP itself); outside one a stop request ends
#: the command at once.
ACTIVE = threading.Event()


def check_stop() -> None:
    """Raise KeyboardInterrupt when a stop was requested (STOP set): a loop's look."""
    if STOP.is_set():
        raise KeyboardInterrupt


def request_stop() -> None:
    """What a stop signal's handler calls: only STOP set, the loops raise at their next look.
    A KeyboardInterrupt raised by the handler itself can land anywhere, e.g. in a fork or
    import-lock callback, where Python only prints it ('Exception ignored')."""
    STOP.set()


def on_stop_signal(signum, frame) -> None:
    """SIGTERM's handler in every command (``signum`` and ``frame`` as Python's signal
    module passes them, unused): a stop request (:func:`request_stop`) that a
    pool's loop answers at its next look; with no pool running, the command ends at once
    (KeyboardInterrupt, as Ctrl-C; no fork or worker is in flight then)."""
    request_stop()
    if not ACTIVE.is_set():
        raise KeyboardInterrupt


def ignore_sigint(environment: dict | None = None) -> None:
    """Worker initializer: Ctrl-C is the parent's to handle (it ends the workers itself), so a
    terminal's SIGINT to the whole process group prints no worker tracebacks; SIGTERM takes
    its default action (a forked worker would inherit the parent's handler, which turns it
    into a KeyboardInterrupt and a traceback when the parent ends the worker). The parent's
    run budgets (``environment``: analytic.budget.VARIABLES as set when the pool started) hold
    in the worker too: a forkserver started earlier has the environment of its own start.
    The worker runs with the library's one BLAS thread (analytic.threads.limit_process)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    limit_process()
    for name, value in (environment or {}).items():
        if value is None:
            os.environ.pop(name, None)
        else:
            os.environ[name] = value


def _budget_environment() -> dict:
    return {name: os.environ.get(name) for name in VARIABLES.values()}


#: Seconds a terminated worker gets to end before it is killed, and the pool's manager
#: thread to wind up (it is joined again at interpreter exit, without a timeout).
END_WORKERS_S = 2.0


def _end_workers(pool) -> None:
    """End the worker processes this pool started (by their Process objects) and its manager
    thread, within about 2 * END_WORKERS_S: SIGTERM, then SIGKILL for a worker that lives on
    (one forked by the ``fork`` start method carries this process's handlers until its
    initializer runs, and a SIGTERM landing there only sets its STOP)."""
    procs = [p for p in list((getattr(pool, "_processes", None) or {}).values())
             if p.is_alive()]
    for proc in procs:
        proc.terminate()
    deadline = time.monotonic() + END_WORKERS_S
    for proc in procs:
        proc.join(max(0.0, deadline - time.monotonic()))
        if proc.is_alive():
            proc.kill()
            proc.join(END_WORKERS_S)
    manager = getattr(pool, "_executor_manager_thread", None)  # shutdown forgets it
    pool.shutdown(wait=False, cancel_futures=True)
    if manager is not None:  # else interpreter exit can race its closing of the wakeup pipe
        manager.join(END_WORKERS_S)  # (concurrent.futures: 'OSError: Bad file descriptor')


#: The modules this process's forkserver imports once for all the workers it forks, beyond
#: the pooled function's own: the ones callers named (:func:`preload_in_workers`), in order.
_PRELOAD: dict[str, None] = {}


def preload_in_workers(*names: str) -> None:
    """Have this process's forkserver import the modules ``names`` (dotted names) once for
    all the workers it forks (0.3-1 s of imports a worker otherwise: the report names its
    record fit's). Read when the forkserver starts, at the first pool of
    :func:`process_map`: a caller names them before its first pool. Each name is looked up
    now: ImportError naming it if there is no such module (the forkserver itself would
    ignore one). Not the engines (a forkserver has no thread to fork, but pybullet prints
    on import)."""
    for name in names:
        _PRELOAD[_found(name)] = None


def _found(name: str) -> str:
    """``name`` if it names a module (found, not imported), else ImportError naming it."""
    if importlib.util.find_spec(name) is None:  # a missing parent package raises here
        raise ImportError(f"preload_in_workers: no module named {name!r}", name=name)
    return name


def _forkserver_preload(modules=()) -> list[str]:
    """What the forkserver imports: the named modules (:func:`preload_in_workers`), then
    ``modules`` that are this package's (the pooled function's), each checked as
    :func:`preload_in_workers` checks it."""
    ours = __name__.partition(".")[0]
    extra = [_found(m) for m in modules if m.partition(".")[0] == ours and m not in _PRELOAD]
    return [*_PRELOAD, *extra]


def _executor(workers: int, start_method: str | None, preload=()):
    ctx = multiprocessing.get_context(start_method) if start_method else None
    if start_method == "forkserver":  # read when this process's forkserver starts
        ctx.set_forkserver_preload(_forkserver_preload(preload))
    return ProcessPoolExecutor(max_workers=workers, initializer=ignore_sigint,
                               initargs=(_budget_environment(),), mp_context=ctx)


def run_chunks(fn, chunks: list, *, workers: int, on_result, on_died, client=None,
               start_method: str | None = None, preload=()) -> int:
    """``fn(chunk) -> outcomes`` (a list, one per item) for every chunk, on ``workers`` local
    processes or the Dask ``client``; ``on_result(chunk, outcomes)`` as each finishes.

    A worker process that dies (a crash inside an engine) breaks a local pool: the chunks it
    broke run again on a fresh pool, and a chunk broken twice runs one item at a time in a
    one-worker pool, so only an item that kills its worker gets ``on_died(item, exc)`` as
    its outcome (on Dask: every item of a chunk that killed every worker it was given).
    ``start_method``: the local pool's multiprocessing start method (None: the default);
    ``preload``: with ``forkserver``, modules it imports too (:func:`preload_in_workers`).
    Returns the number of items run."""
    ACTIVE.set()
    try:
        return _run_chunks(fn, chunks, workers=workers, on_result=on_result,
                           on_died=on_died, client=client, start_method=start_method,
                           preload=preload)
    except Exception:
        if STOP.is_set():  # the stop signal reached the group too: a forkserver or worker it
            raise KeyboardInterrupt from None  # ended mid-start (EOFError...) is the stop
        raise
    finally:
        ACTIVE.clear()


def _run_chunks(fn, chunks: list, *, workers: int, on_result, on_died, client,
                start_method: str | None, preload) -> int:
    if client is not None:
        return _run_dask(fn, chunks, client, on_result, on_died)

    ran = 0
    pending = list(chunks)
    strikes: dict[int, int] = {}
    suspects = []
    while pending:
        broken, unsent, futures = [], [], {}
        pool = _executor(min(workers, len(pending)), start_method, preload)
        try:
            for c in pending:
                try:
                    futures[pool.submit(fn, c)] = c
                except BrokenProcessPool:  # broke while submitting: not this chunk's doing
                    unsent.append(c)
            for fut in _as_completed(futures):
                check_stop()
                try:
                    outcomes = fut.result()
                except BrokenProcessPool:
                    broken.append(futures[fut])
                    continue
                on_result(futures[fut], outcomes)
                ran += len(outcomes)
        except BaseException:
            _end_workers(pool)
            raise
        pool.shutdown(wait=True)
        pending = unsent
        for c in broken:
            strikes[id(c)] = strikes.get(id(c), 0) + 1
            (suspects if strikes[id(c)] >= 2 else pending).append(c)
    pool = None
    try:
        for item in (i for c in suspects for i in c):
            if pool is None:
                pool = _executor(1, start_method, preload)
            try:
                outcome = next(_as_completed([pool.submit(fn, [item])])).result()[0]
            except BrokenProcessPool as exc:
                outcome = on_died(item, exc)
                pool.shutdown(wait=True)
                pool = None
            on_result([item], [outcome])
            ran += 1
            check_stop()
    except BaseException:
        if pool is not None:
            _end_workers(pool)
        raise
    if pool is not None:
        pool.shutdown(wait=True)
    return ran


def _as_completed(futures):
    """The futures as they finish, looking at STOP every POLL_S s while none does."""
    pending = set(futures)
    while pending:
        done, pending = wait(pending, timeout=POLL_S, return_when=FIRST_COMPLETED)
        check_stop()
        yield from done


def connect(scheduler):
    """(Dask client, whether this call opened it): ``scheduler`` is an address or a Client."""
    # lazy: +482 ms at import otherwise (dask, distributed, jinja2, numpy),
    # which this module's other callers do not need
    from distributed import Client

    if isinstance(scheduler, Client):
        return scheduler, False
    if not isinstance(scheduler, str) or not scheduler.strip():
        raise ParameterError(f"--scheduler {scheduler!r}: allowed: the address of a running "
                             f"Dask scheduler, tcp://HOST:PORT")
    try:
        return Client(scheduler, timeout=SCHEDULER_TIMEOUT_S), True
    except (OSError, ValueError, TypeError) as exc:
        raise ParameterError(f"--scheduler {scheduler!r}: cannot connect ({one_line(exc)}); "
                             f"allowed: the address of a running Dask scheduler, "
                             f"tcp://HOST:PORT") from None


def dask_workers(client) -> int:
    """Worker threads of the Dask ``client``'s cluster, once one has joined (else a one-line
    ParameterError after SCHEDULER_TIMEOUT_S)."""
    try:
        client.wait_for_workers(1, timeout=SCHEDULER_TIMEOUT_S)
    except (TimeoutError, OSError) as exc:
        raise ParameterError(f"{_where(client)}: no worker joined within "
                             f"{SCHEDULER_TIMEOUT_S} s ({one_line(exc)}): start dask "
                             "workers for it") from None
    return max(1, sum(client.nthreads().values()))


def _where(client) -> str:
    return f"--scheduler {client.scheduler.address!r}" if client.scheduler else "--scheduler"


def _blas_limited_call(fn, chunk):
    """``fn(chunk)`` on a Dask worker with the library's one BLAS thread, the worker's own
    setting back after it (a Dask worker is the user's process, its threads share the
    limit: analytic.threads)."""
    with blas_limit():
        return fn(chunk)


def _run_dask(fn, chunks, client, on_result, on_died) -> int:
    # lazy: +482 ms at import otherwise (dask, distributed, jinja2, numpy),
    # which this module's other callers do not need
    from distributed import as_completed

    # lazy: +402 ms at import otherwise (dask, distributed, jinja2, numpy),
    # which this module's other callers do not need
    from distributed.scheduler import KilledWorker

    ran = 0
    futures = client.map(partial(_blas_limited_call, fn), chunks, pure=False)
    owner = {f.key: c for f, c in zip(futures, chunks)}
    try:
        for fut in as_completed(futures):
            check_stop()
            try:
                outcomes = fut.result()
            except KilledWorker as exc:  # the chunk killed every worker it was given
                outcomes = [on_died(item, exc) for item in owner[fut.key]]
            on_result(owner[fut.key], outcomes)
            ran += len(outcomes)
    except (OSError, TimeoutError) as exc:  # the scheduler went away (CommClosedError too)
        raise ParameterError(f"{_where(client)}: lost the scheduler ({type(exc).__name__}: "
                             f"{one_line(exc)}); the finished rows are kept: rerun to "
                             "resume") from None
    finally:
        try:
            client.cancel(futures)
        except (OSError, TimeoutError):  # nothing left to cancel on a lost scheduler
            pass
    return ran


def process_map(fn, items, *, workers: int | None = None, done=None, died=None) -> list:
    """``[fn(item) for item in items]`` on :func:`run_chunks`' local processes, in the items'
    order. ``fn`` must pickle (a module-level function). ``workers``: default the CPU count;
    1, or a single item, runs in this process. Workers start by ``forkserver`` (the engines'
    thread pools are never forked), which imports ``fn``'s module once for them. ``done()`` is called once per finished item (progress);
    ``died(item, exc)`` is the outcome of an item that kills its worker (default: raise)."""
    items = list(items)
    if workers is None:
        workers = os.cpu_count() or 1
    out = [None] * len(items)
    if workers <= 1 or len(items) <= 1:
        for i, item in enumerate(items):
            out[i] = fn(item)
            check_stop()
            if done is not None:
                done()
        return out

    def on_result(chunk, outcomes):
        for (i, _), outcome in zip(chunk, outcomes):
            out[i] = outcome
            if done is not None:
                done()

    def on_died(indexed, exc):
        if died is None:
            raise exc
        return died(indexed[1], exc)

    run_chunks(partial(_each_indexed, fn), [[(i, x)] for i, x in enumerate(items)],
               workers=workers, on_result=on_result, on_died=on_died,
               start_method="forkserver", preload=(getattr(fn, "__module__", None) or "",))
    return out


def _each_indexed(fn, chunk: list) -> list:
    return [fn(item) for _, item in chunk]
