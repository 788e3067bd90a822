"""The command line's process policy, apart from the commands: how a command ends (its exit
code and one line on stderr for every way it can end), the stop signals, the run budget it
sets for itself and its workers, and Python warnings as one stderr line each.

Exit codes (:class:`compare.runs.exits.ExitCode`): 0 success; 2 bad input; 3 a simulation
diverged; 4 ran but not achieved (or outside the model's validity); 130 interrupted (Ctrl-C
or SIGTERM).
"""

from __future__ import annotations

import _thread
import math
import os
import signal
import sys
import threading
import time
import warnings
from contextlib import contextmanager
from pathlib import Path

from treeimpact.analytic import budget
from treeimpact.analytic.errors import (
    ImplausibleInput,
    NotAchieved,
    OutsideValidity,
    ParameterError,
    SimulationDiverged,
    one_line,
)
from treeimpact.analytic.model.plausible import RUN_AS_GIVEN

from ..runs.exits import ExitCode
from ..runs.pool import STOP
from ..runs.progress import Progress, end_open_bars
from ..runs.progress import finish as finish_progress


#: The running command's implausible inputs (ImplausibleInput warnings, each once): printed
#: as warning lines when it returns, or added to its one error line when it is refused.
_NOTES: list = []


def _error(text: str, notes: bool = True) -> None:
    """``text`` as one stderr line, on a line of its own (a progress bar drawn is ended),
    with the command's implausible inputs (:data:`_NOTES`) added to it when ``notes``: the
    slip that may explain a refusal stays on the refusal's one line."""
    end_open_bars()
    said = "".join(f" (note: {n.removesuffix(RUN_AS_GIVEN)})" for n in _NOTES) if notes else ""
    _NOTES.clear()
    print(f"treeimpact: {text}{said}", file=sys.stderr)


def _warn_notes() -> None:
    """The command's implausible inputs as one warning line each (:data:`_NOTES`)."""
    for note in _NOTES:
        print(f"treeimpact: warning: {note}", file=sys.stderr)
    _NOTES.clear()


def run_command(command, args) -> int:
    """``command(args)``'s exit code, with every way it can end as one line on stderr:
    bad input (ParameterError, an unreadable path, too little memory) exit 2, a diverged
    simulation exit 3, a run that could not do what was asked (NotAchieved; OutsideValidity
    worded as outside the model's validity) exit 4, Ctrl-C or SIGTERM exit 130; output piped
    into ``head`` ends quietly.
    Once the command has returned or raised, a stop signal only marks it interrupted (its
    one line is printed whole, never cut by a second KeyboardInterrupt)."""
    _COMMAND["ended"] = False
    _NOTES.clear()
    try:
        try:
            code = command(args)
        finally:
            _COMMAND["ended"] = True  # from here a stop signal only sets STOP
            finish_progress()  # every bar ended before the command's last lines
        if STOP.is_set() and code != ExitCode.INTERRUPTED:  # asked after the last look
            raise KeyboardInterrupt
        if code == ExitCode.INTERRUPTED:  # the command said so itself (a sweep's own line)
            _forget_unhandled_interrupt()
        _warn_notes()
        return code
    except KeyboardInterrupt:
        _forget_unhandled_interrupt()
        _error("interrupted (Ctrl-C or SIGTERM); nothing more was written", notes=False)
        return ExitCode.INTERRUPTED
    except ParameterError as exc:
        _error(f"error: {exc}")
        return ExitCode.BAD_INPUT
    except OutsideValidity as exc:
        _error(f"outside the model's validity: {exc}")
        return ExitCode.NOT_ACHIEVED
    except NotAchieved as exc:
        _error(f"not achieved: {exc}")
        return ExitCode.NOT_ACHIEVED
    except SimulationDiverged as exc:
        _error(f"simulation diverged: {exc}")
        return ExitCode.DIVERGED
    except BrokenPipeError:  # output piped into head & co.
        sys.stderr.close()
        return ExitCode.OK
    except MemoryError:
        _error("error: the run needs more memory than this machine has: a shorter --t-end "
               "or a softer contact")
        return ExitCode.BAD_INPUT
    except ArithmeticError as exc:  # overflow or division by zero: no numbers to report
        _error(f"simulation diverged: {type(exc).__name__} ({one_line(exc)})")
        return ExitCode.DIVERGED
    except OSError as exc:  # a path that cannot be read or written
        where = f" {exc.filename!r}" if exc.filename else ""
        _error(f"error:{where} {exc.strerror or one_line(exc)}")
        return ExitCode.BAD_INPUT


#: The running command's state, read by the stop signals' handler: ``ended`` once
#: run_command has its outcome (a late signal, or an interrupt delivered again, then only
#: sets STOP instead of raising into the exit line).
_COMMAND = {"ended": True}


def _forget_unhandled_interrupt() -> None:
    """CPython records a KeyboardInterrupt that escaped an ``exec`` of source text (dataclasses
    and namedtuple build their methods so, at import) and, under ``python -m``, ends the
    process by SIGINT (exit -2) even when the interrupt was handled; the next such exec that
    ends normally clears the record. Called once the interrupt is handled (exit 130)."""
    exec("None")  # noqa: S102 - a constant: only CPython's record of the interrupt is reset


def _on_stop_signal(signum, frame) -> None:
    """The stop signals' handler while a command runs: :func:`compare.runs.pool.on_stop_signal`
    (``signum``, ``frame`` as the signal module passes them), and once the command has its
    outcome only the stop request. Imports nothing (a handler can land inside an import)."""
    pool = sys.modules["treeimpact.compare.runs.pool"]  # imported by stop_signals
    if _COMMAND["ended"]:
        pool.request_stop()
        return
    pool.on_stop_signal(signum, frame)


