"""The README and docs/ show only commands and test ids that exist and run."""

from __future__ import annotations

import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

from treeimpact.compare.interface.cli import build_parser, main

ROOT = Path(__file__).resolve().parent.parent
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


def _code(text: str) -> list[str]:
    """Inline code spans and the lines of code blocks, continuation lines joined."""
    blocks = re.findall(r"```[a-z]*\n(.*?)```", text, flags=re.S)
    spans = re.findall(r"`([^`\n]+)`", re.sub(r"```.*?```", "", text, flags=re.S))
    return spans + [line for b in blocks for line in b.replace("\\\n", " ").splitlines()]


def _commands(prefix: str) -> list[tuple[str, str]]:
    """(page, command) for every concrete command starting with ``prefix`` (templates with
    placeholders such as SCENARIO or [--json] are syntax, not commands)."""
    out = []
    for page in PAGES:
        for code in _code(page.read_text()):
            code = code.split("#")[0].strip()
            if code.startswith(prefix) and not re.search(r"[A-Z]{2,}|\[|\.\.\.|\|", code):
                out.append((page.name, code))
    return out


TREEIMPACT = _commands("treeimpact ")


def test_the_pages_show_commands():
    assert len(TREEIMPACT) >= 4 and any(p == "README.md" for p, _ in TREEIMPACT)


@pytest.mark.parametrize("page, command", TREEIMPACT, ids=[c for _, c in TREEIMPACT])
def test_every_treeimpact_command_shown_parses(page, command):
    build_parser().parse_args(shlex.split(command)[1:])  # argparse errors raise


def test_the_add_your_own_tree_example_runs(tmp_path, monkeypatch, capsys):
    readme = (ROOT / "README.md").read_text()
    section = readme[readme.index("## Add your own tree"):]
    commands = [c for c in _code(section[:section.index("\n## ", 3)])
                if c.startswith("treeimpact ")]
    assert [c.split()[1] for c in commands] == ["scenario", "simulate"]
    monkeypatch.chdir(tmp_path)
    for command in commands:
        assert main(shlex.split(command)[1:]) == 0, command
    assert "my-tree (analytic)" in capsys.readouterr().out


def test_the_tree_from_its_geometry_example_runs(tmp_path, monkeypatch, capsys):
    """The README's tree from its geometry: one `scenario --crown-mass`, its file written
    with the assumptions named (issue 50 item 6)."""
    readme = (ROOT / "README.md").read_text()
    section = readme[readme.index("## Add your own tree from its geometry"):]
    commands = [c for c in _code(section[:section.index("\n## ", 3)])
                if c.startswith("treeimpact ")]
    assert [c.split()[1] for c in commands] == ["scenario"] and "--crown-mass" in commands[0]
    monkeypatch.chdir(tmp_path)
    assert main(shlex.split(commands[0])[1:]) == 0
    text = (tmp_path / "plum.toml").read_text()
    assert "assumed_base_stiffness" in text and "assumed_damping" in text


def test_the_identify_your_own_tree_example_runs_from_the_cli_alone(tmp_path, monkeypatch,
                                                                  capsys):
    """The README's identify example: `simulate --record` writes the record, `identify`
    reads it back and explains it."""
    readme = (ROOT / "README.md").read_text()
    section = readme[readme.index("## Identify your own tree from a record"):]
    commands = [c for c in _code(section[:section.index("\n## ", 3)])
                if c.startswith("treeimpact ")]
    assert [c.split()[1] for c in commands] == ["simulate", "identify"]
    monkeypatch.chdir(tmp_path)
    for command in commands:
        assert main(shlex.split(command)[1:]) == 0, command
    out = capsys.readouterr().out
    assert "verdict: explained" in out and (tmp_path / "fit.png").exists()


def test_every_make_target_shown_exists():
    targets = set(re.findall(r"^([a-z]+):", (ROOT / "Makefile").read_text(), flags=re.M))
    shown = {c.split()[1] for _, c in _commands("make ")}
    assert shown and shown <= targets, shown - targets


