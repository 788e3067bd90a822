"""The command's progress display (compare.runs.progress): quiet off a terminal, bars named by
job and stage, the overall line's fraction, and a child job's records drawn by its parent."""

from __future__ import annotations

import io

import pytest
from treeimpact.compare.runs import progress


class _Terminal(io.StringIO):
    def isatty(self):
        return True


@pytest.fixture(autouse=True)
def _fresh(monkeypatch):
    monkeypatch.delenv(progress.RELAY_ENV, raising=False)
    progress.set_job("report")
    yield
    progress.finish()


def test_nothing_when_not_on_a_terminal():
    """A log or a pipe gets no progress at all."""
    stream = io.StringIO()
    with progress.Progress(4, "runs", stream=stream) as bar:
        for _ in range(4):
            bar.update()
    assert stream.getvalue() == ""


def test_the_job_line_counts_planned_stages_and_names_the_active_ones():
    """Two planned stages, the first done and the second half done: the job's line says
    75 % of 2 stages and names the active stage with its count; at the end, 100 %."""
    stream = _Terminal()
    progress.plan(2, stream)
    with progress.Progress(2, "runs", stream=stream) as bar:
        bar.update(2)
    second = progress.Progress(4, "record fits", unit="fit", stream=stream)
    second.update(2)
    job = progress._JOBS["report"]
    assert job.percent == pytest.approx(75.0)
    assert job.bar.desc == "report: overall" and job.bar.postfix == "record fits 2/4 fits"
    second.close()
    assert job.percent == pytest.approx(100.0) and job.bar is None  # the line ended
    assert "report: overall 100 % of 2 stages" in stream.getvalue()


def test_an_unplanned_job_draws_its_active_stage():
    """Without a plan (simulate's one long run, a study's sweeps) the line is the active
    stage's own bar, named by job and stage."""
    stream = _Terminal()
    with progress.Progress(3, "sweep", unit="row", stream=stream) as bar:
        bar.update(3)
    assert "report: sweep: 100%" in stream.getvalue() and "3/3" in stream.getvalue()


def test_a_child_job_sends_records_that_its_parent_draws(monkeypatch):
    """The child (RELAY_ENV set) writes records, not bars; the parent's Relay draws them on
    the study's line on its terminal and passes other lines on after 'study: '."""
    child_out = io.StringIO()
    monkeypatch.setenv(progress.RELAY_ENV, "study")
    progress.set_job("sweep")
    progress.plan(1, child_out)
    with progress.Progress(3, "sweep", unit="row", stream=child_out) as bar:
        bar.update(3)
    print("table: results.parquet", file=child_out)
    lines = child_out.getvalue().splitlines(keepends=True)
    assert [ln.split("\t")[2] for ln in lines[:2]] == ["plan", "open"]
    assert lines[-2].split("\t")[2] == "close" and not lines[-1].startswith(progress.RECORD)
    monkeypatch.delenv(progress.RELAY_ENV)
    parent = _Terminal()
    relay = progress.Relay("study", parent)
    relay.line(lines[0])
    relay.line(lines[1])
    job = progress._JOBS["study"]
    assert job.bar.desc == "study: overall" and job.bar.postfix == "sweep 0/3 rows"
    for line in lines[2:]:
        relay.line(line)
    text = parent.getvalue()
    assert "study: overall 100 % of 1 stages" in text and "study: table: results.parquet" in text
    assert progress.RECORD not in text and job.percent == pytest.approx(100.0)


def test_a_parent_off_a_terminal_passes_on_only_the_child_s_text():
    relay = progress.Relay("study", io.StringIO())
    relay.line(f"{progress.RECORD}1\topen\tsweep\trow\t0\t5\n")
    relay.line(f"{progress.RECORD}1\tclose\tsweep\trow\t5\t5\n")
    relay.line("wall time: 3.0 s\n")
    assert relay.stream.getvalue() == "study: wall time: 3.0 s\n"
