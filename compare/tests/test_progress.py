"""Progress lines of long runs when stderr is not a terminal (logs, CI)."""

from __future__ import annotations

import io

from treeimpact.compare import progress


def test_a_line_every_few_seconds_and_the_wall_time_at_the_end(monkeypatch):
    stream = io.StringIO()  # not a terminal
    clock = iter([0.0, 1.0, 6.0, 7.0, 12.5, 13.0])
    monkeypatch.setattr(progress.time, "perf_counter", lambda: next(clock))
    with progress.Progress(4, "runs", stream=stream) as bar:
        for _ in range(4):
            bar.update()
    lines = stream.getvalue().splitlines()
    # t = 1 s: too soon; 6 s: a line; 7 s: too soon; 12.5 s: the last item, close() says it
    assert lines == ["runs: 2/4 runs (50 %), 6.0 s, running",
                     "runs: 4/4 runs (100 %), 13.0 s, done"]


def test_a_run_shorter_than_a_line_interval_prints_nothing(monkeypatch):
    stream = io.StringIO()
    clock = iter([0.0, 0.5, 1.0, 1.2])
    monkeypatch.setattr(progress.time, "perf_counter", lambda: next(clock))
    with progress.Progress(2, "runs", stream=stream) as bar:
        bar.update()
        bar.update()
    assert stream.getvalue() == ""