def test_every_test_id_shown_is_collected(whole_suite):
    """Each test id a page shows is collected: among this session's tests when it collected
    the whole suite, else by a ``--collect-only`` of it."""
    ids = sorted({m for page in PAGES for m in re.findall(r"`(test_\w+\[[^\]`]+\])`",
                                                              page.read_text())})
    assert ids
    files = {i: next(p for d in ("tests", "compare/tests") for p in (ROOT / d).glob("test_*.py")
                     if f"def {i.split('[')[0]}(" in p.read_text()) for i in ids}
    collected = None if whole_suite is None else {item.nodeid for item in whole_suite}
    for test_id, path in files.items():
        node = f"{path.relative_to(ROOT).as_posix()}::{test_id}"
        if collected is not None:
            assert node in collected, node
            continue
        proc = subprocess.run([sys.executable, "-m", "pytest", "--collect-only", "-q", node],
                              cwd=ROOT, capture_output=True, text=True)
        assert proc.returncode == 0 and node in proc.stdout, f"{node}: {proc.stdout[-300:]}"


def test_the_readme_limits_table_is_the_code_s():
    from treeimpact.analytic.model.parameters import LIMITS

    readme = (ROOT / "README.md").read_text()
    rows = dict(re.findall(r"^\| `([a-z_.]+)` \| (\[[^|]+\]) \|", readme, flags=re.M))
    assert rows == {k: f"[{lo:g}, {hi:g}]" for k, (lo, hi, _) in LIMITS.items()}


def test_every_local_link_and_image_resolves():
    """Markdown links and images to files of the repository exist (a clone shows them)."""
    import re

    missing = []
    for page in PAGES:
        for target in re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", page.read_text()):
            if target.startswith(("http://", "https://", "mailto:")):
                continue
            if not (page.parent / target).exists():
                missing.append(f"{page.name}: {target}")
    assert not missing, missing


def test_the_readme_names_the_cpus_its_timings_were_measured_on():
    """The README's install note names, as the machine it measured on, the CPU each
    benchmark file it quotes records (benchmarks/results/make.json, kernels.json)."""
    import json

    text = (ROOT / "README.md").read_text()
    note = " ".join(text[text.index("## Start here"):text.index("([reproducibility]")].split())
    cpus = {json.loads((ROOT / "benchmarks" / "results" / f"{name}.json").read_text())
            ["machine"]["cpu"] for name in ("make", "kernels")}
    assert len(cpus) == 1, f"make.json and kernels.json were measured on different CPUs: {cpus}"
    assert f"Measured on this project's 2-core machine, an {cpus.pop()} " in note


def test_the_numerics_count_the_pages_quote_is_the_suite_s_now(whole_suite):
    """benchmarks/results/kernels.json's numerics_tests (quoted by the README and
    docs/reproducibility.md) is the number of tests marked ``numerics`` collected now: this
    session's count when it collected the whole suite, else a ``--collect-only`` of it."""
    import json

    quoted = json.loads((ROOT / "benchmarks" / "results" / "kernels.json").read_text())[
        "numbers"]["numerics_tests"]
    count = None if whole_suite is None else sum(
        1 for item in whole_suite if item.get_closest_marker("numerics"))
    if count is None:
        proc = subprocess.run([sys.executable, "-m", "pytest", "--collect-only", "-q", "-m",
                               "numerics", "-p", "no:cacheprovider", "tests", "compare"],
                              cwd=ROOT, capture_output=True, text=True, timeout=300)
        found = re.search(r"^(\d+)/\d+ tests collected", proc.stdout, flags=re.M)
        assert found, proc.stdout[-500:] + proc.stderr[-500:]
        count = int(found.group(1))
    assert count == quoted, (
        f"{count} numerics tests now, kernels.json says {quoted}: rerun "
        "benchmarks/bench_kernels.py")
