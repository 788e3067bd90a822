"""The library's own BLAS thread limit: its matrices are small (a beam's 54 x 54 modal
matrices, 2 x 2 to 6 x 6 fits), where OpenBLAS's threads cost far more than they share
(a beam run 30x slower with numpy's default threads on a loaded 2-core machine;
docs/reproducibility.md, "BLAS threads"). Every public entry point runs inside
:func:`blas_limited` or :class:`blas_limit` (the API, the command line), and every pool
worker calls :func:`limit_process` at its start: no ``OPENBLAS_NUM_THREADS`` is needed.

The limit is scoped: the outermost call sets :data:`THREADS` on numpy's and scipy's OpenBLAS
(by threadpoolctl) and puts the caller's own settings back when it returns; nested calls
and calls from other threads meanwhile only count (one process-wide depth under a lock:
the BLAS setting is process-wide, so a user's thread running numpy beside our call runs
single-threaded until our last call returns). The libraries are found once per process.
"""

from __future__ import annotations

import functools
import os
import threading

#: BLAS threads inside the library's calls.
THREADS = 1

_LOCK = threading.Lock()
_libraries = None  # threadpoolctl's controllers of the BLAS libraries, found on first use
_depth = 0  # calls inside the limit, all threads together
_saved: list = []  # (library, its thread count before the outermost call) where not THREADS


def _reset_after_fork() -> None:
    """A forked child starts with a free lock (the parent's may have been held by a thread
    the child does not have); its depth and saved settings are the parent's."""
    global _LOCK
    _LOCK = threading.Lock()


os.register_at_fork(after_in_child=_reset_after_fork)


def blas_libraries() -> list:
    """threadpoolctl's controllers of the BLAS libraries loaded by numpy and scipy (two
    OpenBLAS builds with numpy's and scipy's wheels), found once per process (the scan of
    the loaded libraries is the costly part, ~ms); scipy.linalg is imported first, since
    its OpenBLAS loads with it."""
    global _libraries
    if _libraries is None:
        # lazy: the libraries are loaded only when the thread limit is first applied
        import numpy  # noqa: F401 - loads numpy's BLAS
        import scipy.linalg  # noqa: F401 - loads scipy's own BLAS
        from threadpoolctl import ThreadpoolController

        _libraries = list(ThreadpoolController().select(user_api="blas").lib_controllers)
    return _libraries


def _set_all(settings) -> None:
    """Set each BLAS library's thread count, ``settings`` (library, threads) pairs, from
    whichever thread holds our lock. threadpoolctl >= 3.8 lets one Python thread at a time
    set a shared OpenBLAS pool (others are ignored): the control is taken for the call and
    given up after it, so the thread restoring a setting need not be the one that set it, and
    a user's threadpoolctl limit later, from any thread, still takes effect."""
    settings = [(lib, n) for lib, n in settings if n is not None]
    if not settings:
        return
    clear = getattr(settings[0][0], "clear_controlling_thread", None)  # shared by OpenBLAS's
    if clear is not None:  # threadpoolctl < 3.8: none
        clear(force=True)
    for lib, n in settings:
        lib.set_num_threads(n)
    if clear is not None:
        clear()


def enter_limit() -> None:
    """Enter the limit: the outermost entry (depth 0 -> 1) saves each BLAS library's thread
    count and sets :data:`THREADS`; inner ones only count. Pair with :func:`exit_limit`."""
    global _depth, _saved
    with _LOCK:
        _depth += 1
        if _depth == 1:
            saved = [(lib, lib.get_num_threads()) for lib in blas_libraries()]
            _saved = [(lib, n) for lib, n in saved if n != THREADS]
            _set_all([(lib, THREADS) for lib, _ in _saved])


def exit_limit() -> None:
    """Leave the limit: the outermost exit (depth 1 -> 0) puts back the thread counts that
    :func:`enter_limit` saved."""
    global _depth, _saved
    with _LOCK:
        _depth -= 1
        if _depth == 0:
            _set_all(_saved)
            _saved = []


def blas_limited(func):
    """``func`` run inside the limit (:func:`enter_limit` to :func:`exit_limit`): a
    decorator for the library's entry points."""
    @functools.wraps(func)
    def limited(*args, **kwargs):
        enter_limit()
        try:
            return func(*args, **kwargs)
        finally:
            exit_limit()
    return limited


class blas_limit:  # noqa: N801 - a context manager named as the function it stands for
    """``with blas_limit(): ...``: :data:`THREADS` BLAS threads inside, the caller's settings
    back on exit; nested uses cost a counter."""

    def __enter__(self):
        enter_limit()
        return self

    def __exit__(self, *exc):
        exit_limit()
        return False


def limit_process() -> None:
    """Set :data:`THREADS` for the rest of this process (a pool worker's start: the process
    is the library's own, nothing to put back)."""
    with _LOCK:
        _set_all([(lib, THREADS) for lib in blas_libraries()])


def blas_threads() -> dict[str, int]:
    """Each BLAS library's current thread count, by its file name (tests, diagnostics)."""
    return {os.path.basename(lib.filepath): lib.get_num_threads() for lib in blas_libraries()}
