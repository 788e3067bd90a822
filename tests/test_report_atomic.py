"""A report's pages are one set (issue 54 item 9): report.html, report.md, report.json and
the figures they link are written into a temporary folder inside the output folder and
swapped in together (compare.report.pageset), so an interrupt at any step leaves the
earlier report's complete set or the new complete set, never a mix and never a temporary
folder, and the command ends with its one line and exit 130; once the command's outcome is
decided a late signal leaves it as it is (exit 0, no line)."""

from __future__ import annotations

import datetime
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import textwrap
import time
import types
from pathlib import Path

import pytest

from treeimpact.compare import report as report_module
from treeimpact.compare.interface.process import run_command, stop_signals
from treeimpact.compare.report import pageset
from treeimpact.compare.runs.cache import RunCache
from treeimpact.compare.runs.pool import STOP

ROOT = Path(__file__).resolve().parents[1]
#: The cheap report the tests write: one tree, the analytic rungs and an engine that does
#: not exist here (its rungs are skipped with their reason), a 4-segment chain.
CHEAP = {"scenarios": ["open-center"], "engines": ("no-such-engine",), "segments": 4}
#: The generation stamps the pages carry, where the report prints when it was generated.
OLD, NEW = "1999-01-01 00:00 UTC (old)", "2001-01-01 00:00 UTC (new)"
#: Appended to each figure of the new set (the old set's figures are the real ones).
NEW_FIGURE = b"(new)"
#: The one line of an interrupted command (compare.interface.process.run_command).
INTERRUPTED = "treeimpact: interrupted"


def _clock(stamp: str):
    """A stand-in for the report's ``datetime`` module whose now() prints as ``stamp``."""
    now = types.SimpleNamespace(strftime=lambda _fmt: stamp)
    return types.SimpleNamespace(timezone=datetime.timezone,
                                 datetime=types.SimpleNamespace(now=lambda _tz: now))


@pytest.fixture(scope="module")
def first(tmp_path_factory):
    """A real report (:data:`CHEAP`) stamped :data:`OLD`: its folder, its files' bytes
    ({name relative to the folder: bytes}) and its sections as built (reused for the new
    set, so that each interrupted write only renders)."""
    out = tmp_path_factory.mktemp("first")
    built = {}
    real = report_module.build_sections

    def keep(*args, **kwargs):
        built["sections"] = real(*args, **kwargs)
        return built["sections"]

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(report_module, "_dt", _clock(OLD))
        mp.setattr(report_module, "build_sections", keep)
        report_module.write_report(out, runs=RunCache(), **CHEAP)
    shutil.rmtree(out / report_module.SWEEPS)  # the report's working data, not its pages
    return out, _files(out), built["sections"]


def _files(folder: Path) -> dict:
    """Every file under ``folder``: {path relative to it (str): bytes}."""
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*"))
            if p.is_file()}


def _generation(folder: Path, old: dict) -> str:
    """'old' or 'new': which report's set ``folder`` holds; fails on a mix, a member
    missing, a figure linked that is not there or not linked, a temporary folder left."""
    assert not [p.name for p in folder.iterdir() if p.name.startswith(".report-")]
    html = (folder / "report.html").read_text()
    md = (folder / "report.md").read_text()
    data = json.loads((folder / "report.json").read_text())
    stamps = {"html": OLD in html, "md": OLD in md, "json": data["generated"] == OLD}
    assert len(set(stamps.values())) == 1, f"pages of two reports: {stamps}"
    linked = set(re.findall(r'src="(figures/[^"]+)"', html))
    assert set(re.findall(r"\]\((figures/[^)]+)\)", md)) == linked
    figures = {k: v for k, v in _files(folder).items() if k.startswith("figures/")}
    assert set(figures) == linked, "figures not the ones the pages link"
    kinds = {"old" if v == old[k] else "new" for k, v in figures.items()}
    generation = "old" if stamps["html"] else "new"
    assert kinds == {generation}, f"{generation} pages with figures {kinds}"
    if generation == "new":
        assert all(v.endswith(NEW_FIGURE) for v in figures.values())
    return generation


