"""Nothing typed is guessed at (issue 34 item 1): every parser refuses abbreviations, and a
prefix, a removed spelling or a paper symbol typed as a flag is refused in one line (exit 2)
naming what it may have meant. The walk covers every flag of every command."""

from __future__ import annotations

import argparse

import pytest

from treeimpact.analytic.errors import ParameterError
from treeimpact.compare.interface.cli import build_parser, main
from treeimpact.compare.interface.commands import COMMANDS

PARSER = build_parser()
SUBPARSERS = next(a for a in PARSER._actions if isinstance(a, argparse._SubParsersAction))

#: Just enough positional arguments for each command to reach its flags.
POSITIONALS = {"simulate": ["open-center"], "modes": ["open-center"], "identify": ["r.csv"],
               "scenario": ["my-tree"]}


def _flags(command: str) -> list[str]:
    sp = SUBPARSERS.choices[command]
    return sorted({f for a in sp._actions for f in a.option_strings
                   if f.startswith("--") and f != "--help"})


def test_no_parser_expands_abbreviations():
    assert PARSER.allow_abbrev is False
    for name, sp in SUBPARSERS.choices.items():
        assert sp.allow_abbrev is False, name


def _prefixes(flag: str, flags: list[str]) -> list[str]:
    """Proper prefixes of ``flag`` that are no flag of the command: the shortest, the one a
    letter short, and one in between."""
    name = flag[2:]
    cuts = sorted({1, max(1, len(name) // 2), len(name) - 1})
    return [p for p in ("--" + name[:c] for c in cuts if c >= 1) if p not in flags]


CASES = [(c, f, p) for c in sorted(COMMANDS) for f in _flags(c) for p in _prefixes(f, _flags(c))]


@pytest.mark.parametrize("command, flag, prefix", CASES,
                         ids=[f"{c}-{p}" for c, _, p in CASES])
def test_a_prefix_of_every_flag_is_refused_and_the_flag_suggested(command, flag, prefix):
    argv = [command, *POSITIONALS.get(command, []), prefix, "1"]
    with pytest.raises(ParameterError) as info:
        PARSER.parse_args(argv)
    text = str(info.value)
    assert text.startswith(f"{prefix}: not an option of treeimpact {command}"), text
    assert "\n" not in text
    if len(prefix) >= 4:  # a one-letter prefix may be a symbol (--e: --restitution first)
        assert flag in text, text


@pytest.mark.parametrize("argv, words", [
    # the trial of issue 34: each was silently taken as another flag
    (["identify", "rec.csv", "--impactor-mass", "132.4", "--e", "0.1"],
     ["--e: not an option of treeimpact identify", "did you mean --restitution"]),
    (["scenario", "my-tree", "--e", "0.2"], ["did you mean --restitution"]),
    (["scenario", "my-tree", "--damping", "4000"], ["--damping", "--damping-rate"]),
    (["simulate", "open-center", "--backend", "beam", "--e", "3"], ["--elements"]),
    (["simulate", "open-center", "--m", "3"], ["--max-seconds"]),
    (["identify", "rec.csv", "--m", "3"], ["did you mean --impactor-mass"]),
    (["identify", "rec.csv", "--mass", "3"], ["renamed", "--impactor-mass"]),
    (["simulate", "open-center", "--t-en=0.1"], ["--t-en: not an option", "--t-end"]),
])
def test_the_trial_s_abbreviations_are_refused_with_what_they_may_mean(capsys, argv, words):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    for w in words:
        assert w in err, (w, err)


def test_a_negative_number_is_a_value_not_a_flag(capsys):
    assert main(["simulate", "open-center", "--restitution", "-0.5"]) == 2
    assert "--restitution = -0.5 is out of range" in capsys.readouterr().err


def test_every_physical_flag_is_spelled_and_explained_as_the_registry_says():
    """Each command's flag for a physical quantity is ``--NAME`` with NAME the registry's
    name, and its help opens with the registry's symbol, unit and meaning (issue 42: one
    name, one place); a removed spelling (``--mass`` for the pendulum's) is refused."""
    from treeimpact.analytic.model.registry import BY_NAME
    from treeimpact.compare.interface.commands._common import registry_help

    seen = set()
    for command, parser in SUBPARSERS.choices.items():
        for action in parser._actions:
            if action.dest in BY_NAME and action.option_strings:
                assert action.option_strings == ["--" + action.dest.replace("_", "-")], (
                    command, action.option_strings)
                assert action.help.replace("%%", "%").startswith(registry_help(action.dest)), (
                    command, action.dest, action.help)
                seen.add(action.dest)
    assert {"impactor_mass", "equivalent_stiffness", "restitution", "contact_duration",
            "clamp_height", "damping_rate", "contact_damping"} <= seen