@contextmanager
def stop_signals(ending: bool = False):
    """Ctrl-C (SIGINT) and SIGTERM end the command alike: a stop request that a pool's loop
    answers at its next look, or at once outside one (compare.runs.pool.on_stop_signal); an
    interrupt that lands where Python can only print it (a weakref callback, a __del__) is
    delivered again, not lost (:func:`_unraisable`). A SIGINT this process inherited as
    ignored (a background job of a shell without job control: Ctrl-C is for the foreground
    job) stays ignored. Restored afterwards (main() may be called from Python); with
    ``ending`` (the process's own command line, which ends next) ignored afterwards instead:
    the outcome is decided, and a signal in the interpreter's last ~0.2 s (its teardown
    puts the default action back) would end the process by the signal, without its line
    and its exit code."""
    STOP.clear()
    signals = [signal.SIGTERM]
    if signal.getsignal(signal.SIGINT) is not signal.SIG_IGN:
        signals.append(signal.SIGINT)
    previous = {s: signal.signal(s, _on_stop_signal) for s in signals}
    hook, sys.unraisablehook = sys.unraisablehook, _unraisable
    try:
        yield
    finally:
        _COMMAND["ended"] = True
        for thread in list(_REDELIVERIES):  # none left to trip a restored handler
            thread.join(timeout=10 * REDELIVER_AFTER_S)
        sys.unraisablehook = hook
        for s, handler in previous.items():
            signal.signal(s, signal.SIG_IGN if ending else handler)


#: Seconds after which a lost interrupt is delivered again (the hook returns in microseconds).
REDELIVER_AFTER_S = 0.02
#: The threads delivering a lost interrupt again (stop_signals waits for them).
_REDELIVERIES: set = set()


def _unraisable(info) -> None:
    """``sys.unraisablehook`` while a command runs: a KeyboardInterrupt that Python could not
    raise (it landed in a callback) is the stop request it was: STOP set and the interrupt
    delivered again to the main thread, from a helper thread once this hook has returned
    (delivered now, it would land in this hook and be lost again); anything else is one
    warning line."""
    if info.exc_type is not None and issubclass(info.exc_type, KeyboardInterrupt):
        STOP.set()

        def again():
            try:
                time.sleep(REDELIVER_AFTER_S)
                if not _COMMAND["ended"]:  # an outcome already decided needs no interrupt
                    _thread.interrupt_main(signal.SIGINT)
            finally:
                _REDELIVERIES.discard(threading.current_thread())

        thread = threading.Thread(target=again, daemon=True)
        _REDELIVERIES.add(thread)
        thread.start()
        return
    _error(f"warning: ignored {info.exc_type.__name__} ({one_line(info.exc_value)})"
           if info.exc_value is not None else "warning: an ignored exception")


@contextmanager
def command_environment(max_seconds):
    """For one command: ``--max-seconds`` (s) as TREEIMPACT_MAX_SECONDS (its workers inherit
    it), long runs' progress on stderr and Python warnings as one line each; everything
    restored afterwards. A ``max_seconds`` that is not a finite positive number is refused
    (ParameterError naming --max-seconds)."""
    restore = install_budget(max_seconds)
    try:
        yield
    finally:
        restore_budget(restore)


def install_budget(max_seconds) -> dict:
    """Set the command's budget (``max_seconds``, s, as TREEIMPACT_MAX_SECONDS; None: the
    default), progress reporter and one-line warnings; returns what
    :func:`restore_budget` puts back. ParameterError naming --max-seconds when it is not a
    finite positive number."""
    name = budget.VARIABLES["seconds"]
    restore = {"environment": (name, os.environ.get(name)), "reporter": budget._REPORTER,
               "showwarning": warnings.showwarning}
    if max_seconds is not None and not (math.isfinite(max_seconds) and max_seconds > 0):
        raise ParameterError(f"--max-seconds = {max_seconds!r} s is out of range: allowed "
                             "(0, inf) s")
    warnings.showwarning = one_line_warning
    if max_seconds is not None:
        os.environ[name] = repr(float(max_seconds))
    budget.set_progress_reporter(lambda desc, total: Progress(total, desc, unit="step"))
    return restore


def restore_budget(restore: dict) -> None:
    """Undo :func:`install_budget` (``restore``: what it returned)."""
    if not restore:
        return
    warnings.showwarning = restore["showwarning"]
    name, value = restore["environment"]
    if value is None:
        os.environ.pop(name, None)
    else:
        os.environ[name] = value
    budget.set_progress_reporter(restore["reporter"])


def one_line_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """A Python warning (numpy's, an engine's) as one stderr line, not a source excerpt:
    ``warnings.showwarning``'s signature; the ``message``, its ``category``'s name and
    ``filename``:``lineno`` on ``file`` (default stderr); ``line`` is not shown. An
    ImplausibleInput is kept in :data:`_NOTES` for :func:`run_command`'s last lines."""
    text = " ".join(str(message).split())
    where = f"{Path(filename).name}:{lineno}"
    if issubclass(category, ImplausibleInput):  # ours: kept for the command's last lines
        if text not in _NOTES:
            _NOTES.append(text)
        return
    print(f"treeimpact: warning: {text} ({category.__name__}, {where})",
          file=file if file is not None else sys.stderr)