class Steps:
    """Counts the writer's steps (a file written, a folder made or removed, a rename) and
    raises SIGINT just before each step numbered in ``at`` (a set; 0 the first step): a
    Ctrl-C at that moment."""

    def __init__(self, monkeypatch, at=frozenset()):
        self.at, self.names = at, []
        for owner, name in ((Path, "write_text"), (Path, "write_bytes"), (os, "replace"),
                            (shutil, "rmtree")):
            monkeypatch.setattr(owner, name, self._step(getattr(owner, name), name))
        monkeypatch.setattr(pageset.tempfile, "mkdtemp",
                            self._step(pageset.tempfile.mkdtemp, "mkdtemp"))

    def _step(self, real, name):
        def step(*args, **kwargs):
            self.names.append(name)
            if len(self.names) - 1 in self.at:
                signal.raise_signal(signal.SIGINT)
            return real(*args, **kwargs)

        return step


def _new_sections(sections, old: dict):
    """A stand-in for build_sections: the first report's ``sections`` again, each figure
    written (into the new set's figure folder) as the old one's bytes plus NEW_FIGURE."""
    def build(*_args, figure_dir, **_kwargs):
        figure_dir.mkdir(parents=True, exist_ok=True)
        for name, data in old.items():
            if name.startswith("figures/"):
                (figure_dir / Path(name).name).write_bytes(data + NEW_FIGURE)
        return sections

    return build


def _interrupted_write(mp, first, out: Path, at=frozenset(), stamp: str = NEW):
    """The report's writer into ``out`` (the first report's set copied in, unless ``out``
    exists) stopped by a SIGINT before each of its steps ``at`` (Steps), as the command
    line runs it (its stop signals, its exit line), ``mp`` a pytest MonkeyPatch undone
    afterwards: (exit code, Steps)."""
    out_old, old, sections = first
    if not out.exists():
        shutil.copytree(out_old, out)
    mp.setattr(report_module, "_dt", _clock(stamp))
    mp.setattr(report_module, "build_sections", _new_sections(sections, old))
    before = signal.signal(signal.SIGINT, signal.default_int_handler)  # not a job's SIG_IGN
    try:
        steps = Steps(mp, at)
        with stop_signals():
            code = run_command(lambda _: _write(out), None)
    finally:
        signal.signal(signal.SIGINT, before)
        STOP.clear()  # later tests' pools look at it
        mp.undo()
    return code, steps


def _write(out: Path) -> int:
    """The report command's part that writes: the report into ``out``, exit 0."""
    report_module.write_report(out, **CHEAP)
    return 0


@pytest.fixture(scope="module")
def counted(first, tmp_path_factory):
    """The steps of an uninterrupted write over the first report (Steps.names)."""
    with pytest.MonkeyPatch.context() as mp:
        code, steps = _interrupted_write(mp, first, tmp_path_factory.mktemp("count") / "out")
    assert code == 0
    return steps.names


def _pages_written_by(names: list) -> int:
    """The number of steps up to and including the last page written into the new set."""
    return max(i for i, n in enumerate(names) if n == "write_text") + 1


def test_an_uninterrupted_write_puts_the_new_set_in_place(monkeypatch, first, tmp_path,
                                                          capsys):
    code, steps = _interrupted_write(monkeypatch, first, tmp_path / "out")
    assert code == 0 and capsys.readouterr().err == ""
    assert _generation(tmp_path / "out", first[1]) == "new"
    assert steps.names.count("replace") == 2 * len(pageset.MEMBERS)  # old out, new in


#: More than the writer's steps (an uninterrupted write's count: 23 here, with the
#: answer's matrix figure): the last parametrised SIGINTs come after every step.
STEP_COUNT = 25


@pytest.mark.parametrize("at", range(STEP_COUNT))
def test_a_sigint_at_any_step_leaves_one_complete_set(monkeypatch, first, counted, tmp_path,
                                                      capsys, at):
    """Before the new set is all written, the old set stays; from the swap on (its signals
    held), the new one is in place; either way exit 130 and the one line."""
    assert len(counted) < STEP_COUNT  # the parametrisation reaches past the last step
    code, steps = _interrupted_write(monkeypatch, first, tmp_path / "out", {at})
    err = capsys.readouterr().err
    if at >= len(counted):  # no step left to interrupt: the write ended normally
        assert code == 0 and err == "" and _generation(tmp_path / "out", first[1]) == "new"
        return
    assert steps.names[:at + 1] == counted[:at + 1]  # the same steps up to the one stopped at
    assert code == 130, err
    assert err.startswith(INTERRUPTED) and err.count("\n") == 1, err
    expected = "old" if at < _pages_written_by(counted) else "new"
    assert _generation(tmp_path / "out", first[1]) == expected, (at, counted, steps.names)


