"""``treeimpact``: the command line (SI units throughout; docs/cli.md). This module only
builds the parser and dispatches: each command lives in :mod:`treeimpact.compare.commands`,
how a command ends (exit codes, signals, warnings) in :mod:`treeimpact.compare.process`.

Exit codes: 0 success; 2 bad input (one line on stderr naming the field and its range,
no traceback); 3 a simulation diverged (reported as such, never as numbers); 130
interrupted.
"""

from __future__ import annotations

import argparse
import sys

from treeimpact.analytic.errors import ParameterError

from .commands import COMMANDS
from .commands._common import backend_options  # noqa: F401 - docs/cli.md names it here
from .commands.modes import MODES_OPTIONS  # noqa: F401 - compare.docs reads it here
from .process import EXIT_BAD_INPUT, EXIT_DIVERGED, EXIT_INTERRUPTED  # noqa: F401


class _Parser(argparse.ArgumentParser):
    """An argparse parser whose errors are one line (exit 2 by :func:`main`), not usage."""

    def error(self, message):
        raise ParameterError(message)


def build_parser() -> argparse.ArgumentParser:
    """The ``treeimpact`` parser: one subparser per module of compare.commands."""
    p = _Parser(prog="treeimpact", description="The fruit-tree trunk impact model of the paper "
                "and its cross-checks against MuJoCo and PyBullet (SI units; exit codes: 0 "
                "success, 2 bad input, 3 the simulation diverged).")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)
    for module in COMMANDS.values():
        sp = sub.add_parser(module.NAME, help=module.HELP)
        module.add_arguments(sp)
    return p


def main(argv=None) -> int:
    """Run ``treeimpact`` with ``argv`` (default: sys.argv[1:]); returns the exit code."""
    from .process import command_environment, run_command, stop_signals

    def command(_):
        args = build_parser().parse_args(argv)
        with command_environment(getattr(args, "max_seconds", None)):
            return COMMANDS[args.command].run(args)

    with stop_signals():
        return run_command(command, None)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
