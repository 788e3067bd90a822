"""What several commands share: the argument types, the backend-option flags, the run-budget
flag, a number's text and a directory checked before a run (SI units throughout)."""

from __future__ import annotations

import argparse
import math
import os
from pathlib import Path

from treeimpact.analytic.budget import MAX_SECONDS, VARIABLES
from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.model.registry import BY_NAME
from treeimpact.compare.runs.backends import BACKENDS
from treeimpact.compare.runs.names import show
from treeimpact.compare.runs.verdicts import relative_step


def number(text: str) -> float:
    """A command-line number (float); an argparse type error naming the text otherwise."""
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None


def count(text: str) -> int:
    """A command-line integer; an argparse type error naming the text otherwise."""
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None


def backend_options() -> dict:
    """option name -> (its Option, the backends that take it), over every backend's
    ``OPTIONS`` (read without loading an engine)."""
    out: dict = {}
    for name, backend in BACKENDS.items():
        try:
            table = backend.options()
        except ParameterError:  # a backend that is not installed offers no flags
            continue
        for key, option in table.items():
            out.setdefault(key, (option, []))[1].append(name)
    return out


def add_option_flags(parser, names=None) -> None:
    """One flag per backend option (``--contact-stiffness``), its type or choices and help
    from the backends' OPTIONS, the backends that take it named."""
    for key, (option, takers) in sorted(backend_options().items()):
        if not option.cli or (names is not None and key not in names):
            continue
        unit = f", {option.unit}" if option.unit not in ("", "1") else ""
        kind = {"type": count} if option.kind is int else {"type": number} \
            if option.choices is None else {"choices": option.choices}
        text = registry_help(key, ", ".join(takers)) if key in BY_NAME else \
            f"{option.help}{unit} ({', '.join(takers)})"
        parser.add_argument("--" + key.replace("_", "-"), dest=key, **kind,
                            help=text.replace("%", "%%"))


def add_parameter_flag(parser, name: str, *, note: str = "", **kw) -> None:
    """``--NAME``, a number, for the registry's parameter ``name`` (analytic.model.registry),
    its help :func:`registry_help`; ``kw`` (``required``) go to ``add_argument``."""
    parser.add_argument(show(name), dest=name, type=number,
                        help=registry_help(name, note).replace("%", "%%"), **kw)


def registry_help(name: str, note: str = "") -> str:
    """A flag's help for the registry's parameter ``name``: "symbol, unit: meaning" (its
    label when it has no meaning), then `` (note)``."""
    p = BY_NAME[name]
    return f"{p.symbol}, {p.unit}: {p.meaning or p.label}" + (f" ({note})" if note else "")


def add_budget_flag(parser) -> None:
    """``--max-seconds``: the longest single run the command admits (s)."""
    parser.add_argument(
        "--max-seconds", type=number, dest="max_seconds",
        help=f"refuse any single run estimated longer than this, s (default {MAX_SECONDS:g}, "
             f"or {VARIABLES['seconds']}); the estimate is printed with the refusal")


def options_of(args, names) -> dict:
    """The ``names`` the user gave (not None) as a dict, from the parsed ``args``."""
    return {n: getattr(args, n) for n in names if getattr(args, n, None) is not None}


def fmt(v) -> str:
    """A value as printed in a table: floats to 6 digits, 'n/a' where not finite."""
    if isinstance(v, float):
        return "n/a" if not math.isfinite(v) else f"{v:.6g}"
    return str(v)


def unit_text(u: str) -> str:
    """A unit's column text: '-' for a dimensionless 1 (not read as a second number)."""
    return "-" if u in ("1", "") else u


def relative_text(value, reference) -> str:
    """:func:`compare.runs.verdicts.relative_step` as text ('' where it has no value)."""
    rel = relative_step(value, reference)
    return f"{rel:+.1%}" if math.isfinite(rel) else ""


def writable_dir(flag: str, path: str) -> None:
    """Create ``path`` (a directory) now, or raise a one-line error naming ``flag``."""
    try:
        Path(path).mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ParameterError(f"{flag} {path!r}: cannot create the directory "
                             f"({exc.strerror or type(exc).__name__})") from None
    if not os.access(path, os.W_OK):
        raise ParameterError(f"{flag} {path!r}: the directory is not writable")