def test_a_second_ctrl_c_cannot_cut_the_cleanup(monkeypatch, first, counted, tmp_path,
                                                 capsys):
    """Ctrl-C as a figure is written and again as the unfinished set is removed: the old
    set, no temporary folder, exit 130 and one line."""
    figure = counted.index("write_bytes")
    code, steps = _interrupted_write(monkeypatch, first, tmp_path / "out",
                                     {figure, figure + 1})
    assert steps.names[figure + 1] == "rmtree"  # the second SIGINT came in the cleanup
    assert code == 130 and capsys.readouterr().err.count("\n") == 1
    assert _generation(tmp_path / "out", first[1]) == "old"


def test_a_failed_swap_puts_the_old_set_back(first, tmp_path, monkeypatch):
    """A rename that fails mid-swap (OSError: a full disk, a permission) leaves the old set
    in place, its error raised, no temporary folder."""
    out_old, old, _ = first
    for fail_at in range(2 * len(pageset.MEMBERS)):
        out = tmp_path / f"out{fail_at}"
        shutil.copytree(out_old, out)
        stage = Path(pageset.tempfile.mkdtemp(prefix=pageset.STAGING, dir=out))
        for name, data in old.items():  # a complete new set: old bytes, new stamp
            target = stage / name
            target.parent.mkdir(parents=True, exist_ok=True)
            target.write_bytes(data.replace(OLD.encode(), NEW.encode()) + (
                NEW_FIGURE if name.startswith("figures/") else b""))
        calls = []
        real = os.replace

        def replace(src, dst, _calls=calls, _at=fail_at, _real=real):
            _calls.append(src)
            if len(_calls) == _at + 1:
                raise OSError(28, "No space left on device")
            return _real(src, dst)

        monkeypatch.setattr(os, "replace", replace)
        with pytest.raises(OSError, match="No space left"):
            pageset.swap_in(stage, out)
        monkeypatch.undo()
        assert _generation(out, old) == "old", fail_at
        assert _files(out) == old


def test_a_first_report_stopped_before_its_swap_leaves_no_page(monkeypatch, first, counted,
                                                               tmp_path, capsys):
    """Into an empty folder: stopped before its last page, no member, no temporary folder."""
    empty = tmp_path / "empty"
    empty.mkdir()
    code, _ = _interrupted_write(monkeypatch, first, empty, {_pages_written_by(counted) - 1})
    assert code == 130 and capsys.readouterr().err.startswith(INTERRUPTED)
    assert list(empty.iterdir()) == []


def test_held_signals_deliver_a_signal_after_the_body():
    """A SIGINT inside the body is held, then delivered to the handler it had."""
    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    reached = []
    try:
        with pytest.raises(KeyboardInterrupt):
            with pageset.held_signals():
                signal.raise_signal(signal.SIGINT)
                reached.append("the body's end")
        assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
    finally:
        signal.signal(signal.SIGINT, before)
    assert reached == ["the body's end"]


