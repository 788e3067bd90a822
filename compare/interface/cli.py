"""``treeimpact``: the command line (SI units throughout; docs/cli.md). This module only
builds the parser and dispatches: each command lives in
:mod:`treeimpact.compare.interface.commands`, how a command ends (exit codes, signals,
warnings) in :mod:`treeimpact.compare.interface.process`.

Exit codes: 0 success; 2 bad input (one line on stderr naming the field and its range,
no traceback); 3 a simulation diverged (reported as such, never as numbers); 4 ran, but
could not do what was asked or its result lies outside the model's validity (one line saying
what was achieved instead); 130 interrupted.
"""

from __future__ import annotations

import argparse
import sys

from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.threads import blas_limit

from ..runs.names import NAMING, did_you_mean
from ..runs.progress import set_job
from .commands import COMMANDS, HELP
from .process import command_environment, run_command, stop_signals


class _Parser(argparse.ArgumentParser):
    """An argparse parser whose errors are one line (exit 2 by :func:`main`), not usage, and
    that never expands an abbreviation (``--e`` is not ``--equivalent-length``)."""

    def __init__(self, *args, **kwargs):
        kwargs["allow_abbrev"] = False  # subparsers too: argparse does not pass it down
        super().__init__(*args, **kwargs)

    def error(self, message):
        """argparse's error as a ParameterError (one line, exit 2)."""
        raise ParameterError(message)


class _TopParser(_Parser):
    """The ``treeimpact`` parser: a flag its command does not have is refused before
    anything else is parsed, naming what it may have meant (compare.runs.names)."""

    def parse_known_args(self, args=None, namespace=None):
        """argparse's, after :func:`refuse_unknown_flags`."""
        args = sys.argv[1:] if args is None else list(args)
        refuse_unknown_flags(self, args)
        return super().parse_known_args(args, namespace)


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def refuse_unknown_flags(parser: argparse.ArgumentParser, argv: list) -> None:
    """A one-line ParameterError for the first flag in ``argv`` that its command (a
    subcommand of ``parser``) does not have (a prefix, a removed spelling, a paper symbol),
    with what it may have meant."""
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    command = named_command(argv)
    if command not in sub.choices:
        return  # argparse names the missing or unknown command
    sp = sub.choices[command]
    flags = {f for a in sp._actions for f in a.option_strings}
    known = [f[2:].replace("-", "_") for f in flags if f.startswith("--") and f != "--help"]
    for token in argv[argv.index(command) + 1:]:
        if token == "--":
            break
        if not token.startswith("-") or len(token) < 2 or _is_number(token):
            continue
        flag = token.split("=", 1)[0]
        if flag not in flags:
            hint = did_you_mean(flag, known, getattr(COMMANDS[command], "RENAMED", None))
            raise ParameterError(f"{flag}: not an option of treeimpact {command} (flags are "
                                 f"never abbreviated){hint}")


def named_command(argv: list) -> str | None:
    """The command ``argv`` names (its first word that is no flag; ``treeimpact`` itself
    has no option taking a value), or None."""
    return next((t for t in argv if not t.startswith("-")), None)


def build_parser(command: str | None = None, *, every: bool = True) -> argparse.ArgumentParser:
    """The ``treeimpact`` parser: one subparser per command of compare.interface.commands (its help
    from :data:`~treeimpact.compare.interface.commands.HELP`), each with its arguments; with
    ``every=False`` only ``command``'s (its module alone imported: ``treeimpact --help``
    imports no command's module, none of numpy, scipy or the engines)."""
    p = _TopParser(prog="treeimpact", description="The fruit-tree trunk impact model of the paper "
                "and its cross-checks against MuJoCo and PyBullet (SI units; exit codes: 0 "
                "success, 2 bad input, 3 the simulation diverged, 4 ran but not as asked or outside "
                "the model's validity).")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)
    for name, text in HELP.items():
        sp = sub.add_parser(name, help=text)
        if every or name == command:
            COMMANDS[name].add_arguments(sp)
    return p


def main(argv=None) -> int:
    """Run ``treeimpact`` with ``argv`` (default: sys.argv[1:]), every command with one BLAS
    thread (analytic.threads; the caller's setting back on return); returns the exit code."""
    return _run(argv, ending=False)


def entry() -> int:
    """The process's command line (the ``treeimpact`` script, ``python -m
    treeimpact.compare.interface.cli``): :func:`main` of sys.argv[1:], after which Ctrl-C
    and SIGTERM are ignored while the interpreter ends
    (compare.interface.process.stop_signals' ``ending``): a signal that comes once the
    outcome is decided leaves it as it is (docs/cli.md)."""
    return _run(None, ending=True)


def _run(argv, ending: bool) -> int:
    """:func:`main` of ``argv``; ``ending``: as compare.interface.process.stop_signals'."""
    def command(_):
        words = sys.argv[1:] if argv is None else list(argv)
        args = build_parser(named_command(words), every=False).parse_args(words)
        set_job(args.command)
        naming = NAMING.set("flag")  # the API the commands call names the flags typed
        try:
            with command_environment(getattr(args, "max_seconds", None)), blas_limit():
                return COMMANDS[args.command].run(args)
        finally:
            NAMING.reset(naming)

    with stop_signals(ending):
        return run_command(command, None)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(entry())
