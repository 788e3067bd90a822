"""The one pool (compare.runs.pool): results in the items' order, progress per item, an item that
kills its worker becomes its own outcome instead of taking the run down."""

import os

import pytest

from treeimpact.compare.runs.pool import process_map


def _square_or_crash(x):
    if x == 3:
        os._exit(1)  # a crash inside an engine: the worker process dies
    return x * x


def test_process_map_keeps_order_and_reports_each_item():
    calls = []
    out = process_map(abs, [-3, 1, -2, 5], workers=2, done=lambda: calls.append(1))
    assert out == [3, 1, 2, 5] and len(calls) == 4


def test_an_item_that_kills_its_worker_is_its_own_outcome():
    out = process_map(_square_or_crash, [1, 2, 3, 4], workers=2,
                      died=lambda item, exc: f"died on {item}")
    assert out == [1, 4, "died on 3", 16]


def test_without_died_a_dead_worker_raises():
    from concurrent.futures.process import BrokenProcessPool

    with pytest.raises(BrokenProcessPool):
        process_map(_square_or_crash, [3, 4], workers=2)


def _sleep_then_mark(path):
    import time
    from pathlib import Path

    time.sleep(60.0)  # an item far longer than any start-up under load
    Path(path).touch()  # reached only by an item the pool waited out
    return path


def test_a_stop_request_ends_a_wait_for_workers_within_the_poll_interval(tmp_path):
    """request_stop (the SIGTERM handler's call) only sets STOP; the pool looks at it while
    it waits (every POLL_S), so two 60 s items are abandoned: the stop is raised and
    neither item got to its end (no wall clock read: a pool that waited them out would
    return their results after 60 s, which is also this test's hang guard)."""
    import threading

    from treeimpact.compare.runs import pool

    marks = [tmp_path / "a", tmp_path / "b"]
    timer = threading.Timer(0.5, pool.request_stop)
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            process_map(_sleep_then_mark, [str(m) for m in marks], workers=2)
    finally:
        timer.cancel()
        pool.STOP.clear()
    assert not any(m.exists() for m in marks)


def test_the_stop_flag_takes_no_lock_a_second_signal_could_wait_for():
    """The SIGTERM handler sets STOP; a threading.Event's set() holds a lock, and a second
    signal landing inside it (timeout signals the command, then its group) waited for that
    lock in the same thread forever: a `treeimpact report` hung until killed. The flag is a
    plain attribute: nothing in it can be acquired."""
    from treeimpact.compare.runs import pool

    assert not any(hasattr(v, "acquire") for v in vars(pool.STOP).values())
    pool.request_stop()
    pool.request_stop()  # as a handler inside a handler would
    try:
        assert pool.STOP.is_set()
    finally:
        pool.STOP.clear()


def test_a_pool_broken_by_the_stop_signal_is_the_stop_not_a_traceback(monkeypatch):
    """A signal to the process group also ends the forkserver and the workers: a pool
    starting then fails with EOFError (measured: a `timeout` during a report's first pool).
    With a stop requested that is the stop (KeyboardInterrupt: one line, exit 130)."""
    from treeimpact.compare.runs import pool

    class Dying:
        _processes = {}
        signalled = True

        def submit(self, *args):
            if self.signalled:
                pool.request_stop()  # the signal lands as the forkserver dies
            raise EOFError("unexpected EOF")

        def shutdown(self, **kw):
            pass

    monkeypatch.setattr(pool, "_executor", lambda *args: Dying())
    try:
        with pytest.raises(KeyboardInterrupt):
            process_map(abs, [1, 2], workers=2)
    finally:
        pool.STOP.clear()
    Dying.signalled = False
    with pytest.raises(EOFError):  # without a stop request it is the error it is
        process_map(abs, [1, 2], workers=2)
    assert not pool.STOP.is_set()


def _deaf_to_sigterm(seconds, mark):
    import signal
    import time
    from pathlib import Path

    signal.signal(signal.SIGTERM, signal.SIG_IGN)  # as a fork-started worker before its
    time.sleep(seconds)  # initializer: the parent's handler only sets its STOP flag
    Path(mark).touch()  # reached only by a worker that was not killed
    return seconds


def test_ending_a_pool_kills_a_worker_that_outlives_sigterm_and_its_manager_thread(tmp_path):
    """A stopped pool's workers are ended even when they ignore SIGTERM (they were killed:
    none ran its 60 s item to the end, and none is alive), and its manager thread has wound
    up (left running, it raced interpreter exit: 'OSError: Bad file descriptor' in
    concurrent.futures). No wall clock read: _end_workers waiting the items out would take
    60 s and leave their marks (that is also the hang guard)."""
    from concurrent.futures import wait

    from treeimpact.compare.runs import pool as pool_module

    marks = [tmp_path / "a", tmp_path / "b"]
    pool = pool_module._executor(2, "fork")
    futures = [pool.submit(_deaf_to_sigterm, 60, str(m)) for m in marks]
    wait(futures, timeout=1.0)  # both started
    procs, manager = list(pool._processes.values()), pool._executor_manager_thread
    pool_module._end_workers(pool)
    assert not any(p.is_alive() for p in procs)
    assert not any(m.exists() for m in marks)
    assert not manager.is_alive()


def test_a_preload_name_that_is_no_module_is_refused_loudly():
    """A renamed module named for the forkserver's preload fails in the caller (the
    forkserver itself ignores an ImportError), and names it."""
    from treeimpact.compare.runs import pool as pool_module

    before = dict(pool_module._PRELOAD)
    with pytest.raises(ImportError, match="treeimpact.compare.studies.no_such_module"):
        pool_module.preload_in_workers("treeimpact.compare.studies.no_such_module")
    with pytest.raises(ImportError):  # a missing package above it too
        pool_module.preload_in_workers("treeimpact.no_such_package.module")
    assert pool_module._PRELOAD == before
    # the pooled function's module joins the named ones when it is the package's
    preload = pool_module._forkserver_preload(("treeimpact.compare.runs.cache", "builtins"))
    assert preload[:len(before)] == list(before) and "builtins" not in preload
    assert "treeimpact.compare.runs.cache" in preload


def test_the_forkserver_imports_what_the_caller_named(tmp_path):
    """In a fresh process (its own forkserver): the workers find the named module already
    imported, and not one nobody named (the control)."""
    import subprocess
    import sys

    (tmp_path / "probe.py").write_text(
        "import sys\n\ndef loaded(name):\n    return name in sys.modules\n")
    code = ("import sys; sys.path.insert(0, '.')\n"
            "from probe import loaded\n"
            "from treeimpact.compare.runs.pool import preload_in_workers, process_map\n"
            "preload_in_workers('treeimpact.compare.studies.ident_fits')\n"
            "names = ['treeimpact.compare.studies.ident_fits',\n"
            "         'treeimpact.compare.studies.sweep.grid']\n"
            "print(process_map(loaded, names, workers=2))\n")
    proc = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True,
                          text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "[True, False]"
