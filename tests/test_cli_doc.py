"""docs/cli.md against the parsers (issue 26 item 1): every option of every command, its
words and its positional arguments are in the command's section, no section shows a flag
its command does not have, the sweep's grid names are all listed, and the verdict names are
all listed where verdicts are explained."""

from __future__ import annotations

import argparse
import re
from pathlib import Path

import pytest

from treeimpact.compare.interface.cli import build_parser
from treeimpact.compare.runs.verdicts import Verdict

ROOT = Path(__file__).resolve().parent.parent
CLI = ROOT / "docs" / "cli.md"


def _commands() -> dict:
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return dict(sub.choices)


def _sections() -> dict:
    """command -> its section of docs/cli.md (heading line included)."""
    text = CLI.read_text()
    heads = list(re.finditer(r"^#{2,3} .*$", text, flags=re.M))
    out = {}
    for h, nxt in zip(heads, heads[1:] + [None]):
        m = re.match(r"### `treeimpact (\w+)", h.group())
        if m:
            out[m[1]] = text[h.start():nxt.start() if nxt else len(text)]
    return out


COMMANDS = _commands()


def test_every_command_has_a_section():
    assert set(_sections()) == set(COMMANDS)


def _flag(action) -> str:
    return max(action.option_strings, key=len)


@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_every_option_of_the_command_is_in_its_section(command):
    section = _sections()[command]
    heading = section.splitlines()[0]
    missing = []
    for action in COMMANDS[command]._actions:
        if isinstance(action, argparse._HelpAction):
            continue
        if not action.option_strings:  # a positional: its metavar in the heading
            if not re.search(rf"\b{action.dest.upper()}\b", heading):
                missing.append(action.dest.upper())
            continue
        flag = _flag(action)
        if not re.search(rf"{re.escape(flag)}(?![\w-])", section):
            missing.append(flag)
        for word in action.choices or ():
            if not re.search(rf"[`|(\s]{re.escape(str(word))}[`|)\]]", section):
                missing.append(f"{flag} {word}")
    assert not missing, f"docs/cli.md, treeimpact {command}: not documented: {missing}"


@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_no_section_shows_a_flag_its_command_does_not_have(command):
    """Flags in the section's code spans and heading: the command's own, or shown with
    another program (``benchmarks/bench_sweep.py --dask-defaults``, ``treeimpact paper``)."""
    section = re.sub(r"<!-- BEGIN generated.*?<!-- END generated: [\w-]+ -->", "",
                     _sections()[command], flags=re.S)  # from the code: not stale
    own = {f for a in COMMANDS[command]._actions for f in a.option_strings}
    stale = []
    for span in re.findall(r"`([^`\n]+)`", section):
        words = span.split()
        if words[0] not in ("treeimpact",) and not words[0].startswith("--"):
            continue
        if words[0] == "treeimpact" and len(words) > 1 and words[1] != command:
            continue
        stale += [w for w in re.findall(r"(?<![\w-])--[a-z][a-z0-9-]*", span) if w not in own]
    assert not stale, f"docs/cli.md, treeimpact {command}: no such option: {sorted(set(stale))}"


def test_every_grid_name_of_the_sweep_is_listed():
    from treeimpact.compare.interface.commands._common import backend_options
    from treeimpact.compare.studies.sweep.grid import ALIASES, DERIVED_RATIOS, RECORD_FIELDS

    section = _sections()["sweep"]
    names = [*ALIASES, *DERIVED_RATIOS, *(f"record.{f}" for f in RECORD_FIELDS),
             *(k for k, (o, _) in backend_options().items() if o.cli)]
    missing = [n for n in names if f"`{n}`" not in section]
    assert not missing and {"contact_duration", "integrator", "restitution"} <= set(names)


#: Where the pages explain the verdicts: (page, the text that starts the explanation).
VERDICT_PLACES = [("cli.md", "Verdicts (`compare.runs.verdicts.Verdict`"),
                  ("ladder.md", "Verdicts (`compare.runs.verdicts.Verdict`"),
                  ("glossary.md", "## Verdicts")]


@pytest.mark.parametrize("page, start", VERDICT_PLACES)
def test_every_verdict_is_named_where_the_verdicts_are_explained(page, start):
    text = (ROOT / "docs" / page).read_text()
    assert start in text, f"docs/{page}: no '{start}'"
    place = text[text.index(start):][:2500]
    missing = [v.value for v in Verdict if f"`{v.value}`" not in place]
    assert not missing, f"docs/{page}: verdicts not explained: {missing}"


# ------------------------------------------------------------- the commands the pages show

#: Pages whose commands are run here, in their order (a page's later command may read what
#: an earlier one wrote: `scenario ... --out .` then `simulate my-tree.toml`).
RUN_PAGES = ("README.md", "docs/cli.md", "docs/contact-settings.md")
#: Commands shown that run for minutes, and what runs and checks them instead.
COVERED = {
    "treeimpact report --out reports --with-study default":
        "make report; its numbers are docs/numbers.json, checked by tests/test_doc_numbers.py",
    "treeimpact sweep --preset default --out reports/study":
        "make report runs it (--with-study default)",
    "treeimpact paper --fit-contact":
        "30 s; docs/results/contact-fit.json is rerun at its fitted parameters by "
        "tests/test_doc_numbers.py",
}


def _shown() -> list[tuple[str, str]]:
    """(page, command) of every concrete `treeimpact ...` command of RUN_PAGES, in order."""
    import sys

    sys.path.insert(0, str(ROOT / "tests"))
    from test_docs import _code

    out = []
    for page in RUN_PAGES:
        for code in _code((ROOT / page).read_text()):
            code = code.split("#")[0].strip()
            if code.startswith("treeimpact ") and not re.search(r"[A-Z]{2,}|\[|\.\.\.|\|",
                                                                 code):
                out.append((page, " ".join(code.split())))
    return out


def test_every_command_shown_runs_and_prints_what_its_page_says(tmp_path, monkeypatch,
                                                              capsys):
    """Every command of the README, docs/cli.md and docs/contact-settings.md, run as shown
    (issue 34 item 5): exit 0; the contact example at MuJoCo's default step prints the
    numbers docs/contact-settings.md quotes (docs/numbers.json holds them)."""
    import json
    import shlex

    from treeimpact.compare.interface.cli import main

    shown = _shown()
    assert {c for _, c in shown} >= set(COVERED), "a covered command is no longer shown"
    numbers = json.loads((ROOT / "docs" / "numbers.json").read_text())["numbers"]
    monkeypatch.chdir(tmp_path)
    ran = []
    for page, command in shown:
        if command in COVERED:
            continue
        code = main(shlex.split(command)[1:])
        out = capsys.readouterr()
        assert code == 0, (page, command, out.err[-300:])
        ran.append(command)
        if "--dt 2e-3 --engine mujoco" in command:  # the example at MuJoCo's default step
            row = next(ln for ln in out.out.splitlines() if "MuJoCo solref (direct)" in ln)
            pct = float(re.search(r"ms \(([-+\d.]+)%", row).group(1))
            assert pct == pytest.approx(numbers["contact_cmd.default_step.duration_pct"],
                                        abs=0.005)  # printed to 0.01 %
            half = float(re.search(r"mm\s+([\d.]+), ", row).group(1))  # at dt/2: e, ms
            assert half == pytest.approx(numbers["contact_cmd.default_step.half_dt_e"],
                                         abs=5e-5)  # printed to 4 decimals
    assert len(ran) >= 8, ran
