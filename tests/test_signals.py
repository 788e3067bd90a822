"""How a command ends when it is stopped (issue 35 item 2): exit 130 and its one line
whatever the interrupt landed in, a SIGINT inherited as ignored kept ignored, a pool's
workers ended even when one ignores SIGTERM, and a progress bar ended before any message.
The report stopped at several moments of its run: tests/test_bad_input.py."""

from __future__ import annotations

import io
import signal
import subprocess
import sys
import textwrap

import pytest
from treeimpact.compare.interface import process
from treeimpact.compare.interface.process import run_command, stop_signals
from treeimpact.compare.runs.pool import STOP


def _python_m(tmp_path, body: str) -> subprocess.CompletedProcess:
    """``body`` run as ``python -m`` (the path whose exit CPython turns into SIGINT after an
    interrupt it saw escape an exec of source text)."""
    (tmp_path / "stopped_command.py").write_text(textwrap.dedent(body))
    return subprocess.run([sys.executable, "-m", "stopped_command"], cwd=tmp_path,
                          capture_output=True, text=True, timeout=60, check=False)


def test_an_interrupt_that_escaped_an_exec_still_exits_130_under_python_m(tmp_path):
    """A Ctrl-C landing while dataclasses build a class (an exec of source text, at import)
    ended `python -m treeimpact.compare.interface.cli` by SIGINT (exit -2) after its exit-130
    line."""
    proc = _python_m(tmp_path, """
        import sys
        from treeimpact.compare.interface.process import run_command, stop_signals

        def command(_):
            exec("raise KeyboardInterrupt")  # as the interrupt lands in dataclasses' exec

        with stop_signals():
            code = run_command(command, None)
        sys.exit(code)
    """)
    assert proc.returncode == 130, proc
    assert proc.stderr.startswith("treeimpact: interrupted") and proc.stderr.count("\n") == 1


def test_a_command_that_reports_its_own_interrupt_exits_130_under_python_m(tmp_path):
    """The sweep prints its own 'sweep interrupted' line and returns 130: same exit."""
    proc = _python_m(tmp_path, """
        import sys
        from treeimpact.compare.interface.process import run_command, stop_signals

        def command(_):
            try:
                exec("raise KeyboardInterrupt")
            except KeyboardInterrupt:
                return 130

        with stop_signals():
            code = run_command(command, None)
        sys.exit(code)
    """)
    assert proc.returncode == 130, proc


def test_a_sigint_inherited_as_ignored_stays_ignored():
    """A background job of a shell without job control starts with SIGINT ignored (Ctrl-C
    is the foreground job's): the command keeps it so; SIGTERM still stops it."""
    before = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        with stop_signals():
            assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN
            assert signal.getsignal(signal.SIGTERM) is process._on_stop_signal
        assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN
    finally:
        signal.signal(signal.SIGINT, before)


def test_a_stop_signal_after_the_outcome_marks_it_interrupted_without_raising(capsys):
    """A SIGINT (or an interrupt delivered again) that arrives once the command has its
    outcome only sets STOP: it cannot raise into the exit line or past main()."""
    def command(_):
        return 0

    # SIGINT at Python's own handler whatever the test run's (a background job inherits it
    # ignored, and stop_signals then rightly leaves it so: the test above)
    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        _stop_after_the_outcome(command)
    finally:
        signal.signal(signal.SIGINT, before)
    assert capsys.readouterr().err == ""


def _stop_after_the_outcome(command) -> None:
    with stop_signals():
        code = run_command(command, None)
        assert code == 0
        try:
            signal.raise_signal(signal.SIGINT)  # lands after the outcome: only STOP is set
        except KeyboardInterrupt:
            pytest.fail("a SIGINT after the outcome raised past run_command")
        finally:
            stopped = STOP.is_set()
            STOP.clear()  # the pools of later tests look at it
        assert stopped


def test_an_error_line_starts_its_own_line_after_a_half_drawn_bar(monkeypatch):
    """A progress bar (tqdm: on a terminal, and a sweep's on any stream) is redrawn in
    place without a newline: the error that ends the command begins a line of its own."""
    from treeimpact.analytic.errors import ParameterError
    from treeimpact.compare.runs.progress import Progress

    stream = io.StringIO()
    monkeypatch.setattr(sys, "stderr", stream)

    def command(_):
        bar = Progress(10, "runs", stream=stream, bar=True)
        bar.update(3)  # never closed: the command fails mid-run
        raise ParameterError("--t-end = -1 s is out of range")

    assert run_command(command, None) == 2  # bad input, as docs/cli.md documents
    text = stream.getvalue()
    assert "3/10" in text  # the bar was drawn
    assert "\ntreeimpact: error: --t-end" in text, repr(text)
    assert text.endswith("out of range\n") and text.count("treeimpact:") == 1


@pytest.mark.parametrize("cause", ["interrupted", "diverged"])
def test_a_closed_bar_is_not_ended_twice(monkeypatch, cause):
    """A bar closed normally leaves nothing for the error path to end (no blank line)."""
    from treeimpact.analytic.errors import SimulationDiverged
    from treeimpact.compare.runs.progress import Progress

    stream = io.StringIO()
    monkeypatch.setattr(sys, "stderr", stream)

    def command(_):
        with Progress(2, "runs", stream=stream, bar=True) as bar:
            bar.update(2)
        raise KeyboardInterrupt if cause == "interrupted" else SimulationDiverged("x_max nan")

    run_command(command, None)
    text = stream.getvalue().replace("\r", "")
    assert "\n\n" not in text and text.count("\ntreeimpact: ") == 1, repr(text)
