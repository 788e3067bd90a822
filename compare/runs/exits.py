"""The command line's exit codes, one enum read by every place that returns or checks one:
the commands, the process policy (:mod:`treeimpact.compare.interface.process`), the sweep
command and a study run beside the report (:mod:`treeimpact.compare.report.validity.study_job`,
which reads its child's). On floor 1 of compare so that every floor above may read it
(docs/architecture.md); the values are the ones docs/cli.md documents."""

from __future__ import annotations

from enum import IntEnum


class ExitCode(IntEnum):
    """How a ``treeimpact`` command ended, as its process's exit status."""

    #: The command did what it was asked.
    OK = 0
    #: Bad input: one line on stderr naming the field and its allowed range, no traceback.
    BAD_INPUT = 2
    #: A simulation diverged (reported as such, never as numbers).
    DIVERGED = 3
    #: Ran, but could not do what was asked: one stderr line saying what was achieved
    #: instead and what would achieve it (a contact target the step cannot hold, a record
    #: not fitted), or that the result lies outside the model's validity.
    NOT_ACHIEVED = 4
    #: Interrupted by Ctrl-C or SIGTERM: 128 + SIGINT, as a shell says.
    INTERRUPTED = 130