#: Runs ``treeimpact report`` (python -m treeimpact.compare.interface.cli, so the command
#: line's own ending) of the CHEAP configuration with SIGINT at Python's own handler (a
#: background job inherits it ignored), paused at one moment of its writing until a file
#: appears:
#: argv = out folder, the file it writes when it pauses, the file that ends the pause,
#: the moment ("staged": all pages written into the new set; "swap": its first rename).
CHILD = textwrap.dedent("""
    import functools, os, runpy, signal, sys, time
    from pathlib import Path
    signal.signal(signal.SIGINT, signal.default_int_handler)
    out, paused, go, moment = sys.argv[1:5]
    import treeimpact.compare.report as rep

    def pause():
        Path(paused).write_text("")
        for _ in range(60000):  # at most 10 min, never a hang
            if Path(go).exists():
                return
            time.sleep(0.01)

    rep.write_report = functools.partial(rep.write_report, engines=("no-such-engine",),
                                         segments=4)
    if moment == "staged":
        real_swap = rep.swap_in
        def swap_in(stage, out_dir):
            pause()
            return real_swap(stage, out_dir)
        rep.swap_in = swap_in
    else:
        real_replace = os.replace
        def replace(src, dst):
            if ".report-old-" in str(dst) and not Path(paused).exists():  # the swap's first
                pause()
            return real_replace(src, dst)
        os.replace = replace
    sys.argv = ["treeimpact", "report", "--scenario", "open-center", "--out", out]
    runpy.run_module("treeimpact.compare.interface.cli", run_name="__main__")
""")


@pytest.mark.slow
@pytest.mark.parametrize("moment, kept", [("staged", "old"), ("swap", "new")])
def test_ctrl_c_while_a_real_report_writes_its_pages(tmp_path, moment, kept):
    """A real `treeimpact report` stopped with every page written into its new set (the
    old set stays) or inside its swap (the signal is held: the new set is put in place):
    exit 130, its one line, no traceback, one complete set, no temporary folder."""
    out = tmp_path / "rep"
    (out / "figures").mkdir(parents=True)
    stale = "an earlier report's page"
    for name in ("report.html", "report.md"):
        (out / name).write_text(f"{stale} ({OLD})")
    (out / "report.json").write_text(json.dumps({"generated": OLD}))
    (out / "figures" / "earlier.png").write_bytes(b"earlier")
    old = _files(out)
    paused, go = tmp_path / "paused", tmp_path / "go"
    proc = subprocess.Popen([sys.executable, "-c", CHILD, str(out), str(paused), str(go),
                             moment], cwd=ROOT, stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        for _ in range(60000):  # the child's pause, polled (at most 10 min)
            if paused.exists() or proc.poll() is not None:
                break
            time.sleep(0.01)
        assert paused.exists(), f"the report ended (exit {proc.poll()}) before its pause"
        proc.send_signal(signal.SIGINT)
        if moment == "swap":  # the signal is held there: the swap goes on once resumed
            go.write_text("")
        err = proc.communicate(timeout=600)[1]
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait(timeout=10)
    assert proc.returncode == 130, err[-500:]
    assert "Traceback" not in err and err.strip().splitlines()[-1].startswith(INTERRUPTED)
    assert not [p for p in out.iterdir() if p.name.startswith(".report-")]
    if kept == "old":
        assert {k: v for k, v in _files(out).items() if not k.startswith("sweeps/")} == old
        return
    pages = {n: (out / n).read_text() for n in ("report.html", "report.md", "report.json")}
    assert not any(stale in p or OLD in p for p in pages.values())
    assert pages["report.html"].rstrip().endswith("</html>")
    linked = set(re.findall(r'src="(figures/[^"]+)"', pages["report.html"]))
    assert {str(p.relative_to(out)) for p in (out / "figures").iterdir()} == linked
    assert json.loads(pages["report.json"])["scenarios"].keys() == {"open-center"}


def test_a_signal_after_the_outcome_leaves_the_exit_code(tmp_path):
    """The command line's ending (compare.interface.cli.entry): a SIGINT once the command has its
    outcome, as the interpreter ends (here: from an atexit hook, where Python's own
    handler would raise, and later its teardown the default action), leaves exit 0 and
    no line. Before, `treeimpact report` so ended by the signal (exit -2)."""
    script = textwrap.dedent("""
        import atexit, os, signal, sys
        signal.signal(signal.SIGINT, signal.default_int_handler)
        atexit.register(lambda: os.kill(os.getpid(), signal.SIGINT))
        sys.argv = ["treeimpact", "paper"]
        from treeimpact.compare.interface.cli import entry
        sys.exit(entry())
    """)
    proc = subprocess.run([sys.executable, "-c", script], cwd=tmp_path, capture_output=True,
                          text=True, timeout=120, check=False)
    assert proc.returncode == 0, proc
    assert proc.stderr == "", proc.stderr
